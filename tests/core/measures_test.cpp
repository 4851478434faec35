#include "core/auto/measures.h"

#include <gtest/gtest.h>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
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

}  // namespace
}  // namespace mdn
