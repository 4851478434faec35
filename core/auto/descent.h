// The coordinate descent over the parameter grid: the search shared by the ground-truth
// tuning (core/auto/tune.h, `meshdenoise --tune`) and ParamMode::Search's refinement by the
// recorrupted score (core/auto/recorrupted.h). It runs the method's stages, never
// mdn::denoise, so the scorer that Auto's choice reaches can include it without an include
// cycle (decision 74).
#pragma once

#include <functional>
#include <vector>

#include "core/mesh.h"
#include "core/params.h"
#include "core/progress.h"
#include "core/topology.h"

namespace mdn {

class Executor;

// The searched values; the lists go beyond the paper's ranges because many optima sit at
// their edges. Iteration counts cost nothing extra to search: one run of the longest count
// observes every shorter one (IterationHook).
struct TuneGrid {
  std::vector<RegionMode> region_mode{RegionMode::Off, RegionMode::On};
  std::vector<double> alpha{0.01, 0.03, 0.06, 0.1, 0.2, 0.4, 0.8};
  std::vector<double> sigma_theta{15, 25, 40, 70};
  std::vector<int> n_aniso{0, 1, 2, 4, 8, 16};
  std::vector<double> sigma_gamma{15, 20, 25, 30, 40, 60, 90};
  std::vector<int> n_normal{2, 3, 5, 10, 20, 30, 50, 70, 100};
  std::vector<int> n_vertex{2, 3, 5, 10, 20, 30, 50, 80};
};

struct TuneOptions {
  TuneGrid grid;
  int max_rounds = 4;  // of coordinate descent over (n_aniso, sigma_gamma, alpha, sigma_theta, region)
  int threads = 1;     // results do not depend on it
  ProgressObserver* progress = nullptr;  // cancellation is honoured between evaluations
};

// What the descent scores: one or more inputs (unit-box positions with faces F) and a score of
// a denoised output of input t (lower is better; summed over the inputs). The ground-truth
// search scores MSAE; ParamMode::Search the recorrupted error (core/auto/recorrupted.h).
struct TuneProblem {
  const Triangles& F;
  const Topology& topo;
  std::vector<Vertices> inputs;
  std::function<double(int input, const Vertices& output)> score;
  double fold_ratio = 0;  // of the noisy input (RegionMode::Auto reads it)
};

struct Descent {
  DenoiseParams best;  // mode Manual, region_mode On or Off
  double score = 0;
  int evaluations = 0;
};

// The coordinate descent over options.grid from `start` (its region_mode On or Off); see
// tune_parameters. Throws InvalidParamsError for an empty or unsorted grid list.
Descent descend(const TuneProblem& problem, const DenoiseParams& start, const TuneOptions& options, Executor& executor);

// Throws InvalidParamsError for an empty grid list or an iteration list that is not sorted and
// non-negative.
void validate_grid(const TuneGrid& g);

}  // namespace mdn
