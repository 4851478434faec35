#include "core/auto/tune.h"

#include <chrono>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/parallel.h"
#include "core/auto/denoise.h"
#include "core/pipeline.h"
#include "core/prefilter.h"
#include "core/topology.h"

namespace mdn {

TuneResult tune_parameters(const TriMesh& truth, const TriMesh& noisy, const DenoiseParams& start,
                           const TuneOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  validate_mesh(truth);
  validate_mesh(noisy);
  if (truth.V.rows() != noisy.V.rows() || truth.F != noisy.F)
    throw InvalidMeshError("tune: the ground truth and the noisy mesh must have the same vertices count and faces");
  start.validate();
  validate_grid(options.grid);

  TuneResult result;
  const RunOptions run{options.threads, nullptr};
  const DenoiseResult start_run = denoise(noisy, start, run);
  result.start_msae = msae(start_run.mesh, truth);
  DenoiseParams ran = start_run.report.params;  // Auto mode: what was chosen
  result.start = ran;
  ran.region_mode = start_run.report.region_prefilter_applied ? RegionMode::On : RegionMode::Off;

  // The descent scores every setting by MSAE against the truth.
  const Vertices P = UnitBox::of(noisy.V).apply(noisy.V);
  const Topology topo = Topology::build(noisy.F, static_cast<std::int32_t>(P.rows()));
  const Vertices truth_normals = face_normals(truth.V, truth.F);
  TuneProblem problem{noisy.F, topo, {P}, [&](int, const Vertices& V) { return msae_of_normals(face_normals(V, noisy.F), truth_normals); },
                      fold_ratio(P, noisy.F, topo, start.fold_angle)};
  Executor executor(options.threads);
  TuneOptions descent_options = options;
  const Descent d = descend(problem, ran, descent_options, executor);

  // The winner, run once more through denoise() exactly as a user would run it.
  const double best_msae = msae(denoise(noisy, d.best, run).mesh, truth);
  if (best_msae < result.start_msae) {
    result.best = d.best;
    result.best_msae = best_msae;
  } else {  // the start was off the grid and better: keep it
    result.best = result.start;
    result.best.mode = ParamMode::Manual;
    result.best_msae = result.start_msae;
  }
  result.evaluations = d.evaluations;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace mdn
