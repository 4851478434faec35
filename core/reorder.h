// A locality order of a mesh's faces and vertices (core/README.md, decision 16): denoise()
// runs on the mesh renumbered so that faces and vertices that are neighbours on the surface
// are close in memory, and maps the result back to the input's numbering. The method's
// arithmetic per element is unchanged; only the order of the elements (and of the sums over
// N(i), which follow the numbering) is.
#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace mdn {

enum class OrderKind {
  Auto,              // BreadthFirst from kReorderMinFaces faces on, Input below (decision 16)
  Input,             // the identity: the input's own order, faces and vertices
  SpaceFillingCurve, // faces along a Morton (Z-order) curve over their centroids
  BreadthFirst,      // faces breadth-first over vertex adjacency, from the lowest face of each component
};

// Below this many faces a run's arrays fit the caches and the input's own order is as good as
// any (measured: the Morton curve cost Fandisk's 13k faces 10% in the normal filter; a
// reordering halved the cost per face of the 75k-face bunny).
inline constexpr std::int64_t kReorderMinFaces = 32768;

class LocalityOrder {
 public:
  // Orders the faces by `kind`, then (except for Input) numbers the vertices in the order the
  // ordered faces first reference them (vertices no face references keep their relative order,
  // at the end).
  // The mesh must be valid (validate_mesh). Deterministic; O(#F) (the curve: a radix sort).
  static LocalityOrder of(const TriMesh& mesh, OrderKind kind = OrderKind::SpaceFillingCurve);

  // #F by 3: row k is input face face_of()[k] with its vertices renumbered (corner order kept).
  const Triangles& faces() const { return F_; }
  // New position -> input index (#F and #V).
  const std::vector<std::int32_t>& face_of() const { return face_of_; }
  const std::vector<std::int32_t>& vertex_of() const { return vertex_of_; }

  // #V by 3 rows from the input's numbering into the order, and back.
  Vertices to_order(const Vertices& V) const;
  Vertices to_input(const Vertices& W) const;

 private:
  Triangles F_;
  std::vector<std::int32_t> face_of_, vertex_of_;
};

}  // namespace mdn
