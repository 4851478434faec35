// Our glTF outputs load in three.js, the most common web viewer: GLTFLoader with DRACOLoader,
// run in headless Chromium (DRACOLoader decodes in Web Workers, which node lacks), through
// tests/tools/check_three.mjs and tests/tools/three_loader.html. Needs `npm install` in
// tests/tools (three is pinned there) and the Debian package `chromium`
// (scripts/deps/apt-test.txt); without them the test fails with a message saying so.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "gltf_fixtures.h"
#include "io_test_support.h"

namespace mdn::io {
namespace {

namespace fs = std::filesystem;
using test_io::Json;
using test_io::tools_dir;

struct Output {
  std::string name;
  EncodeOptions options;
  bool draco;
};

// Coordinates as read back may differ from ours by at most this much: Draco's 16-bit positions
// over a box of side 2 move a coordinate by at most 2 / 65535 / 2 = 1.5e-5; float32 storage
// by about 1e-7.
double tolerance(bool draco) { return draco ? 1e-4 : 1e-6; }

struct Box {
  Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(1e300), hi = Eigen::RowVector3d::Constant(-1e300);
  void add(const Eigen::RowVector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
};

// The fixture scene's world box for surface positions V: node "scan-a" rotates the sphere by
// 90 degrees about y ((x, y, z) -> (z, y, -x)) and moves it to (1.5, 0, -2); "scan-b" scales it
// by 2; "markers" holds the points (0, 0, +-1.5).
Box world_box(const Vertices& V) {
  Box box;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    box.add(Eigen::RowVector3d(V(i, 2) + 1.5, V(i, 1), -V(i, 0) - 2.0));
    box.add(2.0 * V.row(i));
  }
  box.add(Eigen::RowVector3d(0, 0, 1.5));
  box.add(Eigen::RowVector3d(0, 0, -1.5));
  return box;
}

TEST(ThreeLoader, GlbAndGltfOutputsLoadInGltfLoaderWithDraco) {
  const fs::path tools = tools_dir();
  for (const char* needed : {"three/build/three.module.js", "three/examples/jsm/loaders/GLTFLoader.js",
                             "three/examples/jsm/loaders/DRACOLoader.js", "three/examples/jsm/libs/draco/gltf/draco_decoder.wasm",
                             "three/examples/jsm/libs/draco/gltf/draco_wasm_wrapper.js"}) {
    ASSERT_TRUE(fs::exists(tools / "node_modules" / needed))
        << "tests/tools/node_modules/" << needed << " is missing: run `npm install` in " << tools
        << " (scripts/install-deps.sh build test does it)";
  }
  std::string which;
  ASSERT_EQ(test_io::run_command("command -v \"${MDN_CHROMIUM:-chromium}\"", &which), 0)
      << "chromium is missing: install the Debian package `chromium` (scripts/deps/apt-test.txt)";

  // Our output: the fixture scene decoded, its surface moved onto the unit sphere (so the
  // page can check every position), re-encoded with and without Draco, as GLB and as glTF.
  const auto f = test_io::make_sphere();
  auto doc = decode(test_io::sphere_scene_glb(f), Format::Glb);
  TriMesh& s = doc->surfaces()[0];
  for (Eigen::Index i = 0; i < s.V.rows(); ++i) s.V.row(i) = s.V.row(i).normalized();
  Box local;
  for (Eigen::Index i = 0; i < s.V.rows(); ++i) local.add(s.V.row(i));
  const Box world = world_box(s.V);
  std::vector<Output> outputs;
  for (const auto& [draco, format] : {std::pair{true, Format::Glb}, {false, Format::Glb}, {true, Format::Gltf}, {false, Format::Gltf}}) {
    EncodeOptions options;
    options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
    options.format = format;
    outputs.push_back({std::string("out") + (draco ? "-draco" : "") + (format == Format::Glb ? ".glb" : ".gltf"), options, draco});
  }
  const fs::path dir = test_io::temp_dir();
  std::string command = "cd '" + tools.string() + "' && node check_three.mjs '" + dir.string() + "'";
  for (const auto& out : outputs) {
    test_io::write_file(dir / out.name, doc->encode(out.options).bytes);
    command += " '" + out.name + "'";
  }

  std::string output;
  const int rc = test_io::run_command(command, &output);
  ASSERT_EQ(rc, 0) << "check_three.mjs failed:\n" << output;
  // The report is the last line (the chromium launcher may print warnings before it).
  const std::size_t line = output.rfind("\n{");
  const Json result = Json::parse(output.substr(line == std::string::npos ? 0 : line + 1), nullptr, false);
  ASSERT_TRUE(result.is_object() && result.contains("reports")) << "check_three.mjs printed no report:\n" << output;
  const Json& reports = result["reports"];
  ASSERT_EQ(reports.size(), outputs.size()) << output;

  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const Json& r = reports[k];
    const std::string& name = outputs[k].name;
    ASSERT_EQ(r["file"], name);
    ASSERT_FALSE(r.contains("error")) << name << " did not load in three.js (" << result["browser"] << "):\n"
                                      << r["error"].get<std::string>();
    // Compressed outputs went through DRACOLoader (the Web Worker decoder), the others did not.
    const Json& used = r["extensionsUsed"];
    EXPECT_EQ(std::find(used.begin(), used.end(), "KHR_draco_mesh_compression") != used.end(), outputs[k].draco) << name << ": " << used;
    // Two nodes instance the two-primitive sphere (four THREE.Mesh), one node holds the points.
    int meshes = 0, points = 0;
    const double tol = tolerance(outputs[k].draco);
    Box read;
    for (const Json& o : r["objects"]) {
      EXPECT_TRUE(o["finite"].get<bool>()) << name << ": " << o;
      EXPECT_GT(o["vertices"].get<int>(), 0) << name << ": " << o;
      if (o["kind"] == "Points") {
        ++points;
        EXPECT_EQ(o["vertices"], 2) << name;
        continue;
      }
      ASSERT_EQ(o["kind"], "Mesh") << name << ": " << o;
      ++meshes;
      // Indexed triangles, with the attributes we wrote (Draco-decoded where compressed).
      ASSERT_FALSE(o["indices"].is_null()) << name;
      EXPECT_GT(o["indices"].get<int>(), 0) << name;
      EXPECT_EQ(o["indices"].get<int>() % 3, 0) << name;
      for (const char* attribute : {"normal", "position", "uv"})
        EXPECT_NE(std::find(o["attributes"].begin(), o["attributes"].end(), attribute), o["attributes"].end())
            << name << " lacks " << attribute << ": " << o;
      // Every position on the unit sphere (Draco: 16-bit quantisation over a box of side 2).
      EXPECT_LT(o["radiusError"].get<double>(), tol) << name;
      for (const char* end : {"min", "max"})
        read.add(Eigen::RowVector3d(o["box"][end][0].get<double>(), o["box"][end][1].get<double>(), o["box"][end][2].get<double>()));
    }
    EXPECT_EQ(meshes, 4) << name << ": " << r["objects"];
    EXPECT_EQ(points, 1) << name;
    // The primitives together span the box of our surface (close to [-1, 1]^3), and the node
    // transforms place the instances where the fixture put them.
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(read.lo[c], local.lo[c], tol) << name << " axis " << c;
      EXPECT_NEAR(read.hi[c], local.hi[c], tol) << name << " axis " << c;
      EXPECT_NEAR(local.lo[c], -1.0, 0.01) << "fixture";
      EXPECT_NEAR(local.hi[c], 1.0, 0.01) << "fixture";
      EXPECT_NEAR(r["worldBox"]["min"][c].get<double>(), world.lo[c], 2 * tol) << name << " axis " << c;
      EXPECT_NEAR(r["worldBox"]["max"][c].get<double>(), world.hi[c], 2 * tol) << name << " axis " << c;
    }
  }
  // Outputs stay for inspection when something failed; otherwise nothing is left behind.
  if (HasFailure()) {
    ADD_FAILURE() << "the files loaded are kept in " << dir;
  } else {
    fs::remove_all(dir);
  }
}

// Issue 51: meshopt outputs (EXT_meshopt_compression + KHR_mesh_quantization) load in three.js
// with GLTFLoader + MeshoptDecoder, every position on the unit sphere once placed by its node.
TEST(ThreeLoader, MeshoptOutputsLoadWithMeshoptDecoder) {
  const fs::path tools = tools_dir();
  ASSERT_TRUE(fs::exists(tools / "node_modules" / "three" / "examples" / "jsm" / "libs" / "meshopt_decoder.module.js"))
      << "three.js is missing: run `npm install` in " << tools;
  TriMesh m = test_io::sphere(24, 48);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) = m.V.row(i).normalized();
  const auto doc = decode(test_io::off_text(m.V, m.F), Format::Off);
  const fs::path dir = test_io::temp_dir();
  std::string command = "cd '" + tools.string() + "' && node check_three.mjs '" + dir.string() + "'";
  std::vector<std::pair<std::string, double>> outputs;  // name, tolerance on the radius
  for (const auto& [bits, format] : {std::pair{16, Format::Glb}, {12, Format::Gltf}, {20, Format::Glb}}) {
    EncodeOptions o;
    o.compression = Compression::Meshopt;
    o.format = format;
    o.position_bits = bits;
    const std::string name = "sphere-" + std::to_string(bits) + (format == Format::Glb ? ".glb" : ".gltf");
    test_io::write_file(dir / name, doc->encode(o).bytes);
    outputs.emplace_back(name, bits > 16 ? 1e-6 : 2.0 / (std::ldexp(1.0, bits) - 1) + 1e-6);
    command += " '" + name + "'";
  }
  std::string output;
  ASSERT_EQ(test_io::run_command(command, &output), 0) << "check_three.mjs failed:\n" << output;
  const std::size_t line = output.rfind("\n{");
  const Json result = Json::parse(output.substr(line == std::string::npos ? 0 : line + 1), nullptr, false);
  ASSERT_TRUE(result.is_object() && result.contains("reports")) << output;
  ASSERT_EQ(result["reports"].size(), outputs.size()) << output;
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const Json& r = result["reports"][k];
    const auto& [name, tolerance] = outputs[k];
    ASSERT_FALSE(r.contains("error")) << name << ": " << r["error"];
    const Json& used = r["extensionsUsed"];
    EXPECT_NE(std::find(used.begin(), used.end(), "EXT_meshopt_compression"), used.end()) << name;
    ASSERT_EQ(r["objects"].size(), 1u) << name;
    const Json& o = r["objects"][0];
    EXPECT_TRUE(o["finite"].get<bool>()) << name;
    EXPECT_EQ(o["vertices"], m.V.rows()) << name;
    EXPECT_EQ(o["indices"], 3 * m.F.rows()) << name;
    EXPECT_LT(o["worldRadiusError"].get<double>(), tolerance) << name;
  }
}

}  // namespace
}  // namespace mdn::io
