// ParamMode::Search: the model's pick refined by an error estimated without ground truth
// (core/auto/README.md; decisions 19-22).
//
// Recorrupted-to-Recorrupted (Pang et al., CVPR 2021): with noise n ~ N(0, sigma^2) on y, draw
// z with the same law and form y1 = y + a z, y2 = y - z / a. The noises of y1 and y2 are
// uncorrelated, so comparing a denoiser's output f(y1) with y2 estimates f's error against the
// unknown clean surface (at noise sigma sqrt(1 + a^2)) up to a constant shared by every f.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/auto/noise_estimate.h"
#include "core/auto/selection.h"
#include "core/params.h"
#include "core/topology.h"

namespace mdn {

class Executor;
class ProgressObserver;
struct SurfaceSample;

struct SelectionOptions {
  std::int64_t max_faces = 8000;   // faces of the scoring sample (decision 21)
  double a = 1.0;                  // recorruption strength (decision 20)
  int draws = 2;                   // recorrupted pairs averaged per score (decision 21)
  int refine = 3;                  // > 0: only this many candidates, the best after one draw, get the other draws
  double scale = 0.92;             // the recorruption's sigma over the estimated noise (decision 20)
  double rescore_below = 0.5;      // rescore at the noise the winner found when under this share of the estimate (0: never)
  double remove_at_most = 1.5;     // > 0: a candidate that removes more than this multiple of the noise is not picked (decision 24)
  double guard_below = 0.3;        // the guard applies where the noise reads below this many edge lengths (0: always)
  std::uint64_t seed = 1;          // of the recorruption draws
  double sigma = 0;                // > 0: the noise level to use (positions' units) instead of the estimate
  bool isotropic = true;           // recorrupt every coordinate (true) or along the normal only (false); decision 20
};

// The recorrupted score of parameter sets on a sample: owns the draws (y1, and y2's face
// normals) and runs the method on each y1. Deterministic for a seed, any thread count.
class RecorruptedScorer {
 public:
  // normals: smoothed_normals of the sample (core/auto/noise_estimate.h), the recorruption's direction.
  RecorruptedScorer(const SurfaceSample& sample, const Vertices& normals, double sigma, const SelectionOptions& options,
                    Executor& executor,
                    ProgressObserver* progress = nullptr);
  ~RecorruptedScorer();
  RecorruptedScorer(const RecorruptedScorer&) = delete;
  RecorruptedScorer& operator=(const RecorruptedScorer&) = delete;

  // Mean over draws [first, last) (last < 0: all) of the mean over scored faces of
  // 1 - n_f(f(y1)) . n_f(y2); `residual`, if given, receives
  // sqrt(max(0, mean over those draws and scored vertices of ((y1 - f(y1)) . n)^2 - (a sigma)^2)).
  double score(const DenoiseParams& params, double* residual = nullptr, int first = 0, int last = -1);
  // The draws' inputs and the normals they are compared with (for core/tune.cpp's search).
  int draws() const;
  const Vertices& input(int draw) const;
  double score_positions(int draw, const Vertices& output) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Estimates the noise on a sample of P (unit-box frame), scores every candidate on recorrupted
// copies of the sample and returns them with the pick: the best score among the eligible
// candidates (decision 24; ties keep the earlier candidate). A surface that reads clean
// (decision 20) keeps the first candidate, unscored. ParamMode::Search then descends from
// the pick (decision 22). Serves ParamMode::Search only (core/auto/choose.h).
Selection select_parameters(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& requested,
                            std::vector<ScoredCandidate> candidates, Executor& executor, ProgressObserver* progress = nullptr,
                            const SelectionOptions& options = {});

}  // namespace mdn
