#include "core/vertex_update.h"

#include "core/errors.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace mdn {

Vertices vertex_update(const Vertices& V, const Triangles& F, const Topology& topo, const Vertices& N,
                       int iterations, Executor* executor, ProgressObserver* progress,
                       const IterationHook& on_iteration) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const std::int64_t nf = F.rows(), nv = V.rows();
  Vertices current = V, next(nv, 3), centroid(nf, 3);
  if (on_iteration) on_iteration(0, current);
  for (int it = 0; it < iterations; ++it) {
    checkpoint(progress, Stage::VertexUpdate, static_cast<double>(it) / iterations);
    ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t f = begin; f < end; ++f)
        centroid.row(f) = (current.row(F(f, 0)) + current.row(F(f, 1)) + current.row(F(f, 2))) / 3.0;
    });
    // Eq. 8: p_i += 1/|NF(i)| sum_j n_j (n_j . (c_j - p_i)).
    ex.parallel_for(nv, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t v = begin; v < end; ++v) {
        const std::int32_t b = topo.vf_offsets[static_cast<std::size_t>(v)], e = topo.vf_offsets[static_cast<std::size_t>(v) + 1];
        const Eigen::RowVector3d p = current.row(v);
        if (b == e) {
          next.row(v) = p;
          continue;
        }
        Eigen::RowVector3d delta = Eigen::RowVector3d::Zero();
        for (std::int32_t k = b; k < e; ++k) {
          const std::int32_t j = topo.vf_faces[static_cast<std::size_t>(k)];
          const Eigen::RowVector3d nj = N.row(j);
          delta += nj * nj.dot(centroid.row(j) - p);
        }
        next.row(v) = p + delta / static_cast<double>(e - b);
      }
    });
    current.swap(next);
    if (on_iteration) on_iteration(it + 1, current);
  }
  if (progress && iterations > 0) progress->on_progress(Stage::VertexUpdate, 1.0);
  return current;
}

}  // namespace mdn
