// OFF (Object File Format), ASCII. Accepted headers: OFF, COFF, NOFF, CNOFF (with optional
// counts on the header line). Whatever follows x y z on a vertex line (colours) and the
// indices on a face line (face colours) is written back verbatim; NOFF vertex normals are
// recomputed from the new positions. Binary OFF is refused.
#include <cmath>
#include <string>

#include "core/io/detail.h"
#include "core/io/plain.h"
#include "core/io/text_table.h"

namespace mdn::io::detail {
namespace {

class OffDocument final : public MeshDocument {
 public:
  Format format() const override { return Format::Off; }
  std::vector<TriMesh>& surfaces() override { return surfaces_; }
  std::vector<std::string> notes() const override {
    if (has_normals_) return {"NOFF vertex normals recomputed from the denoised surface"};
    return {};
  }

  Encoded encode(const EncodeOptions& options) const override {
    check_surface_sizes(surfaces_, {vertex_count_});
    if (options.format && *options.format != Format::Off) return encode_plain(surfaces_, *options.format, options);
    const TriMesh& mesh = surfaces_.front();
    std::string out;
    out.reserve(static_cast<std::size_t>(mesh.V.rows() * 40 + mesh.F.rows() * 24 + 64));
    out += keyword_;
    out += '\n';
    out += std::to_string(mesh.V.rows()) + ' ' + std::to_string(mesh.F.rows()) + " 0\n";
    Vertices normals;
    if (has_normals_) normals = vertex_normals(mesh.V, mesh.F);
    CancelPoll cancel(options.cancel);
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
      cancel.poll();
      for (int k = 0; k < 3; ++k) {
        if (k) out += ' ';
        append_number(out, mesh.V(i, k));
      }
      if (has_normals_)
        for (int k = 0; k < 3; ++k) {
          out += ' ';
          append_number(out, normals(i, k));
        }
      if (vertex_extra_.any() && !vertex_extra_[static_cast<std::size_t>(i)].empty()) {
        out += ' ';
        out += vertex_extra_[static_cast<std::size_t>(i)];
      }
      out += '\n';
    }
    for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
      cancel.poll();
      out += '3';
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        append_number(out, std::int64_t{mesh.F(f, k)});
      }
      if (face_extra_.any() && !face_extra_[static_cast<std::size_t>(f)].empty()) {
        out += ' ';
        out += face_extra_[static_cast<std::size_t>(f)];
      }
      out += '\n';
    }
    return {std::move(out), Compression::None};
  }

  std::string keyword_ = "OFF";
  bool has_normals_ = false;
  std::int64_t vertex_count_ = 0;
  TextColumn vertex_extra_, face_extra_;
  std::vector<TriMesh> surfaces_;
};

// Next line that is neither blank nor a comment; a trailing comment is cut off.
bool next_content_line(LineReader& reader, std::string_view& line) {
  while (reader.next(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    line = trim(line);
    if (!line.empty()) return true;
  }
  return false;
}

}  // namespace

std::unique_ptr<MeshDocument> decode_off(std::string_view bytes, const Limits& limits) {
  auto doc = std::make_unique<OffDocument>();
  LineReader reader(bytes);
  std::string_view line;
  if (!next_content_line(reader, line)) throw FormatError("OFF: the input is empty");
  std::string_view rest = line;
  const std::string_view keyword = next_token(rest);
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
    throw FormatError("OFF: the first line must be the OFF keyword, found '" + std::string(keyword.substr(0, 32)) + "'");
  const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find_first_not_of("CN") != std::string_view::npos)
    throw UnsupportedError("OFF variant '" + std::string(keyword) + "' is not supported (OFF, COFF, NOFF, CNOFF are)");
  if (trim(rest) == "BINARY") throw UnsupportedError("binary OFF is not supported; use ASCII OFF or PLY");
  doc->keyword_ = std::string(keyword);
  doc->has_normals_ = prefix.find('N') != std::string_view::npos;

  // The counts may follow the keyword on the same line.
  if (trim(rest).empty()) {
    if (!next_content_line(reader, line)) fail_at_line("OFF", reader, "missing vertex and face counts");
    rest = line;
  }
  std::int64_t nv = 0, nf = 0, ne = 0;
  if (!parse_integer(next_token(rest), nv) || !parse_integer(next_token(rest), nf))
    fail_at_line("OFF", reader, "expected '<vertices> <faces> <edges>'");
  const std::string_view edges = next_token(rest);
  if (!edges.empty() && !parse_integer(edges, ne)) fail_at_line("OFF", reader, "the edge count is not an integer");
  check_count(nv, limits.max_vertices, "vertices");
  check_count(nf, limits.max_faces, "faces");
  // Each vertex line takes at least 6 bytes ("0 0 0\n") and each face line 8: a header that
  // promises more than the input can hold is rejected before anything is allocated.
  if (nv * 6 + nf * 8 > static_cast<std::int64_t>(bytes.size()))
    throw FormatError("OFF: the header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                      " faces, more than the " + std::to_string(bytes.size()) + " bytes can hold");

  PolygonMesh poly;
  poly.V.resize(nv, 3);
  CancelPoll cancel(limits.cancel);
  for (std::int64_t i = 0; i < nv; ++i) {
    cancel.poll();
    if (!next_content_line(reader, line)) fail_at_line("OFF", reader, "the file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    rest = line;
    for (int k = 0; k < 3; ++k) {
      double value = 0;
      if (!parse_number(next_token(rest), value)) fail_at_line("OFF", reader, "expected three vertex coordinates");
      if (!std::isfinite(value)) fail_at_line("OFF", reader, "non-finite vertex coordinate");
      poly.V(i, k) = value;
    }
    if (doc->has_normals_)
      for (int k = 0; k < 3; ++k) next_token(rest);
    doc->vertex_extra_.push_back(trim(rest));
  }
  poly.offsets.reserve(static_cast<std::size_t>(nf) + 1);
  poly.indices.reserve(static_cast<std::size_t>(nf) * 3);
  for (std::int64_t f = 0; f < nf; ++f) {
    cancel.poll();
    if (!next_content_line(reader, line)) fail_at_line("OFF", reader, "the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    rest = line;
    std::int64_t n = 0;
    if (!parse_integer(next_token(rest), n) || n < 1 || n > 1'000'000) fail_at_line("OFF", reader, "expected a face vertex count");
    for (std::int64_t k = 0; k < n; ++k) {
      std::int64_t v = 0;
      if (!parse_integer(next_token(rest), v)) fail_at_line("OFF", reader, "expected " + std::to_string(n) + " vertex indices");
      poly.indices.push_back(v);
    }
    poly.offsets.push_back(static_cast<std::int64_t>(poly.indices.size()));
    doc->face_extra_.push_back(trim(rest));
  }
  // The core's documented error for non-triangles and out-of-range indices.
  doc->surfaces_.push_back(to_tri_mesh(poly));
  doc->vertex_count_ = nv;
  return doc;
}

}  // namespace mdn::io::detail
