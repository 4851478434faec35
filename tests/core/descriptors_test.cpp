#include "core/auto/descriptors.h"

#include <gtest/gtest.h>

#include "core/noise.h"
#include "core/parallel.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

Descriptors describe(const TriMesh& m, std::int64_t max_faces) {
  const Topology topo = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  Executor executor(2);
  return describe_input(m.V, m.F, topo, executor, max_faces);
}

// The descriptor called `name` in d.
double value(const Descriptors& d, const std::string& name) {
  for (std::size_t i = 0; i < d.values.size(); ++i)
    if (descriptor_names()[i] == name) return d.values[i];
  ADD_FAILURE() << "no descriptor " << name;
  return 0.0;
}

// Decision 33: above 20,000 faces the descriptors are read on patches; they must say what the
// whole surface says (scale-free readings within 0.15 in log or 0.03 in share).
TEST(Descriptors, ALargeSurfaceReadOnPatchesReadsLikeTheWholeSurface) {
  for (const double sigma : {0.1, 0.4}) {
    const TriMesh noisy = test::with_noise(test::torus(256, 128, 0.3), sigma);  // 65,536 faces
    const Descriptors sampled = describe(noisy, kDescribedFaces), whole = describe(noisy, noisy.F.rows());
    ASSERT_EQ(sampled.values.size(), descriptor_names().size());
    for (std::size_t i = 0; i < sampled.values.size(); ++i)
      EXPECT_NEAR(sampled.values[i], whole.values[i], 0.15) << descriptor_names()[i] << " at sigma " << sigma;
    EXPECT_NEAR(sampled.noise.sigma_edges, whole.noise.sigma_edges, 0.1 * whole.noise.sigma_edges);
    EXPECT_NEAR(whole.noise.sigma_edges, sigma, 0.25 * sigma);  // the quick reading is a noise level
  }
}

TEST(Descriptors, ExactlyFlatNeighboursSetACleanCadSurfaceApartFromALightlyNoisyOne) {
  const auto flat_share = [](const Descriptors& d) { return value(d, "dihedral_flat_share"); };
  const TriMesh clean = test::cube(24);
  EXPECT_GT(flat_share(describe(clean, kDescribedFaces)), 0.9);
  EXPECT_LT(flat_share(describe(test::with_noise(clean, 0.05), kDescribedFaces)), 0.05);
}

// Decision 46: impulses are a heavy upper tail of the vertices' distances to their rings'
// planes. The same surface with 10% of its vertices displaced by 0.6 l, against Gaussian noise
// of about the same energy on every vertex (0.6 l x sqrt(0.1) = 0.19 l): the tail over the
// median and the share of vertices above four medians both stand apart.
TEST(Descriptors, ImpulsesLiftTheTailOfTheVertexPlaneDistances) {
  const TriMesh clean = test::torus(96, 48, 0.3);
  NoiseSpec spec;
  spec.sigma = 0.6;
  spec.impulse_fraction = 0.1;
  const Descriptors impulses = describe(TriMesh{add_noise(clean, spec), clean.F}, kDescribedFaces);
  const Descriptors gaussian = describe(test::with_noise(clean, 0.19), kDescribedFaces);
  EXPECT_GT(value(impulses, "vdist_tail"), value(gaussian, "vdist_tail") + 1.0);
  EXPECT_GT(value(impulses, "vdist_outliers"), 2 * value(gaussian, "vdist_outliers"));
  EXPECT_GT(value(impulses, "vdist_outliers"), 0.05);
  // A clean surface reads its curvature only: far below either noisy copy.
  EXPECT_LT(value(describe(clean, kDescribedFaces), "vdist_median"), value(gaussian, "vdist_median") - 1.0);
}

// Decision 50: scanner spikes (1% of the vertices thrown 1 l off) on a clean CAD surface. The
// bulk of the surface reads clean, so only the spike readings tell the two apart; creases and
// corners (a cube's) must not read as spikes, and Gaussian noise of the same energy on every
// vertex (0.1 l) reads lower at the top.
TEST(Descriptors, SpikesStandOutOfTheirRingsAndCreasesDoNot) {
  const TriMesh clean = test::cube(24);
  NoiseSpec spec;
  spec.sigma = 1.0;
  spec.impulse_fraction = 0.01;
  const Descriptors spikes = describe(TriMesh{add_noise(clean, spec), clean.F}, kDescribedFaces);
  const Descriptors plain = describe(clean, kDescribedFaces);
  const Descriptors gaussian = describe(test::with_noise(clean, 0.1), kDescribedFaces);
  EXPECT_EQ(value(plain, "spike_share"), 0.0);
  EXPECT_GT(value(spikes, "spike_share"), 0.004);
  EXPECT_GT(value(spikes, "spike_p999"), value(plain, "spike_p999") + 1.0);
  EXPECT_GT(value(spikes, "spike_p999"), value(gaussian, "spike_p999") + 0.3);
}

}  // namespace
}  // namespace mdn
