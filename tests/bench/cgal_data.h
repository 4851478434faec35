// CGAL's demo meshes (Debian's libcgal-demo) for the benchmarks: locating the folder,
// fetching it with scripts/fetch-cgal-data.sh when absent, and reading one mesh.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "core/io/document.h"
#include "core/mesh.h"

namespace mdn::bench {

// The default data folder: $MDN_CGAL_DATA, else <source>/third_party_data/cgal.
inline std::filesystem::path default_cgal_data() {
  if (const char* env = std::getenv("MDN_CGAL_DATA"); env && *env) return env;
  return std::filesystem::path(MDN_SOURCE_DIR) / "third_party_data" / "cgal";
}

// The folder holding fandisk.off and the other meshes under `data`; runs
// scripts/fetch-cgal-data.sh first if they are not there.
inline std::filesystem::path cgal_meshes(const std::filesystem::path& data) {
  namespace fs = std::filesystem;
  const auto find = [&]() -> fs::path {
    for (const fs::path& p : {data / "data" / "meshes", data / "meshes", data})
      if (fs::exists(p / "fandisk.off")) return p;
    return {};
  };
  fs::path dir = find();
  if (dir.empty()) {
    const std::string cmd = "bash '" + (fs::path(MDN_SOURCE_DIR) / "scripts" / "fetch-cgal-data.sh").string() +
                            "' '" + data.string() + "' >/dev/null";
    std::printf("fandisk.off not found under %s; running %s\n", data.c_str(), cmd.c_str());
    std::fflush(stdout);
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("fetch-cgal-data.sh failed");
    dir = find();
    if (dir.empty()) throw std::runtime_error("fandisk.off still missing under " + data.string());
  }
  return dir;
}

// The single surface of an OFF file (polygons triangulated by the OFF adapter).
inline TriMesh load_off(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto doc = io::decode(bytes, io::Format::Off);
  if (doc->surfaces().size() != 1) throw std::runtime_error("expected one surface in " + path.string());
  return doc->surfaces()[0];
}

}  // namespace mdn::bench
