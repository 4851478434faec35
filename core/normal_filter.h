// L1-median normal filter, Sec. 5 (Eq. 6-7) of Lu, Chen, Schaefer.
#pragma once

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

class Executor;
class ProgressObserver;

struct NormalFilterSettings {
  double sigma_gamma_deg = 30;     // angle scale, Eq. 6
  int iterations = 20;             // Jacobi iterations of Eq. 7
  double sigma_c_factor = 1.5;     // sigma_c = factor x mean centroid distance of edge-adjacent faces
  double bilateral_switch = 1e-3;  // below this ||n_i - n_j|| the weight drops its 1/||n_i - n_j||
  bool l1_median = true;           // false: always bilateral weights (for comparison only)
  IterationHook on_iteration;      // optional; sees the normals after every iteration
  // Optional guidance normals (issue 48; decision 53): #F by 3, one per face in the mesh's face
  // order, unit or zero rows, borrowed for the call. When set, Eq. 7's range factor
  // phi((1 - cos gamma_ij) / (1 - cos sigma_gamma)) reads the angle gamma_ij between the
  // guidance normals of i and j, once per run (the guidance is fixed), while the L1-median's
  // 1/||n_i - n_j|| stays on the current iterate. Null (the default): the paper's filter, the
  // range factor on the current normals, unchanged to the bit.
  const Vertices* guidance = nullptr;
};

// Filters the face normals of the mesh (V, F). Areas and centroids are those of (V, F)
// and stay fixed; each iteration updates all faces from the previous iterate (Jacobi) and
// renormalises. Returns #F by 3 unit normals (zero rows stay zero for degenerate faces
// without usable neighbours). Throws InvalidParamsError (field "guidance") when the guidance is
// not #F by 3 or holds a non-finite value.
Vertices l1_median_normal_filter(const Vertices& V, const Triangles& F, const Topology& topo,
                                 const NormalFilterSettings& settings, Executor* executor = nullptr,
                                 ProgressObserver* progress = nullptr);

// Throws InvalidParamsError (field "guidance") unless `guidance` is #F (= faces) by 3 and finite;
// the one check of the filter and of the callers that carry guidance to it (decision 53).
void check_guidance(const Vertices& guidance, std::int64_t faces);

namespace detail {
// How the iterations read N(i) (decision 51): the smallest form that holds every entry (Auto),
// or one form forced, for tests; a forced compact form that does not fit throws
// std::invalid_argument. Every form gives the same output.
enum class NeighbourForm { Auto, Compact16, Compact32, Plain };
Vertices l1_median_normal_filter(const Vertices& V, const Triangles& F, const Topology& topo,
                                 const NormalFilterSettings& settings, Executor* executor, ProgressObserver* progress,
                                 NeighbourForm form);
}  // namespace detail

}  // namespace mdn
