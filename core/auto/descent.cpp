#include "core/auto/descent.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <tuple>

#include "core/errors.h"
#include "core/normal_filter.h"
#include "core/parallel.h"
#include "core/pipeline.h"
#include "core/prefilter.h"
#include "core/topology.h"
#include "core/vertex_update.h"

namespace mdn {

namespace {

// A point of the outer search: indices into the grid lists.
struct Point {
  int region = 0, alpha = 0, theta = 0, aniso = 0, gamma = 0;
  auto key() const { return std::make_tuple(region, alpha, theta, aniso, gamma); }
};
// The best iteration counts (indices) for one outer point.
struct Inner {
  double msae = std::numeric_limits<double>::infinity();
  int normal = 0, vertex = 0;
};

template <class T>
int nearest(const std::vector<T>& list, double value) {
  int best = 0;
  for (int i = 1; i < static_cast<int>(list.size()); ++i)
    if (std::abs(static_cast<double>(list[static_cast<std::size_t>(i)]) - value) <
        std::abs(static_cast<double>(list[static_cast<std::size_t>(best)]) - value))
      best = i;
  return best;
}

class Search {
 public:
  Search(const TuneProblem& problem, const DenoiseParams& base, const TuneOptions& options, Executor& executor)
      : grid_(options.grid), base_(base), options_(options), executor_(executor), problem_(problem) {
    report_.fold_ratio = problem.fold_ratio;
  }

  DenoiseParams params_at(const Point& p, const Inner& inner) const {
    DenoiseParams q = base_;
    q.mode = ParamMode::Manual;
    q.region_mode = grid_.region_mode[static_cast<std::size_t>(p.region)];
    q.alpha = grid_.alpha[static_cast<std::size_t>(p.alpha)];
    q.sigma_theta = grid_.sigma_theta[static_cast<std::size_t>(p.theta)];
    q.n_aniso = grid_.n_aniso[static_cast<std::size_t>(p.aniso)];
    q.sigma_gamma = grid_.sigma_gamma[static_cast<std::size_t>(p.gamma)];
    q.n_normal = grid_.n_normal[static_cast<std::size_t>(inner.normal)];
    q.n_vertex = grid_.n_vertex[static_cast<std::size_t>(inner.vertex)];
    return q;
  }

  // Best MSAE over all (n_normal, n_vertex) of the grid at an outer point (cached).
  const Inner& evaluate(const Point& p) {
    if (auto it = inner_.find(p.key()); it != inner_.end()) return it->second;
    if (options_.progress && options_.progress->cancel_requested()) throw CancelledError();
    ++evaluations_;
    // Summed over the problem's inputs: score[k][j] for n_normal k and n_vertex j.
    std::vector<std::vector<double>> score(grid_.n_normal.size(), std::vector<double>(grid_.n_vertex.size(), 0.0));
    for (int t = 0; t < static_cast<int>(problem_.inputs.size()); ++t) {
      const Vertices& P = prefiltered(p, t);
      // Sec. 5: one run of the longest n_normal, keeping the normals at every listed count.
      std::vector<Vertices> normals(grid_.n_normal.size());
      NormalFilterSettings nfs = normal_filter_settings(params_at(p, {}));
      nfs.iterations = grid_.n_normal.back();
      nfs.on_iteration = [&](int done, const Vertices& N) {
        for (std::size_t k = 0; k < grid_.n_normal.size(); ++k)
          if (grid_.n_normal[k] == done) normals[k] = N;
      };
      l1_median_normal_filter(P, problem_.F, problem_.topo, nfs, &executor_);
      // Sec. 6: for each, one run of the longest n_vertex, scoring every listed count.
      for (std::size_t k = 0; k < normals.size(); ++k) {
        vertex_update(P, problem_.F, problem_.topo, normals[k], grid_.n_vertex.back(), &executor_, nullptr,
                      [&](int done, const Vertices& V) {
                        for (std::size_t j = 0; j < grid_.n_vertex.size(); ++j)
                          if (grid_.n_vertex[j] == done) score[k][j] += problem_.score(t, V);
                      });
      }
    }
    Inner best;
    for (std::size_t k = 0; k < score.size(); ++k)
      for (std::size_t j = 0; j < score[k].size(); ++j)
        if (score[k][j] < best.msae) best = {score[k][j], static_cast<int>(k), static_cast<int>(j)};
    return inner_.emplace(p.key(), best).first->second;
  }

  int evaluations() const { return evaluations_; }

 private:
  // Sec. 4 output at an outer point; one run of Eq. 3 serves every shorter n_aniso: a miss
  // runs up to aniso_horizon (the end of the current n_aniso scan) and keeps every listed count.
  const Vertices& prefiltered(const Point& p, int input) {
    const auto key = std::make_tuple(input, p.region, p.alpha, p.theta, p.aniso);
    if (auto it = prefilter_.find(key); it != prefilter_.end()) return it->second;
    while (prefilter_.size() > 48) {  // bounded memory: forget the oldest runs
      prefilter_.erase(order_.front());
      order_.pop_front();
    }
    DenoiseParams q = params_at(p, {});
    q.n_aniso = std::max(q.n_aniso, aniso_horizon);
    DenoiseReport report = report_;
    prefilter_stage(problem_.inputs[static_cast<std::size_t>(input)], problem_.F, problem_.topo, q, executor_, nullptr, report,
                    [&](int done, const Vertices& V) {
      const auto at = std::find(grid_.n_aniso.begin(), grid_.n_aniso.end(), done);
      if (at == grid_.n_aniso.end()) return;
      const auto k = std::make_tuple(input, p.region, p.alpha, p.theta, static_cast<int>(at - grid_.n_aniso.begin()));
      if (prefilter_.emplace(k, V).second) order_.push_back(k);
    });
    return prefilter_.at(key);
  }

 public:
  int aniso_horizon = 0;

 private:
  const TuneGrid& grid_;
  const DenoiseParams base_;
  const TuneOptions& options_;
  Executor& executor_;
  const TuneProblem& problem_;
  DenoiseReport report_;
  std::map<std::tuple<int, int, int, int, int>, Inner> inner_;
  std::map<std::tuple<int, int, int, int, int>, Vertices> prefilter_;
  std::deque<std::tuple<int, int, int, int, int>> order_;
  int evaluations_ = 0;
};

}  // namespace

void validate_grid(const TuneGrid& g) {
  const auto require = [](bool nonempty, const char* field) {
    if (!nonempty) throw InvalidParamsError(field, std::string("tune: the search list of ") + field + " is empty");
  };
  require(!g.region_mode.empty(), "region_mode");
  require(!g.alpha.empty(), "alpha");
  require(!g.sigma_theta.empty(), "sigma_theta");
  require(!g.n_aniso.empty(), "n_aniso");
  require(!g.sigma_gamma.empty(), "sigma_gamma");
  require(!g.n_normal.empty(), "n_normal");
  require(!g.n_vertex.empty(), "n_vertex");
  for (auto* list : {&g.n_aniso, &g.n_normal, &g.n_vertex})
    require(std::is_sorted(list->begin(), list->end()) && list->front() >= 0, "iteration lists (sorted, >= 0)");
}

Descent descend(const TuneProblem& problem, const DenoiseParams& start, const TuneOptions& options, Executor& executor) {
  validate_grid(options.grid);
  const TuneGrid& g = options.grid;
  Search search(problem, start, options, executor);
  Point at;
  const bool region_on = start.region_mode == RegionMode::On;
  at.region = 0;
  for (int i = 0; i < static_cast<int>(g.region_mode.size()); ++i)
    if ((g.region_mode[static_cast<std::size_t>(i)] == RegionMode::On) == region_on) at.region = i;
  at.alpha = nearest(g.alpha, start.alpha);
  at.theta = nearest(g.sigma_theta, start.sigma_theta);
  at.aniso = nearest(g.n_aniso, start.n_aniso);
  at.gamma = nearest(g.sigma_gamma, start.sigma_gamma);

  // Coordinate descent, cheapest coordinates first (n_aniso and sigma_gamma reuse the
  // pre-filter). Ties keep the current value, so the search is deterministic.
  using Member = int Point::*;
  const std::pair<Member, std::size_t> coordinates[] = {
      {&Point::aniso, g.n_aniso.size()}, {&Point::gamma, g.sigma_gamma.size()}, {&Point::alpha, g.alpha.size()},
      {&Point::theta, g.sigma_theta.size()}, {&Point::region, g.region_mode.size()}};
  search.aniso_horizon = g.n_aniso[static_cast<std::size_t>(at.aniso)];
  Inner current = search.evaluate(at);
  for (int round = 0; round < options.max_rounds; ++round) {
    bool improved = false;
    for (const auto& [member, size] : coordinates) {
      if (member == &Point::theta && g.n_aniso[static_cast<std::size_t>(at.aniso)] == 0) continue;  // unused
      const int here = at.*member;
      const int lo = round == 0 ? 0 : std::max(0, here - 1);
      const int hi = round == 0 ? static_cast<int>(size) - 1 : std::min(static_cast<int>(size) - 1, here + 1);
      search.aniso_horizon = g.n_aniso[static_cast<std::size_t>(member == &Point::aniso ? hi : at.aniso)];
      for (int v = lo; v <= hi; ++v) {
        if (v == here) continue;
        Point p = at;
        p.*member = v;
        const Inner& e = search.evaluate(p);
        if (e.msae < current.msae) {
          current = e;
          at = p;
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
  return {search.params_at(at, current), current.msae, search.evaluations()};
}

}  // namespace mdn
