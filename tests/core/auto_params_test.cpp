#include "core/auto_params.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/pipeline.h"
#include "core/topology.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

TriMesh noisy_copy(const TriMesh& clean, double sigma) { return test::with_noise(clean, sigma, NoiseKind::AlongNormal, 3); }

InputMeasures measure(const TriMesh& m) {
  const Vertices P = UnitBox::of(m.V).apply(m.V);
  return measure_input(P, m.F, Topology::build(m.F, static_cast<std::int32_t>(P.rows())), DenoiseParams{});
}

TEST(MeasureInput, NoiseEstimateTracksTheNoiseLevel) {
  const TriMesh plane = test::plane(40);
  EXPECT_LT(measure(plane).noise, 1e-12);  // a clean plane: every vertex on its neighbours' plane
  double previous = 0;
  for (const double sigma : {0.05, 0.1, 0.2, 0.4}) {
    SCOPED_TRACE(sigma);
    const double noise = measure(noisy_copy(plane, sigma)).noise;
    EXPECT_GT(noise, previous);
    // Gaussian along the normal: median |n . (p - mean of 6 neighbours)| = 0.674 sigma sqrt(1 + 1/6).
    EXPECT_NEAR(noise / sigma, 0.674 * std::sqrt(1 + 1.0 / 6), 0.15);
    previous = noise;
  }
}

TEST(MeasureInput, FeaturesStandOutOfTheNoiseOnACubeNotOnASphere) {
  const InputMeasures cube = measure(noisy_copy(test::cube(16), 0.05));
  const InputMeasures sphere = measure(noisy_copy(test::sphere(4), 0.05));
  EXPECT_GT(cube.tail, sphere.tail);
  EXPECT_GT(cube.feature_share, 2 * sphere.feature_share);
}

TEST(MeasureInput, ClusterAreaRatioSeesIrregularSamplingThroughNoise) {
  const InputMeasures regular = measure(noisy_copy(test::sphere(3), 0.2));
  const InputMeasures irregular = measure(noisy_copy(test::irregular_sphere(3), 0.2));
  EXPECT_LT(regular.cluster_area_ratio, 4);
  EXPECT_GT(irregular.cluster_area_ratio, 8);  // the cap is 16x denser
}

TEST(PrototypeParameters, PinnedFieldsKeepTheirValuesAndThePaperRowComesFirst) {
  const InputMeasures m = measure(noisy_copy(test::cube(12), 0.2));
  DenoiseParams request;
  request.mode = ParamMode::Auto;
  // The paper's Table 1 Fandisk row (DenoiseParams' defaults) is prototype 0.
  const DenoiseParams paper, first = prototype_parameters(0, m, request);
  EXPECT_EQ(first.mode, ParamMode::Manual);
  EXPECT_EQ(first.alpha, paper.alpha);
  EXPECT_EQ(first.sigma_theta, paper.sigma_theta);
  EXPECT_EQ(first.n_aniso, paper.n_aniso);
  EXPECT_EQ(first.sigma_gamma, paper.sigma_gamma);
  EXPECT_EQ(first.n_normal, paper.n_normal);
  EXPECT_EQ(first.n_vertex, paper.n_vertex);
  EXPECT_EQ(first.region_mode, RegionMode::Off);  // the regular cube
  for (int k = 0; k < rule_prototype_count(); ++k) EXPECT_NO_THROW(prototype_parameters(k, m, request).validate());
  EXPECT_THROW(prototype_parameters(rule_prototype_count(), m, request), std::out_of_range);
  EXPECT_THROW(prototype_parameters(-1, m, request), std::out_of_range);

  request.alpha = 0.123;
  request.pin(AutoField::Alpha);
  request.n_normal = 77;
  request.pin(AutoField::NNormal);
  request.region_mode = RegionMode::Auto;
  request.pin(AutoField::RegionMode);
  const DenoiseParams pinned = prototype_parameters(2, m, request), free = prototype_parameters(2, m, DenoiseParams{});
  EXPECT_EQ(pinned.alpha, 0.123);
  EXPECT_EQ(pinned.n_normal, 77);
  EXPECT_EQ(pinned.region_mode, RegionMode::Auto);
  EXPECT_EQ(pinned.sigma_gamma, free.sigma_gamma);  // the others are the prototype's
  EXPECT_EQ(pinned.n_vertex, free.n_vertex);
}

TEST(PrototypeParameters, IrregularSamplingTurnsTheRegionPrefilterOn) {
  InputMeasures m = measure(noisy_copy(test::sphere(3), 0.2));
  EXPECT_EQ(prototype_parameters(1, m, DenoiseParams{}).region_mode, RegionMode::Off);
  m.cluster_area_ratio = 12;
  EXPECT_EQ(prototype_parameters(1, m, DenoiseParams{}).region_mode, RegionMode::On);
}

TEST(DenoiseAuto, ReportsWhatRanAndEqualsAManualRunOfIt) {
  const TriMesh noisy = noisy_copy(test::cube(10), 0.2);
  DenoiseParams request;
  request.mode = ParamMode::Auto;
  request.n_vertex = 12;
  request.pin(AutoField::NVertex);
  const DenoiseResult a = denoise(noisy, request);
  EXPECT_EQ(a.report.mode, ParamMode::Auto);
  ASSERT_TRUE(a.report.measures.has_value());
  EXPECT_GT(a.report.measures->noise, 0);
  EXPECT_EQ(a.report.params.mode, ParamMode::Manual);
  EXPECT_EQ(a.report.params.n_vertex, 12);
  EXPECT_GT(a.report.timings.measure_ms, 0);  // measuring and scoring the candidates
  ASSERT_TRUE(a.report.selection.has_value());
  const DenoiseResult m = denoise(noisy, a.report.params);
  EXPECT_FALSE(m.report.measures.has_value());
  EXPECT_EQ(m.report.mode, ParamMode::Manual);
  EXPECT_TRUE(a.mesh.V == m.mesh.V);  // auto = measure + choose + the manual pipeline
}

}  // namespace
}  // namespace mdn
