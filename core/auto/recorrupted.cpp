#include "core/auto/recorrupted.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/errors.h"
#include "core/noise.h"
#include "core/parallel.h"
#include "core/pipeline.h"
#include "core/progress.h"
#include "core/prefilter.h"
#include "core/auto/surface_sample.h"
#include "core/auto/descent.h"

namespace mdn {

namespace {
// An input is clean when one quadric pass reads less noise than this many mean edge lengths
// (it reads 1.19x the noise at the median over the training cases: 0.02 of noise).
constexpr double kCleanOnePassEdges = 0.024;
}  // namespace

struct RecorruptedScorer::Impl {
  const SurfaceSample& sample;
  Executor& executor;
  ProgressObserver* progress;
  std::vector<Vertices> y1, n2;  // per draw: the input, and y2's face normals
  Vertices normals;              // of the smoothed sample, per vertex
  double recorruption = 0;       // variance of a z along the normal
};

RecorruptedScorer::RecorruptedScorer(const SurfaceSample& sample, const Vertices& N, double sigma, const SelectionOptions& options,
                                     Executor& executor, ProgressObserver* progress)
    : impl_(new Impl{sample, executor, progress, {}, {}, {}, options.a * options.a * sigma * sigma}) {
  // z per coordinate (decision 20), or along the normals of a smoothed copy of the sample.
  impl_->normals = N;
  const auto n = static_cast<std::size_t>(sample.P.rows());
  for (int d = 0; d < options.draws; ++d) {
    const std::vector<double> g = gaussian_draws(3 * n, options.seed + static_cast<std::uint64_t>(d) * 0x9e3779b97f4a7c15ull);
    Vertices y1 = sample.P, y2 = sample.P;
    for (std::size_t v = 0; v < n; ++v) {
      const auto i = static_cast<Eigen::Index>(v);
      const Eigen::RowVector3d z = options.isotropic ? Eigen::RowVector3d(sigma * g[3 * v], sigma * g[3 * v + 1], sigma * g[3 * v + 2])
                                                     : Eigen::RowVector3d(sigma * g[v] * N.row(i));
      y1.row(i) += options.a * z;
      y2.row(i) -= z / options.a;
    }
    impl_->y1.push_back(std::move(y1));
    impl_->n2.push_back(face_normals(y2, sample.F));
  }
}

RecorruptedScorer::~RecorruptedScorer() = default;

int RecorruptedScorer::draws() const { return static_cast<int>(impl_->y1.size()); }
const Vertices& RecorruptedScorer::input(int draw) const { return impl_->y1[static_cast<std::size_t>(draw)]; }

double RecorruptedScorer::score_positions(int draw, const Vertices& output) const {
  const Vertices N = face_normals(output, impl_->sample.F);
  const Vertices& T = impl_->n2[static_cast<std::size_t>(draw)];
  double sum = 0;
  std::int64_t count = 0;
  for (Eigen::Index f = 0; f < N.rows(); ++f) {
    if (!impl_->sample.scored[static_cast<std::size_t>(f)]) continue;
    if (N.row(f).squaredNorm() == 0 || T.row(f).squaredNorm() == 0) continue;  // degenerate: no orientation
    sum += 1 - N.row(f).dot(T.row(f));
    ++count;
  }
  return count ? sum / static_cast<double>(count) : 0;
}

double RecorruptedScorer::score(const DenoiseParams& params, double* residual, int first, int last) {
  if (last < 0) last = draws();
  double total = 0, squares = 0;
  for (int d = first; d < last; ++d) {
    checkpoint(impl_->progress, Stage::SelectParameters, 0);  // cancellation between runs
    DenoiseReport scratch;
    const Vertices out = run_method(input(d), impl_->sample.F, impl_->sample.topo, params, impl_->executor, nullptr, scratch);
    total += score_positions(d, out);
    for (const std::int32_t v : impl_->sample.scored_vertices)
      squares += std::pow((input(d).row(v) - out.row(v)).dot(impl_->normals.row(v)), 2);
  }
  const int used = std::max(1, last - first);
  if (residual) {
    const double n = static_cast<double>(std::max<std::size_t>(1, impl_->sample.scored_vertices.size())) * used;
    *residual = std::sqrt(std::max(0.0, squares / n - impl_->recorruption));
  }
  return total / used;
}

namespace {

// Decision 24: a candidate that takes more off y1 than the noise can explain removes shape,
// where the noise is low enough for the input to be a clean surface read as noisy.
bool takes_shape(const SelectionOptions& options, const NoiseEstimate& estimate, double residual, double noise) {
  const bool low = options.guard_below <= 0 || noise < options.guard_below * estimate.edge_length;
  return options.remove_at_most > 0 && low && residual > options.remove_at_most * noise;
}

// Decision 22: the ground-truth search's coordinate descent (core/auto/descent.h), started from the
// pick and driven by the recorrupted score of the same draws; its result joins the candidates.
void descend_from_pick(Selection& sel, const SurfaceSample& sample, RecorruptedScorer& scorer, const DenoiseParams& requested,
                       const SelectionOptions& options, Executor& executor, ProgressObserver* progress) {
  TuneProblem problem{sample.F, sample.topo, {}, [&](int t, const Vertices& V) { return scorer.score_positions(t, V); },
                      fold_ratio(sample.P, sample.F, sample.topo, requested.fold_angle)};
  for (int d = 0; d < scorer.draws(); ++d) problem.inputs.push_back(scorer.input(d));
  TuneOptions tune;
  tune.progress = progress;
  // Pinned fields keep the caller's value: their grid lists hold that value alone.
  const DenoiseParams& r = requested;
  if (r.is_pinned(AutoField::RegionMode)) tune.grid.region_mode = {r.region_mode};
  if (r.is_pinned(AutoField::Alpha)) tune.grid.alpha = {r.alpha};
  if (r.is_pinned(AutoField::SigmaTheta)) tune.grid.sigma_theta = {r.sigma_theta};
  if (r.is_pinned(AutoField::NAniso)) tune.grid.n_aniso = {r.n_aniso};
  if (r.is_pinned(AutoField::SigmaGamma)) tune.grid.sigma_gamma = {r.sigma_gamma};
  if (r.is_pinned(AutoField::NNormal)) tune.grid.n_normal = {r.n_normal};
  if (r.is_pinned(AutoField::NVertex)) tune.grid.n_vertex = {r.n_vertex};
  const Descent d = descend(problem, sel.candidates[static_cast<std::size_t>(sel.chosen)].params, tune, executor);
  DenoiseParams best = d.best;
  best.pinned = requested.pinned;
  sel.evaluations += d.evaluations;
  ScoredCandidate found_by_search{"search", best, 0, scorer.draws()};
  found_by_search.score = scorer.score(best, &found_by_search.residual);
  // Decision 24 holds for the search's result too.
  found_by_search.eligible = !takes_shape(options, sel.noise, found_by_search.residual, sel.noise.sigma);
  sel.candidates.push_back(found_by_search);
  if (found_by_search.eligible && found_by_search.score < sel.candidates[static_cast<std::size_t>(sel.chosen)].score)
    sel.chosen = static_cast<int>(sel.candidates.size() - 1);
}

}  // namespace

Selection select_parameters(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& requested,
                            std::vector<ScoredCandidate> candidates, Executor& executor, ProgressObserver* progress,
                            const SelectionOptions& options) {
  Selection sel;
  const SurfaceSample sample = sample_surface(P, F, topo, options.max_faces);
  sel.sample_faces = sample.F.rows();
  sel.scored_faces = std::count(sample.scored.begin(), sample.scored.end(), 1);
  const Vertices normals = smoothed_normals(sample.P, sample.F, sample.topo, &executor);
  sel.noise = estimate_noise(sample.P, sample.F, sample.topo, normals, sample.scored_vertices, &executor);
  sel.candidates = std::move(candidates);
  const auto removes_shape = [&](double residual, double noise) { return takes_shape(options, sel.noise, residual, noise); };
  const auto score_all = [&](RecorruptedScorer& scorer, double noise) {
    // Decision 21: every candidate on the first draw; the best `refine` of them on the others.
    const int draws = scorer.draws();
    const bool staged = options.refine > 0 && draws > 1;
    const auto eligible = [&](std::size_t k) {
      ScoredCandidate& c = sel.candidates[k];
      c.eligible = !removes_shape(c.residual, noise);
      return c.eligible;
    };
    std::vector<std::size_t> order;
    const auto by_score = [&](std::size_t x, std::size_t y) { return sel.candidates[x].score < sel.candidates[y].score; };
    for (std::size_t k = 0; k < sel.candidates.size(); ++k) {
      checkpoint(progress, Stage::SelectParameters, static_cast<double>(k) / static_cast<double>(sel.candidates.size()));
      ScoredCandidate& c = sel.candidates[k];
      c.draws = staged ? 1 : draws;
      c.score = scorer.score(c.params, &c.residual, 0, c.draws);
      ++sel.evaluations;
      if (eligible(k)) order.push_back(k);
    }
    std::stable_sort(order.begin(), order.end(), by_score);
    if (staged) {
      order.resize(std::min(order.size(), static_cast<std::size_t>(options.refine)));
      for (const std::size_t k : order) {
        ScoredCandidate& c = sel.candidates[k];
        double residual = 0;
        const double rest = scorer.score(c.params, &residual, 1, draws);
        c.score = (c.score + rest * (draws - 1)) / draws;
        c.residual = std::sqrt((c.residual * c.residual + residual * residual * (draws - 1)) / draws);
        c.draws = draws;
      }
      std::erase_if(order, [&](std::size_t k) { return !eligible(k); });
      std::stable_sort(order.begin(), order.end(), by_score);
    }
    sel.chosen = order.empty() ? 0 : static_cast<int>(order.front());
  };
  // Decision 20: below 2% of an edge, noise tilts a face by ~1 degree at most (no more than the
  // flattest shape detail): such a surface is taken as clean and left alone, without scoring.
  if (options.sigma <= 0 && sel.noise.one_pass_edges < kCleanOnePassEdges) {
    return sel;  // chosen = 0, the first candidate (the model's pick), unscored
  }
  auto scoring = std::make_unique<RecorruptedScorer>(sample, normals, options.sigma > 0 ? options.sigma : options.scale * sel.noise.sigma,
                                                    options, executor, progress);
  score_all(*scoring, options.sigma > 0 ? options.sigma : sel.noise.sigma);
  // Decision 20: the winner's residual on y1, less the recorruption's share, is the noise it
  // found. Far less than the estimate means the estimate read shape as noise (a clean or nearly
  // clean surface with many features): score again at the noise the winner found.
  const double found = sel.candidates[static_cast<std::size_t>(sel.chosen)].residual;
  if (options.sigma <= 0 && found > 0 && found < options.rescore_below * sel.noise.sigma) {
    sel.noise.sigma = found;
    sel.noise.sigma_edges = sel.noise.edge_length > 0 ? found / sel.noise.edge_length : 0;
    scoring = std::make_unique<RecorruptedScorer>(sample, normals, std::max(options.scale * found, 1e-12 * sel.noise.edge_length),
                                                  options, executor, progress);
    score_all(*scoring, found);
  }
  if (requested.mode == ParamMode::Search) descend_from_pick(sel, sample, *scoring, requested, options, executor, progress);
  return sel;
}

}  // namespace mdn
