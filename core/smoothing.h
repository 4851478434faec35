// Plain uniform Laplacian smoothing: the "floor" baseline row of the benchmark.
#pragma once

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

// `iterations` explicit steps p_i <- p_i + lambda (mean of one-ring neighbours - p_i).
Vertices laplacian_smoothing(const Vertices& V, const Topology& topo, int iterations, double lambda = 0.5);

}  // namespace mdn
