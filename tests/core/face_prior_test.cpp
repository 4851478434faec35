#include "core/auto/face_prior.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/auto/face_features.h"
#include "core/parallel.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

FacePrior prior(const TriMesh& m, int threads) {
  const Topology topo = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  Executor executor(threads);
  return face_prior(m.V, m.F, topo, executor);
}

double angle_deg(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI; }

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Decision 89: the C++ network reproduces what torch computed on the probe rows (float32 there,
// double here: within 1e-4).
TEST(FacePrior, ReproducesTheTrainersProbeRows) {
  const auto& probes = face_prior_probes();
  ASSERT_GE(probes.size(), 3u);
  Eigen::MatrixXd X(static_cast<Eigen::Index>(probes.size()), kFaceFeatures);
  for (std::size_t i = 0; i < probes.size(); ++i)
    for (int j = 0; j < kFaceFeatures; ++j) X(static_cast<Eigen::Index>(i), j) = probes[i].inputs[static_cast<std::size_t>(j)];
  const Eigen::MatrixXd Y = face_network(X);
  for (std::size_t i = 0; i < probes.size(); ++i)
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(Y(static_cast<Eigen::Index>(i), k), probes[i].outputs[static_cast<std::size_t>(k)], 1e-4);
  EXPECT_EQ(face_prior_version().rfind("face-mlp-", 0), 0u);
}

TEST(FacePrior, IsBitIdenticalForOneAndTwoThreads) {
  const TriMesh noisy = test::with_noise(test::cube(24), 0.3);
  const FacePrior one = prior(noisy, 1), two = prior(noisy, 2);
  EXPECT_GT(one.evaluated, 0);
  EXPECT_EQ(one.evaluated, two.evaluated);
  EXPECT_TRUE(one.guidance == two.guidance);
  EXPECT_TRUE(one.noise_deg == two.noise_deg);
}

// The prior reads its faces block by block (FaceReader); the result is the network on
// face_features' table, rows of non-flat faces, mapped back by from_frame (to 1e-12: the
// network on one row takes Eigen's matrix-vector product, the prior's blocks the matrix one).
TEST(FacePrior, EqualsTheNetworkOnTheFeatureTable) {
  const TriMesh noisy = test::with_noise(test::fold(12, 100), 0.2);
  const Topology topo = Topology::build(noisy.F, static_cast<std::int32_t>(noisy.V.rows()));
  Executor ex(2);
  const FacePrior p = face_prior(noisy.V, noisy.F, topo, ex);
  const FaceFeatures ff = face_features(noisy.V, noisy.F, topo, ex);
  std::int64_t evaluated = 0;
  for (Eigen::Index f = 0; f < noisy.F.rows(); ++f) {
    if (ff.flat[static_cast<std::size_t>(f)]) {
      EXPECT_TRUE(p.guidance.row(f) == ff.smoothed.row(f)) << f;
      continue;
    }
    ++evaluated;
    const Eigen::MatrixXd y = face_network(Eigen::MatrixXd(ff.X.row(f)));
    const Vec3 local = y.row(0).head<3>().transpose();
    const Vec3 expected = from_frame(ff, f, local / local.norm());
    EXPECT_NEAR((p.guidance.row(f).transpose() - expected).cwiseAbs().maxCoeff(), 0.0, 1e-12) << f;
  }
  EXPECT_EQ(p.evaluated, evaluated);
  EXPECT_GT(evaluated, 0);
}

// The prior's normals are closer to the clean ones than the noisy normals, on the cube's faces
// along its edges and corners as well as on its flat sides; its noise reading tells noise from none.
TEST(FacePrior, PredictsCleanerNormalsThanTheNoisyOnesAndReadsTheNoise) {
  const TriMesh clean = test::cube(20);
  const TriMesh noisy = test::with_noise(clean, 0.3);
  const FacePrior p = prior(noisy, 2);
  const Vertices truth = face_normals(clean.V, clean.F), N0 = face_normals(noisy.V, noisy.F);
  const Topology topo = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  Executor ex(1);
  const std::vector<FaceClass> cls = face_classes(clean.V, clean.F, topo, ex);
  std::vector<double> prior_flat, noisy_flat, prior_sharp, noisy_sharp;
  for (Eigen::Index f = 0; f < clean.F.rows(); ++f) {
    const bool flat = cls[static_cast<std::size_t>(f)] == FaceClass::Flat;
    (flat ? prior_flat : prior_sharp).push_back(angle_deg(p.guidance.row(f).transpose(), truth.row(f).transpose()));
    (flat ? noisy_flat : noisy_sharp).push_back(angle_deg(N0.row(f).transpose(), truth.row(f).transpose()));
  }
  ASSERT_FALSE(prior_sharp.empty());
  EXPECT_LT(median(prior_flat), 0.5 * median(noisy_flat));
  EXPECT_LT(median(prior_sharp), 0.7 * median(noisy_sharp));
  EXPECT_GT(p.summary.median_deg, 4.0);
  EXPECT_GT(p.summary.share_over_2deg, 0.8);
  const FacePrior quiet = prior(clean, 2);
  EXPECT_LT(quiet.summary.median_deg, 1.0);
  EXPECT_LT(quiet.summary.share_over_2deg, 0.25);
}

// A plane reads plainly flat everywhere: the network does not run, the guidance is the normal.
TEST(FacePrior, APlaneKeepsItsNormalWithoutTheNetwork) {
  const TriMesh plane = test::plane(16);
  const FacePrior p = prior(plane, 1);
  EXPECT_EQ(p.evaluated, 0);
  const Vertices N = face_normals(plane.V, plane.F);
  EXPECT_LT((p.guidance - N).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(p.summary.p90_deg, 0.0);
}

// Scale-free and rotation-free: a rotated, scaled copy gets the rotated guidance.
TEST(FacePrior, TurnsWithTheSurface) {
  const TriMesh noisy = test::with_noise(test::sphere(3), 0.2);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  TriMesh turned = noisy;
  turned.V = (7.5 * noisy.V * R.transpose()).eval();
  const FacePrior a = prior(noisy, 1), b = prior(turned, 1);
  EXPECT_LT(((a.guidance * R.transpose()) - b.guidance).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((a.noise_deg - b.noise_deg).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(FaceFeatures, ClassesTellFlatFromCreaseAndCorner) {
  const TriMesh cube = test::cube(8);
  const Topology topo = Topology::build(cube.F, static_cast<std::int32_t>(cube.V.rows()));
  Executor ex(1);
  const std::vector<FaceClass> cls = face_classes(cube.V, cube.F, topo, ex);
  std::array<int, kFaceClasses> count{};
  for (const FaceClass c : cls) ++count[static_cast<std::size_t>(c)];
  // 6 sides of 8x8 cells, 2 triangles each: the inner 6x6 cells are flat, the rim touches an edge.
  EXPECT_EQ(count[0], 6 * 6 * 6 * 2);
  EXPECT_GT(count[2], 0);
  EXPECT_GT(count[3], 0);
  EXPECT_EQ(count[1], 0);
}

}  // namespace
}  // namespace mdn
