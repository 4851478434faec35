#include "core/pipeline.h"

#include <chrono>

#include "core/errors.h"
#include "core/normal_filter.h"
#include "core/parallel.h"
#include "core/prefilter.h"
#include "core/topology.h"
#include "core/vertex_update.h"

namespace mdn {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

DenoiseResult denoise(const TriMesh& input, const DenoiseParams& params, const RunOptions& options) {
  const auto t_start = Clock::now();
  params.validate();
  validate_mesh(input);
  ProgressObserver* progress = options.progress;
  DenoiseResult result;
  DenoiseReport& report = result.report;
  StageTimings& times = report.timings;
  Executor executor(options.threads);

  // Sec. 3: work in the unit box (NOTES reading 1); undone at the end.
  auto t0 = Clock::now();
  const UnitBox box = UnitBox::of(input.V);
  const Triangles& F = input.F;
  Vertices P = box.apply(input.V);
  const Topology topo = Topology::build(F, static_cast<std::int32_t>(P.rows()));
  report.fold_ratio = fold_ratio(P, F, topo, params.fold_angle);  // on the noisy input (reading 5)
  times.setup_ms = ms_since(t0);

  // Sec. 4.1, Eq. 1. One solver serves Eq. 1 and every Eq. 3 step (it keeps the edge
  // incidence for CG, the pattern and symbolic analysis for LDLT).
  t0 = Clock::now();
  checkpoint(progress, Stage::InitialPrefilter, 0);
  ShapingSolver solver(topo, params.solver, params.cg_tolerance, &executor);
  P = solver.solve(P, params.alpha, {});
  times.initial_ms = ms_since(t0);

  // Sec. 4.2: irregular-sampling detection and the region-based pre-filter (Eq. 2).
  t0 = Clock::now();
  if (params.region_mode != RegionMode::Off) {
    checkpoint(progress, Stage::RegionPrefilter, 0);
    const FaceClusters clusters = cluster_faces(P, F, params.kmeans_k, params.kmeans_seed, 100, &executor);
    report.cluster_area_ratio = clusters.area_ratio;
    const bool irregular = clusters.area_ratio >= params.irregular_area_ratio;
    const bool noisy = report.fold_ratio >= params.fold_ratio;
    if (params.region_mode == RegionMode::On || (irregular && noisy)) {
      std::vector<std::int32_t> small;
      for (std::size_t f = 0; f < clusters.label.size(); ++f)
        if (clusters.label[f] == clusters.smallest) small.push_back(static_cast<std::int32_t>(f));
      P = region_prefilter(P, F, topo, small, params.beta, &report.region_vertices);
      report.region_prefilter_applied = true;
    }
  }
  times.region_ms = ms_since(t0);

  // Sec. 4.3, Eq. 3-4, iterated.
  t0 = Clock::now();
  P = anisotropic_prefilter(P, F, topo, params, &solver, progress);
  times.anisotropic_ms = ms_since(t0);

  // Sec. 5, Eq. 6-7.
  t0 = Clock::now();
  NormalFilterSettings nfs;
  nfs.sigma_gamma_deg = params.sigma_gamma;
  nfs.iterations = params.n_normal;
  nfs.sigma_c_factor = params.sigma_c_factor;
  nfs.bilateral_switch = params.bilateral_switch;
  const Vertices N = l1_median_normal_filter(P, F, topo, nfs, &executor, progress);
  times.normal_ms = ms_since(t0);

  // Sec. 6, Eq. 8, starting from the pre-filtered positions.
  t0 = Clock::now();
  P = vertex_update(P, F, topo, N, params.n_vertex, &executor, progress);
  times.vertex_ms = ms_since(t0);

  result.mesh.V = box.undo(P);
  result.mesh.F = F;
  times.total_ms = ms_since(t_start);
  return result;
}

}  // namespace mdn
