// Single inputs that crashed, pinned or exhausted the process (issue 17's probe), generated
// here byte for byte: each must now give its typed error (HTTP 400 / 413 / 422) before the
// memory or the time it asked for is spent, and the error names the limit it hit.
#include <gtest/gtest.h>

#include <string>

#include "core/io/document.h"
#include "gltf_fixtures.h"
#include "io_test_support.h"
#include "support/shapes.h"

namespace mdn::io {
namespace {

using test_io::Json;

// what() of the exception `f` throws, which must be of type E.
template <class E, class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw another type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "did not throw";
  return "";
}

bool mentions(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string encode_as(std::string_view off, Format format) {
  EncodeOptions options;
  options.format = format;
  return decode(off, Format::Off)->encode(options).bytes;
}

// ---- encoders ----

TEST(EncoderInput, CoordinatesPastTheFloatRangeAreRefusedBeforeDracoRuns) {
  // Its span (6e38) is no float: Draco's quantisation grid became infinite and the encoder
  // crashed (SIGSEGV) for glb and drc.
  const std::string span = "OFF\n3 1 0\n3e38 0 0\n-3e38 0 0\n0 1 0\n3 0 1 2\n";
  for (const Format f : {Format::Glb, Format::Drc, Format::Gltf})
    EXPECT_TRUE(mentions(message_of<UnsupportedError>([&] { encode_as(span, f); }), "float")) << to_string(f);
  EXPECT_NO_THROW(encode_as(span, Format::Ply));  // each coordinate is a float
  EXPECT_NO_THROW(encode_as(span, Format::Off));
  // 1e300 is no float at all: every float container refuses it, the text ones keep it.
  const std::string huge = "OFF\n3 1 0\n1e300 0 0\n0 0 0\n0 1 0\n3 0 1 2\n";
  for (const Format f : {Format::Glb, Format::Drc, Format::Gltf, Format::Ply})
    EXPECT_TRUE(mentions(message_of<UnsupportedError>([&] { encode_as(huge, f); }), "float range")) << to_string(f);
  EXPECT_TRUE(mentions(encode_as(huge, Format::Obj), "1e+300"));
  // A large but representable span still encodes.
  EXPECT_NO_THROW(encode_as("OFF\n3 1 0\n1e30 0 0\n-1e30 0 0\n0 1 0\n3 0 1 2\n", Format::Drc));
}

TEST(EncoderInput, OnlyDegenerateTrianglesAreRefusedForDraco) {
  // "Draco encoding failed: All triangles are degenerate" was a 500.
  const std::string degenerate = "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 0 1\n3 2 2 1\n";
  for (const Format f : {Format::Glb, Format::Drc})
    EXPECT_TRUE(mentions(message_of<UnsupportedError>([&] { encode_as(degenerate, f); }), "degenerate")) << to_string(f);
  EncodeOptions plain;
  plain.format = Format::Glb;
  plain.compression = mdn::io::Compression::None;
  EXPECT_NO_THROW(decode(degenerate, Format::Off)->encode(plain).bytes);
  // One good triangle among degenerate ones: Draco drops the others.
  EXPECT_NO_THROW(encode_as("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 0 1\n3 0 1 2\n", Format::Drc));
}

// ---- PLY ----

TEST(PlyLimits, AnElementWithoutPropertiesCannotDeclareRows) {
  // Its rows take no bytes, so no size check bounded 4e18 of them: the job ignored its time
  // limit, DELETE and SIGTERM (binary), or filled memory writing them back (ascii).
  const std::string header = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\n"
                             "element nothing 4000000000000000000\nend_header\n";
  const std::string ascii = "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_TRUE(mentions(message_of<FormatError>([&] { decode(ascii, Format::Ply); }), "no properties"));
  std::string binary = "ply\nformat binary_little_endian 1.0\n" + header;
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  binary.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  const std::int32_t face[3] = {0, 1, 2};
  binary += char(3);
  binary.append(reinterpret_cast<const char*>(face), sizeof face);
  EXPECT_TRUE(mentions(message_of<FormatError>([&] { decode(binary, Format::Ply); }), "no properties"));
  // Without the empty element, the same file decodes.
  std::string fine = ascii;
  fine.replace(fine.find("element nothing"), std::string("element nothing 4000000000000000000\n").size(), "");
  EXPECT_NO_THROW(decode(fine, Format::Ply));
}

TEST(PlyLimits, AsciiValuesMustFitTheirDeclaredType) {
  // Written back with their type: 300 in a uchar was an undefined float-to-int conversion.
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                          "property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0 300\n1 0 0 0\n0 1 0 0\n3 0 1 2\n";
  EXPECT_TRUE(mentions(message_of<FormatError>([&] { decode(ply, Format::Ply); }), "does not fit"));
  std::string in_range = ply;
  in_range.replace(in_range.find("300"), 3, "255");
  EXPECT_NO_THROW(decode(in_range, Format::Ply)->encode({}).bytes);
  std::string float_overflow = in_range;
  float_overflow.replace(float_overflow.find("0 0 0 255"), 1, "1e300");
  EXPECT_THROW(decode(float_overflow, Format::Ply), FormatError);
}

// ---- Draco ----

// Bitstream 2.2 header for a mesh with the given encoder method (0 sequential, 1 edgebreaker).
std::string draco_header(std::uint8_t method) { return std::string("DRACO\x02\x02\x01", 8) + char(method) + std::string(2, '\0'); }

std::string varint(std::uint64_t v) {
  std::string out;
  do {
    std::uint8_t byte = v & 0x7F;
    v >>= 7;
    if (v) byte |= 0x80;
    out += char(byte);
  } while (v);
  return out;
}

TEST(DracoLimits, DeclaredFacesAreCheckedBeforeDracoAllocatesThem) {
  // Edgebreaker: traversal type, vertices, faces, attribute data, symbols, split symbols. A
  // payload of 25 bytes declaring 4e8 faces took the process to 6 GB inside Draco.
  const std::string bomb = draco_header(1) + '\0' + varint(3) + varint(400'000'000) + '\0' + varint(1) + varint(0) +
                           std::string(8, '\0');
  const std::string m = message_of<LimitError>([&] { decode(bomb, Format::Drc); });
  EXPECT_TRUE(mentions(m, "400000000 faces") && mentions(m, "max_faces")) << m;
}

TEST(DracoLimits, DeclaredPointsAreCheckedBeforeEveryAttributeAllocatesThem) {
  // Sequential: one face of uint32 indices, 4e9 points; then one float POSITION attribute,
  // which Draco sized for every declared point (23 GB).
  std::string bomb = draco_header(0) + varint(1) + varint(4'000'000'000) + '\1' + std::string(12, '\0');
  bomb += std::string("\x01") + varint(1) + "\x00\x09\x03\x00" + varint(0) + std::string("\x00", 1) + std::string(16, '\0');
  const std::string m = message_of<LimitError>([&] { decode(bomb, Format::Drc); });
  EXPECT_TRUE(mentions(m, "4000000000 vertices") && mentions(m, "max_vertices")) << m;
}

TEST(DracoLimits, AttributeBytesAreChargedBeforeDecodingThem) {
  // Draco allows 3 points per face: 21,845 faces of uint16 indices (131 KB) carry 65,535
  // points, and each attribute of 255 float64 components then takes 134 MB before any of its
  // values is read; a few bytes more declare another such attribute. Charged against the limit
  // before Draco decodes them (64 MB here).
  std::string bomb = draco_header(0) + varint(21'845) + varint(65'535) + '\1';
  for (int f = 0; f < 21'845; ++f) bomb += std::string("\0\0\1\0\2\0", 6);
  bomb += std::string("\x01") + varint(1) + std::string("\x04\x0A\xFF\x00", 4) + varint(0) + std::string("\x00", 1) +
          std::string(16, '\0');
  Limits limits;
  limits.max_decoded_bytes = 64 << 20;
  const std::string m = message_of<LimitError>([&] { decode(bomb, Format::Drc, limits); });
  EXPECT_TRUE(mentions(m, "max_decoded_bytes")) << m;
  // A real payload decodes as before.
  const std::string drc = encode_as(test::off_text(test_io::sphere(8, 12)), Format::Drc);
  EXPECT_EQ(decode(drc, Format::Drc)->surfaces().front().num_faces(), 8 * 12 * 2 - 2 * 12);
}

TEST(DracoLimits, APositionOfTypeBoolIsAFormatError) {
  // Found by fuzz_drc under UBSan: Draco's ConvertValue loaded the byte 222 as a bool.
  const std::string payload(
      "\x44\x52\x41\x43\x4f\x02\x02\x01\x01\x00\x00\x00\x0c\x14\x00\x13\x00\x00\x05\x6f\xab\x55\x55\x0a"
      "\x01\x01\x10\x01\xff\x00\x00\x01\x00\x0b\x03\x00\x00\x00\x70\x1c\x76\xe3\x01\x00\xde\x78\x00\x80"
      "\x00\xe3\xe0\x30\x38\xec\xc6\x03\x00\x00\x00\x00\xff\xff\x00\x00\x40\xc4\x5d\x59\xbf\x40\xc4\x59"
      "\xbf\x40\xc4\x59\xbf\x40\xc4\xd9\x35\x10",
      82);
  EXPECT_TRUE(mentions(message_of<FormatError>([&] { decode(payload, Format::Drc); }), "numeric type"));
}

// ---- glTF ----

std::string small_gltf() {
  EncodeOptions options;
  options.format = Format::Gltf;
  options.compression = mdn::io::Compression::None;
  return decode(test::off_text(test_io::sphere(4, 6)), Format::Off)->encode(options).bytes;
}

TEST(GltfLimits, DeepJsonIsRefusedBeforeTinygltfWalksIt) {
  // extras nested 20,000 deep (41 KB) overflowed the stack in tinygltf's recursive walk.
  Json j = Json::parse(small_gltf());
  const std::string text = j.dump();
  auto nested = [&](int depth) {
    std::string deep = std::string(static_cast<std::size_t>(depth), '[') + std::string(static_cast<std::size_t>(depth), ']');
    return text.substr(0, text.size() - 1) + ",\"extras\":" + deep + "}";
  };
  const std::string m = message_of<LimitError>([&] { decode(nested(20'000), Format::Gltf); });
  EXPECT_TRUE(mentions(m, "max_json_depth")) << m;
  EXPECT_NO_THROW(decode(nested(40), Format::Gltf));
  // In a GLB too.
  EXPECT_THROW(decode(test_io::Builder{Json::parse(nested(200)), ""}.glb(), Format::Glb), LimitError);
}

TEST(GltfLimits, NodeCountsAreCheckedBeforeTheSceneIsBuilt) {
  // 10^6 nodes in 12 MB of JSON took 712 MB; 200,001 nodes here against the default 100,000.
  Json j = Json::parse(small_gltf());
  j["nodes"] = Json::array({{{"mesh", 0}}});
  for (int i = 1; i <= 200'000; ++i) j["nodes"].push_back(Json::object());
  const std::string text = j.dump();
  const std::string m = message_of<LimitError>([&] { decode(text, Format::Gltf); });
  EXPECT_TRUE(mentions(m, "200001 nodes") && mentions(m, "max_nodes")) << m;
  Limits more;
  more.max_nodes = 300'000;
  EXPECT_NO_THROW(decode(text, Format::Gltf, more));
  more.max_decoded_bytes = 1 << 20;  // the scene's memory counts against the decoded bytes
  EXPECT_TRUE(mentions(message_of<LimitError>([&] { decode(text, Format::Gltf, more); }), "max_decoded_bytes"));
}

TEST(GltfLimits, JsonOfTheWrongShapeIsAFormatError) {
  // "nodes": 0 was a JSON type error, answered 500.
  const Json good = Json::parse(small_gltf());
  const auto with = [&](const char* pointer, const Json& value) {
    Json j = good;
    j[Json::json_pointer(pointer)] = value;
    return j.dump();
  };
  for (const auto& [pointer, value] :
       std::vector<std::pair<const char*, Json>>{{"/nodes", 0},
                                                 {"/nodes", Json::array({1})},
                                                 {"/meshes/0/primitives", "x"},
                                                 {"/meshes/0/primitives/0/attributes", Json::array()},
                                                 {"/meshes/0/primitives/0/attributes/POSITION", "0"},
                                                 {"/meshes/0/primitives/0/indices", Json::object()},
                                                 {"/accessors", Json::object()},
                                                 {"/extensionsUsed", Json::array({3})},
                                                 {"/nodes/0/extensions", 1},
                                                 {"/scene", "0"}}) {
    const std::string m = message_of<FormatError>([&] { decode(with(pointer, value), Format::Gltf)->encode({}).bytes; });
    EXPECT_TRUE(mentions(m, "glTF")) << pointer << ": " << m;
  }
}

TEST(GltfLimits, AnUnsupportedRequiredExtensionIsRefused) {
  // glTF 2.0, 3.12: a loader must refuse an asset whose extensionsRequired it does not support.
  Json j = Json::parse(small_gltf());
  j["extensionsUsed"] = {"EXT_something_new"};
  EXPECT_NO_THROW(decode(j.dump(), Format::Gltf));  // used only: optional, ignored and kept
  j["extensionsRequired"] = {"EXT_something_new"};
  EXPECT_TRUE(mentions(message_of<UnsupportedError>([&] { decode(j.dump(), Format::Gltf); }), "EXT_something_new"));
  j["extensionsUsed"] = {"KHR_texture_transform", "KHR_materials_clearcoat"};
  j["extensionsRequired"] = {"KHR_texture_transform", "KHR_materials_clearcoat"};
  EXPECT_NO_THROW(decode(j.dump(), Format::Gltf));
}

}  // namespace
}  // namespace mdn::io
