#include "core/normal_filter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.h"
#include "core/fast_math.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace mdn {

namespace {

// range[q] <- phi(x[q]) / ||n_i - n_j||, the symmetric factor of omega_ij (Eq. 7), with
// bilateral weights where ||n_i - n_j|| = sqrt(dist2[q]) < sw; phi(x) = exp(-x^2). On entry
// range[q] holds ||n_i - n_j||^2. Branch-free so that it vectorises; compiled for AVX2 too
// and picked at run time. Without FMA contraction (-ffp-contract=off) both versions do the
// same IEEE operations, so the weights are identical on every x86-64 machine.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx2", "default")))
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

// sigma_c = factor x mean distance between centroids of edge-adjacent faces (Eq. 6).
double sigma_c_of(const Vertices& centroid, const Topology& topo, std::int64_t nf, double sigma_c_factor) {
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
  return mean_dist > 0 ? sigma_c_factor * mean_dist : 1.0;
}

// The spatial part of omega_ij, a_j phi(||c_i - c_j|| / sigma_c), is fixed: precompute it
// once per neighbour entry, in the CSR order of N(i).
// Areas and centroids are those of the pre-filtered mesh and stay fixed (core/README.md, decision 9).
// They are read only to set sigma_c and these weights, and are released on return, before the
// iterations, where the run's memory peaks (decision 31).
std::vector<double> spatial_weights(const Vertices& V, const Triangles& F, const Topology& topo, double sigma_c_factor,
                                    Executor& ex) {
  const std::int64_t nf = F.rows();
  const Eigen::VectorXd area = face_areas(V, F);
  const Vertices centroid = face_centroids(V, F);
  const double sigma_c = sigma_c_of(centroid, topo, nf, sigma_c_factor);
  std::vector<double> spatial(topo.ff_faces.size());
  const double inv_sigma_c2 = 1.0 / (sigma_c * sigma_c);
  ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i)
      for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(i)]; k < topo.ff_offsets[static_cast<std::size_t>(i) + 1]; ++k) {
        const std::int32_t j = topo.ff_faces[static_cast<std::size_t>(k)];
        const double d2 = (centroid.row(i) - centroid.row(j)).squaredNorm();
        spatial[static_cast<std::size_t>(k)] = area(j) * detail::exp_nonpositive(-d2 * inv_sigma_c2);
      }
  });
  return spatial;
}

// The range part, phi((1 - cos gamma_ij) / (1 - cos sigma_gamma)) / ||n_i - n_j||, is
// symmetric in i and j: evaluate it once per unordered pair (half the exp and sqrt calls).
// N(i) is sorted, so the pairs (i, j > i) are the tail of i's list, from upper[i] on; pairs
// are numbered along those tails in face order (face i's from pair_start[i]), and
// pair_of[k] maps CSR entry k (face i -> neighbour j) to its pair. N(j) contains i because
// vertex adjacency is symmetric. No pair list is stored: the pair pass walks the tails.
struct PairIndex {
  std::vector<std::int32_t> upper, pair_start, pair_of;
};

PairIndex index_pairs(const Topology& topo, std::int64_t nf, Executor& ex) {
  PairIndex p;
  p.upper.resize(static_cast<std::size_t>(nf));
  p.pair_start.assign(static_cast<std::size_t>(nf) + 1, 0);
  std::vector<std::int32_t>& upper = p.upper;
  std::vector<std::int32_t>& pair_start = p.pair_start;
  for (std::int64_t i = 0; i < nf; ++i) {
    const auto b = topo.ff_faces.begin() + topo.ff_offsets[static_cast<std::size_t>(i)];
    const auto e = topo.ff_faces.begin() + topo.ff_offsets[static_cast<std::size_t>(i) + 1];
    const auto u = std::upper_bound(b, e, static_cast<std::int32_t>(i));
    upper[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(u - topo.ff_faces.begin());
    pair_start[static_cast<std::size_t>(i) + 1] = pair_start[static_cast<std::size_t>(i)] + static_cast<std::int32_t>(e - u);
  }
  p.pair_of.resize(topo.ff_faces.size());
  std::vector<std::int32_t>& pair_of = p.pair_of;
  ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      const auto iu = static_cast<std::size_t>(i);
      for (std::int32_t k = topo.ff_offsets[iu]; k < upper[iu]; ++k) {  // j < i: the pair is in j's tail
        const auto j = static_cast<std::size_t>(topo.ff_faces[static_cast<std::size_t>(k)]);
        const auto jt = topo.ff_faces.begin() + upper[j];
        const auto je = topo.ff_faces.begin() + topo.ff_offsets[j + 1];
        pair_of[static_cast<std::size_t>(k)] = pair_start[j] + static_cast<std::int32_t>(std::lower_bound(jt, je, static_cast<std::int32_t>(i)) - jt);
      }
      for (std::int32_t k = upper[iu]; k < topo.ff_offsets[iu + 1]; ++k) pair_of[static_cast<std::size_t>(k)] = pair_start[iu] + (k - upper[iu]);
    }
  });
  return p;
}

// The range factor of every pair (i, j > i) for faces [begin, end), normals n (row-major
// #F x 3). Blocks of about kBlock pairs: gather (1 - cos gamma_ij) / (1 - cos sigma_gamma)
// into a small buffer and ||n_i - n_j||^2 into range, then the weights while both are in L1
// (branch-free, vectorised).
void range_pass(const double* n, const Topology& topo, const PairIndex& pairs, double inv_range,
                const NormalFilterSettings& s, std::vector<double>& range, std::int64_t begin, std::int64_t end) {
  const std::vector<std::int32_t>& upper = pairs.upper;
  const std::vector<std::int32_t>& pair_start = pairs.pair_start;
  constexpr std::int32_t kBlock = 512;
  std::vector<double> x(kBlock);
  for (std::int64_t i = begin; i < end;) {
    std::int64_t stop = i + 1;  // at least one face, however many pairs it has
    while (stop < end && pair_start[static_cast<std::size_t>(stop) + 1] - pair_start[static_cast<std::size_t>(i)] <= kBlock) ++stop;
    const std::int32_t q0 = pair_start[static_cast<std::size_t>(i)];
    const std::int32_t count = pair_start[static_cast<std::size_t>(stop)] - q0;
    if (static_cast<std::size_t>(count) > x.size()) x.resize(static_cast<std::size_t>(count));
    for (std::int32_t q = q0; i < stop; ++i) {
      const double* ni = n + 3 * i;
      for (std::int32_t k = upper[static_cast<std::size_t>(i)]; k < topo.ff_offsets[static_cast<std::size_t>(i) + 1]; ++k, ++q) {
        const double* nj = n + 3 * topo.ff_faces[static_cast<std::size_t>(k)];
        const double dx = ni[0] - nj[0], dy = ni[1] - nj[1], dz = ni[2] - nj[2];
        x[static_cast<std::size_t>(q - q0)] = (1.0 - (ni[0] * nj[0] + ni[1] * nj[1] + ni[2] * nj[2])) * inv_range;
        range[static_cast<std::size_t>(q)] = dx * dx + dy * dy + dz * dz;
      }
    }
    range_weights(x.data(), range.data() + q0, count, s.bilateral_switch, s.l1_median);
  }
}

// Eq. 7: one Jacobi step of the weighted L1-median for faces [begin, end), all faces from the
// previous iterate `current`; omega_ij = spatial[k] * range[pair_of[k]].
void jacobi_step(const Vertices& current, const Topology& topo, const std::vector<double>& spatial,
                 const std::vector<double>& range, const std::vector<std::int32_t>& pair_of, Vertices& next,
                 std::int64_t begin, std::int64_t end) {
  for (std::int64_t i = begin; i < end; ++i) {
    if (current.row(i).squaredNorm() == 0) {  // degenerate face: nothing to filter
      next.row(i).setZero();
      continue;
    }
    const double* n = current.data();
    double sx = 0, sy = 0, sz = 0;
    for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(i)]; k < topo.ff_offsets[static_cast<std::size_t>(i) + 1]; ++k) {
      const double w = spatial[static_cast<std::size_t>(k)] * range[static_cast<std::size_t>(pair_of[static_cast<std::size_t>(k)])];
      const double* nj = n + 3 * topo.ff_faces[static_cast<std::size_t>(k)];
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

}  // namespace

Vertices l1_median_normal_filter(const Vertices& V, const Triangles& F, const Topology& topo,
                                 const NormalFilterSettings& s, Executor* executor, ProgressObserver* progress) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const std::int64_t nf = F.rows();
  Vertices current = face_normals(V, F);
  if (s.iterations <= 0 || nf == 0) return current;

  const std::vector<double> spatial = spatial_weights(V, F, topo, s.sigma_c_factor, ex);
  const PairIndex pairs = index_pairs(topo, nf, ex);
  std::vector<double> range(static_cast<std::size_t>(pairs.pair_start.back()));

  // Eq. 7 typo: both denominators mean 1 - cos(sigma_gamma) (core/README.md, decision 8).
  const double inv_range = 1.0 / (1.0 - std::cos(s.sigma_gamma_deg * std::numbers::pi / 180.0));
  Vertices next(nf, 3);
  if (s.on_iteration) s.on_iteration(0, current);
  for (int it = 0; it < s.iterations; ++it) {
    checkpoint(progress, Stage::NormalFilter, static_cast<double>(it) / s.iterations);
    ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
      range_pass(current.data(), topo, pairs, inv_range, s, range, begin, end);
    });
    ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
      jacobi_step(current, topo, spatial, range, pairs.pair_of, next, begin, end);
    });
    current.swap(next);
    if (s.on_iteration) s.on_iteration(it + 1, current);
  }
  if (progress) progress->on_progress(Stage::NormalFilter, 1.0);
  return current;
}
}  // namespace mdn
