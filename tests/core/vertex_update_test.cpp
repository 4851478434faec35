#include "core/vertex_update.h"

#include <gtest/gtest.h>

#include "core/noise.h"
#include "support/shapes.h"

namespace mdn {
namespace {

// Eq. 8 fixed point: with the mesh's own face normals, every vertex lies in the plane of
// each of its faces, so n_j . (c_j - p_i) = 0 and nothing moves.
TEST(VertexUpdate, OwnNormalsAreAFixedPoint) {
  const TriMesh m = test::sphere(2);
  const Topology t = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  const Vertices out = vertex_update(m.V, m.F, t, face_normals(m.V, m.F), 10);
  EXPECT_LT((out - m.V).cwiseAbs().maxCoeff(), 1e-12);
}

// With the true normals of a plane, a noisy plane is pulled back onto a plane.
TEST(VertexUpdate, FlattensANoisyPlaneGivenItsNormal) {
  const TriMesh clean = test::plane(12);
  NoiseSpec spec;
  spec.kind = NoiseKind::AlongNormal;
  spec.sigma = 0.2;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  Vertices N = Vertices::Zero(clean.F.rows(), 3);
  N.col(2).setOnes();
  const Vertices out = vertex_update(noisy, clean.F, t, N, 200);
  const double spread_before = noisy.col(2).maxCoeff() - noisy.col(2).minCoeff();
  const double spread_after = out.col(2).maxCoeff() - out.col(2).minCoeff();
  EXPECT_LT(spread_after, 0.05 * spread_before);
}

TEST(VertexUpdate, IsolatedVertexStaysPut) {
  TriMesh m = test::plane(2);
  m.V.conservativeResize(m.V.rows() + 1, 3);
  m.V.row(m.V.rows() - 1) << 5, 5, 5;
  const Topology t = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  Vertices N = Vertices::Zero(m.F.rows(), 3);
  N.col(0).setOnes();
  const Vertices out = vertex_update(m.V, m.F, t, N, 5);
  EXPECT_EQ(out.row(m.V.rows() - 1), m.V.row(m.V.rows() - 1));
}

}  // namespace
}  // namespace mdn
