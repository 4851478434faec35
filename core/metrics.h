// Error metrics of Sec. 7 (MSAE, E_v) and the exact point-to-surface distance they need.
#pragma once

#include <memory>

#include "core/mesh.h"

namespace mdn {

class Executor;

// Mean over faces of the squared angle (radians) between the face normals of `result` and
// `truth`, which must have the same faces (same #F, same indices). Faces degenerate in either
// mesh are skipped. Throws InvalidMeshError if the connectivity differs, if either mesh is
// invalid (validate_mesh), or if every face is degenerate.
double msae(const TriMesh& result, const TriMesh& truth);
// The same mean from the two meshes' face normals (#F by 3 each, unit or zero rows), for
// callers that compare many results with one truth (core/auto/tune.h). Throws InvalidMeshError if
// the row counts differ or every face is degenerate.
double msae_of_normals(const Vertices& result_normals, const Vertices& truth_normals);

// Exact closest-point queries against a triangle soup, accelerated by an AABB tree
// (built once, queried many times; queries are const and thread-safe). Degenerate
// triangles count as their edges. Throws InvalidMeshError for an invalid surface or a
// non-finite query point.
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const TriMesh& surface);
  ~SurfaceDistance();
  SurfaceDistance(SurfaceDistance&&) noexcept;
  double distance(const Vec3& p) const;  // Euclidean distance from p to the closest point of the surface
 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// E_v (Sun et al. 2007): sqrt( sum_i (sum_{j in F(i)} A_j) d_i^2 / (3 sum_f A_f) ), d_i the
// exact distance from result vertex i to the truth surface, A the result's face areas.
// Both meshes are first mapped by the truth's unit box (UnitBox::of(truth.V)), so E_v is
// in the ground truth's unit-box frame. With an executor, the d_i are computed in parallel
// and summed serially: the value is identical for every thread count. Throws
// InvalidMeshError for an invalid mesh or a result with zero total area.
double vertex_error(const TriMesh& result, const TriMesh& truth, Executor* executor = nullptr);

}  // namespace mdn
