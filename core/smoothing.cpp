// Uniform ("umbrella") Laplacian smoothing, the baseline the benchmark prints as a floor.
#include "core/smoothing.h"

#include <cmath>
#include <string>

#include "core/errors.h"

namespace mdn {

Vertices laplacian_smoothing(const Vertices& V, const Topology& topo, int iterations, double lambda) {
  if (V.rows() != topo.num_vertices)
    throw InvalidMeshError("laplacian_smoothing: " + std::to_string(V.rows()) + " positions for a topology of " +
                           std::to_string(topo.num_vertices) + " vertices");
  if (!V.allFinite()) throw InvalidMeshError("laplacian_smoothing: a vertex has a non-finite coordinate");
  if (iterations < 0)
    throw InvalidParamsError("iterations", "iterations must be >= 0, got " + std::to_string(iterations));
  // lambda in (0, 1]: beyond 1 the step overshoots the neighbour mean and the explicit
  // scheme can oscillate.
  if (!std::isfinite(lambda) || lambda <= 0 || lambda > 1)
    throw InvalidParamsError("lambda", "lambda must lie in (0, 1], got " + std::to_string(lambda));

  Vertices current = V;
  Vertices next = V;
  for (int it = 0; it < iterations; ++it) {
    // Jacobi step: every vertex moves towards the mean of its neighbours' previous positions.
    for (std::int32_t v = 0; v < topo.num_vertices; ++v) {
      const std::int32_t begin = topo.vv_offsets[v];
      const std::int32_t end = topo.vv_offsets[v + 1];
      if (begin == end) {  // isolated vertex: no neighbours, stays
        next.row(v) = current.row(v);
        continue;
      }
      Vec3 mean = Vec3::Zero();
      for (std::int32_t k = begin; k < end; ++k) mean += current.row(topo.vv_vertices[k]).transpose();
      mean /= static_cast<double>(end - begin);
      next.row(v) = current.row(v) + lambda * (mean.transpose() - current.row(v));
    }
    std::swap(current, next);
  }
  return current;
}

}  // namespace mdn
