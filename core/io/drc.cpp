// Raw Draco (.drc) meshes. Every attribute the payload carries (texture coordinates,
// colours, generic attributes, metadata) is kept; positions are replaced and normals
// recomputed. Output is always Draco, re-encoded with the caller's quantisation bits.
#include <draco/mesh/mesh.h>

#include "core/io/detail.h"
#include "core/io/draco_codec.h"
#include "core/io/plain.h"

namespace mdn::io::detail {
namespace {

class DrcDocument final : public MeshDocument {
 public:
  Format format() const override { return Format::Drc; }
  std::vector<TriMesh>& surfaces() override { return surfaces_; }
  std::vector<std::string> notes() const override {
    std::vector<std::string> notes;
    if (mesh_->GetNamedAttributeId(draco::GeometryAttribute::NORMAL) >= 0)
      notes.emplace_back("Draco NORMAL recomputed from the denoised surface");
    return notes;
  }
  Compression compression() const override { return Compression::Draco; }
  Encoded encode(const EncodeOptions& options) const override {
    check_surface_sizes(surfaces_, {welded_count_});
    if (options.format && *options.format != Format::Drc) return encode_plain(surfaces_, *options.format, options);
    draco::Mesh copy;
    copy.Copy(*mesh_);
    draco_update_geometry(copy, surfaces_.front().V, point_to_weld_);
    return {draco_encode(copy, options), Compression::Draco};
  }

  std::unique_ptr<draco::Mesh> mesh_;
  std::vector<std::int32_t> point_to_weld_;
  std::int64_t welded_count_ = 0;
  std::vector<TriMesh> surfaces_;
};

}  // namespace

std::unique_ptr<MeshDocument> decode_drc(std::string_view bytes, const Limits& limits) {
  auto doc = std::make_unique<DrcDocument>();
  doc->mesh_ = draco_decode(bytes, "DRC", limits);
  // Draco splits points wherever any attribute differs (e.g. at UV seams): weld them.
  Weld weld = weld_positions(draco_positions(*doc->mesh_), 1e-6, limits.cancel);
  const Triangles F = draco_faces(*doc->mesh_);
  TriMesh surface;
  surface.V = std::move(weld.V);
  surface.F.resize(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) surface.F(f, k) = weld.map[static_cast<std::size_t>(F(f, k))];
  doc->point_to_weld_ = std::move(weld.map);
  doc->welded_count_ = surface.V.rows();
  doc->surfaces_.push_back(std::move(surface));
  return doc;
}

}  // namespace mdn::io::detail
