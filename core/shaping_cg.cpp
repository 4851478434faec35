#include "core/shaping_cg.h"

#include <algorithm>
#include <functional>

#include "core/errors.h"
#include "core/parallel.h"

namespace mdn::detail {

namespace {
using Row4f = Eigen::Array4f;
using Ref4f = Eigen::Map<Row4f, Eigen::Aligned16>;
using ConstRef4f = Eigen::Map<const Row4f, Eigen::Aligned16>;
// The signed sum over v's incident edges of the 4-float rows of s: the +1 entries, less the
// -1 entries (two independent sums, no multiply by the sign). Raw pointers and local sums, so
// that nothing is reloaded or stored inside the loops.
inline Row4f gather(const ShapingIncidence& op, const float* s, std::int64_t v) {
  const std::int32_t* edges = op.edges->data();
  const std::int32_t begin = (*op.offsets)[static_cast<std::size_t>(v)], split = (*op.split)[static_cast<std::size_t>(v)],
                     end = (*op.offsets)[static_cast<std::size_t>(v) + 1];
  Row4f plus = Row4f::Zero(), minus = Row4f::Zero();
  for (std::int32_t k = begin; k < split; ++k) plus += ConstRef4f(s + 4 * std::int64_t{edges[k] >> 1});
  for (std::int32_t k = split; k < end; ++k) minus += ConstRef4f(s + 4 * std::int64_t{edges[k] >> 1});
  return plus - minus;
}

Eigen::Array3d xyz(const Row4f& a) { return a.head<3>().cast<double>(); }
Row4f to4f(const Eigen::Array3d& a) {
  return Row4f(static_cast<float>(a(0)), static_cast<float>(a(1)), static_cast<float>(a(2)), 0.0f);
}
}  // namespace

void SingleCG::prepare(const ShapingIncidence& op, double alpha, const Eigen::VectorXd& weights,
                       const Eigen::VectorXd& inv_diag) {
  const auto E = op.topo->num_interior_edges();
  const auto n = static_cast<std::int64_t>(op.topo->num_vertices);
  ws_.resize(static_cast<std::size_t>(E));
  chunked(op.executor, E, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t e = begin; e < end; ++e) ws_[static_cast<std::size_t>(e)] = static_cast<float>(alpha * (weights.size() ? weights(e) : 1.0));
  });
  inv_diag_.resize(static_cast<std::size_t>(n));
  chunked(op.executor, n, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t v = begin; v < end; ++v) inv_diag_[static_cast<std::size_t>(v)] = static_cast<float>(inv_diag(v));
  });
  // Every row of these is written, all four lanes, before it is read (initial_residual, apply):
  // kept from the last solve, not cleared.
  for (auto* v : {&s_, &r_, &p_, &ap_}) v->resize(static_cast<std::size_t>(4 * (v == &s_ ? E : n)));
}

// r = P - A x0 = (P - x0) - alpha D^T W D x0, x0 = start or P (then r = -alpha D^T W D P), with
// S(e) and P - x0 formed in double (the coordinates are ~1 and S(e) ~ an edge length: in float
// the difference would lose four digits), then rounded; p = z = D^-1 r. Returns r . z and
// r . r in double.
Sums SingleCG::initial_residual(const ShapingIncidence& op, const Vertices& P, const Vertices* start, double alpha,
                                const Eigen::VectorXd& weights) {
  const auto& ie = op.topo->interior_edges;
  const Vertices& x0 = start ? *start : P;
  chunked(op.executor, op.topo->num_interior_edges(), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t e = begin; e < end; ++e) {
      const double w = alpha * (weights.size() ? weights(e) : 1.0);
      const Eigen::RowVector3d se = w * (x0.row(ie(e, 0)) - x0.row(ie(e, 1)) + x0.row(ie(e, 2)) - x0.row(ie(e, 3)));
      Ref4f(s_.data() + 4 * e) << static_cast<float>(se(0)), static_cast<float>(se(1)), static_cast<float>(se(2)), 0.0f;
    }
  });
  return blocked_sums(op.executor, P.rows(), [&](std::int64_t v, Sums& sum) {
    Ref4f r(r_.data() + 4 * v), p(p_.data() + 4 * v);
    if (start)
      r = to4f((P.row(v) - start->row(v)).array().transpose()) - gather(op, s_.data(), v);
    else
      r = -gather(op, s_.data(), v);
    p = inv_diag_[static_cast<std::size_t>(v)] * r;
    sum.col(0) += xyz(r) * xyz(p);
    sum.col(1) += xyz(r) * xyz(r);
  });
}

// Ap = A p = p + D^T (ws .* (D p)), all in float; returns p . Ap in double.
Eigen::Array3d SingleCG::apply(const ShapingIncidence& op) {
  const auto& ie = op.topo->interior_edges;
  chunked(op.executor, op.topo->num_interior_edges(), [&](std::int64_t begin, std::int64_t end) {
    const float* p = p_.data();
    const float* ws = ws_.data();
    const std::int32_t* quad = ie.data();  // row-major #E x 4
    float* s = s_.data();
    for (std::int64_t e = begin; e < end; ++e) {
      const std::int32_t* q = quad + 4 * e;
      Ref4f(s + 4 * e) = ws[e] * (ConstRef4f(p + 4 * std::int64_t{q[0]}) - ConstRef4f(p + 4 * std::int64_t{q[1]}) +
                                  ConstRef4f(p + 4 * std::int64_t{q[2]}) - ConstRef4f(p + 4 * std::int64_t{q[3]}));
    }
  });
  const float* s = s_.data();
  return blocked_sums(op.executor, op.topo->num_vertices, [&](std::int64_t v, Sums& sum) {
           const ConstRef4f p(p_.data() + 4 * v);
           Ref4f ap(ap_.data() + 4 * v);
           ap = p + gather(op, s, v);
           sum.col(0) += xyz(p) * xyz(ap);
         }).col(0);
}

// x += step p (double), r -= step Ap (float); returns r . z and r . r, z = D^-1 r.
Sums SingleCG::step(const ShapingIncidence& op, const Eigen::Array3d& step, Vertices& x) {
  const Row4f step_f = to4f(step);
  const float *p = p_.data(), *ap = ap_.data(), *inv_diag = inv_diag_.data();
  float* r = r_.data();
  double* xd = x.data();  // row-major #V x 3
  return blocked_sums(op.executor, x.rows(), [&](std::int64_t v, Sums& sum) {
    const Row4f pv = ConstRef4f(p + 4 * v);
    for (int c = 0; c < 3; ++c) xd[3 * v + c] += step(c) * static_cast<double>(pv[c]);
    Ref4f rv(r + 4 * v);
    rv -= step_f * ConstRef4f(ap + 4 * v);
    const Row4f z = inv_diag[v] * rv;
    sum.col(0) += xyz(rv) * xyz(z);
    sum.col(1) += xyz(rv) * xyz(rv);
  });
}

int SingleCG::solve(const ShapingIncidence& op, const Vertices& P, double alpha, const Eigen::VectorXd& weights,
                    const Eigen::VectorXd& inv_diag, double tolerance, int max_iterations, Vertices& x, bool from_x) {
  const Eigen::Index n = P.rows();
  prepare(op, alpha, weights, inv_diag);
  if (!from_x) x = P;
  const Sums rz_rr0 = initial_residual(op, P, from_x ? &x : nullptr, alpha, weights);
  Eigen::Array3d rz = rz_rr0.col(0), r_norm2 = rz_rr0.col(1);
  const Eigen::Array3d threshold =
      (tolerance * tolerance) * blocked_sums(op.executor, n, [&](std::int64_t v, Sums& sum) {
                                  sum.col(0) += P.row(v).array().transpose().square();
                                }).col(0).max(1e-300);
  for (int it = 0; it < max_iterations; ++it) {
    const Eigen::Array3d active = (r_norm2 > threshold).cast<double>();  // converged columns are frozen
    if ((active == 0).all()) return it;
    const Eigen::Array3d pAp = apply(op);
    const Sums rz_rr = step(op, active * rz / pAp.max(1e-300), x);
    const Eigen::Array3d rz_new = rz_rr.col(0);
    const Row4f beta = to4f(active * rz_new / rz.max(1e-300));
    chunked(op.executor, n, [&](std::int64_t begin, std::int64_t end) {
      const float *r = r_.data(), *inv_diag = inv_diag_.data();
      float* p = p_.data();
      for (std::int64_t v = begin; v < end; ++v) Ref4f(p + 4 * v) = inv_diag[v] * ConstRef4f(r + 4 * v) + beta * ConstRef4f(p + 4 * v);
    });
    rz = active * rz_new + (1 - active) * rz;
    r_norm2 = rz_rr.col(1);
  }
  return max_iterations;
}

void SingleCG::release() {
  for (auto* v : {&ws_, &s_, &r_, &p_, &ap_, &inv_diag_}) *v = std::vector<float>();
}

// Eq. 2 (decision 38): decision 4's relative residual.
constexpr double kRegionTolerance = 1e-10;
void solve_region(const RegionSystem& op, const Vertices& B, Vertices& X) {
  const Eigen::Index m = B.rows();
  Eigen::VectorXd inv_diag(m);
  chunked(op.executor, m, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) inv_diag(r) = 1.0 / op.diagonal(r);
  });
  Vertices y(m, 3), r, p, Ap;
  // M x = x + beta L^T (L x), and x . M x in the same sweep.
  const auto apply = [&](const Vertices& x, Vertices& Mx) {
    op.laplacian(x, y);
    return blocked_sums(op.executor, m, [&](std::int64_t i, Sums& sum) {
             Mx.row(i) = x.row(i) + op.beta * op.transpose_row(i, y);
             sum.col(0) += x.row(i).array().transpose() * Mx.row(i).array().transpose();
           }).col(0).eval();
  };
  if (jacobi_cg(op.executor, apply, B, inv_diag, kRegionTolerance, X, r, p, Ap) < 0)
    throw SolverError("conjugate gradients did not converge on the region pre-filter (Eq. 2)");
}

}  // namespace mdn::detail
