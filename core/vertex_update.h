// Vertex update of Sun et al. 2007, Sec. 6 (Eq. 8) of Lu, Chen, Schaefer.
#pragma once

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

class Executor;
class ProgressObserver;

// Eq. 8: p_i <- p_i + 1/|NF(i)| sum_{j in NF(i)} n_j (n_j . (c_j - p_i)), centroids c_j
// recomputed every iteration, `iterations` times. N: #F by 3 target face normals.
// All vertices move, boundary ones included (see core/README.md).
Vertices vertex_update(const Vertices& V, const Triangles& F, const Topology& topo, const Vertices& N,
                       int iterations, Executor* executor = nullptr, ProgressObserver* progress = nullptr,
                       const IterationHook& on_iteration = {});

}  // namespace mdn
