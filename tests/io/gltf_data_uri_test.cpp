// A .gltf's data-URI buffers, decoded from the body without tinygltf (decision 82): the same
// document as the .glb of the same content and as tinygltf's own decoding, every other data URI
// kept verbatim, and every malformed one a FormatError (or a LimitError), never a crash.
#include <gtest/gtest.h>

#include <string>

#include "core/io/document.h"
#include "gltf_fixtures.h"
#include "io_test_support.h"

namespace mdn::io {
namespace {

using test_io::Json;

constexpr std::string_view kHeader = "data:application/octet-stream;base64,";

// The sphere scene (two primitives, a PNG image in a buffer view, a points primitive, extras)
// as a GLB and as the .gltf the library writes from it: the same accessors and bytes, one
// buffer as a data URI.
struct Assets {
  std::string glb, gltf;
};
const Assets& assets() {
  static const Assets a = [] {
    Assets out;
    out.glb = test_io::sphere_scene_glb(test_io::make_sphere());
    EncodeOptions options;
    options.format = Format::Gltf;
    options.compression = Compression::None;
    out.gltf = decode(out.glb, Format::Glb)->encode(options).bytes;
    return out;
  }();
  return a;
}

// The .gltf split around its one buffer's base64 payload.
struct Split {
  std::string before, payload, after;
  std::string join() const { return before + payload + after; }
};
Split split_gltf(const std::string& gltf) {
  const std::size_t at = gltf.find(kHeader);
  EXPECT_NE(at, std::string::npos);
  const std::size_t start = at + kHeader.size(), end = gltf.find('"', start);
  return {gltf.substr(0, start), gltf.substr(start, end - start), gltf.substr(end)};
}

// The byteLength as written, replaced.
std::string with_byte_length(const std::string& gltf, const std::string& value) {
  Json j = Json::parse(gltf);
  const std::string old = "\"byteLength\":" + j["buffers"][0]["byteLength"].dump();
  const std::size_t at = gltf.find(old, gltf.find("\"buffers\""));
  EXPECT_NE(at, std::string::npos);
  return gltf.substr(0, at) + "\"byteLength\":" + value + gltf.substr(at + old.size());
}

void expect_same_surfaces(MeshDocument& a, MeshDocument& b) {
  ASSERT_EQ(a.surfaces().size(), b.surfaces().size());
  for (std::size_t s = 0; s < a.surfaces().size(); ++s) {
    EXPECT_EQ(a.surfaces()[s].V, b.surfaces()[s].V);
    EXPECT_EQ(a.surfaces()[s].F, b.surfaces()[s].F);
  }
  EXPECT_EQ(a.placements(), b.placements());
}

std::string encoded(const MeshDocument& doc, Format format) {
  EncodeOptions options;
  options.format = format;
  options.compression = Compression::None;
  return doc.encode(options).bytes;
}

TEST(GltfDataUri, DecodesLikeTheGlbOfTheSameContent) {
  auto from_glb = decode(assets().glb, Format::Glb);
  auto from_gltf = decode(assets().gltf, Format::Gltf);
  expect_same_surfaces(*from_glb, *from_gltf);
  EXPECT_EQ(encoded(*from_glb, Format::Glb), encoded(*from_gltf, Format::Glb));
}

// A body that holds the placeholder's prefix is not lifted: tinygltf decodes its data URI as it
// did before decision 82. Both paths give the same document and the same output bytes.
TEST(GltfDataUri, SameOutputAsTinygltfsOwnDecoding) {
  Json j = Json::parse(assets().gltf);
  j["asset"]["extras"]["note"] = "data:mdn-lifted;0";
  auto by_tinygltf = decode(j.dump(), Format::Gltf);
  auto lifted = decode(assets().gltf, Format::Gltf);
  expect_same_surfaces(*lifted, *by_tinygltf);
  Json expected = Json::parse(encoded(*by_tinygltf, Format::Gltf));
  expected["asset"]["extras"].erase("note");
  EXPECT_EQ(expected, Json::parse(encoded(*lifted, Format::Gltf)));  // the buffer's bytes too (its data URI)
}

TEST(GltfDataUri, OwnedBytesDecodeAlikeAndAreFreed) {
  std::string bytes = assets().gltf;
  auto owned = decode_owned(std::move(bytes), Format::Gltf, DecodeOptions{});
  EXPECT_TRUE(bytes.empty());
  expect_same_surfaces(*owned, *decode(assets().gltf, Format::Gltf));
  std::string broken = assets().gltf.substr(0, assets().gltf.size() / 2);
  EXPECT_THROW(decode_owned(std::move(broken), Format::Gltf, DecodeOptions{}), FormatError);
  EXPECT_TRUE(broken.empty());
}

// "\/" (a writer that escapes the solidus) and the other media types tinygltf reads a buffer
// under decode the same bytes.
TEST(GltfDataUri, EscapedSolidusAndOtherBufferMediaTypes) {
  auto expected = decode(assets().gltf, Format::Gltf);
  Split s = split_gltf(assets().gltf);
  std::string escaped;
  for (const char c : s.payload) escaped += c == '/' ? std::string("\\/") : std::string(1, c);
  ASSERT_NE(escaped, s.payload);
  expect_same_surfaces(*expected, *decode(s.before + escaped + s.after, Format::Gltf));
  const std::string prefix = s.before.substr(0, s.before.size() - kHeader.size());
  for (const char* header : {"data:application/gltf-buffer;base64,", "data:application\\/octet-stream;base64,"})
    expect_same_surfaces(*expected, *decode(prefix + header + s.payload + s.after, Format::Gltf));
}

// Data URIs that are not a buffer's (an image's, an extra's, an object key) come back verbatim.
TEST(GltfDataUri, OtherDataUrisAreKeptVerbatim) {
  Json j = Json::parse(assets().gltf);
  const std::string image = "data:image/png;base64,iVBORw0KGgo=";
  j["images"].push_back({{"uri", image}});
  j["extras"] = {{"data:key", "data:text/plain,a\\/b"}, {"escaped", "data:text/plain;base64,QQ\\u003d\\u003d"}};
  const auto doc = decode(j.dump(), Format::Gltf);
  const Json out = Json::parse(encoded(*doc, Format::Gltf));
  EXPECT_EQ(out["images"].back()["uri"], image);
  EXPECT_EQ(out["extras"], j["extras"]);
}

TEST(GltfDataUri, MalformedDataUrisAreFormatErrors) {
  const Split s = split_gltf(assets().gltf);
  const std::string prefix = s.before.substr(0, s.before.size() - kHeader.size());
  const std::size_t n = s.payload.size();
  ASSERT_EQ(n % 4, 0u);
  const std::string body = s.payload.substr(0, n - 4);  // whole groups, padding dropped
  const std::vector<std::pair<const char*, std::string>> cases = {
      {"a character outside the alphabet", s.before + s.payload.substr(0, 100) + "!" + s.payload.substr(101) + s.after},
      {"a space", s.before + s.payload.substr(0, 100) + " " + s.payload.substr(101) + s.after},
      {"truncated by a group", s.before + body + s.after},
      {"truncated inside a group", s.before + body + s.payload.substr(n - 4, 1) + s.after},
      {"padding in the middle", s.before + s.payload.substr(0, 100) + "=" + s.payload.substr(101) + s.after},
      {"three padding characters", s.before + body + "A===" + s.after},
      {"padding short of a group", s.before + body + "AA=" + s.after},
      {"a character after the padding", s.before + body + "AA=A" + s.after},
      {"one more group", s.before + s.payload + "AAAA" + s.after},
      {"empty", s.before + s.after},
      {"a media type tinygltf does not read", prefix + "data:model/gltf-binary;base64," + s.payload + s.after},
      {"not base64", prefix + "data:application/octet-stream," + s.payload + s.after},
      {"byteLength one more", with_byte_length(assets().gltf, std::to_string(Json::parse(assets().gltf)["buffers"][0]["byteLength"].get<int>() + 1))},
      {"byteLength one less", with_byte_length(assets().gltf, std::to_string(Json::parse(assets().gltf)["buffers"][0]["byteLength"].get<int>() - 1))},
      {"byteLength of a petabyte", with_byte_length(assets().gltf, "1000000000000000")},
      {"byteLength negative", with_byte_length(assets().gltf, "-4")},
      {"byteLength a string", with_byte_length(assets().gltf, "\"4\"")},
  };
  for (const auto& [what, text] : cases) {
    SCOPED_TRACE(what);
    EXPECT_THROW(decode(text, Format::Gltf), FormatError);
  }
}

TEST(GltfDataUri, DecodedBytesCountAgainstTheLimit) {
  const auto bytes = Json::parse(assets().gltf)["buffers"][0]["byteLength"].get<std::int64_t>();
  Limits limits;
  limits.max_decoded_bytes = bytes;  // the scene's JSON costs more than nothing
  EXPECT_THROW(decode(assets().gltf, Format::Gltf, limits), LimitError);
  limits.max_decoded_bytes = bytes + (std::int64_t{1} << 20);
  EXPECT_NO_THROW(decode(assets().gltf, Format::Gltf, limits));
}

// The command-line tool's .gltf with its buffer in a file beside it: the file's bytes go to the
// model as a data URI's do; its size must be the byteLength.
TEST(GltfDataUri, ExternalBufferFilesAreReadAsTheyAre) {
  const std::string& glb = assets().glb;
  std::uint32_t json_length;
  std::memcpy(&json_length, glb.data() + 12, 4);
  const std::string bin = glb.substr(20 + json_length + 8);
  Json j = Json::parse(glb.substr(20, json_length));
  j["buffers"][0] = {{"byteLength", bin.size()}, {"uri", "scan.bin"}};
  const auto dir = test_io::temp_dir();
  test_io::write_file(dir / "scan.bin", bin);
  DecodeOptions options;
  options.resource_dir = dir.string();
  auto from_files = decode(j.dump(), Format::Gltf, options);
  auto from_glb = decode(glb, Format::Glb);
  expect_same_surfaces(*from_glb, *from_files);
  EXPECT_EQ(encoded(*from_glb, Format::Glb), encoded(*from_files, Format::Glb));
  test_io::write_file(dir / "scan.bin", bin + "pad!");
  EXPECT_THROW(decode(j.dump(), Format::Gltf, options), FormatError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mdn::io
