// Mesh connectivity in compact arrays (CSR style). Built once per mesh; read-only after.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace mdn {

class Executor;

struct Topology {
  std::int32_t num_vertices = 0;
  std::int32_t num_faces = 0;

  // Interior manifold edges (exactly two incident faces). Row e: (e1, e2, e3, e4) with
  // (e1, e3) the edge and e2, e4 the opposite vertices of its two faces, so that the
  // shaping term of Eq. 1 is S(e) = p_e1 - p_e2 + p_e3 - p_e4. edge_faces row e holds
  // the face containing e2 and the face containing e4.
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 4, Eigen::RowMajor> interior_edges;
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2, Eigen::RowMajor> edge_faces;
  // Edges with one incident face, and with three or more (vertex pairs, smaller first).
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2, Eigen::RowMajor> boundary_edges;
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2, Eigen::RowMajor> nonmanifold_edges;

  // Vertex -> incident faces: faces of v are vf_faces[vf_offsets[v] .. vf_offsets[v+1]).
  std::vector<std::int32_t> vf_offsets, vf_faces;
  // Vertex -> neighbouring vertices (one-ring over all incident faces, no duplicates).
  std::vector<std::int32_t> vv_offsets, vv_vertices;
  // Face -> faces sharing at least one vertex with it, itself excluded (N(i), Eq. 6).
  std::vector<std::int32_t> ff_offsets, ff_faces;

  // executor: optional threads for the face -> faces lists (the result does not depend on it).
  static Topology build(const Triangles& F, std::int32_t num_vertices, Executor* executor = nullptr);

  std::int64_t num_interior_edges() const { return interior_edges.rows(); }
  // Mean length of the unique undirected edges under positions V: mean_edge_length(V, F) bit
  // for bit (same edges, same order), without its sort (a large share of ParamMode::Auto's
  // measuring otherwise).
  double mean_edge_length(const Vertices& V) const;
  // True if the vertex lies on a boundary or non-manifold edge.
  std::vector<bool> boundary_vertex_mask() const;
};

// Vertex -> incident faces as compressed rows (each face listed once per distinct vertex, in
// face order): Topology's vf_offsets / vf_faces, for callers that need no more of it.
void build_vertex_faces(const Triangles& F, std::int32_t num_vertices, std::vector<std::int32_t>& offsets,
                        std::vector<std::int32_t>& faces);

}  // namespace mdn
