// Single-precision conjugate gradients for the pre-filter's systems (I + alpha D^T W D) x = P
// (Eq. 1, Eq. 3), internal to ShapingSolver (core/README.md, decision 37). The operator's
// products, the work vectors and the preconditioner are floats (4 per row, the fourth 0); the
// dot products are summed in double with decision 11's fixed blocking, and the iterate x is
// double. ShapingSolver checks the true residual in double afterwards and continues in double
// where it is above the tolerance.
#pragma once

#include <Eigen/Core>
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
  using Sums = Eigen::Array<double, 3, 2>;
  void prepare(const ShapingIncidence& op, double alpha, const Eigen::VectorXd& weights);
  Sums initial_residual(const ShapingIncidence& op, const Vertices& P, double alpha, const Eigen::VectorXd& weights);
  Eigen::Array3d apply(const ShapingIncidence& op);
  Sums step(const ShapingIncidence& op, const Eigen::Array3d& step, Vertices& x);
  std::vector<float> ws_, s_, r_, p_, ap_, inv_diag_;
};

}  // namespace mdn::detail
