#include "core/topology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "support/shapes.h"

namespace mdn {
namespace {

// Found by tests/fuzz/fuzz_job (issue 49, item 9): faces that repeat one index three times have
// no half-edge, so the sort's buckets are all empty and the insertion sort stepped past a null
// array (undefined behaviour; the asan preset's UBSan stops there). Such faces give no edge.
TEST(Topology, FacesWithOneRepeatedIndexGiveNoEdge) {
  Triangles F(3, 3);
  F << 0, 0, 0, 1, 1, 1, 2, 2, 2;
  const Topology t = Topology::build(F, 3);
  EXPECT_EQ(t.num_interior_edges(), 0);
  EXPECT_EQ(t.boundary_edges.rows(), 0);
  EXPECT_EQ(t.nonmanifold_edges.rows(), 0);
}

TEST(Topology, ClosedCubeHasOnlyInteriorEdges) {
  const TriMesh m = test::cube(3);
  const Topology t = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  EXPECT_EQ(t.num_interior_edges(), m.F.rows() * 3 / 2);
  EXPECT_EQ(t.boundary_edges.rows(), 0);
  EXPECT_EQ(t.nonmanifold_edges.rows(), 0);
  // Euler characteristic of a sphere: V - E + F = 2.
  EXPECT_EQ(m.V.rows() - t.num_interior_edges() + m.F.rows(), 2);
}

TEST(Topology, InteriorEdgeRowsAreEdgeThenOppositeVertices) {
  const TriMesh m = test::sphere(1);
  const Topology t = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  for (Eigen::Index e = 0; e < t.num_interior_edges(); ++e) {
    for (int side = 0; side < 2; ++side) {
      const auto f = t.edge_faces(e, side);
      const std::int32_t opposite = t.interior_edges(e, side == 0 ? 1 : 3);
      std::array<std::int32_t, 3> face{m.F(f, 0), m.F(f, 1), m.F(f, 2)};
      std::array<std::int32_t, 3> expected{t.interior_edges(e, 0), t.interior_edges(e, 2), opposite};
      std::sort(face.begin(), face.end());
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(face, expected) << "edge " << e << " side " << side;
    }
  }
}

TEST(Topology, PlaneBoundaryAndVertexAdjacentFaces) {
  const int n = 4;
  const TriMesh m = test::plane(n);
  const Topology t = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  EXPECT_EQ(t.boundary_edges.rows(), 4 * n);
  const auto mask = t.boundary_vertex_mask();
  EXPECT_EQ(std::count(mask.begin(), mask.end(), true), 4 * n);
  // N(i) excludes i, is sorted, and is symmetric.
  for (std::int32_t f = 0; f < t.num_faces; ++f)
    for (auto k = t.ff_offsets[f]; k < t.ff_offsets[f + 1]; ++k) {
      const std::int32_t g = t.ff_faces[static_cast<std::size_t>(k)];
      EXPECT_NE(g, f);
      const auto b = t.ff_faces.begin() + t.ff_offsets[g], e = t.ff_faces.begin() + t.ff_offsets[g + 1];
      EXPECT_TRUE(std::binary_search(b, e, f));
    }
}

TEST(Topology, NonManifoldAndDegenerateEdgesGetNoShapingTerm) {
  // Three triangles around edge (0, 1), plus a degenerate face (2, 2, 3).
  Triangles F(4, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4, 2, 2, 3;
  const Topology t = Topology::build(F, 5);
  EXPECT_EQ(t.num_interior_edges(), 0);
  // (0, 1) has three faces; (2, 3) is traversed twice by the degenerate face alone.
  ASSERT_EQ(t.nonmanifold_edges.rows(), 2);
  EXPECT_EQ(t.nonmanifold_edges.row(0), (Eigen::RowVector2i(0, 1)));
  EXPECT_EQ(t.nonmanifold_edges.row(1), (Eigen::RowVector2i(2, 3)));
}

TEST(Topology, MeanEdgeLengthEqualsTheFaceListVersionExactly) {
  // Boundary, a non-manifold edge and a degenerate face (as above), and an irregular sphere.
  Triangles F(4, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4, 2, 2, 3;
  Vertices V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 0.3, 0.9, 0.1, 0.5, -0.7, 0.2, 0.4, 0.1, 1.3;
  EXPECT_EQ(Topology::build(F, 5).mean_edge_length(V), mean_edge_length(V, F));
  const TriMesh m = test::sphere(3);
  Vertices P = m.V;
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) *= 1.0 + 0.1 * std::sin(7.0 * static_cast<double>(i));
  const Topology t = Topology::build(m.F, static_cast<std::int32_t>(P.rows()));
  EXPECT_EQ(t.mean_edge_length(P), mean_edge_length(P, m.F));
  EXPECT_GT(t.mean_edge_length(P), 0);
  EXPECT_EQ(Topology::build(Triangles(0, 3), 0).mean_edge_length(Vertices(0, 3)), 0);
}

}  // namespace
}  // namespace mdn
