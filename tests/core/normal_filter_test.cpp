#include "core/normal_filter.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.h"
#include "core/noise.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "support/shapes.h"

namespace mdn {
namespace {

double row_angle_deg(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b) {
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
    sum += row_angle_deg(filtered.row(f), truth.row(f));
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
    e0 += row_angle_deg(before.row(f), truth.row(f));
    e1 += row_angle_deg(after.row(f), truth.row(f));
    ASSERT_NEAR(after.row(f).norm(), 1.0, 1e-12);
  }
  EXPECT_LT(e1, 0.5 * e0);
}

TEST(L1MedianFilter, IdenticalForAnyThreadCount) {
  const TriMesh clean = test::sphere(3);
  NoiseSpec spec;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  // Unguided, and guided by the clean normals (decision 53).
  const Vertices truth = face_normals(clean.V, clean.F);
  NormalFilterSettings guided;
  guided.guidance = &truth;
  for (const NormalFilterSettings& s : {NormalFilterSettings{}, guided}) {
    const Vertices one = l1_median_normal_filter(noisy, clean.F, t, s);
    for (int threads : {2, 3, 8}) {
      Executor ex(threads);
      const Vertices many = l1_median_normal_filter(noisy, clean.F, t, s, &ex);
      EXPECT_TRUE((one.array() == many.array()).all()) << threads << " threads" << (s.guidance ? ", guided" : "");
    }
  }
}

// Decision 51: the compact forms of N(i) read the same faces and pairs as the plain one.
TEST(L1MedianFilter, EveryNeighbourFormGivesTheSameNormals) {
  const TriMesh clean = test::sphere(3);
  NoiseSpec spec;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  Executor ex(2);
  // Unguided, and guided by the clean normals (decision 53's pass reads N(i) the same way).
  const Vertices truth = face_normals(clean.V, clean.F);
  NormalFilterSettings guided;
  guided.guidance = &truth;
  for (const NormalFilterSettings& s : {NormalFilterSettings{}, guided}) {
    const Vertices plain = detail::l1_median_normal_filter(noisy, clean.F, t, s, &ex, nullptr, detail::NeighbourForm::Plain);
    for (auto form : {detail::NeighbourForm::Auto, detail::NeighbourForm::Compact16, detail::NeighbourForm::Compact32}) {
      const Vertices other = detail::l1_median_normal_filter(noisy, clean.F, t, s, &ex, nullptr, form);
      EXPECT_TRUE((plain.array() == other.array()).all()) << static_cast<int>(form) << (s.guidance ? " guided" : "");
    }
  }
}

// Neighbours numbered more than 32,767 faces apart (a sphere split in two halves with 40,000
// loose triangles between them): the 16-bit forms refuse, Auto falls back to the plain form.
TEST(L1MedianFilter, FarApartNeighboursFallBackToThePlainForm) {
  const TriMesh sphere = test::sphere(3);
  NoiseSpec spec;
  const Vertices noisy = add_noise(sphere, spec);
  constexpr Eigen::Index kLoose = 40000;
  const Eigen::Index half = sphere.F.rows() / 2, nv = sphere.V.rows();
  Vertices V(nv + 3 * kLoose, 3);
  V.topRows(nv) = noisy;
  Triangles F(sphere.F.rows() + kLoose, 3);
  F.topRows(half) = sphere.F.topRows(half);
  for (Eigen::Index i = 0; i < kLoose; ++i) {
    const auto v = static_cast<std::int32_t>(nv + 3 * i);
    V.row(nv + 3 * i) << 3.0 + 0.01 * static_cast<double>(i), 0, 0;
    V.row(nv + 3 * i + 1) << 3.0 + 0.01 * static_cast<double>(i), 0.01, 0;
    V.row(nv + 3 * i + 2) << 3.0 + 0.01 * static_cast<double>(i), 0, 0.01;
    F.row(half + i) << v, v + 1, v + 2;
  }
  F.bottomRows(sphere.F.rows() - half) = sphere.F.bottomRows(sphere.F.rows() - half);
  const Topology t = Topology::build(F, static_cast<std::int32_t>(V.rows()));
  Executor ex(2);
  const Vertices plain = detail::l1_median_normal_filter(V, F, t, {}, &ex, nullptr, detail::NeighbourForm::Plain);
  const Vertices automatic = detail::l1_median_normal_filter(V, F, t, {}, &ex, nullptr, detail::NeighbourForm::Auto);
  EXPECT_TRUE((plain.array() == automatic.array()).all());
  for (auto form : {detail::NeighbourForm::Compact16, detail::NeighbourForm::Compact32})
    EXPECT_THROW(detail::l1_median_normal_filter(V, F, t, {}, &ex, nullptr, form), std::invalid_argument);
  // The sphere's normals are filtered as on the sphere alone (its faces keep their order).
  const Vertices alone = l1_median_normal_filter(noisy, sphere.F, Topology::build(sphere.F, static_cast<std::int32_t>(nv)), {}, &ex);
  EXPECT_TRUE((plain.topRows(half).array() == alone.topRows(half).array()).all());
}


// Decision 53, the identity the guidance keeps: guidance equal to the filter's own input normals
// (those of (V, F)) gives the first Jacobi step of the unguided filter to the bit, since the
// first step's range factor reads exactly those normals.
TEST(GuidedL1MedianFilter, GuidanceOfTheInputNormalsIsTheUnguidedFirstStep) {
  const TriMesh clean = test::fold(20, 90);
  NoiseSpec spec;
  spec.sigma = 0.05;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  const Vertices input_normals = face_normals(noisy, clean.F);
  NormalFilterSettings plain;
  plain.iterations = 1;
  NormalFilterSettings guided = plain;
  guided.guidance = &input_normals;
  const Vertices a = l1_median_normal_filter(noisy, clean.F, t, plain);
  const Vertices b = l1_median_normal_filter(noisy, clean.F, t, guided);
  EXPECT_TRUE((a.array() == b.array()).all());
  // After the first step the unguided filter reads its new iterate, the guided one the fixed
  // guidance: they part.
  plain.iterations = guided.iterations = 5;
  EXPECT_FALSE((l1_median_normal_filter(noisy, clean.F, t, plain).array() ==
                l1_median_normal_filter(noisy, clean.F, t, guided).array())
                   .all());
}

// With the clean normals as guidance, a heavily noised 90-degree crease comes out closer to the
// truth than the paper's filter leaves it (the range weight no longer mixes across the crease
// where the noise blurs it).
TEST(GuidedL1MedianFilter, CleanGuidanceKeepsANoisyCreaseBetter) {
  const TriMesh clean = test::fold(20, 90);
  NoiseSpec spec;
  spec.sigma = 0.3;
  spec.seed = 3;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  const Vertices truth = face_normals(clean.V, clean.F);
  NormalFilterSettings plain;
  NormalFilterSettings guided = plain;
  guided.guidance = &truth;
  const double plain_err = crease_error(clean, l1_median_normal_filter(noisy, clean.F, t, plain));
  const double guided_err = crease_error(clean, l1_median_normal_filter(noisy, clean.F, t, guided));
  EXPECT_LT(guided_err, 0.5 * plain_err) << plain_err << " " << guided_err;
}

TEST(GuidedL1MedianFilter, GuidanceOfTheWrongShapeOrNotFiniteIsRefused) {
  const TriMesh clean = test::cube(3);
  const Topology t = Topology::build(clean.F, static_cast<std::int32_t>(clean.V.rows()));
  NormalFilterSettings guided;
  const Vertices short_rows = face_normals(clean.V, clean.F).topRows(clean.F.rows() - 1);
  guided.guidance = &short_rows;
  EXPECT_THROW(l1_median_normal_filter(clean.V, clean.F, t, guided), InvalidParamsError);
  Vertices nan_row = face_normals(clean.V, clean.F);
  nan_row(2, 1) = std::nan("");
  guided.guidance = &nan_row;
  try {
    l1_median_normal_filter(clean.V, clean.F, t, guided);
    ADD_FAILURE() << "a non-finite guidance was accepted";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "guidance");
  }
}

}  // namespace
}  // namespace mdn
