// Outputs read back by tools we did not write: the Khronos glTF validator and glTF-Transform
// (tests/tools/check_gltf.mjs, Draco through draco3dgltf), and Draco's own draco_decoder.
// Needs `npm install` in tests/tools (scripts/install-deps.sh test does it) and the Debian
// package `draco`; without them these tests fail with a message saying so.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/io/document.h"
#include "gltf_fixtures.h"
#include "io_test_support.h"
#include "meshopt_fixture.h"

namespace mdn::io {
namespace {

namespace fs = std::filesystem;
using test_io::Json;
using test_io::tools_dir;

// Runs check_gltf.mjs on bytes written to `name`; fails the test if the tool cannot run.
Json check(const std::string& bytes, const std::string& name) {
  const fs::path dir = tools_dir();
  if (!fs::exists(dir / "node_modules" / "gltf-validator")) {
    ADD_FAILURE() << "tests/tools/node_modules is missing: run `npm install` in " << dir
                  << " (scripts/install-deps.sh build test does it)";
    return Json();
  }
  const fs::path file = test_io::temp_dir() / name;
  test_io::write_file(file, bytes);
  std::string output;
  const int rc = test_io::run_command("cd '" + dir.string() + "' && node check_gltf.mjs '" + file.string() + "'", &output);
  if (rc != 0) {
    ADD_FAILURE() << "check_gltf.mjs failed on " << name << ":\n" << output;
    return Json();
  }
  return Json::parse(output.substr(output.find('{')));
}

// Sorted UVs of every corner of every primitive of mesh 0 (independent of vertex order).
std::vector<std::vector<double>> corner_uvs(const Json& report) {
  std::vector<std::vector<double>> uvs;
  for (const auto& prim : report["meshes"][0])
    for (const auto& c : prim["corners"])
      if (c.size() == 5) uvs.push_back({c[3].get<double>(), c[4].get<double>()});
  std::sort(uvs.begin(), uvs.end());
  return uvs;
}

TEST(ExternalTools, GlbAndGltfOutputsValidateAndLoad) {
  const auto f = test_io::make_sphere();
  for (auto variant : {test_io::Variant::Plain, test_io::Variant::Quantized, test_io::Variant::Sparse}) {
    const std::string input = test_io::sphere_scene_glb(f, variant);
    const Json in = check(input, "input.glb");
    ASSERT_TRUE(in.is_object());
    EXPECT_EQ(in["errors"], 0) << in["messages"];  // the fixture itself is valid
    auto doc = decode(input, Format::Glb);
    TriMesh& s = doc->surfaces()[0];
    for (Eigen::Index i = 0; i < s.V.rows(); ++i) s.V.row(i) = s.V.row(i).normalized();
    for (const auto& [draco, format] : {std::pair{true, Format::Glb}, {false, Format::Glb}, {true, Format::Gltf}, {false, Format::Gltf}}) {
      EncodeOptions options;
      options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
      options.format = format;
      options.texcoord_bits = 0;  // lossless UVs: compared bit for bit below
      const std::string name = std::string("out") + (draco ? "-draco" : "") + (format == Format::Glb ? ".glb" : ".gltf");
      const Json out = check(doc->encode(options).bytes, name);
      ASSERT_TRUE(out.is_object()) << name;
      EXPECT_EQ(out["errors"], 0) << name << ": " << out["messages"];
      const bool listed = std::find(out["extensionsUsed"].begin(), out["extensionsUsed"].end(), "KHR_draco_mesh_compression") !=
                          out["extensionsUsed"].end();
      EXPECT_EQ(listed, draco) << name;
      // Same corners, same UVs (bit for bit: Draco stores them losslessly with 0 bits).
      EXPECT_EQ(corner_uvs(out), corner_uvs(in)) << name;
      // Positions are the clean sphere (16-bit Draco quantisation: within 1e-4).
      double worst = 0;
      for (const auto& prim : out["meshes"][0])
        for (const auto& c : prim["corners"])
          worst = std::max(worst, std::abs(std::hypot(c[0].get<double>(), c[1].get<double>(), c[2].get<double>()) - 1.0));
      EXPECT_LT(worst, 1e-4) << name;
      // The points primitive passed through.
      EXPECT_EQ(out["meshes"][1], in["meshes"][1]) << name;
    }
  }
}

TEST(ExternalTools, StripsAndDracoInputsValidate) {
  auto strips = decode(test_io::strip_and_fan_glb(6), Format::Glb);
  for (bool draco : {false, true}) {
    EncodeOptions options;
    options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
    const Json out = check(strips->encode(options).bytes, draco ? "strips-draco.glb" : "strips.glb");
    ASSERT_TRUE(out.is_object());
    EXPECT_EQ(out["errors"], 0) << out["messages"];
  }
  // Draco in (our own output), uncompressed and Draco out again.
  const auto f = test_io::make_sphere();
  auto first = decode(test_io::sphere_scene_glb(f), Format::Glb);
  auto doc = decode(first->encode({}).bytes, Format::Glb);
  for (bool draco : {false, true}) {
    EncodeOptions options;
    options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
    const Json out = check(doc->encode(options).bytes, draco ? "redraco.glb" : "undraco.glb");
    ASSERT_TRUE(out.is_object());
    EXPECT_EQ(out["errors"], 0) << out["messages"];
  }
}

// A unit sphere (float32, from OFF) and the meshopt fixture (quantized, meshopt-compressed).
std::unique_ptr<MeshDocument> unit_sphere_glb() {
  TriMesh m = test_io::sphere(24, 48);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) = m.V.row(i).normalized();
  EncodeOptions glb;
  glb.format = Format::Glb;
  glb.compression = Compression::None;
  return decode(decode(test_io::off_text(m.V, m.F), Format::Off)->encode(glb).bytes, Format::Glb);
}

// Issue 51: every meshopt output validates (Khronos), reads in glTF-Transform (meshoptimizer's
// decoder) with its positions where they were, re-packs in gltfpack, and reads back here.
TEST(ExternalTools, MeshoptOutputsValidateReadAndRepack) {
  const fs::path gltfpack = tools_dir() / "node_modules" / ".bin" / "gltfpack";
  ASSERT_TRUE(fs::exists(gltfpack)) << gltfpack << " is missing: run `npm install` in " << tools_dir();
  struct Case {
    std::string name;
    std::string bytes;
    double radius_tolerance;  // < 0: not a unit sphere
  };
  std::vector<Case> cases;
  const auto sphere = unit_sphere_glb();
  for (const auto& [bits, format] : {std::pair{16, Format::Glb}, {14, Format::Gltf}, {20, Format::Glb}}) {
    EncodeOptions o;
    o.compression = Compression::Meshopt;
    o.format = format;
    o.position_bits = bits;
    // Half a step of the grid over the box (side 2), plus float32 rounding of the transform.
    const double tolerance = bits > 16 ? 1e-6 : 2.0 / (std::ldexp(1.0, bits) - 1) + 1e-6;
    cases.push_back({"sphere-" + std::to_string(bits) + (format == Format::Glb ? ".glb" : ".gltf"), sphere->encode(o).bytes, tolerance});
  }
  EncodeOptions as_input;
  as_input.compression = Compression::AsInput;
  cases.push_back({"fixture-as-input.glb", decode(test_io::meshopt_sphere_glb(test_io::make_sphere(), true), Format::Glb)->encode(as_input).bytes, -1});
  EncodeOptions meshopt;
  meshopt.compression = Compression::Meshopt;
  meshopt.texcoord_bits = 12;
  cases.push_back({"scene-meshopt.glb", decode(test_io::sphere_scene_glb(test_io::make_sphere()), Format::Glb)->encode(meshopt).bytes, -1});
  for (const Case& c : cases) {
    const Json out = check(c.bytes, c.name);
    ASSERT_TRUE(out.is_object()) << c.name;
    EXPECT_EQ(out["errors"], 0) << c.name << ": " << out["messages"];
    EXPECT_EQ(out["warnings"], 0) << c.name << ": " << out["messages"];
    const Json& used = out["extensionsUsed"];
    EXPECT_NE(std::find(used.begin(), used.end(), "EXT_meshopt_compression"), used.end()) << c.name << ": " << used;
    if (c.radius_tolerance > 0) {
      // glTF-Transform's decoded corners, placed by the node that instances the mesh.
      const Json& m = out["meshWorld"][0];
      double worst = 0;
      for (const auto& prim : out["meshes"][0])
        for (const auto& corner : prim["corners"]) {
          Eigen::Vector3d p;
          for (int r = 0; r < 3; ++r)
            p(r) = m[r].get<double>() * corner[0].get<double>() + m[4 + r].get<double>() * corner[1].get<double>() +
                   m[8 + r].get<double>() * corner[2].get<double>() + m[12 + r].get<double>();
          worst = std::max(worst, std::abs(p.norm() - 1));
        }
      EXPECT_LT(worst, c.radius_tolerance) << c.name;
    }
    // Our own reader, and gltfpack re-packing it (meshopt again), which validates too.
    const auto back = decode(c.bytes, c.name.ends_with(".gltf") ? Format::Gltf : Format::Glb);
    EXPECT_EQ(back->compression(), Compression::Meshopt) << c.name;
    if (c.name.ends_with(".gltf")) continue;  // gltfpack reads .gltf with external files only
    const fs::path in = test_io::temp_dir() / c.name, repacked = test_io::temp_dir() / ("repacked-" + c.name);
    std::string log;
    ASSERT_EQ(test_io::run_command("'" + gltfpack.string() + "' -c -i '" + in.string() + "' -o '" + repacked.string() + "'", &log), 0)
        << c.name << ": " << log;
    const Json again = check(test_io::read_file(repacked), "repacked-" + c.name);
    ASSERT_TRUE(again.is_object()) << c.name;
    EXPECT_EQ(again["errors"], 0) << c.name << ": " << again["messages"];
  }
}

TEST(ExternalTools, DrcOutputDecodesWithDracoDecoder) {
  std::string which;
  if (test_io::run_command("command -v draco_decoder", &which) != 0) {
    FAIL() << "draco_decoder is missing: install the Debian package `draco` (scripts/deps/apt-test.txt)";
  }
  const TriMesh m = test_io::sphere(10, 16);
  std::string off = "OFF\n" + std::to_string(m.V.rows()) + " " + std::to_string(m.F.rows()) + " 0\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) off += std::to_string(m.V(i, 0)) + " " + std::to_string(m.V(i, 1)) + " " + std::to_string(m.V(i, 2)) + "\n";
  for (Eigen::Index i = 0; i < m.F.rows(); ++i) off += "3 " + std::to_string(m.F(i, 0)) + " " + std::to_string(m.F(i, 1)) + " " + std::to_string(m.F(i, 2)) + "\n";
  auto doc = decode(off, Format::Off);
  EncodeOptions options;
  options.format = Format::Drc;
  const std::string drc = doc->encode(options).bytes;
  const fs::path dir = test_io::temp_dir();
  test_io::write_file(dir / "sphere.drc", drc);
  std::string output;
  ASSERT_EQ(test_io::run_command("draco_decoder -i '" + (dir / "sphere.drc").string() + "' -o '" + (dir / "sphere.ply").string() + "'", &output), 0) << output;
  auto ply = decode(test_io::read_file(dir / "sphere.ply"), Format::Ply);
  EXPECT_EQ(ply->surfaces()[0].F.rows(), m.F.rows());
  for (Eigen::Index i = 0; i < ply->surfaces()[0].V.rows(); ++i) EXPECT_NEAR(ply->surfaces()[0].V.row(i).norm(), 1.0, 1e-3);
  // And a .drc made by draco_encoder reads back, and re-encodes as .drc.
  ASSERT_EQ(test_io::run_command("draco_encoder -i '" + (dir / "sphere.ply").string() + "' -o '" + (dir / "again.drc").string() + "'", &output), 0) << output;
  auto again = decode(test_io::read_file(dir / "again.drc"), Format::Drc);
  EXPECT_EQ(again->surfaces()[0].F.rows(), m.F.rows());
  EXPECT_EQ(sniff_format(again->encode({}).bytes), Format::Drc);
}

}  // namespace
}  // namespace mdn::io
