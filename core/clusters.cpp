// Sec. 4.2's K-means over faces in (centroid, area) space: the clustering that finds a
// densely sampled region (cluster_faces, sampled_area_ratio in core/prefilter.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/mesh.h"
#include "core/parallel.h"
#include "core/prefilter.h"
#include "core/shaping_cg.h"

namespace mdn {

namespace {
using Features = detail::ClusterFeatures;

// Feature scaling (core/README.md, decision 6): the three centroid coordinates share one
// scale so that together they carry unit variance (distances stay isotropic), and the
// area enters as log(area), standardised to unit variance on its own. Sampling density is
// a ratio, so log-area separates a 16x denser region as clearly wherever it lies, and the
// area block weighs as much as the whole position block: on a regular mesh the split is
// spatial and the cluster area ratio stays near 1. Raw areas (~1e-5 in a unit box) would
// not count at all.
Features cluster_features(const Vertices& C, const Eigen::VectorXd& A) {
  const auto nf = static_cast<std::size_t>(C.rows());
  const Eigen::RowVector3d c_mean = C.colwise().mean();
  const double c_scale = std::sqrt((C.rowwise() - c_mean).squaredNorm() / static_cast<double>(nf));
  const double a_floor = std::max(A.maxCoeff(), 1e-300) * 1e-12;  // zero-area faces: clamp before the log
  const Eigen::ArrayXd log_area = A.array().max(a_floor).log();
  const double a_mean = log_area.mean();
  const double a_scale = std::sqrt((log_area - a_mean).square().sum() / static_cast<double>(nf));
  Features X(static_cast<Eigen::Index>(nf), 4);
  X.leftCols<3>() = (C.rowwise() - c_mean) / (c_scale > 0 ? c_scale : 1.0);
  X.col(3) = (log_area - a_mean) / (a_scale > 0 ? a_scale : 1.0);
  return X;
}

// k-means++ seeding with a fixed seed: deterministic.
Features seed_centers(const Features& X, int k, std::uint64_t seed) {
  const auto nf = static_cast<std::size_t>(X.rows());
  std::mt19937_64 rng(seed);
  auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  Features centers(k, 4);
  centers.row(0) = X.row(static_cast<Eigen::Index>(rng() % nf));
  Eigen::VectorXd d2(static_cast<Eigen::Index>(nf));
  for (std::size_t i = 0; i < nf; ++i) d2(static_cast<Eigen::Index>(i)) = (X.row(static_cast<Eigen::Index>(i)) - centers.row(0)).squaredNorm();
  for (int c = 1; c < k; ++c) {
    const double total = d2.sum();
    std::size_t pick = 0;
    if (total > 0) {
      double r = uniform() * total;
      for (pick = 0; pick + 1 < nf; ++pick) {
        r -= d2(static_cast<Eigen::Index>(pick));
        if (r <= 0) break;
      }
    }
    centers.row(c) = X.row(static_cast<Eigen::Index>(pick));
    for (std::size_t i = 0; i < nf; ++i)
      d2(static_cast<Eigen::Index>(i)) = std::min(d2(static_cast<Eigen::Index>(i)), (X.row(static_cast<Eigen::Index>(i)) - centers.row(c)).squaredNorm());
  }
  return centers;
}

}  // namespace

namespace detail {
namespace {
// Per block of Lloyd's faces: its sums and counts per cluster, its faces' changed labels in
// the current iteration, and the least of its faces' bounds.
struct LloydBlocks {
  static constexpr std::int64_t kBlock = 8192;
  std::int64_t faces, count;
  std::vector<ClusterFeatures> sum;
  std::vector<std::int64_t> members;  // count x k
  std::vector<std::int64_t> changed;
  std::vector<float> bound;
  LloydBlocks(std::int64_t nf, int k)
      : faces(nf), count((nf + kBlock - 1) / kBlock), sum(static_cast<std::size_t>(count), ClusterFeatures::Zero(k, 4)),
        members(static_cast<std::size_t>(count * k)), changed(static_cast<std::size_t>(count)),
        bound(static_cast<std::size_t>(count), -std::numeric_limits<float>::infinity()) {}
};

// One iteration on block `blk`: measures the faces whose bound is not above skip_above,
// relabels them, and sums the block again if a label changed (always at the first iteration).
void lloyd_block(const ClusterFeatures& X, const ClusterFeatures& centers, std::int64_t blk, bool first,
                 double skip_above, double drift, std::vector<std::int32_t>& label, std::vector<float>& bound,
                 LloydBlocks& blocks) {
  const auto k = static_cast<int>(centers.rows());
  const std::int64_t lo = blk * LloydBlocks::kBlock, hi = std::min(blocks.faces, lo + LloydBlocks::kBlock);
  const auto b_at = static_cast<std::size_t>(blk);
  std::int64_t& changed = blocks.changed[b_at];
  changed = 0;
  if (blocks.bound[b_at] > skip_above) return;
  float lowest = std::numeric_limits<float>::infinity();
  for (std::int64_t i = lo; i < hi; ++i) {
    float& b = bound[static_cast<std::size_t>(i)];
    if (b > skip_above) {
      lowest = std::min(lowest, b);
      continue;
    }
    int best = 0;
    double best_d = std::numeric_limits<double>::infinity(), second_d = best_d;
    for (int c = 0; c < k; ++c) {
      const double d = (X.row(i) - centers.row(c)).squaredNorm();
      if (d < best_d) second_d = best_d, best_d = d, best = c;
      else second_d = std::min(second_d, d);
    }
    std::int32_t& l = label[static_cast<std::size_t>(i)];
    changed += l != best;
    l = best;
    const double gap = std::sqrt(second_d) - std::sqrt(best_d) + drift;  // inf for k = 1
    b = static_cast<float>(gap);
    if (static_cast<double>(b) > gap) b = std::nextafter(b, -std::numeric_limits<float>::infinity());
    lowest = std::min(lowest, b);
  }
  blocks.bound[b_at] = lowest;
  if (changed == 0 && !first) return;  // the block's sums stand
  ClusterFeatures& sum = blocks.sum[b_at];
  std::int64_t* members = &blocks.members[static_cast<std::size_t>(blk * k)];
  sum.setZero();
  std::fill(members, members + k, 0);
  if (k == 2) {  // Sec. 4.2's K: both sums in registers, each added in face order as below
    Eigen::Array4d s0 = Eigen::Array4d::Zero(), s1 = Eigen::Array4d::Zero();
    for (std::int64_t i = lo; i < hi; ++i) {
      const Eigen::Array4d x = X.row(i).transpose().array();
      if (label[static_cast<std::size_t>(i)] == 0) {
        s0 += x;
        ++members[0];
      } else {
        s1 += x;
        ++members[1];
      }
    }
    sum.row(0) = s0.matrix().transpose();
    sum.row(1) = s1.matrix().transpose();
    return;
  }
  for (std::int64_t i = lo; i < hi; ++i) {
    const std::int32_t l = label[static_cast<std::size_t>(i)];
    sum.row(l) += X.row(i);
    ++members[l];
  }
}
}  // namespace

// Lloyd iterations, one pass per iteration (decision 39): each block of kBlock faces takes its
// faces' nearest centres, counts the changed labels and sums the features per label; the
// blocks' sums are added in block order, so the centres do not depend on the number of
// threads.
//
// Decision 49 (Hamerly's bound, 2010): Lloyd runs a few dozen iterations at 1.2M faces, and
// after the first few most faces keep their label; a face's label provably stays while the
// centres have drifted less than its margin. Per face, `bound` holds the gap between its
// second-nearest and nearest centre when it was last measured, plus the drift D accumulated
// until then; every iteration adds to D the two largest centre moves (the most that gap can
// shrink by). A face whose bound still exceeds D (with a rounding margin) is not measured; a
// block none of whose faces changed keeps its sums, which are then exactly what a fresh pass
// would add up in the same order. So labels and centres are bit for bit those of passes that
// measure every face.
void lloyd_iterations(const ClusterFeatures& X, ClusterFeatures& centers, int max_iterations, Executor* executor,
                      std::vector<std::int32_t>& label) {
  const auto nf = static_cast<std::int64_t>(X.rows());
  const auto k = static_cast<int>(centers.rows());
  LloydBlocks blocks(nf, k);
  // float bounds rounded down: a quarter of the memory traffic of the features they spare.
  std::vector<float> bound(static_cast<std::size_t>(nf), -std::numeric_limits<float>::infinity());
  // Rounding in a measured gap (squared norms of differences of features up to |X|max) and in
  // the drift's sum; far below any gap that matters for the saving.
  const double slack = 1e-9 * (1 + (nf > 0 ? X.cwiseAbs().maxCoeff() : 0.0));
  double drift = 0;
  for (int it = 0; it < max_iterations; ++it) {
    const double skip_above = drift + slack * (1 + drift);
    auto assign = [&](std::int64_t first, std::int64_t last) {
      for (std::int64_t blk = first; blk < last; ++blk) lloyd_block(X, centers, blk, it == 0, skip_above, drift, label, bound, blocks);
    };
    if (Executor* threads = detail::threads_for(executor, nf))  // serial where dispatch costs more
      threads->parallel_for(blocks.count, 1, assign);
    else
      assign(0, blocks.count);
    std::int64_t changed = 0;
    const ClusterFeatures previous = centers;
    centers.setZero();
    std::vector<std::int64_t> count(static_cast<std::size_t>(k), 0);
    for (std::int64_t blk = 0; blk < blocks.count; ++blk) {
      centers += blocks.sum[static_cast<std::size_t>(blk)];
      for (int c = 0; c < k; ++c) count[static_cast<std::size_t>(c)] += blocks.members[static_cast<std::size_t>(blk * k + c)];
      changed += blocks.changed[static_cast<std::size_t>(blk)];
    }
    for (int c = 0; c < k; ++c)
      if (count[static_cast<std::size_t>(c)] > 0) centers.row(c) /= static_cast<double>(count[static_cast<std::size_t>(c)]);
    if (changed == 0 && it > 0) break;
    double move1 = 0, move2 = 0;  // the two largest centre moves
    for (int c = 0; c < k; ++c) {
      const double m = (centers.row(c) - previous.row(c)).norm();
      if (m > move1) move2 = move1, move1 = m;
      else move2 = std::max(move2, m);
    }
    drift += move1 + move2;
  }
}
}  // namespace detail

namespace {
// Each cluster's mean face area, the smallest cluster and the largest-to-smallest ratio, from
// out.label and the areas A.
void cluster_areas(const Eigen::VectorXd& A, int k, FaceClusters& out) {
  std::vector<std::int64_t> count(static_cast<std::size_t>(k), 0);
  for (std::size_t i = 0; i < out.label.size(); ++i) {
    out.mean_area[static_cast<std::size_t>(out.label[i])] += A(static_cast<Eigen::Index>(i));
    ++count[static_cast<std::size_t>(out.label[i])];
  }
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (int c = 0; c < k; ++c) {
    auto& m = out.mean_area[static_cast<std::size_t>(c)];
    if (count[static_cast<std::size_t>(c)] == 0) continue;
    m /= static_cast<double>(count[static_cast<std::size_t>(c)]);
    if (m < lo) lo = m, out.smallest = c;
    hi = std::max(hi, m);
  }
  out.area_ratio = lo > 0 ? hi / lo : (hi > 0 ? std::numeric_limits<double>::infinity() : 1.0);
}
}  // namespace

// Sec. 4.2: K-means over (centroid, area).
FaceClusters cluster_faces(const Vertices& P, const Triangles& F, int k, std::uint64_t seed, int max_iterations,
                           Executor* executor) {
  const auto nf = static_cast<std::size_t>(F.rows());
  FaceClusters out;
  out.label.assign(nf, 0);
  out.mean_area.assign(static_cast<std::size_t>(k), 0);
  if (nf == 0 || k < 1) return out;

  const Vertices C = face_centroids(P, F);
  const Eigen::VectorXd A = face_areas(P, F);
  const Features X = cluster_features(C, A);
  Features centers = seed_centers(X, k, seed);
  detail::lloyd_iterations(X, centers, max_iterations, executor, out.label);
  cluster_areas(A, k, out);
  return out;
}

double sampled_area_ratio(const Vertices& P, const Triangles& F, int k, std::uint64_t seed, std::int64_t max_faces,
                          Executor* executor) {
  const std::int64_t stride = std::max<std::int64_t>(1, (F.rows() + max_faces - 1) / std::max<std::int64_t>(max_faces, 1));
  Triangles sample((F.rows() + stride - 1) / stride, 3);
  for (std::int64_t f = 0, s = 0; f < F.rows(); f += stride, ++s) sample.row(s) = F.row(f);
  return sample.rows() >= k ? cluster_faces(P, sample, k, seed, 100, executor).area_ratio : 1.0;
}

}  // namespace mdn
