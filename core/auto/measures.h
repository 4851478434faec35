// What the parameter choice measures on the noisy input (reported, one part of the
// descriptors of core/auto/descriptors.h, and the sampling irregularity decides the region
// mode).
#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/params.h"
#include "core/topology.h"

namespace mdn {

class Executor;

// What ParamMode::Auto measures on the noisy input (unit-box frame). Distances are in mean
// edge lengths l. r_i below is the distance of vertex i from the plane through the centroid
// of its 1-ring neighbours, normal to the area-weighted vertex normal: noise moves it by
// about the noise level, smooth curvature by O(l^2 kappa), sharp features by O(l).
struct InputMeasures {
  double noise = 0;               // median r_i / l: noise level (Gaussian sigma ~ 0.68 x this on a plane)
  double tail = 0;                // 90th percentile of r_i / median r_i: > 2.4 when features stand out of the noise
  double feature_share = 0;       // share of vertices with r_i > 4 x median r_i (features and impulses)
  // The same after 4 umbrella smoothing steps (lambda 1/2), which remove most of the noise but
  // keep curvature and creases: flat-and-crease (CAD) shapes get a long tail even at high
  // noise, smooth organic shapes do not.
  double smooth_residual = 0;     // median r_i / l after smoothing
  double smooth_tail = 0;         // 90th / 50th percentile of r_i after smoothing
  double cluster_area_ratio = 1;  // Sec. 4.2: K-means area ratio on the input's faces (sampling irregularity)
  double measure_ms = 0;          // time taken by measure_input
};

// r_i at `vertices` (all if empty), in the order given; NaN where a vertex has no neighbour or
// no normal. With over_ring_radius, r_i over the mean distance from the vertex to its 1-ring
// neighbours (scale-free per vertex; decision 46), NaN where that is 0.
std::vector<double> ring_plane_distances(const Vertices& P, const Triangles& F, const Topology& topo,
                                         const std::vector<std::int32_t>& vertices, Executor& ex,
                                         bool over_ring_radius = false);

// Measures the input. P in the unit-box frame; K-means uses params.kmeans_k and kmeans_seed
// on at most 4000 faces (a fixed-stride sample: the area ratio does not need them all). The
// residuals are read at `vertices` (all if empty).
InputMeasures measure_input(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                            Executor* executor = nullptr, const std::vector<std::int32_t>& vertices = {});

}  // namespace mdn
