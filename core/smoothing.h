// Plain uniform Laplacian smoothing: the "floor" baseline row of the benchmark.
#pragma once

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

// `iterations` explicit (Jacobi) steps p_i <- p_i + lambda (mean of one-ring neighbours - p_i)
// over Topology::vv; isolated vertices stay. iterations >= 0, lambda in (0, 1] (default 0.5),
// else InvalidParamsError; InvalidMeshError if V does not match the topology or is not finite.
Vertices laplacian_smoothing(const Vertices& V, const Topology& topo, int iterations, double lambda = 0.5);

}  // namespace mdn
