// Small helpers for the io tests: procedural meshes and temporary files.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "core/mesh.h"

namespace mdn::test_io {

// A (n+1) x (n+1) grid on z = 0 over [0, 1]^2, two triangles per cell, CCW from +z.
inline TriMesh grid(int n) {
  TriMesh m;
  m.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.V.row(j * (n + 1) + i) << double(i) / n, double(j) / n, 0.0;
  m.F.resize(2 * n * n, 3);
  int f = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.F.row(f++) << a, b, d;
      m.F.row(f++) << a, d, c;
    }
  return m;
}

// A UV sphere of radius 1 (poles included), CCW from outside.
inline TriMesh sphere(int rings, int segments) {
  TriMesh m;
  const int nv = 2 + (rings - 1) * segments;
  m.V.resize(nv, 3);
  m.V.row(0) << 0, 0, 1;
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double th = M_PI * r / rings, ph = 2 * M_PI * s / segments;
      m.V.row(1 + (r - 1) * segments + s) << std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th);
    }
  m.V.row(nv - 1) << 0, 0, -1;
  std::vector<std::array<int, 3>> faces;
  auto id = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) faces.push_back({0, id(1, s), id(1, s + 1)});
  for (int r = 1; r < rings - 1; ++r)
    for (int s = 0; s < segments; ++s) {
      faces.push_back({id(r, s), id(r + 1, s), id(r + 1, s + 1)});
      faces.push_back({id(r, s), id(r + 1, s + 1), id(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) faces.push_back({id(rings - 1, s), nv - 1, id(rings - 1, s + 1)});
  m.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) m.F.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  return m;
}

// Adds Gaussian noise of std sigma to every coordinate (fixed seed).
inline Vertices jitter(const Vertices& V, double sigma, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  Vertices out = V;
  for (Eigen::Index i = 0; i < out.rows(); ++i)
    for (int k = 0; k < 3; ++k) out(i, k) += normal(rng);
  return out;
}

// An OFF file of a mesh (9 significant digits: float32 positions come back exactly).
inline std::string off_text(const Vertices& V, const Triangles& F) {
  std::string off = "OFF\n" + std::to_string(V.rows()) + " " + std::to_string(F.rows()) + " 0\n";
  char line[128];
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", V(i, 0), V(i, 1), V(i, 2));
    off += line;
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    std::snprintf(line, sizeof line, "3 %d %d %d\n", int(F(f, 0)), int(F(f, 1)), int(F(f, 2)));
    off += line;
  }
  return off;
}

inline std::filesystem::path temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  auto dir = std::filesystem::temp_directory_path() / ("mdn_io_" + std::string(info->test_suite_name()) + "_" + info->name());
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs a shell command, returns its exit status and (via `output`) stdout+stderr.
inline int run_command(const std::string& command, std::string* output = nullptr) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  std::string text;
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) text.append(buffer, n);
  const int status = pclose(pipe);
  if (output) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// tests/tools (the npm tools that read our outputs back).
inline std::filesystem::path tools_dir() {
  const char* source = std::getenv("MDN_SOURCE_DIR");
  // Run by hand, the tree is found from this file (tests/io/io_test_support.h).
  const std::filesystem::path root =
      source ? std::filesystem::path(source) : std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
  return root / "tests" / "tools";
}

}  // namespace mdn::test_io
