#include "core/auto/choose.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/auto/denoise.h"
#include "core/auto/descriptors.h"
#include "core/auto/model.h"
#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

using test::automatic;

double diagonal(const TriMesh& m) { return (m.V.colwise().maxCoeff() - m.V.colwise().minCoeff()).norm(); }
using test::max_displacement;

TEST(ChooseParameters, ACleanSurfaceComesBackUnchanged) {
  for (const TriMesh& clean : {test::sphere(4), test::cube(16), test::torus(64, 24, 0.3)}) {
    const DenoiseResult r = denoise(clean, automatic());
    ASSERT_TRUE(r.report.choice);
    EXPECT_EQ(r.report.choice->chosen, "identity");
    EXPECT_LT(max_displacement(r.mesh, clean), 1e-9 * diagonal(clean));
  }
}

TEST(ChooseParameters, NoisySurfacesAreFilteredAndTheCadShapeBeatsThePaperRow) {
  for (const TriMesh& clean : {test::cube(16), test::sphere(4)}) {
    const TriMesh noisy = test::with_noise(clean, 0.3);
    const DenoiseResult r = denoise(noisy, automatic());
    EXPECT_NE(r.report.choice->chosen, "identity");
    EXPECT_EQ(r.report.choice->method, "model");
    EXPECT_LT(msae(r.mesh, clean), 0.2 * msae(noisy, clean));  // the noise's MSAE down 5x at least
  }
  // A sharp CAD part wants many normal iterations, not the paper's 20.
  const TriMesh clean = test::cube(16), noisy = test::with_noise(clean, 0.3);
  EXPECT_LT(msae(denoise(noisy, automatic()).mesh, clean), 0.5 * msae(denoise(noisy, DenoiseParams{}).mesh, clean));
}

TEST(ChooseParameters, ReportsTheModelItsReadingsAndThePickAndEqualsAManualRunOfIt) {
  const TriMesh noisy = test::with_noise(test::cube(10), 0.2);
  const DenoiseResult r = denoise(noisy, automatic());
  ASSERT_TRUE(r.report.choice);
  const ParameterChoice& c = *r.report.choice;
  const ParameterModel& model = ParameterModel::shipped();
  EXPECT_EQ(c.model_version, model.version());
  EXPECT_EQ(c.descriptors.size(), descriptor_names().size());
  ASSERT_EQ(static_cast<int>(c.sets.size()), model.set_count());
  const auto best = std::min_element(c.sets.begin(), c.sets.end(),
                                     [](const PredictedSet& a, const PredictedSet& b) { return a.predicted < b.predicted; });
  EXPECT_EQ(c.chosen, best->name);
  EXPECT_EQ(c.predicted, best->predicted);
  EXPECT_GE(c.predicted, 0.0);
  EXPECT_GT(c.noise.sigma_edges, 0.1);
  EXPECT_EQ(r.report.params.mode, ParamMode::Manual);
  const DenoiseResult manual = denoise(noisy, r.report.params);
  EXPECT_TRUE(manual.mesh.V == r.mesh.V);  // auto = choose + the manual pipeline
  EXPECT_FALSE(manual.report.choice);
  // The noise is reported in the input's units; the pick does not depend on the scale.
  TriMesh larger = noisy;
  larger.V *= 250.0;
  const DenoiseResult big = denoise(larger, automatic());
  EXPECT_NEAR(big.report.choice->noise.sigma, 250.0 * c.noise.sigma, 1e-6 * big.report.choice->noise.sigma);
  EXPECT_EQ(big.report.choice->chosen, c.chosen);
}

TEST(ChooseParameters, PinnedFieldsKeepTheirValueInEverySet) {
  DenoiseParams p = automatic();
  p.n_vertex = 7;
  p.pin(AutoField::NVertex);
  p.region_mode = RegionMode::Off;
  p.pin(AutoField::RegionMode);
  const DenoiseResult r = denoise(test::with_noise(test::cube(10), 0.2), p);
  for (const PredictedSet& s : r.report.choice->sets) {
    EXPECT_EQ(s.params.n_vertex, 7) << s.name;
    EXPECT_EQ(s.params.region_mode, RegionMode::Off) << s.name;
  }
  EXPECT_EQ(r.report.params.n_vertex, 7);
}

TEST(ChooseParameters, IrregularSamplingTurnsTheRegionPrefilterOn) {
  const DenoiseResult regular = denoise(test::with_noise(test::sphere(3), 0.2), automatic());
  const DenoiseResult irregular = denoise(test::with_noise(test::irregular_sphere(3), 0.2), automatic());
  EXPECT_EQ(regular.report.params.region_mode, RegionMode::Off);
  EXPECT_EQ(irregular.report.params.region_mode, RegionMode::On);
}

TEST(ChooseParameters, IsBitIdenticalForAnyThreadCount) {
  const TriMesh noisy = test::with_noise(test::sphere(5), 0.2);  // 20480 faces
  const DenoiseResult one = denoise(noisy, automatic(), {1, nullptr}), three = denoise(noisy, automatic(), {3, nullptr});
  EXPECT_EQ(one.report.choice->descriptors, three.report.choice->descriptors);
  EXPECT_TRUE(one.mesh.V == three.mesh.V);
}

TEST(ChooseParameters, AMeshOutsideTheTrainingRangeGetsTheFallbackAndANote) {
  // 48 faces: fewer than the model was trained on. Noisy: the paper's row beats no filtering.
  const DenoiseResult tiny = denoise(test::with_noise(test::cube(2), 0.3), automatic());
  EXPECT_EQ(tiny.report.choice->method, "fallback");
  EXPECT_TRUE(tiny.report.choice->sets.empty());
  ASSERT_TRUE(tiny.report.choice->search);
  EXPECT_EQ(tiny.report.choice->search->candidates.size(), 2u);
  ASSERT_EQ(tiny.report.choice->notes.size(), 1u);
  EXPECT_NE(tiny.report.choice->notes[0].find("fewer than"), std::string::npos);
  // A clean triangle soup (every edge a boundary edge) is left alone.
  const TriMesh sphere = test::sphere(3);
  TriMesh soup;
  soup.V.resize(3 * sphere.F.rows(), 3);
  soup.F.resize(sphere.F.rows(), 3);
  for (Eigen::Index f = 0; f < sphere.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      soup.V.row(3 * f + c) = sphere.V.row(sphere.F(f, c));
      soup.F(f, c) = static_cast<std::int32_t>(3 * f + c);
    }
  const DenoiseResult r = denoise(soup, automatic());
  EXPECT_EQ(r.report.choice->method, "fallback");
  EXPECT_EQ(r.report.choice->chosen, "identity");
  EXPECT_NE(r.report.choice->notes.at(0).find("boundary"), std::string::npos);
  EXPECT_LT(max_displacement(r.mesh, soup), 1e-9 * diagonal(soup));
}

TEST(ChooseParameters, SearchRefinesThePickByTheRecorruptedScoreAndKeepsPinnedFields) {
  const TriMesh noisy = test::with_noise(test::cube(10), 0.3);
  DenoiseParams s = automatic();
  s.mode = ParamMode::Search;
  s.sigma_gamma = 30;
  s.pin(AutoField::SigmaGamma);
  const DenoiseResult b = denoise(noisy, s);
  ASSERT_TRUE(b.report.choice->search);
  const Selection& sel = *b.report.choice->search;
  EXPECT_EQ(b.report.choice->method, "search");
  EXPECT_EQ(sel.candidates.back().name, "search");
  EXPECT_GT(sel.evaluations, static_cast<int>(sel.candidates.size()));
  for (const ScoredCandidate& c : sel.candidates)
    if (c.eligible) {
      EXPECT_GE(c.score, sel.candidates[static_cast<std::size_t>(sel.chosen)].score) << c.name;
    }
  EXPECT_EQ(b.report.params.sigma_gamma, 30);
  EXPECT_EQ(b.report.mode, ParamMode::Search);
}

class CancelAtChoice : public ProgressObserver {
 public:
  void on_progress(Stage stage, double) override { seen = seen || stage == Stage::SelectParameters; }
  bool cancel_requested() override { return seen; }
  bool seen = false;
};

TEST(ChooseParameters, HonoursCancellation) {
  CancelAtChoice cancel;
  EXPECT_THROW(denoise(test::with_noise(test::cube(10), 0.2), automatic(), {1, &cancel}), CancelledError);
  EXPECT_TRUE(cancel.seen);
}

TEST(ParameterModel, TheShippedModelLoadsAndReproducesTheTrainersPredictions) {
  const ParameterModel& model = ParameterModel::shipped();
  EXPECT_FALSE(model.version().empty());
  EXPECT_GE(model.set_count(), 40);
  int identities = 0;
  for (int k = 0; k < model.set_count(); ++k) identities += model.is_identity(k);
  EXPECT_EQ(identities, 1);
  EXPECT_THROW(model.predict(std::vector<double>(3, 0.0)), std::invalid_argument);
  // tools/train/train.py records a few holdout cases' descriptors and scikit-learn's predictions.
  const std::vector<ModelProbe>& probes = model_probes();
  ASSERT_GE(probes.size(), 3u);
  for (const ModelProbe& p : probes) {
    const Eigen::VectorXd got = model.predict(p.descriptors);
    ASSERT_EQ(static_cast<std::size_t>(got.size()), p.predicted.size());
    for (Eigen::Index k = 0; k < got.size(); ++k) EXPECT_NEAR(got(k), p.predicted[static_cast<std::size_t>(k)], 1e-9) << p.name;
  }
}

}  // namespace
}  // namespace mdn
