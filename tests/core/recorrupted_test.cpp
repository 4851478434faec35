#include "core/auto/recorrupted.h"

#include <gtest/gtest.h>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/parallel.h"
#include "core/auto/denoise.h"
#include "core/auto/measures.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

using test::automatic;

using test::max_displacement;

// Candidates as Search scores them: the identity, the paper's row, a strong CAD-like set and a
// heavy smoothing one.
std::vector<ScoredCandidate> candidates() {
  DenoiseParams identity, paper, strong, smooth;
  identity.alpha = 0;
  identity.n_aniso = identity.n_normal = identity.n_vertex = 0;
  strong.alpha = 0.3;
  strong.sigma_theta = 50;
  strong.n_aniso = 2;
  strong.sigma_gamma = 45;
  strong.n_normal = 70;
  strong.n_vertex = 30;
  smooth.alpha = 0.8;
  smooth.sigma_theta = 70;
  smooth.n_aniso = 16;
  smooth.sigma_gamma = 90;
  smooth.n_normal = 100;
  smooth.n_vertex = 30;
  for (DenoiseParams* p : {&identity, &paper, &strong, &smooth}) p->region_mode = RegionMode::Off;
  return {{"identity", identity, 0}, {"paper", paper, 0}, {"strong", strong, 0}, {"smooth", smooth, 0}};
}

TEST(RecorruptedSelection, ACandidateThatRemovesShapeIsNotPickedSoACoarseCleanPartStaysPut) {
  // Decision 24. The estimate reads the creases of a clean low-poly cylinder as noise; the
  // best-scored candidate at that noise flattens them. Without the guard Search would move
  // the part by more than 1% of its diagonal; with it that candidate is not picked.
  const TriMesh clean = test::closed_cylinder(32, 4, 1.0);
  const double diagonal = (clean.V.colwise().maxCoeff() - clean.V.colwise().minCoeff()).norm();
  const Vertices P = UnitBox::of(clean.V).apply(clean.V);
  const Topology topo = Topology::build(clean.F, static_cast<int>(clean.V.rows()));
  Executor ex(1);
  SelectionOptions unguarded;
  unguarded.remove_at_most = 0;
  const Selection loose = select_parameters(P, clean.F, topo, automatic(), candidates(), ex, nullptr, unguarded);
  const ScoredCandidate& flattening = loose.candidates[static_cast<std::size_t>(loose.chosen)];
  ASSERT_NE(flattening.name, "identity");
  EXPECT_GT(max_displacement(denoise(clean, flattening.params).mesh, clean), 0.01 * diagonal);

  const Selection sel = select_parameters(P, clean.F, topo, automatic(), candidates(), ex);
  const ScoredCandidate& chosen = sel.candidates[static_cast<std::size_t>(sel.chosen)];
  EXPECT_TRUE(chosen.eligible);
  for (const ScoredCandidate& c : sel.candidates) {
    EXPECT_EQ(c.eligible, c.residual <= 1.5 * sel.noise.sigma) << c.name;
    if (c.eligible) {
      EXPECT_GE(c.score, chosen.score) << c.name;
    }
  }
  EXPECT_FALSE(sel.candidates[static_cast<std::size_t>(loose.chosen)].eligible);
}

TEST(RecorruptedSelection, IsBitIdenticalForAnyThreadCountAndSampledWhenLarge) {
  const TriMesh noisy = test::with_noise(test::sphere(5), 0.2);  // 20480 faces
  const Vertices P = UnitBox::of(noisy.V).apply(noisy.V);
  const Topology topo = Topology::build(noisy.F, static_cast<std::int32_t>(P.rows()));
  SelectionOptions small;
  small.max_faces = 5000;
  DenoiseParams p = automatic();
  std::vector<Selection> runs;
  for (const int threads : {1, 2, 3}) {
    Executor ex(threads);
    runs.push_back(select_parameters(P, noisy.F, topo, p, candidates(), ex, nullptr, small));
  }
  EXPECT_LE(runs[0].sample_faces, 5000);
  EXPECT_LT(runs[0].scored_faces, runs[0].sample_faces);
  for (std::size_t k = 1; k < runs.size(); ++k) {
    EXPECT_EQ(runs[k].chosen, runs[0].chosen);
    EXPECT_EQ(runs[k].noise.sigma, runs[0].noise.sigma);
    for (std::size_t c = 0; c < runs[0].candidates.size(); ++c) EXPECT_EQ(runs[k].candidates[c].score, runs[0].candidates[c].score);
  }
}

}  // namespace
}  // namespace mdn
