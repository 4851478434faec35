#include "core/vertex_update.h"

#include "core/errors.h"
#include "core/parallel.h"
#include "core/progress.h"

#include <algorithm>
#include <vector>

namespace mdn {

namespace {

// True where face f, with positions P, faces away from its target normal n_f.
bool faces_away(const Vertices& P, const Triangles& F, const Vertices& N, std::int64_t f) {
  const Eigen::RowVector3d a = P.row(F(f, 0)), b = P.row(F(f, 1)), c = P.row(F(f, 2));
  return (b - a).cross(c - a).dot(N.row(f)) < 0;
}

// Decision 27: the step never turns a face over. A face that faced its target normal before
// the step and faces away after it has its vertices' steps halved, up to kRounds times, then
// withdrawn (a withdrawn vertex may turn a neighbour over, which is then limited in turn); faces already turned over keep Eq. 8's step (it turns them back).
void limit_flips(const Vertices& current, Vertices& next, const Triangles& F, const Vertices& N,
                 Executor& ex, std::vector<char>& flipped, std::vector<double>& step) {
  constexpr int kRounds = 3;
  const std::int64_t nf = F.rows();
  std::fill(step.begin(), step.end(), 1.0);
  // Ends: each round lowers some step, and a step takes at most kRounds + 1 values.
  for (int round = 0;; ++round) {
    ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t f = begin; f < end; ++f)
        flipped[static_cast<std::size_t>(f)] = faces_away(next, F, N, f) && !faces_away(current, F, N, f);
    });
    bool any = false;
    for (std::int64_t f = 0; f < nf; ++f)
      if (flipped[static_cast<std::size_t>(f)])
        for (int c = 0; c < 3; ++c) {
          const auto v = static_cast<std::size_t>(F(f, c));
          const double limited = round >= kRounds ? 0.0 : step[v] * 0.5;
          if (limited >= step[v]) continue;
          // next = current + step * delta throughout; rescale to the limited step.
          next.row(F(f, c)) = current.row(F(f, c)) + (limited / step[v]) * (next.row(F(f, c)) - current.row(F(f, c)));
          step[v] = limited;
          any = true;
        }
    if (!any) break;
  }
}

}  // namespace

Vertices vertex_update(const Vertices& V, const Triangles& F, const Topology& topo, const Vertices& N,
                       int iterations, Executor* executor, ProgressObserver* progress,
                       const IterationHook& on_iteration) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const std::int64_t nf = F.rows(), nv = V.rows();
  Vertices current = V, next(nv, 3), centroid(nf, 3);
  std::vector<char> flipped(static_cast<std::size_t>(nf));
  std::vector<double> step(static_cast<std::size_t>(nv));
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
    limit_flips(current, next, F, N, ex, flipped, step);
    current.swap(next);
    if (on_iteration) on_iteration(it + 1, current);
  }
  if (progress && iterations > 0) progress->on_progress(Stage::VertexUpdate, 1.0);
  return current;
}

}  // namespace mdn
