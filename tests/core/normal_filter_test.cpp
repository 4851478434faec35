#include "core/normal_filter.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/noise.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "support/shapes.h"

namespace mdn {
namespace {

double angle_deg(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

// Mean angle between filtered normals and the true ones, over the faces touching the crease.
double crease_error(const TriMesh& clean, const Vertices& filtered) {
  const Vertices truth = face_normals(clean.V, clean.F);
  double sum = 0;
  int count = 0;
  for (Eigen::Index f = 0; f < clean.F.rows(); ++f) {
    bool touches = false;
    for (int k = 0; k < 3; ++k) touches |= std::abs(clean.V(clean.F(f, k), 0)) < 1e-12;
    if (!touches) continue;
    sum += angle_deg(filtered.row(f), truth.row(f));
    ++count;
  }
  return sum / count;
}

// The L1-median keeps a 90-degree crease that plain averaging of the same neighbourhoods blurs.
TEST(L1MedianFilter, KeepsACreaseThatAveragingBlurs) {
  const TriMesh clean = test::fold(20, 90);
  TriMesh noisy = clean;
  NoiseSpec spec;
  spec.sigma = 0.05;
  noisy.V = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));

  NormalFilterSettings l1;
  l1.iterations = 20;
  const double l1_err = crease_error(clean, l1_median_normal_filter(noisy.V, noisy.F, t, l1));
  NormalFilterSettings average = l1;
  average.l1_median = false;
  average.sigma_gamma_deg = 180;   // range weight ~ constant: plain (area, distance) averaging
  average.sigma_c_factor = 100;
  const double avg_err = crease_error(clean, l1_median_normal_filter(noisy.V, noisy.F, t, average));
  EXPECT_LT(l1_err, 5.0);
  EXPECT_GT(avg_err, 15.0);
}

TEST(L1MedianFilter, ReducesNormalNoiseOnASphere) {
  const TriMesh clean = test::sphere(3);
  NoiseSpec spec;
  spec.sigma = 0.1;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  const Vertices truth = face_normals(clean.V, clean.F);
  const Vertices before = face_normals(noisy, clean.F);
  const Vertices after = l1_median_normal_filter(noisy, clean.F, t, {});
  double e0 = 0, e1 = 0;
  for (Eigen::Index f = 0; f < truth.rows(); ++f) {
    e0 += angle_deg(before.row(f), truth.row(f));
    e1 += angle_deg(after.row(f), truth.row(f));
    ASSERT_NEAR(after.row(f).norm(), 1.0, 1e-12);
  }
  EXPECT_LT(e1, 0.5 * e0);
}

TEST(L1MedianFilter, IdenticalForAnyThreadCount) {
  const TriMesh clean = test::sphere(3);
  NoiseSpec spec;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  const Vertices one = l1_median_normal_filter(noisy, clean.F, t, {});
  for (int threads : {2, 3, 8}) {
    Executor ex(threads);
    const Vertices many = l1_median_normal_filter(noisy, clean.F, t, {}, &ex);
    EXPECT_TRUE((one.array() == many.array()).all()) << threads << " threads";
  }
}

}  // namespace
}  // namespace mdn
