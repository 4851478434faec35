// Noise level of a noisy surface from the surface alone, no ground truth (ParamMode::Search
// scores its candidates on recorrupted copies and needs it; docs/design/decisions.md, decision 19).
#pragma once

#include <vector>

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

class Executor;

struct NoiseEstimate {
  double sigma = 0;          // RMS displacement along the surface normal, in the positions' units (decision 19)
  double sigma_edges = 0;    // sigma / edge_length: the noise in mean edge lengths
  double gaussian_sigma = 0; // the same read off the median residual (the Gaussian core, blind to impulses)
  double edge_length = 0;    // mean edge length of the clean surface, estimated (noise lengthens edges)
  double one_pass_edges = 0; // the statistic of one quadric pass, in edge lengths: ~0 on a clean CAD surface (decision 20)
  double estimate_ms = 0;
};

// Leave-one-out local fits (decision 19): vertex i's height over the tangent plane of a
// smoothed normal is predicted from its ring by least squares, and the prediction error,
// filtered again by the same operator, is normalised by its variance under white noise.
// Planes over the 1-ring (three passes) and quadrics over the 2-ring (two); the smaller
// reading is kept; above 0.3 edge lengths it is read again in frames smoothed 16 steps.
// Features and impulses give large errors; see decision 19 for how they are combined.
// `vertices`: where to estimate (all if empty). `normals`: smoothed_normals(P, F, topo),
// passed in by callers that need them too.
NoiseEstimate estimate_noise(const Vertices& P, const Triangles& F, const Topology& topo, const Vertices& normals,
                             const std::vector<std::int32_t>& vertices = {}, Executor* executor = nullptr);

// Decision 33: the cheap reading the parameter choice's descriptors take: one pass of each of
// the two fits in smoothed_normals frames at `vertices` (all if empty); no high-noise re-reading,
// no widened frames. Reads shape as noise on coarse curved surfaces.
NoiseEstimate estimate_noise_quick(const Vertices& P, const Triangles& F, const Topology& topo,
                                   const std::vector<std::int32_t>& vertices = {}, Executor* executor = nullptr);

// Per-vertex squared errors of one fit, (I - W)^passes h, over their variance under white
// noise (NaN where no fit was possible), in the order of `vertices` (or of all vertices).
// Exposed for the benchmark of the estimate and its tests.
struct LocalFit {
  int rings = 2;   // the neighbourhood: vertices within this many edges
  int degree = 2;  // of the height polynomial (1 plane, 2 quadric, 3 cubic), lowered where the ring is small
  int passes = 1;  // how many times the fit's residual operator is applied (shape error varies slowly and cancels)
};
// `first_pass`, if given and passes > 1, receives the one-pass values at the same vertices.
std::vector<double> local_fit_residuals(const Vertices& P, const Topology& topo, const Vertices& normals, LocalFit fit = {},
                                        const std::vector<std::int32_t>& vertices = {}, Executor* executor = nullptr,
                                        std::vector<double>* first_pass = nullptr);

// Unit vertex normals of P after 4 umbrella steps (lambda 1/2): the frame of the quadric fits
// and the recorruption's direction. The noisy normal tilts towards the very noise being
// measured and reads low at high noise.
Vertices smoothed_normals(const Vertices& P, const Triangles& F, const Topology& topo, Executor* executor = nullptr);

// Decision 19: where vertex i's 1-ring is narrow across (its second principal spread under
// `spread` and under half its first: long thin triangles), the normal of the PCA plane of a patch
// grown ring by ring until it is `spread` wide across (at most 12 rings, 200 vertices); elsewhere,
// or where that plane tilts more than ~45 degrees from `normals`, `normals` itself.
Vertices patch_normals(const Vertices& P, const Topology& topo, const Vertices& normals, double spread, Executor* executor = nullptr);

// Umbrella smoothing p_i += lambda (mean of neighbours - p_i), Jacobi, `steps` times.
Vertices umbrella_smooth(const Vertices& P, const Topology& topo, int steps, double lambda, Executor* executor = nullptr);

}  // namespace mdn
