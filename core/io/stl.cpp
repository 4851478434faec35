// STL (stereolithography), binary and ASCII. STL is a triangle soup: every facet carries its
// own three corners, so shared corners are welded (weld_positions, its default tolerance: a few
// float32 ulps of the model's size) into one surface to denoise. The output keeps the input's
// facets, in their order and number, and its encoding: binary keeps the 80-byte header and each
// facet's 2 attribute bytes (colour in some writers), ASCII keeps the solid's name. Facet
// normals are recomputed from the written corners.
//
// Binary:  80-byte header, uint32 n, n x (float32 normal[3], float32 corner[3][3], uint16 attr);
//          its size is exactly 84 + 50 n, which is how it is told apart from ASCII (binary
//          headers often start with "solid" too).
// ASCII:   solid [name] { facet normal x y z outer loop (vertex x y z) x3 endloop endfacet }
//          endsolid [name]; keywords are whitespace separated, case as written by every tool.
#include <bit>
#include <cmath>
#include <cstring>
#include <algorithm>
#include <string>

#include "core/io/detail.h"
#include "core/io/plain.h"
#include "core/io/weld.h"

namespace mdn::io::detail {
namespace {

constexpr std::size_t kHeaderBytes = 80;
constexpr std::size_t kFacetBytes = 50;
// The shortest ASCII facet: "facet normal 0 0 0 outer loop vertex 0 0 0 vertex 0 0 0 vertex 0 0 0
// endloop endfacet" with single separators.
constexpr std::size_t kMinAsciiFacetBytes = 85;

static_assert(std::endian::native == std::endian::little, "the binary STL reader and writer assume a little-endian host");

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Whether the first whitespace-separated token of the text is "solid".
bool starts_with_solid(std::string_view bytes) {
  std::string_view rest = bytes.substr(0, 256);
  while (!rest.empty() && is_space(rest.front())) rest.remove_prefix(1);
  return rest.substr(0, 5) == "solid" && (rest.size() == 5 || is_space(rest[5]));
}

class StlDocument final : public MeshDocument {
 public:
  Format format() const override { return Format::Stl; }
  std::vector<TriMesh>& surfaces() override { return surfaces_; }
  std::vector<std::string> notes() const override { return {"STL facet normals recomputed from the denoised surface"}; }

  Encoded encode(const EncodeOptions& options) const override;

  bool ascii_ = false;
  std::string header_;                     // binary: the 80 header bytes
  std::string name_;                       // ASCII: the text after "solid" on its line
  std::vector<std::uint16_t> attributes_;  // binary: per facet
  std::int64_t welded_count_ = 0;
  std::vector<TriMesh> surfaces_;
};

// Charges the facets' soup (3 corners of 3 doubles, the weld's map and hash table, the faces)
// against the limits before it is allocated.
constexpr std::int64_t kBytesPerFacet = 3 * 3 * 8 + 3 * 4 + 3 * 2 * 32 + 3 * 4;
void check_facets(std::int64_t facets, const Limits& limits) {
  check_count(facets, limits.max_faces, "triangles");
  if (facets > limits.max_decoded_bytes / kBytesPerFacet)
    throw LimitError("STL: " + std::to_string(facets) + " triangles exceed the decoded size limit (" +
                     std::to_string(limits.max_decoded_bytes) + " bytes)");
}

std::unique_ptr<StlDocument> read_binary(std::string_view bytes, const Limits& limits) {
  if (bytes.size() < kHeaderBytes + 4)
    throw FormatError("STL: the input is " + std::to_string(bytes.size()) +
                      " bytes, shorter than a binary STL's 84-byte header and not ASCII STL ('solid ... facet normal')");
  std::uint32_t declared = 0;
  std::memcpy(&declared, bytes.data() + kHeaderBytes, 4);
  const std::int64_t n = declared;
  const auto expected = static_cast<std::int64_t>(kHeaderBytes + 4) + n * static_cast<std::int64_t>(kFacetBytes);
  if (expected != static_cast<std::int64_t>(bytes.size())) {
    const std::int64_t held = (static_cast<std::int64_t>(bytes.size()) - 84) / static_cast<std::int64_t>(kFacetBytes);
    throw FormatError("STL: the binary header declares " + std::to_string(n) + " triangles (" + std::to_string(expected) +
                      " bytes) but the input is " + std::to_string(bytes.size()) + " bytes (" + std::to_string(held) +
                      " whole triangles): truncated or not STL");
  }
  check_facets(n, limits);
  auto doc = std::make_unique<StlDocument>();
  doc->header_.assign(bytes.substr(0, kHeaderBytes));
  Vertices P(3 * n, 3);
  doc->attributes_.resize(static_cast<std::size_t>(n));
  const char* facet = bytes.data() + kHeaderBytes + 4;
  CancelPoll cancel(limits.cancel);
  for (std::int64_t f = 0; f < n; ++f, facet += kFacetBytes) {
    cancel.poll();
    float corner[9];
    std::memcpy(corner, facet + 12, sizeof corner);
    for (int k = 0; k < 9; ++k) {
      if (!std::isfinite(corner[k]))
        throw FormatError("STL: triangle " + std::to_string(f) + " has a non-finite vertex coordinate");
      P(3 * f + k / 3, k % 3) = corner[k];
    }
    std::memcpy(&doc->attributes_[static_cast<std::size_t>(f)], facet + 48, 2);
  }
  doc->surfaces_.push_back(TriMesh{std::move(P), {}});
  return doc;
}

// Token reader over the ASCII text, counting lines for error messages.
class Tokens {
 public:
  explicit Tokens(std::string_view text) : text_(text) {}
  std::string_view next() {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    const std::size_t begin = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    return text_.substr(begin, pos_ - begin);
  }
  // The rest of the current line (the solid's name), trimmed.
  std::string_view rest_of_line() {
    const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
    std::string_view rest = text_.substr(pos_, end - pos_);
    pos_ = end;
    while (!rest.empty() && is_space(rest.front())) rest.remove_prefix(1);
    while (!rest.empty() && is_space(rest.back())) rest.remove_suffix(1);
    return rest;
  }
  std::int64_t line() const { return line_; }
  std::size_t remaining() const { return text_.size() - pos_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::int64_t line_ = 1;
};

std::unique_ptr<StlDocument> read_ascii(std::string_view bytes, const Limits& limits) {
  auto doc = std::make_unique<StlDocument>();
  doc->ascii_ = true;
  Tokens tokens(bytes);
  const auto fail = [&](const std::string& message) {
    throw FormatError("STL line " + std::to_string(tokens.line()) + ": " + message);
  };
  const auto expect = [&](std::string_view keyword) {
    const std::string_view token = tokens.next();
    if (token != keyword)
      fail("expected '" + std::string(keyword) + "', found '" + std::string(token.substr(0, 32)) + "'");
  };
  const auto number = [&](const char* what) {
    const std::string_view token = tokens.next();
    double value = 0;
    if (!parse_number(token, value)) fail(std::string("expected a ") + what + ", found '" + std::string(token.substr(0, 32)) + "'");
    return value;
  };
  // A facet takes at least kMinAsciiFacetBytes: reserve for what the size can hold, within the limits.
  std::vector<double> corners;
  corners.reserve(9 * std::min<std::size_t>(bytes.size() / kMinAsciiFacetBytes,
                                            static_cast<std::size_t>(std::min(limits.max_faces, limits.max_decoded_bytes / kBytesPerFacet))));
  std::int64_t facets = 0;
  expect("solid");
  doc->name_ = std::string(tokens.rest_of_line().substr(0, 1024));
  // Several solids may follow one another; their facets form one surface.
  CancelPoll cancel(limits.cancel);
  for (;;) {
    cancel.poll();
    const std::string_view token = tokens.next();
    if (token == "endsolid") {
      tokens.rest_of_line();
      const std::string_view after = tokens.next();
      if (after.empty()) break;
      if (after != "solid") fail("expected 'solid' or the end of the input after 'endsolid', found '" + std::string(after.substr(0, 32)) + "'");
      tokens.rest_of_line();
      continue;
    }
    if (token.empty()) fail("the input ends before 'endsolid' (truncated)");
    if (token != "facet") fail("expected 'facet' or 'endsolid', found '" + std::string(token.substr(0, 32)) + "'");
    if (facets + 1 > limits.max_faces || facets + 1 > limits.max_decoded_bytes / kBytesPerFacet)
      throw LimitError("STL: the input holds more than " + std::to_string(facets) +
                       " triangles, past the limit (max_faces " + std::to_string(limits.max_faces) + ")");
    expect("normal");
    for (int k = 0; k < 3; ++k) number("facet normal component");  // recomputed on output
    expect("outer");
    expect("loop");
    for (int c = 0; c < 3; ++c) {
      expect("vertex");
      for (int k = 0; k < 3; ++k) {
        const double value = number("vertex coordinate");
        if (!std::isfinite(value)) fail("non-finite vertex coordinate");
        corners.push_back(value);
      }
    }
    expect("endloop");
    expect("endfacet");
    ++facets;
  }
  Vertices P(3 * facets, 3);
  for (std::int64_t i = 0; i < 3 * facets; ++i)
    for (int k = 0; k < 3; ++k) P(i, k) = corners[static_cast<std::size_t>(3 * i + k)];
  doc->surfaces_.push_back(TriMesh{std::move(P), {}});
  return doc;
}

Vec3 facet_normal(const TriMesh& mesh, Eigen::Index f) {
  const Vec3 a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)), c = mesh.V.row(mesh.F(f, 2));
  const Vec3 n = (b - a).cross(c - a);
  const double length = n.norm();
  return length > 0 && std::isfinite(length) ? Vec3(n / length) : Vec3::Zero();
}

}  // namespace

bool looks_like_ascii_stl(std::string_view bytes) {
  if (!starts_with_solid(bytes)) return false;
  Tokens tokens(bytes.substr(0, 1 << 12));
  tokens.next();         // solid
  tokens.rest_of_line();  // its name
  const std::string_view first = tokens.next();
  if (first == "endsolid") return true;  // an empty solid
  return first == "facet" && tokens.next() == "normal";
}

bool is_binary_stl_size(std::string_view bytes) {
  if (bytes.size() < kHeaderBytes + 4) return false;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + kHeaderBytes, 4);
  return static_cast<std::uint64_t>(bytes.size()) == kHeaderBytes + 4 + std::uint64_t{n} * kFacetBytes;
}

std::unique_ptr<MeshDocument> decode_stl(std::string_view bytes, const Limits& limits) {
  // The size identity first: ASCII text cannot satisfy it (bytes 80..83 would declare at least
  // 0x20202020 facets, a 27 GB file), binary files whose header starts with "solid" do.
  std::unique_ptr<StlDocument> doc =
      !is_binary_stl_size(bytes) && looks_like_ascii_stl(bytes) ? read_ascii(bytes, limits) : read_binary(bytes, limits);
  TriMesh& soup = doc->surfaces_.front();
  Weld weld = weld_positions(soup.V, 1e-6, limits.cancel);
  check_count(weld.V.rows(), limits.max_vertices, "vertices (welded)");
  const Eigen::Index facets = soup.V.rows() / 3;
  soup.F.resize(facets, 3);
  for (Eigen::Index f = 0; f < facets; ++f)
    for (int k = 0; k < 3; ++k) soup.F(f, k) = weld.map[static_cast<std::size_t>(3 * f + k)];
  soup.V = std::move(weld.V);
  doc->welded_count_ = soup.V.rows();
  return doc;
}

std::string write_stl_binary(const TriMesh& mesh, std::string_view header, const std::vector<std::uint16_t>& attributes) {
  std::string out(header.substr(0, kHeaderBytes));
  if (out.empty()) out = "binary STL written by meshdenoise";
  out.resize(kHeaderBytes, ' ');
  const auto n = static_cast<std::uint32_t>(mesh.F.rows());
  out.append(reinterpret_cast<const char*>(&n), 4);
  out.reserve(out.size() + kFacetBytes * n);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const Vec3 normal = facet_normal(mesh, f);
    float values[12];
    for (int k = 0; k < 3; ++k) values[k] = static_cast<float>(normal(k));
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) values[3 + 3 * c + k] = static_cast<float>(mesh.V(mesh.F(f, c), k));
    out.append(reinterpret_cast<const char*>(values), sizeof values);
    const std::uint16_t attribute = static_cast<std::size_t>(f) < attributes.size() ? attributes[static_cast<std::size_t>(f)] : 0;
    out.append(reinterpret_cast<const char*>(&attribute), 2);
  }
  return out;
}

std::string write_stl_ascii(const TriMesh& mesh, std::string_view name) {
  std::string out = "solid";
  if (!name.empty()) (out += ' ') += name;
  out += '\n';
  out.reserve(out.size() + static_cast<std::size_t>(mesh.F.rows()) * 200);
  const auto triple = [&](const char* prefix, float x, float y, float z) {
    out += prefix;
    for (const float v : {x, y, z}) {
      out += ' ';
      append_number(out, v);
    }
    out += '\n';
  };
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const Vec3 n = facet_normal(mesh, f);
    triple("  facet normal", float(n(0)), float(n(1)), float(n(2)));
    out += "    outer loop\n";
    for (int c = 0; c < 3; ++c) {
      const auto row = mesh.V.row(mesh.F(f, c));
      triple("      vertex", float(row(0)), float(row(1)), float(row(2)));
    }
    out += "    endloop\n  endfacet\n";
  }
  out += "endsolid";
  if (!name.empty()) (out += ' ') += name;
  out += '\n';
  return out;
}

Encoded StlDocument::encode(const EncodeOptions& options) const {
  check_surface_sizes(surfaces_, {welded_count_});
  if (options.format && *options.format != Format::Stl) return encode_plain(surfaces_, *options.format, options);
  check_float_coordinates(surfaces_, Format::Stl);
  const TriMesh& mesh = surfaces_.front();
  return {ascii_ ? write_stl_ascii(mesh, name_) : write_stl_binary(mesh, header_, attributes_), Compression::None};
}

}  // namespace mdn::io::detail
