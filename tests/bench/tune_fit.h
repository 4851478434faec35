// tune_bench fit (tune_fit.cpp): fits the candidates of ParamMode::Auto on training cases.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/auto_params.h"

struct FitCase {
  std::string name;          // mesh/config
  mdn::InputMeasures measures;
  mdn::DenoiseParams best;   // found by the search
  double best_msae = 0;
};

// MSAE of training case i denoised with the given parameters.
using FitScore = std::function<double(std::size_t i, const mdn::DenoiseParams& params)>;

// Prints `prototypes` candidates (the paper's row, `start`, then a greedy cover) as the C++
// data core/auto_rule.inc holds; returns a process exit code.
// matrix_path (optional): the cost matrix's cache, by case name and candidate. Entries found
// there are read; the others are computed (the expensive part) and the whole matrix written back.
int fit(const std::vector<FitCase>& cases, const FitScore& score, int jobs, const std::string& matrix_path = {},
        int prototypes = 10, const std::vector<mdn::DenoiseParams>& start = {});
