#include "core/prefilter.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <functional>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/errors.h"
#include "core/fast_math.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/shaping_cg.h"

namespace mdn {

namespace {
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
constexpr double kDegToRad = std::numbers::pi / 180.0;
// Coefficients of S(e) = p_e1 - p_e2 + p_e3 - p_e4 over the row (e1, e2, e3, e4).
constexpr double kShape[4] = {1, -1, 1, -1};
}  // namespace

// ---------------------------------------------------------------------------------------
// ShapingSolver: A = I + alpha D^T W D (Eq. 1 with W = I, Eq. 3 with W = diag(w_e)).
//
// Ldlt: the pattern of A depends on the topology only. It is assembled once, every solve
// rewrites the values through a precomputed edge -> value-slot map, and the symbolic
// analysis (AMD ordering) is shared by Eq. 1 and all Eq. 3 steps.
// ConjugateGradient: matrix-free. A x = x + alpha D^T (w .* (D x)) costs one pass over the
// edges; A is very well conditioned (its eigenvalues lie in [1, 1 + 16 alpha max w]), so
// Jacobi-preconditioned CG started from the anchor P (the previous iterate, for Eq. 3)
// converges in a few dozen passes. Serial, hence deterministic.
struct ShapingSolver::Impl {
  LinearSolver kind;
  double cg_tolerance;
  const Topology* topo;
  Executor* executor;
  // ConjugateGradient only: vertex -> (edge, coefficient of the vertex in S(e)), CSR, so that
  // D^T s is a gather per vertex (parallel, fixed summation order). An entry is 2 e + 1 where
  // the coefficient is -1 and 2 e where it is +1: 4 bytes per incidence, not 12. A vertex's +1
  // entries come first, up to ve_split[v] (build_incidence).
  std::vector<std::int32_t> ve_offsets, ve_edges, ve_split;
  static Eigen::Index edge_of(std::int32_t entry) { return entry >> 1; }
  static double coef_of(std::int32_t entry) { return (entry & 1) ? -1.0 : 1.0; }
  // Ldlt only.
  SparseMatrix A;
  std::vector<int> diagonal_slot;           // #V
  std::vector<int> edge_slot;               // #E x 16, slot of (row a, col b) for a, b in 0..3
  Eigen::SimplicialLDLT<SparseMatrix> ldlt;
  bool analyzed = false;
  int last_iterations = 0;
  // CG's work vectors, kept across solves: Eq. 1 and every Eq. 3 step allocate nothing
  // (decision 29). z = D^-1 r is not stored: it is formed where it is read, the same product.
  Vertices s_buf, r_buf, p_buf, Ap_buf;
  Eigen::VectorXd inv_diag_buf;
  // CG runs in single precision first, then checks and polishes in double (decision 37).
  detail::SingleCG single;

  Impl(const Topology& t, LinearSolver k, double tol, Executor* ex)
      : kind(k), cg_tolerance(tol), topo(&t), executor(ex) {
    if (kind == LinearSolver::Ldlt)
      build_pattern();
    else
      build_incidence();
  }

  void build_incidence() {
    const Topology& t = *topo;
    const auto E = t.num_interior_edges();
    std::vector<std::int32_t> count(static_cast<std::size_t>(t.num_vertices) + 1, 0);
    for (Eigen::Index e = 0; e < E; ++e)
      for (int a = 0; a < 4; ++a) ++count[static_cast<std::size_t>(t.interior_edges(e, a)) + 1];
    ve_offsets.assign(count.size(), 0);
    for (std::size_t v = 1; v < count.size(); ++v) ve_offsets[v] = ve_offsets[v - 1] + count[v];
    ve_edges.resize(static_cast<std::size_t>(4 * E));
    std::vector<std::int32_t> cursor(ve_offsets.begin(), ve_offsets.end() - 1);
    for (Eigen::Index e = 0; e < E; ++e)
      for (int a = 0; a < 4; ++a) {
        const auto slot = static_cast<std::size_t>(cursor[static_cast<std::size_t>(t.interior_edges(e, a))]++);
        ve_edges[slot] = static_cast<std::int32_t>(2 * e + (kShape[a] < 0 ? 1 : 0));
      }
    // Each vertex's +1 entries first, then its -1 entries (each in edge order), split at
    // ve_split[v]: the single-precision product sums them without a multiply by the sign.
    ve_split.resize(static_cast<std::size_t>(t.num_vertices));
    for (std::size_t v = 0; v < ve_split.size(); ++v) {
      const auto first = ve_edges.begin() + ve_offsets[v], last = ve_edges.begin() + ve_offsets[v + 1];
      ve_split[v] = static_cast<std::int32_t>(std::stable_partition(first, last, [](std::int32_t x) { return (x & 1) == 0; }) - ve_edges.begin());
    }
  }

  // Serial below detail::kParallelRows vertices, chunked above (shaping_cg.h).
  Executor* threads() const { return detail::threads_for(executor, topo->num_vertices); }
  void parallel(std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& fn) const {
    detail::chunked(threads(), n, fn);
  }

  // Column sums in decision 11's fixed blocks (shaping_cg.h), on this solver's threads.
  using Sums = detail::Sums;
  template <class Body>
  Sums blocked_sums(std::int64_t n, const Body& body) const {
    return detail::blocked_sums(threads(), n, body);
  }

  void build_pattern() {
    const Topology& t = *topo;
    const auto n = static_cast<Eigen::Index>(t.num_vertices);
    const auto E = t.num_interior_edges();
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(static_cast<std::size_t>(n + 16 * E));
    for (Eigen::Index i = 0; i < n; ++i) triplets.emplace_back(i, i, 1.0);
    for (Eigen::Index e = 0; e < E; ++e)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) triplets.emplace_back(t.interior_edges(e, a), t.interior_edges(e, b), 1.0);
    A.resize(n, n);
    A.setFromTriplets(triplets.begin(), triplets.end());
    A.makeCompressed();
    auto slot = [&](int row, int col) {
      const int* begin = A.innerIndexPtr() + A.outerIndexPtr()[col];
      const int* end = A.innerIndexPtr() + A.outerIndexPtr()[col + 1];
      return static_cast<int>(std::lower_bound(begin, end, row) - A.innerIndexPtr());
    };
    diagonal_slot.resize(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) diagonal_slot[static_cast<std::size_t>(i)] = slot(static_cast<int>(i), static_cast<int>(i));
    edge_slot.resize(static_cast<std::size_t>(16 * E));
    for (Eigen::Index e = 0; e < E; ++e)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          edge_slot[static_cast<std::size_t>(16 * e + 4 * a + b)] = slot(t.interior_edges(e, a), t.interior_edges(e, b));
  }

  void assemble(double alpha, const Eigen::VectorXd& weights) {
    double* values = A.valuePtr();
    std::fill(values, values + A.nonZeros(), 0.0);
    for (int s : diagonal_slot) values[s] += 1.0;
    const auto E = topo->num_interior_edges();
    for (Eigen::Index e = 0; e < E; ++e) {
      const double w = alpha * (weights.size() ? weights(e) : 1.0);
      const int* slots = &edge_slot[static_cast<std::size_t>(16 * e)];
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) values[slots[4 * a + b]] += w * kShape[a] * kShape[b];
    }
  }

  Vertices solve_ldlt(const Vertices& P, double alpha, const Eigen::VectorXd& weights) {
    assemble(alpha, weights);
    if (!analyzed) {
      ldlt.analyzePattern(A);
      analyzed = true;
    }
    ldlt.factorize(A);
    if (ldlt.info() != Eigen::Success) throw SolverError("LDLT factorisation of the pre-filter system failed");
    const Eigen::MatrixXd x = ldlt.solve(Eigen::MatrixXd(P));
    return Vertices(x);
  }

  // y = A x = x + alpha D^T W D x: s_e = alpha w_e S(e) per edge, then a gather per vertex.
  // Returns x . y (column-wise, in decision 11's blocks). Measured and not kept (decision 29): forming
  // s_e at each of its four vertices instead of storing it (bit-identical) cost 8% more CPU in
  // the pre-filter at 75k faces and 23% on Fandisk, and saved 3% at 1.2M: the arrays sit in L3
  // here, and the arithmetic is what the pass pays for.
  Eigen::Array3d apply(const Vertices& x, double alpha, const Eigen::VectorXd& weights, Vertices& s, Vertices& y) const {
    const auto E = topo->num_interior_edges();
    const auto& ie = topo->interior_edges;
    parallel(E, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t e = begin; e < end; ++e) {
        const double w = alpha * (weights.size() ? weights(e) : 1.0);
        s.row(e) = w * (x.row(ie(e, 0)) - x.row(ie(e, 1)) + x.row(ie(e, 2)) - x.row(ie(e, 3)));
      }
    });
    return blocked_sums(x.rows(), [&](std::int64_t v, Sums& sum) {
             Eigen::RowVector3d acc = x.row(v);
             for (std::int32_t k = ve_offsets[static_cast<std::size_t>(v)]; k < ve_offsets[static_cast<std::size_t>(v) + 1]; ++k)
               acc += coef_of(ve_edges[static_cast<std::size_t>(k)]) * s.row(edge_of(ve_edges[static_cast<std::size_t>(k)]));
             y.row(v) = acc;
             sum.col(0) += x.row(v).array().transpose() * acc.array().transpose();
           }).col(0);
  }

  // Jacobi preconditioner into inv_diag_buf: diag(A)_v = 1 + alpha sum_{e containing v} w_e
  // (coefficients +-1). Formed once per solve, for the float CG and the double check.
  void jacobi_preconditioner(double alpha, const Eigen::VectorXd& weights) {
    Eigen::VectorXd& inv_diag = inv_diag_buf;
    inv_diag.resize(topo->num_vertices);
    parallel(inv_diag.size(), [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t v = begin; v < end; ++v) {
        double d = 1;
        for (std::int32_t k = ve_offsets[static_cast<std::size_t>(v)]; k < ve_offsets[static_cast<std::size_t>(v) + 1]; ++k)
          d += alpha * (weights.size() ? weights(edge_of(ve_edges[static_cast<std::size_t>(k)])) : 1.0);
        inv_diag(v) = 1.0 / d;
      }
    });
  }

  // The shared double CG (shaping_cg.h) from x (the anchor P, or single's result): the first
  // residual is formed in double, so a start that already meets the tolerance returns after one
  // product. Needs jacobi_preconditioner(alpha, weights) first.
  Vertices solve_cg(const Vertices& P, double alpha, const Eigen::VectorXd& weights, Vertices x) {
    s_buf.resize(topo->num_interior_edges(), 3);
    const auto apply_A = [&](const Vertices& v, Vertices& Av) { return apply(v, alpha, weights, s_buf, Av); };
    last_iterations = detail::jacobi_cg(threads(), apply_A, P, inv_diag_buf, cg_tolerance, x, r_buf, p_buf, Ap_buf);
    if (last_iterations < 0) throw SolverError("conjugate gradients did not converge on the pre-filter system");
    return x;
  }

  Vertices solve(const Vertices& P, double alpha, const Eigen::VectorXd& weights, std::optional<Vertices> start) {
    if (weights.size() != 0 && weights.size() != topo->num_interior_edges())
      throw std::invalid_argument("ShapingSolver: one weight per interior edge expected");
    Vertices x;
    if (kind == LinearSolver::Ldlt) {
      x = solve_ldlt(P, alpha, weights);
    } else {  // start from the anchor (A = I + (small), so P is already close) or the caller's start
      const detail::ShapingIncidence op{topo, &ve_offsets, &ve_edges, &ve_split, threads()};
      jacobi_preconditioner(alpha, weights);
      if (start) x = std::move(*start);
      const int single_iterations = single.solve(op, P, alpha, weights, inv_diag_buf, cg_tolerance, 1000, x, start.has_value());
      x = solve_cg(P, alpha, weights, std::move(x));
      last_iterations += single_iterations;
    }
    if (!x.allFinite()) throw SolverError("pre-filter solve produced non-finite positions");
    return x;
  }
};

ShapingSolver::ShapingSolver(const Topology& topo, LinearSolver kind, double cg_tolerance, Executor* executor)
    : impl_(std::make_unique<Impl>(topo, kind, cg_tolerance, executor)) {}
ShapingSolver::~ShapingSolver() = default;
Vertices ShapingSolver::solve(const Vertices& P, double alpha, const Eigen::VectorXd& weights,
                               std::optional<Vertices> start) {
  return impl_->solve(P, alpha, weights, std::move(start));
}
int ShapingSolver::last_iterations() const { return impl_->last_iterations; }
Executor* ShapingSolver::executor() const { return impl_->executor; }
void ShapingSolver::release_buffers() {
  impl_->s_buf = Vertices();
  impl_->r_buf = Vertices();
  impl_->p_buf = Vertices();
  impl_->Ap_buf = Vertices();
  impl_->inv_diag_buf = Eigen::VectorXd();
  impl_->single.release();
}

// Eq. 1: argmin sum ||p~_i - p_i||^2 + alpha sum_e ||S(e)||^2  <=>  (I + alpha D^T D) P~ = P.
Vertices initial_prefilter(const Vertices& P, const Topology& topo, double alpha, LinearSolver kind) {
  ShapingSolver solver(topo, kind, 1e-10);
  return solver.solve(P, alpha, {});
}

namespace {
// w_e = b^-((1 - cos theta) / (1 - cos sigma_theta)) from y_e = -ln b (1 - cos theta) / (1 - cos
// sigma_theta) <= 0, in place; y_e > 0 marks an edge with a degenerate face, whose w_e is 1.
// Branch-free so that it vectorises (the same IEEE operations as the scalar exp_nonpositive:
// no FMA contraction), compiled for AVX2 too and picked at run time.
MDN_AVX2_CLONE
void edge_weights_from_exponents(double* w, std::int64_t n) {
  for (std::int64_t e = 0; e < n; ++e) w[e] = w[e] > 0 ? 1.0 : detail::exp_nonpositive(w[e]);
}

// Eq. 4 into w (#E), with the face normals of P in N (both kept by the caller across passes),
// over the executor's threads if given. A degenerate face has no normal; its edges get w_e = 1
// (smoothed like flat ones). Per chunk: the exponents from the normals (gathers), then the exp
// over the chunk in one vectorised loop.
void edge_weights_into(const Vertices& P, const Triangles& F, const Topology& topo, double sigma_theta_deg, double b,
                       Executor* executor, Vertices& N, Eigen::VectorXd& w) {
  face_normals(P, F, N, executor);
  const double inv = 1.0 / (1.0 - std::cos(sigma_theta_deg * kDegToRad));
  const double log_b = std::log(b);  // b >= 1 (params.h), so the exponents are <= 0
  w.resize(topo.num_interior_edges());
  auto body = [&](std::int64_t begin, std::int64_t end) {
    for (Eigen::Index e = begin; e < end; ++e) {
      const auto n1 = N.row(topo.edge_faces(e, 0)), n2 = N.row(topo.edge_faces(e, 1));
      if (n1.squaredNorm() == 0 || n2.squaredNorm() == 0) {
        w(e) = 1;  // marks w_e = 1
        continue;
      }
      const double cos_theta = std::clamp(n1.dot(n2), -1.0, 1.0);
      w(e) = -log_b * (1.0 - cos_theta) * inv;
    }
    edge_weights_from_exponents(w.data() + begin, end - begin);
  };
  if (executor)
    executor->parallel_for(w.size(), 8192, body);
  else
    body(0, w.size());
}
}  // namespace

Eigen::VectorXd anisotropic_edge_weights(const Vertices& P, const Triangles& F, const Topology& topo,
                                         double sigma_theta_deg, double b) {
  Vertices N;
  Eigen::VectorXd w;
  edge_weights_into(P, F, topo, sigma_theta_deg, b, nullptr, N, w);
  return w;
}

// Eq. 3, iterated: each step anchored to the previous output, w_e recomputed from it. From the
// second pass on, CG starts from P_k + (P_k - P_k-1), the last pass's step repeated (decision
// 42): the weights change little from pass to pass, so the step does too, and the start is
// nearer the solution than the anchor (1.2M faces, heavy: 126 -> 104 CG iterations over 16
// passes).
Vertices anisotropic_prefilter(const Vertices& P, const Triangles& F, const Topology& topo,
                               const DenoiseParams& params, ShapingSolver* solver, ProgressObserver* progress,
                               const IterationHook& on_iteration) {
  std::unique_ptr<ShapingSolver> own;
  if (!solver) {
    own = std::make_unique<ShapingSolver>(topo, params.solver, params.cg_tolerance);
    solver = own.get();
  }
  Vertices current = P;
  Vertices previous;  // the last pass's anchor, then (in place) the next pass's start
  Vertices normals;   // reused by every pass
  Eigen::VectorXd w;
  if (on_iteration) on_iteration(0, current);
  for (int it = 0; it < params.n_aniso; ++it) {
    checkpoint(progress, Stage::AnisotropicPrefilter, static_cast<double>(it) / params.n_aniso);
    edge_weights_into(current, F, topo, params.sigma_theta, params.b, solver->executor(), normals, w);
    Vertices next;
    if (it == 0) {
      next = solver->solve(current, params.alpha, w);
    } else {
      previous = 2 * current - previous;  // taken over by the solve: no third array is held
      next = solver->solve(current, params.alpha, w, std::move(previous));
    }
    previous = std::move(current);
    current = std::move(next);
    if (on_iteration) on_iteration(it + 1, current);
  }
  return current;
}

double fold_ratio(const Vertices& P, const Triangles& F, const Topology& topo, double fold_angle_deg, Executor* executor) {
  const auto E = topo.num_interior_edges();
  if (E == 0) return 0;
  Vertices N;
  face_normals(P, F, N, executor);
  const double cos_fold = std::cos(fold_angle_deg * kDegToRad);
  std::int64_t folded = 0;
  for (Eigen::Index e = 0; e < E; ++e) {
    const auto n1 = N.row(topo.edge_faces(e, 0)), n2 = N.row(topo.edge_faces(e, 1));
    if (n1.squaredNorm() == 0 || n2.squaredNorm() == 0) continue;
    if (n1.dot(n2) < cos_fold) ++folded;  // angle between the normals > fold angle
  }
  return static_cast<double>(folded) / static_cast<double>(E);
}

// Eq. 2 on the vertices of `faces`; all other vertices are fixed and enter the
// Laplacian rows of their unknown neighbours as constants.
Vertices region_prefilter(const Vertices& P, const Triangles& F, const Topology& topo,
                          const std::vector<std::int32_t>& faces, double beta, std::int64_t* num_unknowns,
                          Executor* executor) {
  const auto nv = static_cast<std::size_t>(P.rows());
  std::vector<std::int32_t> unknown(nv, -1);
  std::vector<std::int32_t> vertices;
  for (std::int32_t f : faces)
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(F(f, k));
      if (unknown[v] < 0) {
        unknown[v] = 0;
        vertices.push_back(F(f, k));
      }
    }
  std::sort(vertices.begin(), vertices.end());
  for (std::size_t i = 0; i < vertices.size(); ++i) unknown[static_cast<std::size_t>(vertices[i])] = static_cast<std::int32_t>(i);
  if (num_unknowns) *num_unknowns = static_cast<std::int64_t>(vertices.size());
  Vertices out = P;
  if (vertices.empty()) return out;

  // L_U: one row per unknown r: x_r - mean of its one-ring; fixed neighbours go to c.
  const auto m = static_cast<Eigen::Index>(vertices.size());
  detail::RegionSystem op{&topo, &vertices, &unknown, Eigen::VectorXd(m), beta, detail::threads_for(executor, m), {}, {}};
  op.index_neighbours();
  Vertices c(m, 3), X(m, 3);
  detail::chunked(op.executor, m, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) {
      const auto v = static_cast<std::size_t>(vertices[static_cast<std::size_t>(r)]);
      X.row(r) = P.row(static_cast<Eigen::Index>(v));
      c.row(r).setZero();
      const std::int32_t deg = topo.vv_offsets[v + 1] - topo.vv_offsets[v];
      op.inv_deg(r) = deg > 0 ? 1.0 / static_cast<double>(deg) : 0.0;  // isolated: no Laplacian row
      for (std::int32_t s = topo.vv_offsets[v]; s < topo.vv_offsets[v + 1]; ++s) {
        const auto j = static_cast<std::size_t>(topo.vv_vertices[static_cast<std::size_t>(s)]);
        if (unknown[j] < 0) c.row(r) -= op.inv_deg(r) * P.row(static_cast<Eigen::Index>(j));
      }
    }
  });
  // argmin ||X - P_U||^2 + beta ||L X + c||^2  <=>  (I + beta L^T L) X = P_U - beta L^T c,
  // solved by CG from X = P_U (decision 38).
  Vertices B(m, 3);
  detail::chunked(op.executor, m, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) B.row(r) = X.row(r) - beta * op.transpose_row(r, c);
  });
  detail::solve_region(op, B, X);
  if (!X.allFinite()) throw SolverError("region pre-filter (Eq. 2) produced non-finite positions");
  for (Eigen::Index r = 0; r < m; ++r) out.row(vertices[static_cast<std::size_t>(r)]) = X.row(r);
  return out;
}

}  // namespace mdn
