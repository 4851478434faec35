// Single-precision conjugate gradients for the pre-filter's systems (I + alpha D^T W D) x = P
// (Eq. 1, Eq. 3), internal to ShapingSolver (core/README.md, decision 37). The operator's
// products, the work vectors and the preconditioner are floats (4 per row, the fourth 0); the
// dot products are summed in double with decision 11's fixed blocking, and the iterate x is
// double. ShapingSolver checks the true residual in double afterwards and continues in double
// where it is above the tolerance.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {
class Executor;
}

namespace mdn::detail {

// The matrix-free operator's incidence: vertex -> signed edge entries (2 e + 1 where the
// vertex's coefficient in S(e) is -1, 2 e where it is +1), CSR, each vertex's +1 entries
// before split[v] and its -1 entries from there; ShapingSolver builds it.
struct ShapingIncidence {
  const Topology* topo = nullptr;
  const std::vector<std::int32_t>* offsets = nullptr;
  const std::vector<std::int32_t>* edges = nullptr;
  const std::vector<std::int32_t>* split = nullptr;
  Executor* executor = nullptr;  // nullptr: serial
};

// Column sums of a sweep with a fixed blocking (decision 11): body(i, sums) runs for every row
// i of [0, n), block by block (kSumBlock rows), the blocks handed to run(blocks, fn, grain)
// (in parallel or not), and the blocks' sums are added in order, so the rounding does not
// depend on the number of threads. Shared by both CGs.
using Sums = Eigen::Array<double, 3, 2>;
constexpr std::int64_t kSumBlock = 2048;
template <class Run, class Body>
Sums blocked_sums(std::int64_t n, std::int64_t grain, const Run& run, const Body& body) {
  const std::int64_t blocks = (n + kSumBlock - 1) / kSumBlock;
  std::vector<Sums> partial(static_cast<std::size_t>(blocks), Sums::Zero());
  run(
      blocks,
      [&](std::int64_t begin, std::int64_t end) {
        for (std::int64_t blk = begin; blk < end; ++blk) {
          Sums sum = Sums::Zero();
          for (std::int64_t i = blk * kSumBlock; i < std::min(n, (blk + 1) * kSumBlock); ++i) body(i, sum);
          partial[static_cast<std::size_t>(blk)] = sum;
        }
      },
      grain);
  Sums total = Sums::Zero();
  for (const auto& p : partial) total += p;
  return total;
}

class SingleCG {
 public:
  // Jacobi-preconditioned CG on A x = P started from x = P, until the (recurrence) residual of
  // every column is at most tolerance x ||P column|| or after max_iterations. weights: #E, or
  // empty for W = I. Returns the iterations run; x is #V x 3.
  int solve(const ShapingIncidence& op, const Vertices& P, double alpha, const Eigen::VectorXd& weights,
            double tolerance, int max_iterations, Vertices& x);
  // Frees the work vectors (the next solve allocates them again).
  void release();

 private:
  void prepare(const ShapingIncidence& op, double alpha, const Eigen::VectorXd& weights);
  Sums initial_residual(const ShapingIncidence& op, const Vertices& P, double alpha, const Eigen::VectorXd& weights);
  Eigen::Array3d apply(const ShapingIncidence& op);
  Sums step(const ShapingIncidence& op, const Eigen::Array3d& step, Vertices& x);
  std::vector<float> ws_, s_, r_, p_, ap_, inv_diag_;
};

}  // namespace mdn::detail
