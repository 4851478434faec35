// Internal to mdn_io: Draco payloads <-> draco::Mesh with the library's core Decoder and
// Encoder (never draco::GltfDecoder, see core/io/README.md), and the geometry update shared
// by raw .drc files and KHR_draco_mesh_compression primitives.
#pragma once

#include <draco/mesh/mesh.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/io/document.h"
#include "core/io/weld.h"

namespace mdn::io::detail {

// Decodes a Draco mesh payload. `what` names it in errors ("DRC", "mesh 2 primitive 0").
// Throws FormatError (corrupt payload), UnsupportedError (a point cloud) or LimitError.
std::unique_ptr<draco::Mesh> draco_decode(std::string_view bytes, const std::string& what, const Limits& limits);

// A position quantisation grid shared by several payloads: the same input position gives
// the same decoded position in each (no cracks between primitives of one mesh).
struct QuantizationBox {
  float origin[3] = {0, 0, 0};
  float range = 1;  // edge of the cube the grid spans
};

// The largest bounding-box edge a Draco position grid may span (a quarter of the float
// range, so that the grid's margins stay finite).
inline constexpr double kMaxDracoSpan = 8.5e37;

// Below this edge of an explicit position grid, levels 9 and 10 predict positions with the
// plain parallelogram scheme (decision 77): Draco 1.5's constrained multi-parallelogram crashes
// on grids narrower than 3e-7 to 1e-6 (measured on 10 x 10 grids, every position_bits).
inline constexpr float kMinConstrainedPredictionRange = 1e-5f;

// Throws UnsupportedError (HTTP 422) for a mesh Draco's encoder cannot take with `options`: a
// value of any attribute it quantises (POSITION always, the others when their bits are not 0)
// that is not finite or lies outside the float grid Draco can build, or only degenerate
// triangles. draco_encode calls it.
void check_draco_encodable(const draco::Mesh& mesh, const EncodeOptions& options);

// Encodes with the quantisation bits and speed of `options` (and `box` for positions when
// given). Deterministic. Throws InvalidParamsError for settings out of range, UnsupportedError
// for a mesh Draco cannot encode or whose tables would exceed options.max_memory_bytes.
std::string draco_encode(const draco::Mesh& mesh, const EncodeOptions& options,
                         const std::optional<QuantizationBox>& box = std::nullopt);

// Reads every point's position (#points by 3) and the faces as point indices.
Vertices draco_positions(const draco::Mesh& mesh);
Triangles draco_faces(const draco::Mesh& mesh);

// Writes new positions into `mesh`: point p gets welded[point_to_weld[p]]. If the mesh has
// a NORMAL attribute, its values are recomputed from the new surface, each normal value from
// the faces whose corners use it (so split normals, i.e. hard edges, stay split).
void draco_update_geometry(draco::Mesh& mesh, const Vertices& welded, const std::vector<std::int32_t>& point_to_weld);

}  // namespace mdn::io::detail
