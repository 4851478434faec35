#include "core/noise_estimate.h"

#include <gtest/gtest.h>

#include <tuple>

#include "core/noise.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

NoiseEstimate estimate(const TriMesh& m) {
  const Vertices P = UnitBox::of(m.V).apply(m.V);
  const Topology topo = Topology::build(m.F, static_cast<std::int32_t>(P.rows()));
  return estimate_noise(P, m.F, topo, smoothed_normals(P, m.F, topo));
}

TEST(EstimateNoise, ACleanSurfaceHasNoNoise) {
  EXPECT_LT(estimate(test::plane(30)).sigma_edges, 1e-9);           // a plane is fitted exactly
  EXPECT_LT(estimate(test::sphere(4)).sigma_edges, 0.01);           // curvature is fitted away
}

TEST(EstimateNoise, TracksGaussianNoiseOnSmoothAndCreasedShapes) {
  // At 0.1 edge lengths the cube's creases weigh as much as the noise (decision 19): from 0.3 on.
  for (const auto& [name, clean, from] : {std::tuple{"sphere", test::sphere(4), 0.1}, std::tuple{"cube", test::cube(24), 0.3}}) {
    for (const double sigma : {0.1, 0.3, 0.6, 1.0}) {
      if (sigma < from) continue;
      // At 1.0 edge lengths the surface folds over itself and the fits read high (decision 19).
      const double tolerance = sigma < 1 ? 0.25 : 0.4;
      SCOPED_TRACE(std::string(name) + " sigma " + std::to_string(sigma));
      const NoiseEstimate e = estimate(test::with_noise(clean, sigma));
      EXPECT_NEAR(e.sigma_edges / sigma, 1.0, tolerance);
      EXPECT_NEAR(e.gaussian_sigma / e.edge_length / sigma, 1.0, tolerance);  // the uncorrected core
    }
  }
}

TEST(EstimateNoise, ImpulseNoiseGivesItsRmsWhileTheMedianSeesOnlyTheCleanCore) {
  const TriMesh clean = test::sphere(4);
  NoiseSpec spec;
  spec.sigma = 0.6;
  spec.impulse_fraction = 0.1;
  spec.seed = 3;
  const NoiseEstimate e = estimate(TriMesh{add_noise(clean, spec), clean.F});
  const double rms = 0.6 * std::sqrt(0.1);
  EXPECT_NEAR(e.sigma_edges / rms, 1.0, 0.25);
  EXPECT_LT(e.gaussian_sigma / e.edge_length, 0.5 * rms);
}

}  // namespace
}  // namespace mdn
