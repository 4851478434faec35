// Single-precision conjugate gradients for the pre-filter's systems (I + alpha D^T W D) x = P
// (Eq. 1, Eq. 3), internal to ShapingSolver (core/README.md, decision 37). The operator's
// products, the work vectors and the preconditioner are floats (4 per row, the fourth 0); the
// dot products are summed in double with decision 11's fixed blocking, and the iterate x is
// double. ShapingSolver checks the true residual in double afterwards and continues in double
// where it is above the tolerance.
// Also Eq. 2's system (the region pre-filter, Sec. 4.2), matrix-free in double (decision 38).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/mesh.h"
#include "core/parallel.h"
#include "core/topology.h"

namespace mdn::detail {

// The matrix-free operator's incidence: vertex -> signed edge entries (2 e + 1 where the
// vertex's coefficient in S(e) is -1, 2 e where it is +1), CSR, each vertex's +1 entries
// before split[v] and its -1 entries from there; ShapingSolver builds it.
struct ShapingIncidence {
  const Topology* topo = nullptr;
  const std::vector<std::int32_t>* offsets = nullptr;
  const std::vector<std::int32_t>* edges = nullptr;
  const std::vector<std::int32_t>* split = nullptr;
  Executor* executor = nullptr;  // threads_for(...): nullptr is serial
};

// The threading of every pre-filter system (Eq. 1-3, both CGs). Below kParallelRows rows a CG
// step is a few microseconds and dispatching it to threads costs more than it saves (measured
// on Fandisk: Eq. 1 6.0 ms serial, 7.1 ms on two threads). Above, chunks of kGrain rows (or
// edges) are claimed by free threads (decision 28): a chunk's vectors stay in L2, and a core
// shared with another process takes fewer of them.
inline constexpr std::int64_t kParallelRows = 32768;
inline constexpr std::int64_t kGrain = 8192;
// The executor a system of `rows` rows runs on: nullptr (serial) below kParallelRows.
inline Executor* threads_for(Executor* executor, std::int64_t rows) { return rows >= kParallelRows ? executor : nullptr; }
// fn over [0, n): in chunks of `grain` on `threads`, or in one call where threads is nullptr.
inline void chunked(Executor* threads, std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& fn,
                    std::int64_t grain = kGrain) {
  if (threads)
    threads->parallel_for(n, grain, fn);
  else
    fn(0, n);
}

// Column sums of a sweep with a fixed blocking (decision 11): body(i, sums) runs for every row
// i of [0, n), block by block (kSumBlock rows; the blocks chunked on `threads`), and the blocks'
// sums are added in order, so the rounding does not depend on the number of threads. Passes
// that update a vector take its dot products in the same sweep.
using Sums = Eigen::Array<double, 3, 2>;
constexpr std::int64_t kSumBlock = 2048;
template <class Body>
Sums blocked_sums(Executor* threads, std::int64_t n, const Body& body) {
  const std::int64_t blocks = (n + kSumBlock - 1) / kSumBlock;
  std::vector<Sums> partial(static_cast<std::size_t>(blocks), Sums::Zero());
  chunked(
      threads, blocks,
      [&](std::int64_t begin, std::int64_t end) {
        for (std::int64_t blk = begin; blk < end; ++blk) {
          Sums sum = Sums::Zero();
          for (std::int64_t i = blk * kSumBlock; i < std::min(n, (blk + 1) * kSumBlock); ++i) body(i, sum);
          partial[static_cast<std::size_t>(blk)] = sum;
        }
      },
      kGrain / kSumBlock);
  Sums total = Sums::Zero();
  for (const auto& p : partial) total += p;
  return total;
}

class SingleCG {
 public:
  // Jacobi-preconditioned CG on A x = P started from x as given where from_x (#V x 3), else
  // from x = P, until the (recurrence) residual of every column is at most tolerance x ||P
  // column|| or after max_iterations. weights: #E, or empty for W = I; inv_diag: #V, 1 /
  // diag(A) in double (ShapingSolver's, shared with its double check), used rounded to float.
  // Returns the iterations run; x is #V x 3.
  int solve(const ShapingIncidence& op, const Vertices& P, double alpha, const Eigen::VectorXd& weights,
            const Eigen::VectorXd& inv_diag, double tolerance, int max_iterations, Vertices& x, bool from_x = false);
  // Frees the work vectors (the next solve allocates them again).
  void release();

 private:
  void prepare(const ShapingIncidence& op, double alpha, const Eigen::VectorXd& weights, const Eigen::VectorXd& inv_diag);
  Sums initial_residual(const ShapingIncidence& op, const Vertices& P, const Vertices* start, double alpha,
                        const Eigen::VectorXd& weights);  // start: nullptr where x0 = P
  Eigen::Array3d apply(const ShapingIncidence& op);
  Sums step(const ShapingIncidence& op, const Eigen::Array3d& step, Vertices& x);
  std::vector<float> ws_, s_, r_, p_, ap_, inv_diag_;
};

// Eq. 2's system M X = B, M = I + beta L^T L, applied without assembling it (decision 38): L is
// the uniform Laplacian of the whole mesh restricted to the unknown rows, read from the one-ring
// lists (topo.vv, symmetric), so L^T y is again a gather over the one-ring: (L^T y)_u = y_u -
// sum over unknown neighbours j of y_j / deg(j). row_vertex[r]: the vertex of unknown r;
// unknown[v]: v's row, or -1 where v is fixed; inv_deg[r]: 1 / deg, 0 for an isolated vertex
// (no Laplacian row). Row r of L x is x_r - inv_deg[r] sum of x over r's unknown neighbours.
struct RegionSystem {
  const Topology* topo;
  const std::vector<std::int32_t>* row_vertex;
  const std::vector<std::int32_t>* unknown;
  Eigen::VectorXd inv_deg;
  double beta;
  Executor* executor;  // threads_for(executor, rows): nullptr is serial
  // Each row's unknown neighbours as rows, in one-ring order (index_neighbours): the products
  // gather from these without looking each neighbour up in `unknown`.
  std::vector<std::int32_t> nb_offsets, nb_rows;

  void index_neighbours() {
    const auto m = static_cast<std::int64_t>(row_vertex->size());
    nb_offsets.assign(static_cast<std::size_t>(m) + 1, 0);
    for (std::int64_t r = 0; r < m; ++r) {
      const auto v = static_cast<std::size_t>((*row_vertex)[static_cast<std::size_t>(r)]);
      std::int32_t count = 0;
      for (std::int32_t s = topo->vv_offsets[v]; s < topo->vv_offsets[v + 1]; ++s)
        count += (*unknown)[static_cast<std::size_t>(topo->vv_vertices[static_cast<std::size_t>(s)])] >= 0;
      nb_offsets[static_cast<std::size_t>(r) + 1] = nb_offsets[static_cast<std::size_t>(r)] + count;
    }
    nb_rows.resize(static_cast<std::size_t>(nb_offsets.back()));
    chunked(executor, m, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t r = begin; r < end; ++r) {
        const auto v = static_cast<std::size_t>((*row_vertex)[static_cast<std::size_t>(r)]);
        std::int32_t slot = nb_offsets[static_cast<std::size_t>(r)];
        for (std::int32_t s = topo->vv_offsets[v]; s < topo->vv_offsets[v + 1]; ++s) {
          const std::int32_t j = (*unknown)[static_cast<std::size_t>(topo->vv_vertices[static_cast<std::size_t>(s)])];
          if (j >= 0) nb_rows[static_cast<std::size_t>(slot++)] = j;
        }
      }
    });
  }

  // The sum over row r's unknown neighbours j of scale(j) x.row(j).
  template <class Scale>
  Eigen::RowVector3d ring_sum(std::int64_t r, const Vertices& x, const Scale& scale) const {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (std::int32_t s = nb_offsets[static_cast<std::size_t>(r)]; s < nb_offsets[static_cast<std::size_t>(r) + 1]; ++s) {
      const std::int32_t j = nb_rows[static_cast<std::size_t>(s)];
      sum += scale(j) * x.row(j);
    }
    return sum;
  }
  // y = L x (0 on an isolated vertex's row).
  void laplacian(const Vertices& x, Vertices& y) const {
    chunked(executor, x.rows(), [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t r = begin; r < end; ++r) {
        const double d = inv_deg(r);
        y.row(r) = d > 0 ? Eigen::RowVector3d(x.row(r) - d * ring_sum(r, x, [](std::int32_t) { return 1.0; }))
                         : Eigen::RowVector3d::Zero();
      }
    });
  }
  // (L^T y)_r.
  Eigen::RowVector3d transpose_row(std::int64_t r, const Vertices& y) const {
    return y.row(r) - ring_sum(r, y, [&](std::int32_t j) { return inv_deg(j); });
  }
  // diag(M)_r = 1 + beta (1 if r has a row, + sum over unknown neighbours j of 1 / deg(j)^2).
  double diagonal(std::int64_t r) const {
    const double own = inv_deg(r) > 0 ? 1.0 : 0.0;
    double sum = 0;
    for (std::int32_t s = nb_offsets[static_cast<std::size_t>(r)]; s < nb_offsets[static_cast<std::size_t>(r) + 1]; ++s)
      sum += inv_deg(nb_rows[static_cast<std::size_t>(s)]) * inv_deg(nb_rows[static_cast<std::size_t>(s)]);
    return 1 + beta * (own + sum);
  }
};

// Jacobi-preconditioned CG in double on A X = B from X (decision 4's iteration), until every
// column's residual is at most tolerance x ||B column||, at most max(1000, rows) iterations.
// apply(x, Ax) writes A x and returns x . Ax per column (blocked_sums). inv_diag: 1 / diag(A).
// r, p, Ap: work arrays (resized). Dot products in decision 11's fixed blocks, so the result does
// not depend on the threads. Returns the iterations run, or -1 if it did not converge. Shared by
// Eq. 3's double check (ShapingSolver, decision 37) and Eq. 2 (solve_region, decision 38).
template <class Apply>
int jacobi_cg(Executor* threads, const Apply& apply, const Vertices& B, const Eigen::VectorXd& inv_diag, double tolerance,
              Vertices& X, Vertices& r, Vertices& p, Vertices& Ap) {
  const Eigen::Index n = B.rows();
  r.resize(n, 3);
  p.resize(n, 3);
  Ap.resize(n, 3);
  apply(X, Ap);
  // r = B - A x, z = D^-1 r (= p), and r . z in the same sweep.
  const Sums rz_rr0 = blocked_sums(threads, n, [&](std::int64_t v, Sums& sum) {
    r.row(v) = B.row(v) - Ap.row(v);
    p.row(v) = inv_diag(v) * r.row(v);
    sum.col(0) += r.row(v).array().transpose() * p.row(v).array().transpose();
    sum.col(1) += r.row(v).array().transpose() * r.row(v).array().transpose();
  });
  Eigen::Array3d rz = rz_rr0.col(0), r_norm2 = rz_rr0.col(1);
  const Eigen::Array3d threshold = (tolerance * tolerance) * blocked_sums(threads, n, [&](std::int64_t v, Sums& sum) {
                                                                 sum.col(0) += B.row(v).array().transpose() * B.row(v).array().transpose();
                                                               }).col(0).max(1e-300);
  const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, n));
  for (int it = 0; it < max_iterations; ++it) {
    // A converged column is frozen (step 0) so that 0/0 never appears.
    const Eigen::Array3d active = (r_norm2 > threshold).cast<double>();
    if ((active == 0).all()) return it;
    const Eigen::Array3d step = active * rz / apply(p, Ap).max(1e-300);
    const Sums rz_rr = blocked_sums(threads, n, [&](std::int64_t v, Sums& sum) {
      X.row(v) += (step * p.row(v).array().transpose()).transpose().matrix();
      r.row(v) -= (step * Ap.row(v).array().transpose()).transpose().matrix();
      const Eigen::Array3d z = inv_diag(v) * r.row(v).array().transpose();
      sum.col(0) += r.row(v).array().transpose() * z;
      sum.col(1) += r.row(v).array().transpose() * r.row(v).array().transpose();
    });
    const Eigen::Array3d beta = active * rz_rr.col(0) / rz.max(1e-300);
    chunked(threads, n, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t v = begin; v < end; ++v) {
        const Eigen::Array3d z = inv_diag(v) * r.row(v).array().transpose();
        p.row(v) = (z + beta * p.row(v).array().transpose()).transpose().matrix();
      }
    });
    rz = active * rz_rr.col(0) + (1 - active) * rz;
    r_norm2 = rz_rr.col(1);
  }
  return -1;
}

// jacobi_cg on M X = B from X to a relative residual of 1e-10 per column; throws SolverError if
// it does not converge.
void solve_region(const RegionSystem& op, const Vertices& B, Vertices& X);

}  // namespace mdn::detail
