// tune_bench fit: fits the candidates of ParamMode::Auto (core/auto_select.cpp) on the
// training cases of a `tune_bench search` table and prints them as core/auto_rule.inc.
//
// Auto scores every candidate on the input and runs the best, so the set should cover the
// regimes (a perfect choice among them should be close to the best found), not predict one:
//  1. Candidates: the best parameters the search found for each training case, plus the
//     paper's Fandisk row. region_mode is not part of a candidate: it is on iff the input is
//     irregularly sampled (cluster area ratio).
//  2. Cost matrix: c(i, j) = ln(MSAE(case i with candidate j) / best MSAE of case i).
//  3. Prototypes: the paper's row, then greedily the candidates that most reduce
//     sum_i min_{p in S} c(i, p) (the cover: a perfect choice's summed log excess).
// Each added prototype costs one more scored run per input; stderr shows the cover's median
// and worst ratio after each, leave-one-mesh-out (a mesh's own optimum never covers it).
// The cost matrix is most of the time (minutes); `--matrix FILE` caches it (see tune_fit.h).
#include "tune_fit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <thread>

#include "bench_stats.h"

namespace {

using mdn::bench::median;
using Matrix = std::vector<std::vector<double>>;

std::string mesh_of(const std::string& name) { return name.substr(0, name.find('/')); }

bool same_params(const mdn::DenoiseParams& a, const mdn::DenoiseParams& b) {
  return a.alpha == b.alpha && a.sigma_theta == b.sigma_theta && a.n_aniso == b.n_aniso &&
         a.sigma_gamma == b.sigma_gamma && a.n_normal == b.n_normal && a.n_vertex == b.n_vertex;
}

// The cache file: the candidates (one per line: alpha sigma_theta n_aniso sigma_gamma n_normal
// n_vertex), then one line per case: its name and its costs, in candidate order.
void write_matrix(const std::string& path, const std::vector<FitCase>& cases,
                  const std::vector<mdn::DenoiseParams>& cand, const Matrix& cost) {
  std::ofstream out(path);
  out << "# tune_bench fit cost matrix: ln(MSAE(case, candidate) / best MSAE(case))\n";
  out << "candidates " << cand.size() << "\n";
  char line[256];
  for (const auto& c : cand) {
    std::snprintf(line, sizeof line, "%.17g %.17g %d %.17g %d %d\n", c.alpha, c.sigma_theta, c.n_aniso, c.sigma_gamma,
                  c.n_normal, c.n_vertex);
    out << line;
  }
  out << "cases " << cases.size() << "\n";
  for (std::size_t i = 0; i < cases.size(); ++i) {
    out << cases[i].name;
    for (const double c : cost[i]) {
      std::snprintf(line, sizeof line, " %.9g", c);
      out << line;
    }
    out << "\n";
  }
  if (!out) throw std::runtime_error("cannot write " + path);
}

std::string candidate_key(const mdn::DenoiseParams& c) {
  char line[256];
  std::snprintf(line, sizeof line, "%.17g %.17g %d %.17g %d %d", c.alpha, c.sigma_theta, c.n_aniso, c.sigma_gamma, c.n_normal,
                c.n_vertex);
  return line;
}

// Whatever the cache holds, by case name and candidate (empty when the file is missing): a
// cache written for other cases or candidates still provides the entries they share.
std::map<std::pair<std::string, std::string>, double> read_matrix(const std::string& path) {
  std::map<std::pair<std::string, std::string>, double> known;
  std::ifstream in(path);
  std::string line, word;
  std::size_t count = 0;
  if (!in || !std::getline(in, line) || !(in >> word >> count) || word != "candidates") return {};
  std::vector<std::string> keys(count);
  for (auto& key : keys) {
    mdn::DenoiseParams p;
    in >> p.alpha >> p.sigma_theta >> p.n_aniso >> p.sigma_gamma >> p.n_normal >> p.n_vertex;
    key = candidate_key(p);
  }
  if (!(in >> word >> count) || word != "cases") return {};
  for (std::size_t i = 0; i < count && in >> word; ++i)
    for (const auto& key : keys) {
      double c = 0;
      if (!(in >> c)) return known;
      known[{word, key}] = c;
    }
  return known;
}

}  // namespace

int fit(const std::vector<FitCase>& train, const FitScore& score, int jobs, const std::string& matrix_path, int prototypes,
        const std::vector<mdn::DenoiseParams>& start) {
  const std::size_t n = train.size();
  if (n < 8) {
    std::fprintf(stderr, "fit: %zu training cases, need at least 8\n", n);
    return 1;
  }
  // Candidates (deduplicated): the paper's row first, then `start`, then the search's optima.
  std::vector<mdn::DenoiseParams> cand{mdn::DenoiseParams{}};
  for (const auto& c : start)
    if (std::none_of(cand.begin(), cand.end(), [&](const auto& d) { return same_params(d, c); })) cand.push_back(c);
  const std::size_t kept = cand.size();
  for (const auto& c : train)
    if (std::none_of(cand.begin(), cand.end(), [&](const auto& d) { return same_params(d, c.best); }))
      cand.push_back(c.best);
  const std::size_t m = cand.size();
  std::fprintf(stderr, "fit: %zu cases x %zu candidates\n", n, m);

  // Cost matrix: the cached entries, the others computed in parallel over cases.
  const auto known = matrix_path.empty() ? decltype(read_matrix("")){} : read_matrix(matrix_path);
  Matrix cost(n, std::vector<double>(m));
  std::atomic<std::size_t> next{0}, computed{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < jobs; ++t)
    pool.emplace_back([&] {
      for (std::size_t i; (i = next++) < n;) {
        for (std::size_t j = 0; j < m; ++j) {
          if (const auto it = known.find({train[i].name, candidate_key(cand[j])}); it != known.end()) {
            cost[i][j] = it->second;
            continue;
          }
          mdn::DenoiseParams p = cand[j];
          p.region_mode = train[i].measures.cluster_area_ratio >= p.irregular_area_ratio ? mdn::RegionMode::On
                                                                                          : mdn::RegionMode::Off;
          cost[i][j] = std::log(std::max(score(i, p), 1e-300) / train[i].best_msae);
          ++computed;
        }
      }
    });
  for (auto& t : pool) t.join();
  std::fprintf(stderr, "fit: %zu of %zu costs computed, the others read from the cache\n", computed.load(), n * m);
  if (!matrix_path.empty() && computed > 0) {
    write_matrix(matrix_path, train, cand, cost);
    std::fprintf(stderr, "fit: cost matrix written to %s\n", matrix_path.c_str());
  }

  // Greedy cover after the paper's row (candidate 0). Leave-one-mesh-out: a case is covered
  // by the chosen prototypes that are not its own mesh's optima.
  const auto own = [&](std::size_t i, std::size_t j) {
    for (std::size_t k = 0; k < n; ++k)
      if (mesh_of(train[k].name) == mesh_of(train[i].name) && same_params(train[k].best, cand[j])) return true;
    return false;
  };
  std::vector<std::size_t> order;
  std::vector<double> cover(n, std::numeric_limits<double>::infinity()), held_out = cover;
  const auto add = [&](std::size_t j) {
    order.push_back(j);
    for (std::size_t i = 0; i < n; ++i) {
      cover[i] = std::min(cover[i], cost[i][j]);
      if (j == 0 || !own(i, j)) held_out[i] = std::min(held_out[i], cost[i][j]);  // the paper's row covers all
    }
  };
  for (std::size_t j = 0; j < kept; ++j) add(j);  // the paper's row and `start`
  const auto print_cover = [&] {
    std::vector<double> in, out;
    for (std::size_t i = 0; i < n; ++i) {
      in.push_back(std::exp(cover[i]));
      out.push_back(std::exp(held_out[i]));
    }
    std::fprintf(stderr, "fit: %2zu prototypes: perfect choice median %.3f worst %.2f; leave-one-mesh-out median %.3f worst %.2f\n",
                 order.size(), median(in), *std::max_element(in.begin(), in.end()), median(out),
                 *std::max_element(out.begin(), out.end()));
  };
  print_cover();
  while (order.size() < std::min<std::size_t>(m, std::max(kept, static_cast<std::size_t>(prototypes)))) {
    std::size_t pick = 0;
    double pick_total = std::numeric_limits<double>::infinity();
    for (std::size_t j = 1; j < m; ++j) {
      if (std::find(order.begin(), order.end(), j) != order.end()) continue;
      double total = 0;
      for (std::size_t i = 0; i < n; ++i) total += std::min(cover[i], cost[i][j]);
      if (total < pick_total) {
        pick_total = total;
        pick = j;
      }
    }
    add(pick);
    print_cover();
  }

  std::printf("// Generated by `tune_bench fit` (tests/bench/tune_fit.cpp) from %zu training cases and %zu\n", n, m);
  std::printf("// candidate parameter sets; do not edit by hand. See core/README.md, \"Automatic parameters\".\n");
  std::printf("constexpr int kRulePrototypes = %zu;\n", order.size());
  std::printf("// alpha, sigma_theta, n_aniso, sigma_gamma, n_normal, n_vertex; the paper's Table 1 row first\n");
  std::printf("constexpr double kPrototype[kRulePrototypes][6] = {\n");
  for (const std::size_t j : order) {
    const auto& c = cand[j];
    std::printf("    {%g, %g, %d, %g, %d, %d},\n", c.alpha, c.sigma_theta, c.n_aniso, c.sigma_gamma, c.n_normal, c.n_vertex);
  }
  std::printf("};\n");
  return 0;
}
