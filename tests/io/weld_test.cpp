// weld_positions (core/io/weld.h, internal to mdn_io) against the rule it promises, checked by
// brute force: each point goes to the first representative within the tolerance, in input
// order, else it becomes one.
#include "core/io/weld.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace mdn::io::detail {
namespace {

Weld brute_force(const Vertices& P, double tol) {
  Weld w;
  std::vector<Eigen::Index> reps;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    std::int32_t found = -1;
    for (std::size_t r = 0; r < reps.size() && found < 0; ++r)
      if ((P.row(reps[r]) - P.row(i)).norm() <= tol) found = static_cast<std::int32_t>(r);
    if (found < 0) {
      found = static_cast<std::int32_t>(reps.size());
      reps.push_back(i);
    }
    w.map.push_back(found);
  }
  w.V.resize(static_cast<Eigen::Index>(reps.size()), 3);
  for (std::size_t r = 0; r < reps.size(); ++r) w.V.row(static_cast<Eigen::Index>(r)) = P.row(reps[r]);
  return w;
}

double tolerance_of(const Vertices& P, double relative) {
  return relative * std::max((P.colwise().maxCoeff() - P.colwise().minCoeff()).norm(), P.cwiseAbs().maxCoeff());
}

TEST(Weld, MatchesTheBruteForceRuleOnClustersChainsAndNearMisses) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  const double relative = 1e-3;  // coarse, so that clusters are easy to build
  std::vector<Eigen::RowVector3d> points;
  for (int k = 0; k < 400; ++k) points.emplace_back(unit(rng), unit(rng), unit(rng));
  points.emplace_back(1, 1, 1);  // the tolerance is then about 1e-3 x the diagonal, 2 sqrt(3)
  points.emplace_back(-1, -1, -1);
  const double tol = relative * std::sqrt(12.0);  // copies may stick out a little: tolerance_of below is exact
  std::vector<Eigen::RowVector3d> all = points;
  for (int k = 0; k < 400; ++k) {
    const Eigen::RowVector3d& p = points[static_cast<std::size_t>(k)];
    Eigen::RowVector3d dir(unit(rng), unit(rng), unit(rng));
    dir.normalize();
    all.push_back(p + 0.5 * tol * dir);    // a copy within the tolerance
    all.push_back(p + 1.01 * tol * dir);   // a near miss: welds only if a copy is nearer
    all.push_back(p + 0.999 * tol * dir);  // just within
    all.push_back(p + 1.9 * tol * dir);    // within tol of the copies, not of p: chains do not weld
  }
  std::shuffle(all.begin() + 402, all.end(), rng);
  Vertices P(static_cast<Eigen::Index>(all.size()), 3);
  for (std::size_t i = 0; i < all.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = all[i];
  ASSERT_NEAR(tolerance_of(P, relative), tol, 0.01 * tol);

  const Weld got = weld_positions(P, relative), want = brute_force(P, tolerance_of(P, relative));
  EXPECT_EQ(got.map, want.map);
  ASSERT_EQ(got.V.rows(), want.V.rows());
  EXPECT_EQ(got.V, want.V);
  EXPECT_LT(got.V.rows(), P.rows());  // some did weld
  EXPECT_GT(got.V.rows(), 402);       // and not everything
}

TEST(Weld, PointsOnCellBoundariesAndTheDefaultTolerance) {
  // Float32 copies of a grid whose points sit on multiples of the cell width, and copies one
  // ulp away: the default tolerance welds each copy to its grid point, never two grid points.
  std::vector<Eigen::RowVector3d> all;
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 6; ++z) {
        const Eigen::RowVector3d p(0.2 * x, 0.2 * y, 0.2 * z);
        all.push_back(p);
        all.push_back(p.cast<float>().cast<double>());
        all.emplace_back(std::nextafter(static_cast<float>(p.x()), 2.0f), p.y(), std::nextafter(static_cast<float>(p.z()), -1.0f));
      }
  Vertices P(static_cast<Eigen::Index>(all.size()), 3);
  for (std::size_t i = 0; i < all.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = all[i];
  const Weld got = weld_positions(P), want = brute_force(P, tolerance_of(P, 1e-6));
  EXPECT_EQ(got.map, want.map);
  EXPECT_EQ(got.V.rows(), 216);
}

TEST(Weld, EmptyAndAllEqualInputs) {
  EXPECT_EQ(weld_positions(Vertices(0, 3)).V.rows(), 0);
  const Weld same = weld_positions(Vertices::Zero(5, 3));  // tolerance 0
  EXPECT_EQ(same.V.rows(), 1);
  EXPECT_EQ(same.map, (std::vector<std::int32_t>{0, 0, 0, 0, 0}));
}

// A non-finite coordinate (decoders refuse it after welding) makes the tolerance infinite and
// the grid's cell 1: huge finite coordinates then have cell indices beyond int64 unless clamped
// (UBSan caught the overflow on a mutated STL). Everything is within an infinite tolerance.
TEST(Weld, HugeAndInfiniteCoordinatesStayDefined) {
  Vertices P(4, 3);
  P << 1e300, -1e300, 0, -1e300, 1e300, 1, std::numeric_limits<double>::infinity(), 0, 0, 0, 0, 0;
  const Weld w = weld_positions(P);
  EXPECT_EQ(w.map.size(), 4u);
  EXPECT_GE(w.V.rows(), 1);
}

}  // namespace
}  // namespace mdn::io::detail
