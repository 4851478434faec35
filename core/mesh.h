// Indexed triangle mesh with double-precision positions.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace mdn {

class Executor;

using Vertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;      // #V by 3
// Observes an iterative filter: called with its input (count 0), then after each iteration
// with the count done so far and the current iterate (positions or normals). Used by the parameter search (core/auto/tune.h),
// which reads every iteration count of one run instead of rerunning the filter.
using IterationHook = std::function<void(int iterations_done, const Vertices& state)>;
using Triangles = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>; // #F by 3
using Vec3 = Eigen::Vector3d;

struct TriMesh {
  Vertices V;   // #V by 3 positions
  Triangles F;  // #F by 3 vertex indices, counter-clockwise seen from outside
  std::int64_t num_vertices() const { return V.rows(); }
  std::int64_t num_faces() const { return F.rows(); }
};

// A polygon mesh as read from a file: faces in CSR form (face f has the vertex indices
// indices[offsets[f] .. offsets[f+1])). Converted to a TriMesh with to_tri_mesh().
struct PolygonMesh {
  Vertices V;
  std::vector<std::int64_t> offsets{0};  // #F+1
  std::vector<std::int64_t> indices;
};

// Throws InvalidMeshError if the mesh is empty (no vertex or no face), has a non-finite
// coordinate, or an index outside [0, #V). Degenerate and duplicate faces are allowed.
void validate_mesh(const TriMesh& mesh);

// Converts a polygon mesh whose faces are all triangles. Throws InvalidMeshError naming
// the first face that is not a triangle, or an index outside [0, #V) / beyond int32.
TriMesh to_tri_mesh(const PolygonMesh& poly);

// A TriMesh from lists of positions and corner indices (shapes made in code: tests, tools/train).
TriMesh tri_mesh_from_lists(const std::vector<Vec3>& positions, const std::vector<std::array<int, 3>>& faces);

// Per-face unit normals (#F by 3). A degenerate (zero-area) face gets the zero vector.
Vertices face_normals(const Vertices& V, const Triangles& F);
// The same into N (resized; no allocation when it already has #F rows), over the executor's
// threads if given: bit for bit the values above.
void face_normals(const Vertices& V, const Triangles& F, Vertices& N, Executor* executor);
// Per-face areas (#F).
Eigen::VectorXd face_areas(const Vertices& V, const Triangles& F);
// Per-face centroids (#F by 3).
Vertices face_centroids(const Vertices& V, const Triangles& F);
// Area-weighted vertex normals (#V by 3), unit length; zero for isolated vertices.
Vertices vertex_normals(const Vertices& V, const Triangles& F);
// Mean length of the mesh's unique undirected edges (0 for an empty mesh).
double mean_edge_length(const Vertices& V, const Triangles& F);

// Unit-box normalisation (core/README.md, decision 1): centre the bounding box at the origin and
// scale its longest side to 1. apply() maps into the box, undo() maps back.
struct UnitBox {
  Vec3 center = Vec3::Zero();
  double scale = 1.0;  // multiply by scale to enter the box
  static UnitBox of(const Vertices& V);
  Vertices apply(const Vertices& V) const;
  Vertices undo(const Vertices& V) const;
};

}  // namespace mdn
