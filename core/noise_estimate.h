// Noise level of a noisy surface from the surface alone, no ground truth (ParamMode::Auto
// scores its candidates on recorrupted copies and needs it; core/README.md, decision 19).
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
  double estimate_ms = 0;
};

// Leave-one-out local quadric fits: vertex i's height over the tangent plane of a smoothed
// normal is predicted from its 2-ring by a least-squares quadric; the prediction error e_i
// has variance sigma^2 (1 + |w_i|^2) under white noise (w_i: the fit's linear weights), while
// smooth curvature is fitted away. Features and impulses give large errors; see decision 19
// for how the per-vertex errors are combined. `vertices`: where to estimate (all if empty).
// `normals`: smoothed_normals(P, F, topo), passed in by callers that need them too.
NoiseEstimate estimate_noise(const Vertices& P, const Triangles& F, const Topology& topo, const Vertices& normals,
                             const std::vector<std::int32_t>& vertices = {}, Executor* executor = nullptr);

// Per-vertex normalised squared errors e_i^2 / (1 + |w_i|^2) (NaN where no fit was possible),
// in the order of `vertices` (or of all vertices). Exposed for the benchmark of the estimate.
std::vector<double> quadric_residuals(const Vertices& P, const Triangles& F, const Topology& topo, const Vertices& normals,
                                      const std::vector<std::int32_t>& vertices = {}, Executor* executor = nullptr);

// Unit vertex normals of P after 4 umbrella steps (lambda 1/2): the frame of the quadric fits
// and the recorruption's direction. The noisy normal tilts towards the very noise being
// measured and reads low at high noise.
Vertices smoothed_normals(const Vertices& P, const Triangles& F, const Topology& topo, Executor* executor = nullptr);

// Umbrella smoothing p_i += lambda (mean of neighbours - p_i), Jacobi, `steps` times.
Vertices umbrella_smooth(const Vertices& P, const Topology& topo, int steps, double lambda, Executor* executor = nullptr);

}  // namespace mdn
