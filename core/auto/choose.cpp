#include "core/auto/choose.h"

#include <cmath>

#include "core/auto/descriptors.h"
#include "core/auto/model.h"
#include "core/auto/recorrupted.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace mdn {

namespace {

// Decision 26: what the model was trained on. Its corpus holds closed and open manifold
// surfaces of 346 to 48,000 faces with at most 4% boundary edges; a mesh far outside that
// gets the fallback below.
constexpr std::int64_t kMinFaces = 100;
constexpr double kMaxBoundaryShare = 0.15;
constexpr double kMaxNonManifoldShare = 0.01;

std::string outside_training_range(const Triangles& F, const Topology& topo) {
  const double edges = static_cast<double>(topo.num_interior_edges() + topo.boundary_edges.rows() + topo.nonmanifold_edges.rows());
  if (F.rows() < kMinFaces)
    return "the mesh has " + std::to_string(F.rows()) + " faces, fewer than the " + std::to_string(kMinFaces) +
           " the parameter model was trained on";
  if (edges > 0 && static_cast<double>(topo.boundary_edges.rows()) > kMaxBoundaryShare * edges)
    return "more than 15% of the edges are boundary edges (a triangle soup or a very open surface), outside what the "
           "parameter model was trained on";
  if (edges > 0 && static_cast<double>(topo.nonmanifold_edges.rows()) > kMaxNonManifoldShare * edges)
    return "more than 1% of the edges are non-manifold, outside what the parameter model was trained on";
  return {};
}

// The paper's Table 1 Fandisk row (DenoiseParams' defaults) with the caller's pinned fields;
// with `filtering` false, the same without pre-filter or iterations (no filtering at all).
DenoiseParams paper_row(const DenoiseParams& requested, bool filtering = true) {
  const DenoiseParams paper;
  const double on = filtering ? 1 : 0;
  return fill_unpinned(requested, {on * paper.alpha, paper.sigma_theta, on * paper.n_aniso, paper.sigma_gamma,
                                   on * paper.n_normal, on * paper.n_vertex});
}

}  // namespace

ParameterChoice choose_parameters(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& requested,
                                  double box_scale, Executor& executor, ProgressObserver* progress, DenoiseParams& chosen) {
  checkpoint(progress, Stage::SelectParameters, 0);
  const ParameterModel& model = ParameterModel::shipped();
  ParameterChoice c;
  c.method = "model";
  c.model_version = model.version();
  const Descriptors d = describe_input(P, F, topo, executor);
  checkpoint(progress, Stage::SelectParameters, 0.5);
  c.measures = d.measures;
  c.noise = d.noise;
  c.noise.sigma /= box_scale;
  c.noise.gaussian_sigma /= box_scale;
  c.noise.edge_length /= box_scale;
  for (std::size_t i = 0; i < d.values.size(); ++i) c.descriptors.emplace_back(descriptor_names()[i], d.values[i]);
  // The region pre-filter where the sampling is irregular (decision 6), unless pinned.
  const RegionMode region = requested.is_pinned(AutoField::RegionMode) ? requested.region_mode
                            : d.measures.cluster_area_ratio >= requested.irregular_area_ratio ? RegionMode::On
                                                                                               : RegionMode::Off;

  if (const std::string why = outside_training_range(F, topo); !why.empty()) {
    // Decision 26: no filtering or the paper's row, whichever the recorrupted score prefers
    // (a surface that reads clean is left alone, decision 20). The paper's row alone moved a
    // clean CAD soup (CGAL's boeing) by 35% of its diagonal.
    c.method = "fallback";
    std::vector<ScoredCandidate> candidates{{"identity", paper_row(requested, false), 0}, {"paper", paper_row(requested), 0}};
    for (ScoredCandidate& k : candidates) k.params.region_mode = region;
    c.search = select_parameters(P, F, topo, requested, std::move(candidates), executor, progress);
    const ScoredCandidate& won = c.search->candidates[static_cast<std::size_t>(c.search->chosen)];
    chosen = won.params;
    c.chosen = won.name;
    c.notes.push_back(why + "; chose between no filtering and the paper's Table 1 row by the recorrupted score instead (" +
                      c.chosen + ", decision 26)");
  } else {
    const Eigen::VectorXd regret = model.predict(d.values);
    int best = 0;
    for (int k = 0; k < model.set_count(); ++k) {
      DenoiseParams p = model.set_params(k, requested);
      p.region_mode = model.is_identity(k) && !requested.is_pinned(AutoField::RegionMode) ? RegionMode::Off : region;
      c.sets.push_back({model.set_name(k), p, std::exp(regret(k))});
      if (regret(k) < regret(best)) best = k;  // ties keep the earlier set
    }
    chosen = c.sets[static_cast<std::size_t>(best)].params;
    c.chosen = c.sets[static_cast<std::size_t>(best)].name;
    c.predicted = c.sets[static_cast<std::size_t>(best)].predicted;
  }
  chosen.region_mode = c.chosen == "identity" && !requested.is_pinned(AutoField::RegionMode) ? RegionMode::Off : region;
  chosen.pinned = requested.pinned;

  if (requested.mode == ParamMode::Search && c.method == "model") {
    // Decision 22: the pick and the paper's row scored on recorrupted copies of a sample, then
    // the coordinate descent from the better of them under the same score.
    std::vector<ScoredCandidate> candidates{{c.chosen, chosen, 0}, {"paper", paper_row(requested), 0}};
    candidates[1].params.region_mode = chosen.region_mode;
    c.search = select_parameters(P, F, topo, requested, std::move(candidates), executor, progress);
    const ScoredCandidate& won = c.search->candidates[static_cast<std::size_t>(c.search->chosen)];
    chosen = won.params;
    chosen.pinned = requested.pinned;
    c.method = "search";
    c.chosen = won.name;
  }
  checkpoint(progress, Stage::SelectParameters, 1);
  return c;
}

}  // namespace mdn
