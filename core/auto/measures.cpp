#include "core/auto/measures.h"

#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>
#include <chrono>
#include <cmath>
#include <vector>

#include "core/auto/noise_estimate.h"
#include "core/parallel.h"
#include "core/prefilter.h"

namespace mdn {

std::vector<double> ring_plane_distances(const Vertices& P, const Triangles& F, const Topology& topo,
                                         const std::vector<std::int32_t>& vertices, Executor& ex, bool over_ring_radius) {
  const Vertices N = vertex_normals(P, F);
  const std::int64_t count = vertices.empty() ? P.rows() : static_cast<std::int64_t>(vertices.size());
  std::vector<double> r(static_cast<std::size_t>(count));
  ex.parallel_for(count, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t k = begin; k < end; ++k) {
      const std::int64_t i = vertices.empty() ? k : vertices[static_cast<std::size_t>(k)];
      const std::int32_t b = topo.vv_offsets[static_cast<std::size_t>(i)], e = topo.vv_offsets[static_cast<std::size_t>(i) + 1];
      const Eigen::RowVector3d n = N.row(i);
      if (b == e || n.squaredNorm() == 0) {
        r[static_cast<std::size_t>(k)] = std::nan("");
        continue;
      }
      Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
      double radius = 0;
      for (std::int32_t a = b; a < e; ++a) {
        c += P.row(topo.vv_vertices[static_cast<std::size_t>(a)]);
        if (over_ring_radius) radius += (P.row(topo.vv_vertices[static_cast<std::size_t>(a)]) - P.row(i)).norm();
      }
      const double d = std::abs(n.dot(P.row(i) - c / static_cast<double>(e - b)));
      if (!over_ring_radius)
        r[static_cast<std::size_t>(k)] = d;
      else
        r[static_cast<std::size_t>(k)] = radius > 0 ? d / (radius / static_cast<double>(e - b)) : std::nan("");
    }
  });
  return r;
}

namespace {

struct Residuals {
  double median = 0, p90 = 0, above4 = 0;  // above4: share of r_i > 4 x median
};

// r_i (see InputMeasures) of every vertex in `vertices` (all if empty) with neighbours and a
// normal, summarised.
Residuals residuals(const Vertices& P, const Triangles& F, const Topology& topo, const std::vector<std::int32_t>& vertices,
                    Executor& ex) {
  std::vector<double> r = ring_plane_distances(P, F, topo, vertices, ex);
  std::erase_if(r, [](double x) { return std::isnan(x); });
  Residuals out;
  if (r.empty()) return out;
  const auto quantile = [&](double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(r.size() - 1));
    std::nth_element(r.begin(), r.begin() + k, r.end());
    return r[static_cast<std::size_t>(k)];
  };
  out.median = quantile(0.5);
  out.p90 = quantile(0.9);
  out.above4 = static_cast<double>(std::count_if(r.begin(), r.end(), [&](double x) { return x > 4 * out.median; })) /
               static_cast<double>(r.size());
  return out;
}

}  // namespace

InputMeasures measure_input(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                            Executor* executor, const std::vector<std::int32_t>& vertices) {
  const auto t0 = std::chrono::steady_clock::now();
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  InputMeasures m;
  const double l = topo.mean_edge_length(P);
  if (l > 0) {
    const Residuals raw = residuals(P, F, topo, vertices, ex);
    m.noise = raw.median / l;
    m.tail = raw.median > 0 ? raw.p90 / raw.median : 1;
    m.feature_share = raw.median > 0 ? raw.above4 : 0;
    const Residuals smooth = residuals(umbrella_smooth(P, topo, 4, 0.5, &ex), F, topo, vertices, ex);
    m.smooth_residual = smooth.median / l;
    m.smooth_tail = smooth.median > 0 ? smooth.p90 / smooth.median : 1;
  }

  // Sec. 4.2 on a fixed-stride sample of the faces.
  m.cluster_area_ratio = sampled_area_ratio(P, F, params.kmeans_k, params.kmeans_seed, 4000, executor);

  m.measure_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return m;
}

}  // namespace mdn
