// The whole method: pre-filter (Sec. 4), L1-median normal filter (Sec. 5), vertex update
// (Sec. 6). Re-entrant: concurrent calls on different meshes are safe.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/normal_filter.h"
#include "core/params.h"
#include "core/progress.h"
#include "core/reorder.h"
#include "core/topology.h"

namespace mdn {

class Executor;
struct ParameterChoice;  // core/auto/choice.h: the pipeline never needs its contents

struct RunOptions {
  int threads = 1;                        // worker threads for this call; output does not depend on it
  ProgressObserver* progress = nullptr;   // optional; progress and cancellation
  OrderKind order = OrderKind::Auto;      // memory order of the run (decision 16); output order is the input's
  // Optional guidance normals for the normal filter (issue 48; decision 53): #F by 3, one per face
  // in the input's face order, borrowed for the call. Null (the default): the paper's method.
  const Vertices* guidance = nullptr;
};

// Wall-clock milliseconds per step.
struct StageTimings {
  double setup_ms = 0;        // validation, normalisation, topology
  double measure_ms = 0;      // ParamMode::Auto / Search: measuring the input and choosing the parameters
  double initial_ms = 0;      // Eq. 1
  double region_ms = 0;       // Sec. 4.2 detection, K-means and Eq. 2
  double anisotropic_ms = 0;  // Eq. 3-4, all iterations
  double normal_ms = 0;       // Eq. 6-7, all iterations
  double vertex_ms = 0;       // Eq. 8, all iterations
  double total_ms = 0;
  double prefilter_ms() const { return initial_ms + region_ms + anisotropic_ms; }
};

// What the pipeline measured and decided (Sec. 4.2).
struct DenoiseReport {
  double fold_ratio = 0;          // fraction of interior edges whose face normals differ by > fold_angle (noisy input)
  double cluster_area_ratio = 1;  // mean face area of the largest-area cluster / smallest (after Eq. 1; on a sample
                                  // where that settles it, decision 48); 1 if not measured
  bool region_prefilter_applied = false;
  std::int64_t region_vertices = 0;  // vertices smoothed by Eq. 2
  ParamMode mode = ParamMode::Manual;     // as requested
  DenoiseParams params;                   // what ran (Auto: the model's choice, pinned fields kept)
  std::shared_ptr<const ParameterChoice> choice;  // ParamMode::Auto / Search only (core/auto/choice.h)
  std::vector<std::string> notes;  // what the caller should know (e.g. faces whose winding was set aside, decision 34)
  StageTimings timings;
};

struct DenoiseResult {
  TriMesh mesh;  // same connectivity as the input, new positions (input frame)
  DenoiseReport report;
};

// Chooses the parameters of ParamMode::Auto / Search (core/auto/choose.h) on the input in the
// unit-box frame (box_scale: UnitBox::scale); returns them (mode Manual) and sets report.choice.
using ParameterChooser = std::function<DenoiseParams(const Vertices& P, const Triangles& F, const Topology& topo,
                                                     double box_scale, Executor& executor, ProgressObserver* progress,
                                                     DenoiseReport& report)>;

// The whole method on one input. ParamMode::Auto / Search need `choose` (the entry point for
// every mode, with the trained choice, is mdn::denoise in core/auto/denoise.h).
// Throws InvalidMeshError, InvalidParamsError, SolverError or CancelledError.
DenoiseResult run_pipeline(const TriMesh& input, const DenoiseParams& params, const RunOptions& options = {},
                           const ParameterChooser& choose = {});

// --- The stages of denoise(), for callers that run them one by one (core/auto/tune.h). ---
// Positions are in the unit-box frame; topo is Topology::build of F.

// Sec. 4: Eq. 1, the region pre-filter by params.region_mode (Sec. 4.2; Auto reads
// report.fold_ratio, which must be set), then Eq. 3-4. Fills report's region fields and
// pre-filter timings. on_aniso_iteration sees every Eq. 3 iterate.
Vertices prefilter_stage(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                         Executor& executor, ProgressObserver* progress, DenoiseReport& report,
                         const IterationHook& on_aniso_iteration = {});

// Sec. 4-6 with `params` as given (mode Manual): prefilter_stage, the L1-median normal filter
// and the vertex update. Returns the denoised positions; fills report's region fields and
// timings (not total_ms). guidance: the normal filter's optional guidance normals (#F by 3 in
// F's order; decision 53).
Vertices run_method(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                    Executor& executor, ProgressObserver* progress, DenoiseReport& report,
                    const Vertices* guidance = nullptr);

// The settings of the normal filter (Sec. 5) that `params` asks for.
NormalFilterSettings normal_filter_settings(const DenoiseParams& params);

}  // namespace mdn
