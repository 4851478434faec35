#include "core/auto/descriptors.h"

#include <gtest/gtest.h>

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
  const auto flat_share = [](const Descriptors& d) {
    for (std::size_t i = 0; i < d.values.size(); ++i)
      if (descriptor_names()[i] == "dihedral_flat_share") return d.values[i];
    return -1.0;
  };
  const TriMesh clean = test::cube(24);
  EXPECT_GT(flat_share(describe(clean, kDescribedFaces)), 0.9);
  EXPECT_LT(flat_share(describe(test::with_noise(clean, 0.05), kDescribedFaces)), 0.05);
}

}  // namespace
}  // namespace mdn
