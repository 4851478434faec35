#include "core/normal_filter.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/errors.h"
#include "core/fast_math.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace mdn {

namespace {

// range[q] <- phi(x_q) / ||n_i - n_j||, the symmetric factor of omega_ij (Eq. 7), with
// bilateral weights where ||n_i - n_j|| < sw; phi(x) = exp(-x^2). On entry range[q] holds
// ||n_i - n_j||^2, and x_q = (1 - cos gamma_ij) / (1 - cos sigma_gamma) is formed from it:
// 1 - cos gamma = ||n_i - n_j||^2 / 2 for unit normals (exact where n_i . n_j would cancel).
// Single precision (decision 36). Branch-free so that it vectorises; compiled for AVX2 too and
// picked at run time. Without FMA contraction (-ffp-contract=off) both versions do the same
// IEEE operations, so the weights are identical on every x86-64 machine.
MDN_AVX2_CLONE
void range_weights(float* range, std::int64_t n, float inv_range, float sw, bool l1_median) {
  const float half_inv_range = 0.5f * inv_range;
  for (std::int64_t q = 0; q < n; ++q) {
    const float x = range[q] * half_inv_range;
    const float dist = std::sqrt(range[q]);
    const float denom = l1_median && dist >= sw ? dist : 1.0f;
    range[q] = detail::exp_nonpositive_f(-x * x) / denom;
  }
}

// Guided range factors (decision 53): range[q] <- guide_phi[q] / ||n_i - n_j||, where guide_phi
// holds phi(x_q) of the guidance normals (range_weights with l1_median = false, once per run) and
// range[q] holds ||n_i - n_j||^2 of the current normals on entry; bilateral where
// ||n_i - n_j|| < sw, as in range_weights. With guidance equal to the current normals this is
// range_weights' own arithmetic: the same phi, the same division.
MDN_AVX2_CLONE
void guided_range_weights(float* range, const float* guide_phi, std::int64_t n, float sw, bool l1_median) {
  for (std::int64_t q = 0; q < n; ++q) {
    const float dist = std::sqrt(range[q]);
    const float denom = l1_median && dist >= sw ? dist : 1.0f;
    range[q] = guide_phi[q] / denom;
  }
}

// out[q] = a[q] exp(y[q]) (y <= 0) rounded to float: the spatial weights (Eq. 6) of a block of
// neighbour entries. Branch-free, compiled for AVX2 too (the same IEEE operations).
MDN_AVX2_CLONE
void area_times_exp(const double* a, const double* y, float* out, std::int64_t n) {
  for (std::int64_t q = 0; q < n; ++q) out[q] = static_cast<float>(a[q] * detail::exp_nonpositive(y[q]));
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
std::vector<float> spatial_weights(const Vertices& V, const Triangles& F, const Topology& topo, double sigma_c_factor,
                                   Executor& ex) {
  const std::int64_t nf = F.rows();
  const Eigen::VectorXd area = face_areas(V, F);
  const Vertices centroid = face_centroids(V, F);
  const double sigma_c = sigma_c_of(centroid, topo, nf, sigma_c_factor);
  std::vector<float> spatial(topo.ff_faces.size());  // computed in double, stored in float (decision 36)
  const double inv_sigma_c2 = 1.0 / (sigma_c * sigma_c);
  // Per block of entries: the exponents and the areas gathered, then the products in one
  // vectorised loop.
  constexpr std::int32_t kBlock = 1024;
  ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
    std::vector<double> y, a;
    for (std::int64_t i = begin; i < end;) {
      const std::int32_t k0 = topo.ff_offsets[static_cast<std::size_t>(i)];
      y.clear();
      a.clear();
      for (; i < end && (y.empty() || topo.ff_offsets[static_cast<std::size_t>(i) + 1] - k0 <= kBlock); ++i)
        for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(i)]; k < topo.ff_offsets[static_cast<std::size_t>(i) + 1]; ++k) {
          const std::int32_t j = topo.ff_faces[static_cast<std::size_t>(k)];
          y.push_back(-(centroid.row(i) - centroid.row(j)).squaredNorm() * inv_sigma_c2);
          a.push_back(area(j));
        }
      area_times_exp(a.data(), y.data(), spatial.data() + k0, static_cast<std::int64_t>(y.size()));
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

// Decision 51: the passes are bound by memory bandwidth at scale, so the iterations read N(i)'s
// entries in fewer bytes where they fit: face j as the 16-bit offset j - i (decision 16's order
// keeps neighbours close: at most 4,174 faces apart on the 1.2M-face bunny, 8,342 at 4.8M), and
// its pair as the offset from i's first pair, in 16 bits where every one fits (up to 25,011 on
// the 1.2M bunny; 49,978 at 4.8M), else in 32. Otherwise (a face offset beyond 16 bits) the
// 32-bit face and pair numbers. Either way the same faces and pairs in the same order: the
// same output.
struct AbsoluteNeighbours {
  const std::int32_t* faces;
  const std::int32_t* pairs;
  std::int64_t face(std::int64_t, std::int32_t k) const { return faces[k]; }
  std::int32_t pair(std::int64_t, std::int32_t k) const { return pairs[k]; }
};
template <class PairDelta>
struct CompactNeighbours {
  std::vector<std::int16_t> face_delta;  // j - i
  std::vector<PairDelta> pair_delta;     // pair - pair_start[i]
  const std::int32_t* pair_start = nullptr;
  std::int64_t face(std::int64_t i, std::int32_t k) const { return i + face_delta[static_cast<std::size_t>(k)]; }
  std::int32_t pair(std::int64_t i, std::int32_t k) const {
    return pair_start[i] + static_cast<std::int32_t>(pair_delta[static_cast<std::size_t>(k)]);
  }
};

// The compact form of N(i) with PairDelta offsets; nothing if an offset does not fit.
template <class PairDelta>
std::optional<CompactNeighbours<PairDelta>> compact_neighbours(const Topology& topo, const PairIndex& pairs,
                                                               std::int64_t nf, Executor& ex) {
  auto fits_in = [](std::int64_t x, auto type) {
    using T = decltype(type);
    return x >= std::numeric_limits<T>::min() && x <= std::numeric_limits<T>::max();
  };
  CompactNeighbours<PairDelta> c;
  c.face_delta.resize(topo.ff_faces.size());
  c.pair_delta.resize(topo.ff_faces.size());
  c.pair_start = pairs.pair_start.data();
  std::atomic<bool> fits{true};
  ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
    bool ok = true;
    for (std::int64_t i = begin; i < end && ok; ++i)
      for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(i)];
           k < topo.ff_offsets[static_cast<std::size_t>(i) + 1]; ++k) {
        const auto ku = static_cast<std::size_t>(k);
        const std::int64_t face = topo.ff_faces[ku] - i;
        const std::int64_t pair = std::int64_t{pairs.pair_of[ku]} - pairs.pair_start[static_cast<std::size_t>(i)];
        ok = ok && fits_in(face, std::int16_t{}) && fits_in(pair, PairDelta{});
        c.face_delta[ku] = static_cast<std::int16_t>(face);
        c.pair_delta[ku] = static_cast<PairDelta>(pair);
      }
    if (!ok) fits.store(false, std::memory_order_relaxed);
  });
  if (!fits.load()) return std::nullopt;
  return c;
}

// The range factor of every pair (i, j > i) for faces [begin, end), normals n (#F x 4 floats,
// decision 36). Blocks of about kBlock pairs: gather ||n_i - n_j||^2 into range, then the
// weights while the block is in L1 (branch-free, vectorised). guide_phi non-null: the guided
// factors (decision 53), phi already read from the guidance normals, per pair.
template <class Neighbours>
void range_pass(const float* n, const std::vector<std::int32_t>& ff_offsets, const PairIndex& pairs,
                const Neighbours& nb, float inv_range, const NormalFilterSettings& s, const float* guide_phi,
                std::vector<float>& range, std::int64_t begin, std::int64_t end) {
  const std::vector<std::int32_t>& pair_start = pairs.pair_start;
  constexpr std::int32_t kBlock = 512;
  for (std::int64_t i = begin; i < end;) {
    std::int64_t stop = i + 1;  // at least one face, however many pairs it has
    while (stop < end &&
           pair_start[static_cast<std::size_t>(stop) + 1] - pair_start[static_cast<std::size_t>(i)] <= kBlock)
      ++stop;
    const std::int32_t q0 = pair_start[static_cast<std::size_t>(i)];
    const std::int32_t count = pair_start[static_cast<std::size_t>(stop)] - q0;
    for (std::int32_t q = q0; i < stop; ++i) {
      const float* ni = n + 4 * i;
      for (std::int32_t k = pairs.upper[static_cast<std::size_t>(i)]; k < ff_offsets[static_cast<std::size_t>(i) + 1];
           ++k, ++q) {
        const float* nj = n + 4 * nb.face(i, k);
        const float dx = ni[0] - nj[0], dy = ni[1] - nj[1], dz = ni[2] - nj[2];
        range[static_cast<std::size_t>(q)] = dx * dx + dy * dy + dz * dz;
      }
    }
    if (guide_phi)
      guided_range_weights(range.data() + q0, guide_phi + q0, count, static_cast<float>(s.bilateral_switch), s.l1_median);
    else
      range_weights(range.data() + q0, count, inv_range, static_cast<float>(s.bilateral_switch), s.l1_median);
  }
}

using Row4f = Eigen::Array4f;
using ConstRow4f = Eigen::Map<const Row4f, Eigen::Aligned16>;

// Eq. 7: one Jacobi step of the weighted L1-median for faces [begin, end), all faces from the
// previous iterate `current` (#F x 4 floats, the fourth 0); omega_ij = spatial[k] *
// range[pair of entry k]. Each neighbour is one 4-wide multiply-add, summed in float (decision 36).
template <class Neighbours>
void jacobi_step(const float* current, const std::vector<std::int32_t>& ff_offsets, const std::vector<float>& spatial,
                 const std::vector<float>& range, const Neighbours& nb, float* next, std::int64_t begin,
                 std::int64_t end) {
  for (std::int64_t i = begin; i < end; ++i) {
    const ConstRow4f ni(current + 4 * i);
    Eigen::Map<Row4f, Eigen::Aligned16> out(next + 4 * i);
    if ((ni * ni).sum() == 0) {  // degenerate face: nothing to filter
      out.setZero();
      continue;
    }
    Row4f sum = Row4f::Zero();
    for (std::int32_t k = ff_offsets[static_cast<std::size_t>(i)]; k < ff_offsets[static_cast<std::size_t>(i) + 1];
         ++k) {
      const float w = spatial[static_cast<std::size_t>(k)] * range[static_cast<std::size_t>(nb.pair(i, k))];
      sum += w * ConstRow4f(current + 4 * nb.face(i, k));
    }
    const float len = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    if (len > 0)
      out = sum / len;
    else
      out = ni;  // no usable neighbour (isolated or all degenerate)
  }
}

// #F x 3 doubles <-> #F x 4 floats (the fourth 0). Back to double, each row is normalised again
// in double, so the filter returns unit normals to double precision.
void to_float4(const Vertices& N, std::vector<float>& out) {
  out.assign(static_cast<std::size_t>(4 * N.rows()), 0.0f);
  for (Eigen::Index i = 0; i < N.rows(); ++i)
    for (int c = 0; c < 3; ++c) out[static_cast<std::size_t>(4 * i + c)] = static_cast<float>(N(i, c));
}
void to_double(const std::vector<float>& n, Vertices& out) {
  out.resize(static_cast<Eigen::Index>(n.size() / 4), 3);
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    for (int c = 0; c < 3; ++c) out(i, c) = n[static_cast<std::size_t>(4 * i + c)];
    const double len = out.row(i).norm();
    if (len > 0) out.row(i) /= len;
  }
}

// Decision 53: with guidance, phi of Eq. 7's range factor is read from the guidance normals,
// which do not change, so once per pair before the iterations: the same pass and arithmetic as
// an iteration's (range_pass), on the guidance in single precision, without the 1/||n_i - n_j||.
template <class Neighbours>
std::vector<float> guidance_factors(const Vertices& guidance, const Topology& topo, const PairIndex& pairs,
                                    const Neighbours& nb, float inv_range, const NormalFilterSettings& s, Executor& ex) {
  std::vector<float> g, phi(static_cast<std::size_t>(pairs.pair_start.back()));
  to_float4(guidance, g);
  NormalFilterSettings phi_only;
  phi_only.bilateral_switch = s.bilateral_switch;
  phi_only.l1_median = false;  // denominators 1: phi alone
  ex.parallel_for(guidance.rows(), [&](std::int64_t begin, std::int64_t end) {
    range_pass(g.data(), topo.ff_offsets, pairs, nb, inv_range, phi_only, nullptr, phi, begin, end);
  });
  return phi;
}

}  // namespace

void check_guidance(const Vertices& guidance, std::int64_t faces) {
  if (guidance.rows() != faces || guidance.cols() != 3)
    throw InvalidParamsError("guidance", "the guidance normals must be one row of 3 per face (" + std::to_string(faces) +
                                             "), got " + std::to_string(guidance.rows()) + " by " +
                                             std::to_string(guidance.cols()));
  if (!guidance.allFinite()) throw InvalidParamsError("guidance", "a guidance normal is not finite");
}

Vertices l1_median_normal_filter(const Vertices& V, const Triangles& F, const Topology& topo,
                                 const NormalFilterSettings& s, Executor* executor, ProgressObserver* progress) {
  return detail::l1_median_normal_filter(V, F, topo, s, executor, progress, detail::NeighbourForm::Auto);
}

Vertices detail::l1_median_normal_filter(const Vertices& V, const Triangles& F, const Topology& topo,
                                         const NormalFilterSettings& s, Executor* executor, ProgressObserver* progress,
                                         NeighbourForm form) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const std::int64_t nf = F.rows();
  if (s.guidance) check_guidance(*s.guidance, nf);
  Vertices normals = face_normals(V, F);
  if (s.iterations <= 0 || nf == 0) return normals;

  const std::vector<float> spatial = spatial_weights(V, F, topo, s.sigma_c_factor, ex);
  PairIndex pairs = index_pairs(topo, nf, ex);
  std::optional<CompactNeighbours<std::int16_t>> compact16;
  std::optional<CompactNeighbours<std::int32_t>> compact32;
  if (form == NeighbourForm::Auto || form == NeighbourForm::Compact16)
    compact16 = compact_neighbours<std::int16_t>(topo, pairs, nf, ex);
  if ((form == NeighbourForm::Auto && !compact16) || form == NeighbourForm::Compact32)
    compact32 = compact_neighbours<std::int32_t>(topo, pairs, nf, ex);
  if ((form == NeighbourForm::Compact16 && !compact16) || (form == NeighbourForm::Compact32 && !compact32))
    throw std::invalid_argument("the forced neighbour form does not hold this mesh's entries");
  if (compact16 || compact32)
    std::vector<std::int32_t>().swap(pairs.pair_of);  // before the iterations' arrays (peak memory)
  std::vector<float> range(static_cast<std::size_t>(pairs.pair_start.back()));
  // Runs body with the form of N(i) chosen above.
  const auto with_neighbours = [&](const auto& body) {
    if (compact16)
      body(*compact16);
    else if (compact32)
      body(*compact32);
    else
      body(AbsoluteNeighbours{topo.ff_faces.data(), pairs.pair_of.data()});
  };

  // Eq. 7 typo: both denominators mean 1 - cos(sigma_gamma) (core/README.md, decision 8).
  const auto inv_range = static_cast<float>(1.0 / (1.0 - std::cos(s.sigma_gamma_deg * std::numbers::pi / 180.0)));
  // The iterations run in single precision (decision 36).
  std::vector<float> current, next(static_cast<std::size_t>(4 * nf));
  to_float4(normals, current);
  std::vector<float> guide_phi;  // decision 53: phi of the guidance, once per pair
  if (s.guidance)
    with_neighbours([&](const auto& nb) { guide_phi = guidance_factors(*s.guidance, topo, pairs, nb, inv_range, s, ex); });
  const float* guided = s.guidance ? guide_phi.data() : nullptr;
  if (s.on_iteration) s.on_iteration(0, normals);
  with_neighbours([&](const auto& neighbours) {
    for (int it = 0; it < s.iterations; ++it) {
      checkpoint(progress, Stage::NormalFilter, static_cast<double>(it) / s.iterations);
      ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
        range_pass(current.data(), topo.ff_offsets, pairs, neighbours, inv_range, s, guided, range, begin, end);
      });
      ex.parallel_for(nf, [&](std::int64_t begin, std::int64_t end) {
        jacobi_step(current.data(), topo.ff_offsets, spatial, range, neighbours, next.data(), begin, end);
      });
      current.swap(next);
      if (s.on_iteration) {
        to_double(current, normals);
        s.on_iteration(it + 1, normals);
      }
    }
  });
  if (progress) progress->on_progress(Stage::NormalFilter, 1.0);
  to_double(current, normals);
  return normals;
}
}  // namespace mdn
