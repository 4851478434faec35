#include "core/normal_filter.h"

#include <algorithm>
#include <vector>
#include <cmath>
#include <numbers>

#include "core/errors.h"
#include "core/fast_math.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace mdn {

namespace {

// Faces per chunk of a parallel pass, claimed by free threads (decision 28): a chunk's
// neighbour lists, weights and pair ranges (about 12 entries of 16 bytes per face) stay in L2.
constexpr std::int64_t kGrain = 4096;

// range[q] <- phi(x[q]) / ||n_i - n_j||, the symmetric factor of omega_ij (Eq. 7), with
// bilateral weights where ||n_i - n_j|| = sqrt(dist2[q]) < sw; phi(x) = exp(-x^2). On entry
// range[q] holds ||n_i - n_j||^2. Branch-free so that it vectorises; compiled for AVX2 too
// and picked at run time. Without FMA contraction (-ffp-contract=off) both versions do the
// same IEEE operations, so the weights are identical on every x86-64 machine.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void range_weights(const double* x, double* range, std::int64_t n, double sw, bool l1_median) {
  if (l1_median) {
    for (std::int64_t q = 0; q < n; ++q) {
      const double dist = std::sqrt(range[q]);
      const double denom = dist >= sw ? dist : 1.0;
      range[q] = detail::exp_nonpositive(-x[q] * x[q]) / denom;
    }
  } else {
    for (std::int64_t q = 0; q < n; ++q) range[q] = detail::exp_nonpositive(-x[q] * x[q]);
  }
}

}  // namespace

Vertices l1_median_normal_filter(const Vertices& V, const Triangles& F, const Topology& topo,
                                 const NormalFilterSettings& s, Executor* executor, ProgressObserver* progress) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const std::int64_t nf = F.rows();
  Vertices current = face_normals(V, F);
  if (s.iterations <= 0 || nf == 0) return current;

  // Areas and centroids are those of the pre-filtered mesh and stay fixed (core/README.md, decision 9).
  const Eigen::VectorXd area = face_areas(V, F);
  const Vertices centroid = face_centroids(V, F);

  // sigma_c = factor x mean distance between centroids of edge-adjacent faces (Eq. 6).
  double mean_dist = 0;
  std::int64_t pairs = topo.edge_faces.rows();
  for (Eigen::Index e = 0; e < topo.edge_faces.rows(); ++e)
    mean_dist += (centroid.row(topo.edge_faces(e, 0)) - centroid.row(topo.edge_faces(e, 1))).norm();
  if (pairs == 0) {  // no manifold edge at all: fall back to vertex-adjacent pairs
    for (std::int64_t f = 0; f < nf; ++f)
      for (std::int32_t s2 = topo.ff_offsets[static_cast<std::size_t>(f)]; s2 < topo.ff_offsets[static_cast<std::size_t>(f) + 1]; ++s2, ++pairs)
        mean_dist += (centroid.row(f) - centroid.row(topo.ff_faces[static_cast<std::size_t>(s2)])).norm();
  }
  mean_dist = pairs > 0 ? mean_dist / static_cast<double>(pairs) : 0;
  const double sigma_c = mean_dist > 0 ? s.sigma_c_factor * mean_dist : 1.0;

  // The spatial part of omega_ij, a_j phi(||c_i - c_j|| / sigma_c), is fixed: precompute
  // it once per neighbour entry, in the CSR order of N(i).
  const std::size_t entries = topo.ff_faces.size();
  std::vector<double> spatial(entries);
  const double inv_sigma_c2 = 1.0 / (sigma_c * sigma_c);
  ex.parallel_for(nf, kGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i)
      for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(i)]; k < topo.ff_offsets[static_cast<std::size_t>(i) + 1]; ++k) {
        const std::int32_t j = topo.ff_faces[static_cast<std::size_t>(k)];
        const double d2 = (centroid.row(i) - centroid.row(j)).squaredNorm();
        spatial[static_cast<std::size_t>(k)] = area(j) * detail::exp_nonpositive(-d2 * inv_sigma_c2);
      }
  });

  // The range part, phi((1 - cos gamma_ij) / (1 - cos sigma_gamma)) / ||n_i - n_j||, is
  // evaluated per neighbour entry, in the pass that uses it (decision 30): a face's entries are
  // gathered into a small block, weighted there (branch-free, vectorised) and summed while the
  // block is in L1. It is symmetric, and its two evaluations (i, j) and (j, i) are the same IEEE
  // operations on the same operands (products commute, the sums keep their order), so the
  // weights are those of decision 17's once-per-pair evaluation bit for bit; the pass no longer
  // writes a range per pair nor reads one back through a pair index (about 250 of the 400 bytes
  // a face cost per iteration).
  // Eq. 7 typo: both denominators mean 1 - cos(sigma_gamma) (core/README.md, decision 8).
  const double inv_range = 1.0 / (1.0 - std::cos(s.sigma_gamma_deg * std::numbers::pi / 180.0));
  Vertices next(nf, 3);
  if (s.on_iteration) s.on_iteration(0, current);
  const std::int32_t* offsets = topo.ff_offsets.data();
  const std::int32_t* neighbours = topo.ff_faces.data();
  for (int it = 0; it < s.iterations; ++it) {
    checkpoint(progress, Stage::NormalFilter, static_cast<double>(it) / s.iterations);
    // Eq. 7: one Jacobi step of the weighted L1-median, all faces from the previous iterate.
    ex.parallel_for(nf, kGrain, [&](std::int64_t begin, std::int64_t end) {
      const double* n = current.data();  // row-major #F x 3
      constexpr std::int32_t kBlock = 512;  // entries per block: x and range stay in L1
      double x[kBlock], range[kBlock];
      std::vector<double> x_big, range_big;  // a face with more than kBlock neighbours
      for (std::int64_t i = begin; i < end;) {
        std::int64_t stop = i + 1;  // at least one face, however many neighbours it has
        while (stop < end && offsets[stop + 1] - offsets[i] <= kBlock) ++stop;
        const std::int32_t k0 = offsets[i], count = offsets[stop] - k0;
        double* xb = x;
        double* rb = range;
        if (count > kBlock) {
          x_big.resize(static_cast<std::size_t>(count));
          range_big.resize(static_cast<std::size_t>(count));
          xb = x_big.data();
          rb = range_big.data();
        }
        for (std::int64_t f = i; f < stop; ++f) {
          const double* ni = n + 3 * f;
          for (std::int32_t k = offsets[f]; k < offsets[f + 1]; ++k) {
            const double* nj = n + 3 * neighbours[k];
            const double dx = ni[0] - nj[0], dy = ni[1] - nj[1], dz = ni[2] - nj[2];
            xb[k - k0] = (1.0 - (ni[0] * nj[0] + ni[1] * nj[1] + ni[2] * nj[2])) * inv_range;
            rb[k - k0] = dx * dx + dy * dy + dz * dz;
          }
        }
        range_weights(xb, rb, count, s.bilateral_switch, s.l1_median);
        for (; i < stop; ++i) {
          if (current.row(i).squaredNorm() == 0) {  // degenerate face: nothing to filter
            next.row(i).setZero();
            continue;
          }
          double sx = 0, sy = 0, sz = 0;
          for (std::int32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
            const double w = spatial[static_cast<std::size_t>(k)] * rb[k - k0];
            const double* nj = n + 3 * neighbours[k];
            sx += w * nj[0];
            sy += w * nj[1];
            sz += w * nj[2];
          }
          const Eigen::RowVector3d sum(sx, sy, sz);
          const double len = sum.norm();
          if (len > 0)
            next.row(i) = sum / len;
          else
            next.row(i) = current.row(i);  // no usable neighbour (isolated or all degenerate)
        }
      }
    });
    current.swap(next);
    if (s.on_iteration) s.on_iteration(it + 1, current);
  }
  if (progress) progress->on_progress(Stage::NormalFilter, 1.0);
  return current;
}

}  // namespace mdn
