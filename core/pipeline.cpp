#include "core/pipeline.h"

#include <chrono>

#include "core/errors.h"
#include "core/normal_filter.h"
#include "core/parallel.h"
#include "core/prefilter.h"
#include "core/reorder.h"
#include "core/topology.h"
#include "core/vertex_update.h"

namespace mdn {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
// Decision 48: above this many faces Sec. 4.2's test reads a fixed-stride sample first.
constexpr std::int64_t kRegionSampleFaces = 65536;
}  // namespace

Vertices prefilter_stage(const Vertices& input, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                         Executor& executor, ProgressObserver* progress, DenoiseReport& report,
                         const IterationHook& on_aniso_iteration) {
  StageTimings& times = report.timings;
  // Sec. 4.1, Eq. 1. One solver serves Eq. 1 and every Eq. 3 step (it keeps the edge
  // incidence for CG, the pattern and symbolic analysis for LDLT).
  auto t0 = Clock::now();
  checkpoint(progress, Stage::InitialPrefilter, 0);
  ShapingSolver solver(topo, params.solver, params.cg_tolerance, &executor);
  Vertices P = solver.solve(input, params.alpha, {});
  times.initial_ms = ms_since(t0);
  solver.release_buffers();  // not held through Sec. 4.2's K-means and Eq. 2 (peak memory)

  // Sec. 4.2: irregular-sampling detection and the region-based pre-filter (Eq. 2).
  t0 = Clock::now();
  const bool noisy = report.fold_ratio >= params.fold_ratio;
  if (params.region_mode != RegionMode::Off) checkpoint(progress, Stage::RegionPrefilter, 0);
  // Decision 48: a large surface whose sample reads under half the threshold is regular; the
  // whole clustering would only confirm it. Otherwise the whole clustering decides, as before.
  bool regular_by_sample = false;
  if (params.region_mode == RegionMode::Auto && F.rows() > kRegionSampleFaces) {
    report.cluster_area_ratio = sampled_area_ratio(P, F, params.kmeans_k, params.kmeans_seed, kRegionSampleFaces, &executor);
    regular_by_sample = report.cluster_area_ratio < 0.5 * params.irregular_area_ratio;
  }
  if (params.region_mode != RegionMode::Off && !regular_by_sample) {
    const FaceClusters clusters = cluster_faces(P, F, params.kmeans_k, params.kmeans_seed, 100, &executor);
    report.cluster_area_ratio = clusters.area_ratio;
    const bool irregular = clusters.area_ratio >= params.irregular_area_ratio;
    if (params.region_mode == RegionMode::On || (irregular && noisy)) {
      std::vector<std::int32_t> small;
      for (std::size_t f = 0; f < clusters.label.size(); ++f)
        if (clusters.label[f] == clusters.smallest) small.push_back(static_cast<std::int32_t>(f));
      P = region_prefilter(P, F, topo, small, params.beta, &report.region_vertices, &executor);
      report.region_prefilter_applied = true;
    }
  }
  times.region_ms = ms_since(t0);

  // Sec. 4.3, Eq. 3-4, iterated.
  t0 = Clock::now();
  P = anisotropic_prefilter(P, F, topo, params, &solver, progress, on_aniso_iteration);
  times.anisotropic_ms = ms_since(t0);
  return P;
}

Vertices run_method(const Vertices& input, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                    Executor& executor, ProgressObserver* progress, DenoiseReport& report, const Vertices* guidance) {
  StageTimings& times = report.timings;
  Vertices P = prefilter_stage(input, F, topo, params, executor, progress, report);

  // Sec. 5, Eq. 6-7.
  auto t0 = Clock::now();
  NormalFilterSettings nfs = normal_filter_settings(params);
  nfs.guidance = guidance;  // decision 53
  const Vertices N = l1_median_normal_filter(P, F, topo, nfs, &executor, progress);
  times.normal_ms = ms_since(t0);

  // Sec. 6, Eq. 8, starting from the pre-filtered positions.
  t0 = Clock::now();
  P = vertex_update(P, F, topo, N, params.n_vertex, &executor, progress);
  times.vertex_ms = ms_since(t0);
  return P;
}

NormalFilterSettings normal_filter_settings(const DenoiseParams& params) {
  NormalFilterSettings nfs;
  nfs.sigma_gamma_deg = params.sigma_gamma;
  nfs.iterations = params.n_normal;
  nfs.sigma_c_factor = params.sigma_c_factor;
  nfs.bilateral_switch = params.bilateral_switch;
  return nfs;
}

DenoiseResult run_pipeline(const TriMesh& input, const DenoiseParams& requested, const RunOptions& options,
                           const ParameterChooser& choose) {
  const auto t_start = Clock::now();
  requested.validate();
  validate_mesh(input);
  ProgressObserver* progress = options.progress;
  DenoiseResult result;
  DenoiseReport& report = result.report;
  StageTimings& times = report.timings;
  report.mode = requested.mode;
  report.params = requested;
  if (requested.mode == ParamMode::None) {  // convert only: no stage runs (core/README.md, decision 23)
    result.mesh = input;
    times.total_ms = ms_since(t_start);
    return result;
  }
  if (requested.mode != ParamMode::Manual && !choose)
    throw InvalidParamsError("mode", "run_pipeline: mode " + std::string(to_string(requested.mode)) +
                                         " needs a parameter chooser (use mdn::denoise, core/auto/denoise.h)");
  Executor executor(options.threads);

  // Sec. 3: work in the unit box (core/README.md, decision 1); undone at the end.
  auto t0 = Clock::now();
  const UnitBox box = UnitBox::of(input.V);
  const LocalityOrder order = LocalityOrder::of(input, options.order);  // decision 16, undone at the end
  const Triangles& F = order.faces();
  Vertices P = box.apply(order.to_order(input.V));
  const Topology topo = Topology::build(F, static_cast<std::int32_t>(P.rows()), &executor);
  report.fold_ratio = fold_ratio(P, F, topo, requested.fold_angle, &executor);  // on the noisy input (decision 5)
  // The guidance in the run's face order, checked before any work (decision 16's order; decision 53).
  Vertices ordered_guidance;
  if (options.guidance) {
    check_guidance(*options.guidance, F.rows());
    ordered_guidance.resize(F.rows(), 3);
    for (Eigen::Index k = 0; k < F.rows(); ++k)
      ordered_guidance.row(k) = options.guidance->row(order.face_of()[static_cast<std::size_t>(k)]);
  }
  times.setup_ms = ms_since(t0);

  // ParamMode::Auto / Search: the parameters per input (core/auto/choose.h).
  if (requested.mode != ParamMode::Manual) {
    t0 = Clock::now();
    report.params = choose(P, F, topo, box.scale, executor, progress, report);
    report.params.validate();
    times.measure_ms = ms_since(t0);
  }

  P = run_method(P, F, topo, report.params, executor, progress, report,
                 options.guidance ? &ordered_guidance : nullptr);

  result.mesh.V = order.to_input(box.undo(P));
  result.mesh.F = input.F;
  times.total_ms = ms_since(t_start);
  return result;
}

}  // namespace mdn
