// What the parameter choice read and decided (the report's `choice`): one shape for
// ParamMode::Auto (the trained model) and ParamMode::Search (the model's pick refined by the
// recorrupted score).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/auto/measures.h"
#include "core/auto/noise_estimate.h"
#include "core/auto/selection.h"
#include "core/params.h"

namespace mdn {

struct PredictedSet {
  std::string name;      // "identity", "a0.1_t30_k2_g30_n20_v10", ...
  DenoiseParams params;  // mode Manual, the caller's pinned fields kept
  double predicted = 0;  // predicted MSAE(set) / MSAE(best labelled set) (1: as good as the best)
};

struct ParameterChoice {
  std::string method;         // "model", "fallback" (outside the model's range; notes say why), "search"
  std::string model_version;  // core/auto/model_data.inc
  std::vector<std::pair<std::string, double>> descriptors;  // what the model read (core/auto/descriptors.h)
  InputMeasures measures;
  NoiseEstimate noise;            // in the input's units
  std::vector<PredictedSet> sets; // every shipped set (empty for the fallback)
  std::string chosen;             // name of the set that ran ("paper" for the fallback, "search" if refined)
  double predicted = 0;           // the chosen set's predicted error ratio (0 when not predicted)
  std::vector<std::string> notes;
  std::optional<Selection> search;  // ParamMode::Search: the recorrupted scores and the descent
};

}  // namespace mdn
