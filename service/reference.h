// A mesh against a reference (a clean scan of the same part, or the noisy mesh's ground truth):
// the whole document as one mesh in its scene's frame, Sec. 7's figures from core/metrics (MSAE
// where the faces match, E_v always), and how far each vertex lies from the reference. What the
// command-line tool's --metrics and the server's reference comparison (the web page) share.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/mesh.h"

namespace mdn {
class Executor;
}

namespace mdn::service {

// All surfaces of a document as one mesh (indices offset), so MSAE and E_v cover a whole
// multi-mesh glTF the same way they cover a single OFF.
TriMesh merge_surfaces(const std::vector<TriMesh>& surfaces);
// All surfaces as the scene shows them: each once per placement (a glTF node that instances
// it, its world matrix applied), or once as it is when nothing places it. Meshes are compared
// in this frame, so a glTF with node transforms compares with the same mesh exported in world
// coordinates, and two glTFs compare as they render.
TriMesh scene_mesh(const std::vector<TriMesh>& surfaces, const std::vector<std::vector<Eigen::Matrix4d>>& placements);

// Whether two meshes have the same faces in the same order (MSAE and vertex-to-vertex
// deviations are defined; formats that renumber faces, Draco, break it).
bool same_faces(const TriMesh& a, const TriMesh& b);

struct ReferenceComparison {
  // MSAE (Sec. 7, squared radians), when `mesh` has the reference's faces; else none.
  std::optional<double> msae;
  // E_v (Sun et al. 2007; core/metrics.h): in the reference's unit-box frame, any two meshes.
  double ev = 0;
  // Per vertex of `mesh` (#V), model units: with the reference's faces, the offset from the
  // same reference vertex along the reference's area-weighted vertex normal (outwards positive);
  // otherwise the unsigned distance to the closest point of the reference surface.
  std::vector<float> deviation;
  bool deviation_signed = false;
  // The reference's mean edge length (model units): the unit people read deviations in.
  double mean_edge_length = 0;
};

// `mesh` against `reference`. Both must be valid (core::validate_mesh). With an executor the
// distances run in parallel; the figures do not depend on the thread count. Throws
// InvalidMeshError for an invalid mesh or a mesh of zero area.
ReferenceComparison compare_with_reference(const TriMesh& reference, const TriMesh& mesh, Executor* executor = nullptr);

// The comparison as JSON: {"same_faces", "msae" (null without), "msae_deg2", "ev",
// "mean_edge_length", "deviation_signed", "deviation": [...]} (proto/openapi.yaml).
nlohmann::json comparison_json(const ReferenceComparison& comparison);

}  // namespace mdn::service
