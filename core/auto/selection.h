// What ParamMode::Search scored and chose (core/auto/recorrupted.h computes it): the types the
// report's choice (core/auto/choice.h) carries, in a header of their own so that the choice
// does not include the scorer, which includes the search (decision 74's include cycle).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/auto/noise_estimate.h"
#include "core/params.h"

namespace mdn {

struct ScoredCandidate {
  std::string name;       // the model's pick, "paper", "search"
  DenoiseParams params;   // mode Manual; what was scored
  double score = 0;       // recorrupted normal error, mean over `draws` draws (lower is better)
  int draws = 0;          // draws the score averages: the pick is among those with the most
  double residual = 0;    // RMS of (y1 - f(y1)) along the normal, less the recorruption's share: the noise f removed (units of `noise.sigma`)
  bool eligible = true;   // false: it removed more than remove_at_most times the noise, so it is not picked (decision 24)
};

struct Selection {
  NoiseEstimate noise;                  // what the recorruption used
  std::int64_t sample_faces = 0;        // faces the candidates ran on
  std::int64_t scored_faces = 0;        // faces the score read
  std::vector<ScoredCandidate> candidates;
  int chosen = 0;                       // index into candidates
  int evaluations = 0;                  // parameter sets scored (Search: with the descent's); 0: taken as clean
};

}  // namespace mdn
