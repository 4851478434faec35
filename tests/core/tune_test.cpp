#include "core/auto/tune.h"

#include <gtest/gtest.h>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/auto/denoise.h"
#include "support/shapes.h"

namespace mdn {
namespace {

struct Pair {
  TriMesh truth, noisy;
};

Pair noisy_cube(double sigma = 0.25) {
  Pair p{test::cube(8), {}};
  NoiseSpec spec;
  spec.sigma = sigma;
  spec.seed = 11;
  p.noisy = TriMesh{add_noise(p.truth, spec), p.truth.F};
  return p;
}

TuneOptions small_grid() {
  TuneOptions o;
  o.grid.alpha = {0.03, 0.1, 0.3};
  o.grid.sigma_theta = {20, 40};
  o.grid.n_aniso = {0, 2, 4};
  o.grid.sigma_gamma = {20, 30, 45};
  o.grid.n_normal = {5, 20, 50};
  o.grid.n_vertex = {5, 10, 30};
  return o;
}

TEST(Tune, FindsParametersAtLeastAsGoodAsTheStartAndReportsTheirTrueMsae) {
  const Pair p = noisy_cube();
  const DenoiseParams start;  // the paper's Fandisk row
  const TuneResult r = tune_parameters(p.truth, p.noisy, start, small_grid());
  EXPECT_EQ(r.start_msae, msae(denoise(p.noisy, start).mesh, p.truth));
  EXPECT_LT(r.best_msae, r.start_msae / 1.5);  // the paper's row is far from best on a cube
  EXPECT_EQ(r.best.mode, ParamMode::Manual);
  EXPECT_NE(r.best.region_mode, RegionMode::Auto);
  EXPECT_EQ(r.best_msae, msae(denoise(p.noisy, r.best).mesh, p.truth));  // exactly what a user gets
  EXPECT_GT(r.evaluations, 3);
  // The grid holds the winner.
  const auto in = [](const auto& list, auto v) { return std::find(list.begin(), list.end(), v) != list.end(); };
  const TuneGrid g = small_grid().grid;
  EXPECT_TRUE(in(g.alpha, r.best.alpha));
  EXPECT_TRUE(in(g.sigma_gamma, r.best.sigma_gamma));
  EXPECT_TRUE(in(g.n_normal, r.best.n_normal));
  EXPECT_TRUE(in(g.n_vertex, r.best.n_vertex));
}

TEST(Tune, IsDeterministicAcrossThreadCounts) {
  const Pair p = noisy_cube();
  TuneOptions one = small_grid(), two = small_grid();
  two.threads = 2;
  const TuneResult a = tune_parameters(p.truth, p.noisy, {}, one);
  const TuneResult b = tune_parameters(p.truth, p.noisy, {}, two);
  EXPECT_EQ(a.best_msae, b.best_msae);
  EXPECT_EQ(a.best.alpha, b.best.alpha);
  EXPECT_EQ(a.best.n_normal, b.best.n_normal);
  EXPECT_EQ(a.best.n_vertex, b.best.n_vertex);
}

TEST(Tune, RefusesMismatchedMeshesAndEmptyLists) {
  const Pair p = noisy_cube();
  TriMesh other = test::cube(6);
  EXPECT_THROW(tune_parameters(other, p.noisy, {}, small_grid()), InvalidMeshError);
  TuneOptions empty = small_grid();
  empty.grid.sigma_gamma.clear();
  EXPECT_THROW(tune_parameters(p.truth, p.noisy, {}, empty), InvalidParamsError);
  TuneOptions unsorted = small_grid();
  unsorted.grid.n_normal = {20, 5};
  EXPECT_THROW(tune_parameters(p.truth, p.noisy, {}, unsorted), InvalidParamsError);
  DenoiseParams bad;
  bad.alpha = -1;
  EXPECT_THROW(tune_parameters(p.truth, p.noisy, bad, small_grid()), InvalidParamsError);
}

class CancelAfterPolls : public ProgressObserver {
 public:
  explicit CancelAfterPolls(int polls) : left_(polls) {}
  void on_progress(Stage, double) override {}
  bool cancel_requested() override { return --left_ < 0; }

 private:
  int left_;
};

TEST(Tune, HonoursCancellation) {
  const Pair p = noisy_cube();
  CancelAfterPolls cancel(2);
  TuneOptions o = small_grid();
  o.progress = &cancel;
  EXPECT_THROW(tune_parameters(p.truth, p.noisy, {}, o), CancelledError);
}

}  // namespace
}  // namespace mdn
