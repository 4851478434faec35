// Tests of core/noise.h: determinism, the three kinds, their scale, impulse selection.
#include "core/noise.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "core/errors.h"
#include "support/shapes.h"

namespace mdn {
namespace {

using test::plane;
using test::sphere;


// First draws of add_noise(plane(2), {PerCoordinate, 1.0, seed 1}) in units of the noise std.
constexpr double kPinned[3] = {-0.039399956754155314, -0.38683176162103955, 1.2990604774761167};

constexpr NoiseKind kAllKinds[] = {NoiseKind::PerCoordinate, NoiseKind::AlongNormal, NoiseKind::RandomDirection};

TEST(Noise, KindNamesRoundTrip) {
  for (const NoiseKind kind : kAllKinds) EXPECT_EQ(noise_kind_from_string(to_string(kind)), kind);
  EXPECT_EQ(to_string(NoiseKind::PerCoordinate), "per_coordinate");
  EXPECT_EQ(to_string(NoiseKind::AlongNormal), "along_normal");
  EXPECT_EQ(to_string(NoiseKind::RandomDirection), "random_direction");
  EXPECT_FALSE(noise_kind_from_string("gaussian").has_value());
  EXPECT_FALSE(noise_kind_from_string("").has_value());
}

TEST(Noise, SameSeedGivesIdenticalOutputDifferentSeedsDiffer) {
  const TriMesh m = sphere(3);
  for (const NoiseKind kind : kAllKinds) {
    const NoiseSpec spec{kind, 0.3, 42, 0};
    const Vertices a = add_noise(m, spec);
    const Vertices b = add_noise(m, spec);
    EXPECT_TRUE(a == b) << to_string(kind);
    NoiseSpec other = spec;
    other.seed = 43;
    const Vertices c = add_noise(m, other);
    EXPECT_GT((a - c).norm(), 0.1 * (a - m.V).norm()) << to_string(kind);
  }
}

TEST(Noise, OutputIsPinnedForAFixedSeed) {
  // Guards cross-platform determinism: the sampler is our own code over mt19937_64, whose
  // sequence the standard fixes, so these values must never change. Regenerate them only
  // on a deliberate change of the sampler (and say so in the commit).
  const TriMesh m = plane(2);
  const Vertices v = add_noise(m, {NoiseKind::PerCoordinate, 1.0, 1, 0});
  const double s = mean_edge_length(m.V, m.F);
  const Vertices d = (v - m.V) / s;
  EXPECT_NEAR(d(0, 0), kPinned[0], 1e-12);
  EXPECT_NEAR(d(0, 1), kPinned[1], 1e-12);
  EXPECT_NEAR(d(8, 2), kPinned[2], 1e-12);
}

TEST(Noise, StandardDeviationIsSigmaTimesMeanEdgeLength) {
  const TriMesh m = plane(200);  // 40401 vertices
  const double sigma = 0.25;
  const double s = sigma * mean_edge_length(m.V, m.F);
  for (const NoiseKind kind : kAllKinds) {
    const Vertices d = add_noise(m, {kind, sigma, 5, 0}) - m.V;
    const double n = static_cast<double>(d.rows());
    if (kind == NoiseKind::PerCoordinate) {
      for (int k = 0; k < 3; ++k) {
        const double mean = d.col(k).mean();
        const double sd = std::sqrt(d.col(k).squaredNorm() / n - mean * mean);
        EXPECT_NEAR(sd / s, 1.0, 0.03) << "coordinate " << k;
        EXPECT_NEAR(mean / s, 0.0, 0.03);
      }
    } else {
      // A 1-D Gaussian displacement: RMS length = s, signed component along the direction has mean 0.
      const double rms = std::sqrt(d.squaredNorm() / n);
      EXPECT_NEAR(rms / s, 1.0, 0.03) << to_string(kind);
    }
  }
}

TEST(Noise, AlongNormalDisplacementsAreParallelToTheNormals) {
  const TriMesh m = sphere(3);
  const Vertices normals = vertex_normals(m.V, m.F);
  const Vertices d = add_noise(m, {NoiseKind::AlongNormal, 0.5, 9, 0}) - m.V;
  double signed_sum = 0;
  for (Eigen::Index i = 0; i < d.rows(); ++i) {
    const Vec3 di = d.row(i), ni = normals.row(i);
    EXPECT_LE(di.cross(ni).norm(), 1e-12 * (1 + di.norm())) << "vertex " << i;
    signed_sum += di.dot(ni);
  }
  // Both signs occur: the mean signed displacement is small next to its spread.
  EXPECT_LT(std::abs(signed_sum) / d.rows(), 0.2 * std::sqrt(d.squaredNorm() / d.rows()));
}

TEST(Noise, RandomDirectionsAreIsotropic) {
  const TriMesh m = plane(150);
  const Vertices d = add_noise(m, {NoiseKind::RandomDirection, 1.0, 3, 0}) - m.V;
  const double total = d.squaredNorm();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(d.col(k).squaredNorm() / total, 1.0 / 3.0, 0.02) << "axis " << k;
}

TEST(Noise, ImpulseMovesExactlyTheExpectedCount) {
  const TriMesh m = plane(40);  // 1681 vertices
  for (const double fraction : {0.1, 0.5, 0.0003, 1.0}) {
    const Vertices v = add_noise(m, {NoiseKind::PerCoordinate, 0.3, 17, fraction});
    int moved = 0;
    for (Eigen::Index i = 0; i < v.rows(); ++i) moved += (v.row(i) != m.V.row(i)) ? 1 : 0;
    EXPECT_EQ(moved, std::lround(fraction * 1681)) << "fraction " << fraction;
  }
  // Different seeds choose different vertices.
  const Vertices a = add_noise(m, {NoiseKind::PerCoordinate, 0.3, 1, 0.1});
  const Vertices b = add_noise(m, {NoiseKind::PerCoordinate, 0.3, 2, 0.1});
  int both = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) both += (a.row(i) != m.V.row(i) && b.row(i) != m.V.row(i)) ? 1 : 0;
  EXPECT_LT(both, 100);  // ~17 expected for independent 10% subsets
}

TEST(Noise, ZeroSigmaLeavesTheMeshInPlace) {
  const TriMesh m = sphere(2);
  for (const NoiseKind kind : kAllKinds) EXPECT_TRUE(add_noise(m, {kind, 0.0, 1, 0}) == m.V);
}

TEST(Noise, IsolatedVerticesHaveNoNormalAndStayUnderAlongNormalNoise) {
  TriMesh m = plane(4);
  m.V.conservativeResize(m.V.rows() + 1, 3);
  m.V.row(m.V.rows() - 1) << 7, 7, 7;
  const Vertices v = add_noise(m, {NoiseKind::AlongNormal, 0.5, 1, 0});
  EXPECT_TRUE(v.row(v.rows() - 1) == m.V.row(m.V.rows() - 1));
}

TEST(Noise, BadSpecsAreRejected) {
  const TriMesh m = plane(3);
  try {
    add_noise(m, {NoiseKind::AlongNormal, -0.1, 1, 0});
    FAIL() << "negative sigma accepted";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "sigma");
  }
  EXPECT_THROW(add_noise(m, {NoiseKind::AlongNormal, std::nan(""), 1, 0}), InvalidParamsError);
  try {
    add_noise(m, {NoiseKind::AlongNormal, 0.1, 1, 1.5});
    FAIL() << "impulse fraction above 1 accepted";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "impulse_fraction");
  }
  TriMesh bad = m;
  bad.V(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(add_noise(bad, {}), InvalidMeshError);
  EXPECT_THROW(add_noise(TriMesh{}, {}), InvalidMeshError);
}

}  // namespace
}  // namespace mdn
