// Wavefront OBJ. Only geometry is rewritten: the output is the input text with the x y z of
// every `v` line replaced (a w or r g b after them is kept) and every referenced `vn` line
// recomputed; texture coordinates, groups, materials, smoothing groups, comments and face
// corner indices (v/vt/vn) are copied byte for byte. A `vn` is recomputed as the
// area-weighted mean of the denoised normals of the faces whose corners use it, so normals
// that the input split at hard edges stay split. Every face must be a triangle.
#include <cmath>
#include <string>
#include <utility>

#include "core/io/detail.h"
#include "core/io/plain.h"
#include "core/io/text_table.h"

namespace mdn::io::detail {
namespace {

struct Span {
  std::size_t begin, end;  // byte range in the source text that the encoder rewrites
};

class ObjDocument final : public MeshDocument {
 public:
  Format format() const override { return Format::Obj; }
  std::vector<TriMesh>& surfaces() override { return surfaces_; }
  std::vector<std::string> notes() const override {
    if (!normal_spans_.empty()) return {"OBJ vertex normals (vn) recomputed from the denoised surface"};
    return {};
  }

  Encoded encode(const EncodeOptions& options) const override {
    check_surface_sizes(surfaces_, {static_cast<std::int64_t>(vertex_spans_.size())});
    if (options.format && *options.format != Format::Obj) return encode_plain(surfaces_, *options.format, options);
    const TriMesh& mesh = surfaces_.front();

    // Per-vn accumulation of (unnormalised, i.e. area-weighted) face normals.
    Vertices normals = Vertices::Zero(static_cast<Eigen::Index>(normal_spans_.size()), 3);
    for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
      const Vec3 a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)), c = mesh.V.row(mesh.F(f, 2));
      const Vec3 n = (b - a).cross(c - a);
      for (int k = 0; k < 3; ++k) {
        const std::int64_t vn = corner_normals_[static_cast<std::size_t>(f * 3 + k)];
        if (vn >= 0) normals.row(vn) += n.transpose();
      }
    }

    // Merge the two sorted span lists and copy everything between them verbatim.
    std::string out;
    out.reserve(source_.size() + source_.size() / 4);
    std::size_t pos = 0, iv = 0, in = 0;
    while (iv < vertex_spans_.size() || in < normal_spans_.size()) {
      const bool vertex = in >= normal_spans_.size() ||
                          (iv < vertex_spans_.size() && vertex_spans_[iv].begin < normal_spans_[in].begin);
      const Span span = vertex ? vertex_spans_[iv] : normal_spans_[in];
      out.append(source_, pos, span.begin - pos);
      if (vertex) {
        for (int k = 0; k < 3; ++k) {
          if (k) out += ' ';
          append_number(out, mesh.V(static_cast<Eigen::Index>(iv), k));
        }
        ++iv;
      } else {
        const Vec3 n = normals.row(static_cast<Eigen::Index>(in));
        const double len = n.norm();
        if (len > 0 && std::isfinite(len)) {
          for (int k = 0; k < 3; ++k) {
            if (k) out += ' ';
            append_number(out, n(k) / len);
          }
        } else {
          out.append(source_, span.begin, span.end - span.begin);  // unused by any face: unchanged
        }
        ++in;
      }
      pos = span.end;
    }
    out.append(source_, pos, std::string::npos);
    return {std::move(out), Compression::None};
  }

  std::string source_;
  std::vector<Span> vertex_spans_, normal_spans_;
  std::vector<std::int64_t> corner_normals_;  // #F*3, index into normal_spans_ or -1
  std::vector<TriMesh> surfaces_;
};

// Resolves a 1-based (or negative, relative) OBJ index against `count` entries seen so far.
std::int64_t resolve(const LineReader& reader, std::string_view token, std::int64_t count, const char* what) {
  std::int64_t index = 0;
  if (!parse_integer(token, index) || index == 0) fail_at_line("OBJ", reader, std::string("bad ") + what + " index '" + std::string(token.substr(0, 32)) + "'");
  return index > 0 ? index - 1 : count + index;
}

}  // namespace

std::unique_ptr<MeshDocument> decode_obj(std::string_view bytes, const Limits& limits) {
  auto doc = std::make_unique<ObjDocument>();
  doc->source_.assign(bytes);
  const std::string_view text = doc->source_;
  LineReader reader(text);
  std::vector<double> coords;
  PolygonMesh poly;
  std::int64_t normal_count = 0, texcoord_count = 0;
  std::vector<std::int64_t> face_normals;  // per polygon corner
  std::string_view line;
  CancelPoll cancel(limits.cancel);
  while (true) {
    cancel.poll();
    const std::size_t line_begin = reader.position();
    if (!reader.next(line)) break;
    std::string_view rest = line;
    const std::string_view keyword = next_token(rest);
    if (keyword == "v") {
      std::string_view after = rest;
      const std::size_t start = static_cast<std::size_t>(next_token(after).data() - text.data());
      after = rest;
      for (int k = 0; k < 3; ++k) {
        double value = 0;
        if (!parse_number(next_token(after), value)) fail_at_line("OBJ", reader, "expected three vertex coordinates");
        if (!std::isfinite(value)) fail_at_line("OBJ", reader, "non-finite vertex coordinate");
        coords.push_back(value);
      }
      doc->vertex_spans_.push_back({start, static_cast<std::size_t>(after.data() - text.data())});
      if (static_cast<std::int64_t>(doc->vertex_spans_.size()) > limits.max_vertices)
        check_count(static_cast<std::int64_t>(doc->vertex_spans_.size()), limits.max_vertices, "vertices");
    } else if (keyword == "vn") {
      std::string_view after = rest;
      const std::size_t start = static_cast<std::size_t>(next_token(after).data() - text.data());
      after = rest;
      for (int k = 0; k < 3; ++k) {
        double value = 0;
        if (!parse_number(next_token(after), value)) fail_at_line("OBJ", reader, "expected three normal coordinates");
      }
      doc->normal_spans_.push_back({start, static_cast<std::size_t>(after.data() - text.data())});
      ++normal_count;
    } else if (keyword == "vt") {
      ++texcoord_count;
    } else if (keyword == "f") {
      const auto nv = static_cast<std::int64_t>(doc->vertex_spans_.size());
      for (std::string_view corner = next_token(rest); !corner.empty(); corner = next_token(rest)) {
        const std::size_t s1 = corner.find('/');
        poly.indices.push_back(resolve(reader, corner.substr(0, s1), nv, "vertex"));
        std::int64_t vn = -1;
        if (s1 != std::string_view::npos) {
          const std::size_t s2 = corner.find('/', s1 + 1);
          const std::string_view vt = corner.substr(s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
          if (!vt.empty()) {
            const std::int64_t t = resolve(reader, vt, texcoord_count, "texture");
            if (t < 0 || t >= texcoord_count) fail_at_line("OBJ", reader, "texture index out of range");
          }
          if (s2 != std::string_view::npos) {
            vn = resolve(reader, corner.substr(s2 + 1), normal_count, "normal");
            if (vn < 0 || vn >= normal_count) fail_at_line("OBJ", reader, "normal index out of range");
          }
        }
        face_normals.push_back(vn);
      }
      if (poly.indices.size() == static_cast<std::size_t>(poly.offsets.back())) fail_at_line("OBJ", reader, "a face without vertices");
      poly.offsets.push_back(static_cast<std::int64_t>(poly.indices.size()));
      check_count(static_cast<std::int64_t>(poly.offsets.size()) - 1, limits.max_faces, "faces");
    }
    (void)line_begin;
  }
  if (doc->vertex_spans_.empty()) throw FormatError("OBJ: the input has no vertex ('v') lines");
  poly.V = Eigen::Map<const Vertices>(coords.data(), static_cast<Eigen::Index>(doc->vertex_spans_.size()), 3);
  doc->surfaces_.push_back(to_tri_mesh(poly));  // the core's documented error for non-triangles
  doc->corner_normals_ = std::move(face_normals);
  return doc;
}

}  // namespace mdn::io::detail
