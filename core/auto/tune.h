// Parameter search against a ground truth: for a clean mesh and a noisy copy with the same
// faces, finds the parameters (Table 1's six and the region mode) with the lowest MSAE.
// Serves `meshdenoise --tune GT NOISY` (users with a clean scan of a calibration object) and
// the tuning harness that fits the ParamMode::Auto rule (tests/bench/tune_bench.cpp).
#pragma once

#include "core/auto/descent.h"
#include "core/mesh.h"
#include "core/params.h"

namespace mdn {

struct TuneResult {
  DenoiseParams best;       // mode Manual, region_mode On or Off
  double best_msae = 0;     // MSAE of denoise(noisy, best) against the truth (radians^2)
  DenoiseParams start;      // where the search started: what the caller's parameters ran (Auto: the rule's choice)
  double start_msae = 0;    // MSAE of denoise(noisy, start)
  int evaluations = 0;      // (prefilter, sigma_gamma) settings evaluated, each over all iteration counts
  double seconds = 0;
};

// Coordinate descent from `start` (snapped to the grid); the first round scans every value
// of each coordinate, later rounds the neighbour each side of the current one, until a
// round improves nothing. Deterministic. Throws InvalidMeshError if the meshes are invalid or
// their faces differ, InvalidParamsError for an empty grid list or bad start parameters.
TuneResult tune_parameters(const TriMesh& truth, const TriMesh& noisy, const DenoiseParams& start,
                           const TuneOptions& options = {});

}  // namespace mdn
