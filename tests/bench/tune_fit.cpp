// tune_bench fit: fits the ParamMode::Auto rule (core/auto_params.cpp) on the training cases
// of a `tune_bench search` table and prints it as core/auto_rule.inc.
//
// The rule picks one of a few prototype parameter sets by the nearest training cases:
//  1. Candidates: the best parameters the search found for each training case, plus the
//     paper's Fandisk row. region_mode is not part of a candidate: it is on iff the input is
//     irregularly sampled (cluster area ratio), as the rule decides it.
//  2. Cost matrix: c(i, j) = ln(MSAE(case i with candidate j) / best MSAE of case i).
//  3. Prototypes: the paper's row, and greedily the candidates that most reduce
//     sum_i min_{p in S} c(i, p).
//  4. For an input: its k nearest training cases in standardised feature space
//     (auto_features), and the prototype with the least summed cost over them.
//  k and the number of prototypes are chosen by leave-one-mesh-out cross-validation on the
//  training set (a case's own mesh never votes for it).
// The cost matrix is most of the time (minutes); `--matrix FILE` caches it (see tune_fit.h).
#include "tune_fit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "bench_stats.h"

namespace {

using mdn::kAutoFeatures;
constexpr int kFeatures = kAutoFeatures - 1;  // auto_features without the constant 1

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

// The cached matrix, or an empty one when the file is missing or holds other cases or candidates.
Matrix read_matrix(const std::string& path, const std::vector<FitCase>& cases,
                   const std::vector<mdn::DenoiseParams>& cand) {
  std::ifstream in(path);
  std::string line, word;
  std::size_t count = 0;
  if (!in || !std::getline(in, line) || !(in >> word >> count) || word != "candidates" || count != cand.size()) return {};
  for (const auto& c : cand) {
    mdn::DenoiseParams p;
    in >> p.alpha >> p.sigma_theta >> p.n_aniso >> p.sigma_gamma >> p.n_normal >> p.n_vertex;
    if (!in || !same_params(p, c)) return {};
  }
  if (!(in >> word >> count) || word != "cases" || count != cases.size()) return {};
  Matrix cost(cases.size(), std::vector<double>(cand.size()));
  for (std::size_t i = 0; i < cases.size(); ++i) {
    if (!(in >> word) || word != cases[i].name) return {};
    for (double& c : cost[i]) in >> c;
  }
  return in ? cost : Matrix{};
}

}  // namespace

int fit(const std::vector<FitCase>& train, const FitScore& score, int jobs, const std::string& matrix_path) {
  const std::size_t n = train.size();
  if (n < 8) {
    std::fprintf(stderr, "fit: %zu training cases, need at least 8\n", n);
    return 1;
  }
  // Candidates (deduplicated), the paper's row first.
  std::vector<mdn::DenoiseParams> cand{mdn::DenoiseParams{}};
  for (const auto& c : train)
    if (std::none_of(cand.begin(), cand.end(), [&](const auto& d) { return same_params(d, c.best); }))
      cand.push_back(c.best);
  const std::size_t m = cand.size();
  std::fprintf(stderr, "fit: %zu cases x %zu candidates\n", n, m);

  // Cost matrix: cached, or computed in parallel over cases.
  Matrix cost = matrix_path.empty() ? Matrix{} : read_matrix(matrix_path, train, cand);
  if (!cost.empty()) {
    std::fprintf(stderr, "fit: cost matrix read from %s\n", matrix_path.c_str());
  } else {
    cost.assign(n, std::vector<double>(m));
    std::atomic<std::size_t> next{0};
    std::vector<std::thread> pool;
    for (int t = 0; t < jobs; ++t)
      pool.emplace_back([&] {
        for (std::size_t i; (i = next++) < n;) {
          for (std::size_t j = 0; j < m; ++j) {
            mdn::DenoiseParams p = cand[j];
            p.region_mode = mdn::auto_features(train[i].measures)[kAutoFeatures - 1] > 0.5 ? mdn::RegionMode::On
                                                                                           : mdn::RegionMode::Off;
            cost[i][j] = std::log(std::max(score(i, p), 1e-300) / train[i].best_msae);
          }
        }
      });
    for (auto& t : pool) t.join();
    if (!matrix_path.empty()) {
      write_matrix(matrix_path, train, cand, cost);
      std::fprintf(stderr, "fit: cost matrix written to %s\n", matrix_path.c_str());
    }
  }

  // Standardised features.
  std::vector<std::array<double, kFeatures>> x(n);
  std::array<double, kFeatures> mean{}, scale{};
  for (std::size_t i = 0; i < n; ++i) {
    const mdn::AutoFeatures f = mdn::auto_features(train[i].measures);
    for (int k = 0; k < kFeatures; ++k) x[i][static_cast<std::size_t>(k)] = f[k + 1];
  }
  for (int k = 0; k < kFeatures; ++k) {
    double s = 0, s2 = 0;
    for (const auto& xi : x) s += xi[static_cast<std::size_t>(k)];
    mean[static_cast<std::size_t>(k)] = s / static_cast<double>(n);
    for (const auto& xi : x) s2 += std::pow(xi[static_cast<std::size_t>(k)] - mean[static_cast<std::size_t>(k)], 2);
    scale[static_cast<std::size_t>(k)] = std::max(std::sqrt(s2 / static_cast<double>(n)), 1e-9);
  }
  for (auto& xi : x)
    for (int k = 0; k < kFeatures; ++k)
      xi[static_cast<std::size_t>(k)] = (xi[static_cast<std::size_t>(k)] - mean[static_cast<std::size_t>(k)]) / scale[static_cast<std::size_t>(k)];

  // Greedy prototypes (order matters: the first ones matter most), then the paper's row
  // (candidate 0) put first: with it among the prototypes, a case whose neighbours do as well
  // with it keeps it (ties go to the earlier prototype). Leave-one-mesh-out this lowered the
  // median and the cases worse than the paper (1.467 -> 1.443, 26 -> 24 of 79). Seeding the
  // greedy cover with the paper's row instead did better leave-one-mesh-out (1.420, 20) but
  // worse on the validation set (median 1.97 against 1.49): it is not used.
  std::vector<std::size_t> order;
  std::vector<double> cover(n, std::numeric_limits<double>::infinity());
  for (std::size_t round = 0; round < std::min<std::size_t>(m - 1, 16); ++round) {
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
    order.push_back(pick);
    for (std::size_t i = 0; i < n; ++i) cover[i] = std::min(cover[i], cost[i][pick]);
  }
  order.insert(order.begin(), 0);

  // The k-NN choice among the first `count` prototypes, leaving out the query's own mesh.
  const auto choose = [&](const std::array<double, kFeatures>& q, std::size_t count, int k, const std::string& skip_mesh) {
    std::vector<std::pair<double, std::size_t>> d;
    for (std::size_t i = 0; i < n; ++i) {
      if (mesh_of(train[i].name) == skip_mesh) continue;
      double s = 0;
      for (int f = 0; f < kFeatures; ++f) s += std::pow(q[static_cast<std::size_t>(f)] - x[i][static_cast<std::size_t>(f)], 2);
      d.emplace_back(s, i);
    }
    std::sort(d.begin(), d.end());
    std::size_t best = 0;
    double best_sum = std::numeric_limits<double>::infinity();
    for (std::size_t p = 0; p < count; ++p) {
      double s = 0;
      for (int r = 0; r < k && r < static_cast<int>(d.size()); ++r) s += cost[d[static_cast<std::size_t>(r)].second][order[p]];
      if (s < best_sum) {
        best_sum = s;
        best = p;
      }
    }
    return best;
  };
  std::size_t best_count = 1;
  int best_k = 1;
  double best_score = std::numeric_limits<double>::infinity();
  for (std::size_t count = 3; count <= order.size(); ++count)
    for (const int k : {3, 5, 7, 9, 13}) {
      std::vector<double> ratios;
      for (std::size_t i = 0; i < n; ++i)
        ratios.push_back(std::exp(cost[i][order[choose(x[i], count, k, mesh_of(train[i].name))]]));
      const double worst = *std::max_element(ratios.begin(), ratios.end());
      const double s = median(ratios) + 0.05 * std::log(worst);  // median first, a little weight on the worst
      std::fprintf(stderr, "fit: %2zu prototypes, k %2d: leave-one-mesh-out median %.3f worst %.2f\n", count, k,
                   median(ratios), worst);
      if (s < best_score) {
        best_score = s;
        best_count = count;
        best_k = k;
      }
    }

  std::printf("// Generated by `tune_bench fit` (tests/bench/tune_fit.cpp) from %zu training cases and %zu\n", n, m);
  std::printf("// candidate parameter sets; do not edit by hand. See core/README.md, \"Automatic parameters\".\n");
  std::printf("constexpr int kRuleNeighbours = %d;\n", best_k);
  std::printf("constexpr int kRulePrototypes = %zu;\n", best_count);
  std::printf("constexpr int kRuleCases = %zu;\n", n);
  std::printf("// alpha, sigma_theta, n_aniso, sigma_gamma, n_normal, n_vertex\n");
  std::printf("constexpr double kPrototype[kRulePrototypes][6] = {\n");
  for (std::size_t p = 0; p < best_count; ++p) {
    const auto& c = cand[order[p]];
    std::printf("    {%g, %g, %d, %g, %d, %d},\n", c.alpha, c.sigma_theta, c.n_aniso, c.sigma_gamma, c.n_normal, c.n_vertex);
  }
  std::printf("};\n// Feature standardisation: (auto_features[1..] - mean) / scale.\n");
  std::printf("constexpr double kFeatureMean[%d] = {", kFeatures);
  for (int k = 0; k < kFeatures; ++k) std::printf("%s%.6g", k ? ", " : "", mean[static_cast<std::size_t>(k)]);
  std::printf("};\nconstexpr double kFeatureScale[%d] = {", kFeatures);
  for (int k = 0; k < kFeatures; ++k) std::printf("%s%.6g", k ? ", " : "", scale[static_cast<std::size_t>(k)]);
  std::printf("};\n// Per training case: standardised features, then ln(MSAE with prototype p / best MSAE).\n");
  std::printf("constexpr double kCaseFeatures[kRuleCases][%d] = {\n", kFeatures);
  for (std::size_t i = 0; i < n; ++i) {
    std::printf("    {");
    for (int k = 0; k < kFeatures; ++k) std::printf("%s%.4f", k ? ", " : "", x[i][static_cast<std::size_t>(k)]);
    std::printf("},  // %s\n", train[i].name.c_str());
  }
  std::printf("};\nconstexpr double kCaseCost[kRuleCases][kRulePrototypes] = {\n");
  for (std::size_t i = 0; i < n; ++i) {
    std::printf("    {");
    for (std::size_t p = 0; p < best_count; ++p) std::printf("%s%.4f", p ? ", " : "", cost[i][order[p]]);
    std::printf("},\n");
  }
  std::printf("};\n");
  return 0;
}
