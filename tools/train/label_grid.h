// The dense grid of parameter sets whose true MSAE labels every corpus case (issue 31, item 2).
// Iteration counts cost almost nothing to label: one run of the longest count observes every
// shorter one (IterationHook), so the grid is pre-filter points x sigma_gamma x n_normal x n_vertex.
// The shipped model's sets (core/auto/model_data.inc) are a subset, chosen by tools/train/train.py.
#pragma once

#include <string>
#include <vector>

#include "core/params.h"

namespace mdn::train {

struct PrefilterFamily {
  double alpha, sigma_theta;
  std::vector<int> n_aniso;  // the counts labelled (one run of the largest)
};

inline const std::vector<PrefilterFamily>& label_families() {
  static const std::vector<PrefilterFamily> f = {
      {0.03, 25, {0, 1, 4}}, {0.1, 30, {0, 2, 8}}, {0.3, 50, {0, 2, 16}}, {0.8, 70, {4, 16}}};
  return f;
}
inline const std::vector<double>& label_sigma_gamma() {
  static const std::vector<double> v = {20, 30, 45, 90};
  return v;
}
inline const std::vector<int>& label_n_normal() {
  static const std::vector<int> v = {2, 5, 10, 20, 40, 70, 100};
  return v;
}
inline const std::vector<int>& label_n_vertex() {
  static const std::vector<int> v = {3, 10, 30};
  return v;
}

// Every labelled set in column order: family, n_aniso, sigma_gamma, n_normal, n_vertex (the
// innermost last). region_mode is left Auto: the labeller fixes it per case as auto would.
inline std::vector<DenoiseParams> label_sets() {
  std::vector<DenoiseParams> out;
  for (const PrefilterFamily& fam : label_families())
    for (const int aniso : fam.n_aniso)
      for (const double gamma : label_sigma_gamma())
        for (const int nn : label_n_normal())
          for (const int nv : label_n_vertex()) {
            DenoiseParams p;
            p.mode = ParamMode::Manual;
            p.alpha = fam.alpha;
            p.sigma_theta = fam.sigma_theta;
            p.n_aniso = aniso;
            p.sigma_gamma = gamma;
            p.n_normal = nn;
            p.n_vertex = nv;
            out.push_back(p);
          }
  return out;
}

// "a0.1_t30_k2_g30_n20_v10": a set's column name.
inline std::string set_name(const DenoiseParams& p) {
  const auto num = [](double x) {
    std::string s = std::to_string(x);
    s.erase(s.find_last_not_of('0') + 1);
    if (s.back() == '.') s.pop_back();
    return s;
  };
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "a" + std::string&&.
  std::string out = "a";
  out += num(p.alpha);
  out += "_t" + num(p.sigma_theta);
  out += "_k" + std::to_string(p.n_aniso);
  out += "_g" + num(p.sigma_gamma);
  out += "_n" + std::to_string(p.n_normal);
  out += "_v" + std::to_string(p.n_vertex);
  return out;
}

}  // namespace mdn::train
