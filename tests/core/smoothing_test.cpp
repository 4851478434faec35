// Tests of core/smoothing.h: the uniform Laplacian baseline.
#include "core/smoothing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.h"
#include "support/shapes.h"

namespace mdn {
namespace {

using test::plane;


double rms_height(const Vertices& V) { return std::sqrt(V.col(2).squaredNorm() / static_cast<double>(V.rows())); }

TEST(LaplacianSmoothing, ReducesTheNoiseOfANoisyPlane) {
  const TriMesh m = plane(30);
  const Topology topo = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  Vertices noisy = m.V;
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0, 0.01);
  for (Eigen::Index i = 0; i < noisy.rows(); ++i) noisy(i, 2) += g(rng);
  const double before = rms_height(noisy);
  const double after5 = rms_height(laplacian_smoothing(noisy, topo, 5));
  const double after20 = rms_height(laplacian_smoothing(noisy, topo, 20));
  EXPECT_LT(after5, before / 3) << "before " << before << " after " << after5;
  EXPECT_LT(after20, after5);
}

TEST(LaplacianSmoothing, OneStepMovesEachVertexTowardsItsNeighbourMean) {
  const TriMesh m = plane(3);
  const Topology topo = Topology::build(m.F, 16);
  Vertices V = m.V;
  V(5, 2) = 1.0;  // lift one interior vertex
  const Vertices out = laplacian_smoothing(V, topo, 1, 0.25);
  EXPECT_NEAR(out(5, 2), 0.75, 1e-15);  // its neighbours are all at height 0
  // A neighbour of vertex 5 rises by lambda x (1 / its valence).
  const int neighbour = 6;
  const int valence = topo.vv_offsets[neighbour + 1] - topo.vv_offsets[neighbour];
  EXPECT_NEAR(out(neighbour, 2), 0.25 / valence, 1e-15);
}

TEST(LaplacianSmoothing, ZeroIterationsIsTheIdentityAndAFlatPlaneStaysFlat) {
  const TriMesh m = plane(5);
  const Topology topo = Topology::build(m.F, 36);
  EXPECT_TRUE(laplacian_smoothing(m.V, topo, 0) == m.V);
  const Vertices out = laplacian_smoothing(m.V, topo, 10);
  EXPECT_EQ(out.col(2).cwiseAbs().maxCoeff(), 0.0);
}

TEST(LaplacianSmoothing, IsolatedVerticesStay) {
  TriMesh m = plane(3);
  m.V.conservativeResize(17, 3);
  m.V.row(16) << 3, 4, 5;
  const Topology topo = Topology::build(m.F, 17);
  const Vertices out = laplacian_smoothing(m.V, topo, 3);
  EXPECT_TRUE(out.row(16) == m.V.row(16));
}

TEST(LaplacianSmoothing, BadArgumentsAreRejected) {
  const TriMesh m = plane(3);
  const Topology topo = Topology::build(m.F, 16);
  EXPECT_THROW(laplacian_smoothing(m.V.topRows(10), topo, 1), InvalidMeshError);
  EXPECT_THROW(laplacian_smoothing(m.V, topo, -1), InvalidParamsError);
  EXPECT_THROW(laplacian_smoothing(m.V, topo, 1, 0.0), InvalidParamsError);
  EXPECT_THROW(laplacian_smoothing(m.V, topo, 1, 1.5), InvalidParamsError);
  Vertices bad = m.V;
  bad(3, 1) = std::nan("");
  EXPECT_THROW(laplacian_smoothing(bad, topo, 1), InvalidMeshError);
}

}  // namespace
}  // namespace mdn
