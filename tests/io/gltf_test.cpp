// glTF / GLB adapter: what gets denoised, what must survive, and the errors.
#include <gtest/gtest.h>

#include <map>

#include "core/io/document.h"
#include "gltf_fixtures.h"
#include "io_test_support.h"

namespace mdn::io {
namespace {

using test_io::Json;

Json glb_json(const std::string& glb) {
  std::uint32_t length;
  std::memcpy(&length, glb.data() + 12, 4);
  return Json::parse(glb.substr(20, length));
}

// Everything that is not geometry must come back unchanged.
void expect_non_geometry_equal(const Json& in, const Json& out) {
  for (const char* key : {"asset", "extras", "scene", "scenes", "nodes", "materials", "textures", "samplers"})
    EXPECT_EQ(in.value(key, Json()), out.value(key, Json())) << key;
  ASSERT_EQ(in["images"].size(), out["images"].size());
  for (std::size_t i = 0; i < in["images"].size(); ++i) {
    Json a = in["images"][i], b = out["images"][i];
    a.erase("bufferView");
    b.erase("bufferView");
    EXPECT_EQ(a, b);
  }
  ASSERT_EQ(in["meshes"].size(), out["meshes"].size());
  for (std::size_t m = 0; m < in["meshes"].size(); ++m) {
    EXPECT_EQ(in["meshes"][m].value("name", ""), out["meshes"][m].value("name", ""));
    EXPECT_EQ(in["meshes"][m].value("extras", Json()), out["meshes"][m].value("extras", Json()));
    for (std::size_t p = 0; p < in["meshes"][m]["primitives"].size(); ++p)
      EXPECT_EQ(in["meshes"][m]["primitives"][p].value("material", -1), out["meshes"][m]["primitives"][p].value("material", -1));
  }
}

// Per-corner (position, uv) of the first mesh's triangles, read back with our decoder's
// surfaces: compares the welded surface against expected positions.
double max_distance_to(const TriMesh& surface, const std::vector<float>& expected_points) {
  // Each welded vertex must coincide with one expected point (nearest search, small sizes).
  double worst = 0;
  for (Eigen::Index i = 0; i < surface.V.rows(); ++i) {
    double best = 1e30;
    for (std::size_t j = 0; j < expected_points.size(); j += 3)
      best = std::min(best, (surface.V.row(i) - Eigen::RowVector3d(expected_points[j], expected_points[j + 1], expected_points[j + 2])).norm());
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(Gltf, SceneDecodesToOneWeldedSurfacePerMesh) {
  const auto f = test_io::make_sphere();
  auto doc = decode(test_io::sphere_scene_glb(f), Format::Glb);
  ASSERT_EQ(doc->surfaces().size(), 1u);  // mesh 0 instanced twice, mesh 1 is points only
  const TriMesh& s = doc->surfaces()[0];
  // Seam copies (last-bit differences) and pole copies welded: rings-1 rows of segments + 2 poles.
  EXPECT_EQ(s.V.rows(), (f.rings - 1) * f.segments + 2);
  EXPECT_EQ(s.F.rows(), static_cast<Eigen::Index>((f.upper.size() + f.lower.size()) / 3));
  EXPECT_LT(max_distance_to(s, f.noisy), 1e-6);
}

class GltfOutputs : public ::testing::TestWithParam<bool> {};  // param: Draco on / off

TEST_P(GltfOutputs, DenoisedGeometryComesBackEverythingElseUnchanged) {
  const auto f = test_io::make_sphere();
  const std::string input = test_io::sphere_scene_glb(f);
  auto doc = decode(input, Format::Glb);
  TriMesh& s = doc->surfaces()[0];
  // Stand-in for the denoiser: the clean position of each welded vertex.
  for (Eigen::Index i = 0; i < s.V.rows(); ++i) s.V.row(i) = s.V.row(i).normalized();
  EncodeOptions options;
  options.compression = GetParam() ? mdn::io::Compression::Draco : mdn::io::Compression::None;
  const std::string out = doc->encode(options).bytes;
  EXPECT_EQ(out, doc->encode(options).bytes);  // deterministic
  EXPECT_EQ(sniff_format(out), Format::Glb);
  const Json in_json = glb_json(input), out_json = glb_json(out);
  expect_non_geometry_equal(in_json, out_json);
  const bool has_draco = out_json.value("extensionsRequired", Json::array()).dump().find("KHR_draco_mesh_compression") != std::string::npos;
  EXPECT_EQ(has_draco, GetParam());
  EXPECT_EQ(out_json["meshes"][1], in_json["meshes"][1]);  // points primitive untouched
  if (GetParam()) {
    EXPECT_LT(out.size(), input.size());
  }

  // Read back: the surface is the clean sphere (within Draco's 16-bit quantisation), welded
  // exactly as before, so seam copies got the same position (no cracks).
  auto back = decode(out, Format::Glb);
  ASSERT_EQ(back->surfaces().size(), 1u);
  const TriMesh& r = back->surfaces()[0];
  EXPECT_EQ(r.V.rows(), s.V.rows());
  EXPECT_EQ(r.F.rows(), s.F.rows());
  for (Eigen::Index i = 0; i < r.V.rows(); ++i) EXPECT_NEAR(r.V.row(i).norm(), 1.0, 1e-4);
  // The normals now follow the new surface: nearly radial everywhere.
  EXPECT_FALSE(doc->notes().empty());
}

INSTANTIATE_TEST_SUITE_P(DracoOnOff, GltfOutputs, ::testing::Values(false, true));

TEST(Gltf, UvsSurviveUncompressedBitForBit) {
  const auto f = test_io::make_sphere();
  const std::string input = test_io::sphere_scene_glb(f);
  auto doc = decode(input, Format::Glb);
  doc->surfaces()[0].V *= 1.01;
  EncodeOptions options;
  options.compression = mdn::io::Compression::None;
  const std::string out = doc->encode(options).bytes;
  const Json j = glb_json(out);
  // The UV accessor and its bytes are unchanged.
  const int uv = j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"];
  const Json& acc = j["accessors"][uv];
  EXPECT_EQ(acc["count"], f.vertices());
  const Json& view = j["bufferViews"][acc["bufferView"].get<int>()];
  const std::size_t bin = 20 + glb_json(out).dump().size();
  (void)bin;
  std::uint32_t json_len;
  std::memcpy(&json_len, out.data() + 12, 4);
  const std::size_t start = 20 + json_len + 8 + view.value("byteOffset", 0) + acc.value("byteOffset", 0);
  ASSERT_LE(start + f.uv.size() * 4, out.size());
  EXPECT_EQ(std::memcmp(out.data() + start, f.uv.data(), f.uv.size() * 4), 0);
}

TEST(Gltf, QuantizedSparseAndStripInputsDecode) {
  const auto f = test_io::make_sphere();
  auto quantized = decode(test_io::sphere_scene_glb(f, test_io::Variant::Quantized), Format::Glb);
  std::vector<float> scaled;
  for (float v : f.noisy) scaled.push_back(std::round(std::clamp(v / 1.2f, -1.0f, 1.0f) * 32767) / 32767.0f);
  EXPECT_LT(max_distance_to(quantized->surfaces()[0], scaled), 1e-6);
  EncodeOptions plain;
  plain.compression = mdn::io::Compression::None;
  auto requantized = decode(quantized->encode(plain).bytes, Format::Glb);
  EXPECT_EQ(requantized->surfaces()[0].F, quantized->surfaces()[0].F);

  auto sparse = decode(test_io::sphere_scene_glb(f, test_io::Variant::Sparse), Format::Glb);
  // Even vertices come from the sparse substitution (noisy), odd ones from the dense data.
  std::vector<float> expected;
  for (int i = 0; i < f.vertices(); ++i)
    for (int k = 0; k < 3; ++k) expected.push_back((i % 2 == 0 ? f.noisy : f.clean)[static_cast<std::size_t>(i * 3 + k)]);
  EXPECT_LT(max_distance_to(sparse->surfaces()[0], expected), 1e-6);
  const std::string sparse_out = sparse->encode(plain).bytes;
  EXPECT_EQ(glb_json(sparse_out).dump().find("\"sparse\""), std::string::npos);

  auto strips = decode(test_io::strip_and_fan_glb(6), Format::Glb);
  ASSERT_EQ(strips->surfaces().size(), 2u);
  EXPECT_EQ(strips->surfaces()[0].F.rows(), 12);  // 14 strip vertices -> 12 triangles
  EXPECT_EQ(strips->surfaces()[1].F.rows(), 6);   // 8 fan vertices -> 6 triangles
  // Strip winding alternates so all triangles face the same side.
  const Vertices N = face_normals(strips->surfaces()[0].V, strips->surfaces()[0].F);
  for (Eigen::Index i = 1; i < N.rows(); ++i) EXPECT_GT(N.row(i).dot(N.row(0)), 0.9);
  for (bool draco : {false, true}) {
    EncodeOptions options;
    options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
    auto again = decode(strips->encode(options).bytes, Format::Glb);
    EXPECT_EQ(again->surfaces()[0].F.rows(), 12);
  }
}

TEST(Gltf, DracoInputRoundTripsAndGltfContainerToo) {
  const auto f = test_io::make_sphere();
  auto doc = decode(test_io::sphere_scene_glb(f), Format::Glb);
  const std::string draco = doc->encode({}).bytes;
  auto from_draco = decode(draco, Format::Glb);
  EXPECT_EQ(from_draco->surfaces()[0].V.rows(), doc->surfaces()[0].V.rows());
  EncodeOptions options;
  options.compression = mdn::io::Compression::None;
  options.format = Format::Gltf;
  const std::string gltf = from_draco->encode(options).bytes;
  EXPECT_EQ(sniff_format(gltf), Format::Gltf);
  EXPECT_EQ(gltf.find("KHR_draco_mesh_compression"), std::string::npos);
  auto from_gltf = decode(gltf, Format::Gltf);
  EXPECT_EQ(from_gltf->surfaces()[0].F.rows(), doc->surfaces()[0].F.rows());
  EXPECT_LT((from_gltf->surfaces()[0].V - from_draco->surfaces()[0].V).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(Gltf, PlainSurfacesConvertToGlb) {
  const TriMesh m = test_io::grid(3);
  std::string off = "OFF\n16 18 0\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) off += std::to_string(m.V(i, 0)) + " " + std::to_string(m.V(i, 1)) + " 0\n";
  for (Eigen::Index i = 0; i < m.F.rows(); ++i) off += "3 " + std::to_string(m.F(i, 0)) + " " + std::to_string(m.F(i, 1)) + " " + std::to_string(m.F(i, 2)) + "\n";
  auto doc = decode(off, Format::Off);
  for (bool draco : {false, true}) {
    EncodeOptions options;
    options.format = Format::Glb;
    options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
    auto back = decode(doc->encode(options).bytes, Format::Glb);
    EXPECT_EQ(back->surfaces()[0].V.rows(), 16);
    EXPECT_EQ(back->surfaces()[0].F.rows(), 18);
  }
}

TEST(Gltf, MalformedAndUnsafeInputsGetTypedErrors) {
  const auto f = test_io::make_sphere();
  const std::string good = test_io::sphere_scene_glb(f);
  EXPECT_THROW(decode(good.substr(0, 10), Format::Glb), FormatError);
  EXPECT_THROW(decode(good.substr(0, good.size() - 100), Format::Glb), FormatError);
  EXPECT_THROW(decode("{not json", Format::Gltf), FormatError);
  EXPECT_THROW(decode("[1,2]", Format::Gltf), FormatError);
  // External URIs are refused and never read.
  const std::string external = R"({"asset":{"version":"2.0"},"buffers":[{"uri":"../../etc/hostname","byteLength":4}]})";
  try {
    decode(external, Format::Gltf);
    FAIL() << "external URI accepted";
  } catch (const UnsupportedError& e) {
    EXPECT_NE(std::string(e.what()).find("../../etc/hostname"), std::string::npos);
  }
  EXPECT_THROW(decode(R"({"asset":{"version":"2.0"},"images":[{"uri":"http://example.com/a.png"}]})", Format::Gltf), UnsupportedError);
  try {
    decode(R"({"asset":{"version":"2.0"},"extensionsUsed":["KHR_meshopt_compression"]})", Format::Gltf);
    FAIL();
  } catch (const UnsupportedError& e) {  // EXT_meshopt_compression is decoded (meshopt_test.cpp)
    EXPECT_NE(std::string(e.what()).find("KHR_meshopt_compression"), std::string::npos);
  }
  // An accessor that claims more elements than its buffer view holds.
  Json j = glb_json(good);
  auto with = [&](const Json& changed) {
    test_io::Builder b;
    b.json = changed;
    std::uint32_t json_len;
    std::memcpy(&json_len, good.data() + 12, 4);
    b.bin = good.substr(20 + json_len + 8);
    b.json.erase("buffers");
    return b.glb();
  };
  Json big = j;
  big["accessors"][0]["count"] = 100000;
  EXPECT_THROW(decode(with(big), Format::Glb), FormatError);
  Json huge = j;
  huge["accessors"][0]["count"] = 4000000000LL;
  EXPECT_ANY_THROW(decode(with(huge), Format::Glb));
  Json bad_index = j;
  bad_index["meshes"][0]["primitives"][0]["indices"] = 99;
  EXPECT_THROW(decode(with(bad_index), Format::Glb), FormatError);
  // A primitive without "attributes": tinygltf drops it and numbers the next one 0; accepting
  // that wrote the first primitive's output into the wrong JSON primitive (found by
  // hostile_input_test under AddressSanitizer).
  Json no_attributes = j;
  no_attributes["meshes"][0]["primitives"][0]["at|ributes"] = no_attributes["meshes"][0]["primitives"][0]["attributes"];
  no_attributes["meshes"][0]["primitives"][0].erase("attributes");
  try {
    decode(with(no_attributes), Format::Glb);
    FAIL() << "a primitive without attributes was accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh 0 has an invalid primitive"), std::string::npos) << e.what();
  }
  // A buffer view no surface reads (the PNG's) reaching past the end of the buffer: the output
  // copies every view, so this read past the end of the input (found under AddressSanitizer).
  Json long_view = j;
  const int image_view = long_view["images"][0]["bufferView"].get<int>();
  long_view["bufferViews"][image_view]["byteLength"] = 1 << 20;
  try {
    decode(with(long_view), Format::Glb);
    FAIL() << "a buffer view past the end of its buffer was accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("buffer view " + std::to_string(image_view) + " reaches past the end"),
              std::string::npos) << e.what();
  }
  Limits small;
  small.max_faces = 10;
  EXPECT_THROW(decode(good, Format::Glb, small), LimitError);
  Limits tiny_bytes;
  tiny_bytes.max_decoded_bytes = 1000;
  EXPECT_THROW(decode(good, Format::Glb, tiny_bytes), LimitError);
  // Garbage Draco payload.
  auto doc = decode(good, Format::Glb);
  std::string draco = doc->encode({}).bytes;
  Json dj = glb_json(draco);
  std::uint32_t json_len;
  std::memcpy(&json_len, draco.data() + 12, 4);
  for (std::size_t i = 20 + json_len + 8 + 40; i < draco.size(); i += 7) draco[i] = static_cast<char>(draco[i] ^ 0x5A);
  EXPECT_ANY_THROW(decode(draco, Format::Glb));
}

}  // namespace
}  // namespace mdn::io
