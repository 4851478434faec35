#include "core/prefilter.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "core/errors.h"
#include "core/progress.h"

namespace mdn {

namespace {
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
constexpr double kDegToRad = std::numbers::pi / 180.0;
// Coefficients of S(e) = p_e1 - p_e2 + p_e3 - p_e4 over the row (e1, e2, e3, e4).
constexpr double kShape[4] = {1, -1, 1, -1};
}  // namespace

// ---------------------------------------------------------------------------------------
// ShapingSolver: A = I + alpha D^T W D (Eq. 1 with W = I, Eq. 3 with W = diag(w_e)).
// The pattern of A depends on the topology only: it is assembled once, and every solve
// only rewrites the values through a precomputed edge -> value-slot map.
struct ShapingSolver::Impl {
  LinearSolver kind;
  double cg_tolerance;
  const Topology* topo;
  SparseMatrix A;
  std::vector<int> diagonal_slot;           // #V
  std::vector<int> edge_slot;               // #E x 16, slot of (row a, col b) for a, b in 0..3
  Eigen::SimplicialLDLT<SparseMatrix> ldlt;
  bool analyzed = false;
  Vertices previous;                        // CG warm start

  Impl(const Topology& t, LinearSolver k, double tol) : kind(k), cg_tolerance(tol), topo(&t) {
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

  Vertices solve(const Vertices& P, double alpha, const Eigen::VectorXd& weights) {
    assemble(alpha, weights);
    const Eigen::MatrixXd rhs = P;  // column-major copy: three right-hand sides
    Eigen::MatrixXd x(P.rows(), 3);
    if (kind == LinearSolver::Ldlt) {
      if (!analyzed) {
        ldlt.analyzePattern(A);  // symbolic analysis (AMD ordering) shared by every solve
        analyzed = true;
      }
      ldlt.factorize(A);
      if (ldlt.info() != Eigen::Success) throw SolverError("LDLT factorisation of the pre-filter system failed");
      x = ldlt.solve(rhs);
    } else {
      Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
      cg.setTolerance(cg_tolerance);
      cg.setMaxIterations(std::max<Eigen::Index>(1000, P.rows()));
      cg.compute(A);
      // Warm start from the previous solution (the systems differ little between
      // iterations), else from the right-hand side itself (A is close to I).
      const Eigen::MatrixXd guess = previous.rows() == P.rows() ? Eigen::MatrixXd(previous) : rhs;
      for (int c = 0; c < 3; ++c) {
        x.col(c) = cg.solveWithGuess(rhs.col(c), guess.col(c));
        if (cg.info() != Eigen::Success)
          throw SolverError("conjugate gradients did not converge on the pre-filter system");
      }
    }
    if (!x.allFinite()) throw SolverError("pre-filter solve produced non-finite positions");
    Vertices out = x;
    if (kind == LinearSolver::ConjugateGradient) previous = out;
    return out;
  }
};

ShapingSolver::ShapingSolver(const Topology& topo, LinearSolver kind, double cg_tolerance)
    : impl_(std::make_unique<Impl>(topo, kind, cg_tolerance)) {}
ShapingSolver::~ShapingSolver() = default;
Vertices ShapingSolver::solve(const Vertices& P, double alpha, const Eigen::VectorXd& weights) {
  return impl_->solve(P, alpha, weights);
}

// Eq. 1: argmin sum ||p~_i - p_i||^2 + alpha sum_e ||S(e)||^2  <=>  (I + alpha D^T D) P~ = P.
Vertices initial_prefilter(const Vertices& P, const Topology& topo, double alpha, LinearSolver kind) {
  ShapingSolver solver(topo, kind, 1e-10);
  return solver.solve(P, alpha, {});
}

// Eq. 4. A degenerate face has no normal; its edges get w_e = 1 (smoothed like flat ones).
Eigen::VectorXd anisotropic_edge_weights(const Vertices& P, const Triangles& F, const Topology& topo,
                                         double sigma_theta_deg, double b) {
  const Vertices N = face_normals(P, F);
  const double inv = 1.0 / (1.0 - std::cos(sigma_theta_deg * kDegToRad));
  const double log_b = std::log(b);
  Eigen::VectorXd w(topo.num_interior_edges());
  for (Eigen::Index e = 0; e < w.size(); ++e) {
    const auto n1 = N.row(topo.edge_faces(e, 0)), n2 = N.row(topo.edge_faces(e, 1));
    if (n1.squaredNorm() == 0 || n2.squaredNorm() == 0) {
      w(e) = 1;
      continue;
    }
    const double cos_theta = std::clamp(n1.dot(n2), -1.0, 1.0);
    w(e) = std::exp(-log_b * (1.0 - cos_theta) * inv);  // b^-((1 - cos theta) / (1 - cos sigma_theta))
  }
  return w;
}

// Eq. 3, iterated: each step anchored to the previous output, w_e recomputed from it.
Vertices anisotropic_prefilter(const Vertices& P, const Triangles& F, const Topology& topo,
                               const DenoiseParams& params, ShapingSolver* solver, ProgressObserver* progress) {
  std::unique_ptr<ShapingSolver> own;
  if (!solver) {
    own = std::make_unique<ShapingSolver>(topo, params.solver, params.cg_tolerance);
    solver = own.get();
  }
  Vertices current = P;
  for (int it = 0; it < params.n_aniso; ++it) {
    if (progress) {
      if (progress->cancel_requested()) throw CancelledError();
      progress->on_progress(Stage::AnisotropicPrefilter, static_cast<double>(it) / params.n_aniso);
    }
    const Eigen::VectorXd w = anisotropic_edge_weights(current, F, topo, params.sigma_theta, params.b);
    current = solver->solve(current, params.alpha, w);
  }
  return current;
}

double fold_ratio(const Vertices& P, const Triangles& F, const Topology& topo, double fold_angle_deg) {
  const auto E = topo.num_interior_edges();
  if (E == 0) return 0;
  const Vertices N = face_normals(P, F);
  const double cos_fold = std::cos(fold_angle_deg * kDegToRad);
  std::int64_t folded = 0;
  for (Eigen::Index e = 0; e < E; ++e) {
    const auto n1 = N.row(topo.edge_faces(e, 0)), n2 = N.row(topo.edge_faces(e, 1));
    if (n1.squaredNorm() == 0 || n2.squaredNorm() == 0) continue;
    if (n1.dot(n2) < cos_fold) ++folded;  // angle between the normals > fold angle
  }
  return static_cast<double>(folded) / static_cast<double>(E);
}

// Sec. 4.2: K-means over (centroid, area).
FaceClusters cluster_faces(const Vertices& P, const Triangles& F, int k, std::uint64_t seed, int max_iterations) {
  const auto nf = static_cast<std::size_t>(F.rows());
  FaceClusters out;
  out.label.assign(nf, 0);
  out.mean_area.assign(static_cast<std::size_t>(k), 0);
  if (nf == 0 || k < 1) return out;

  const Vertices C = face_centroids(P, F);
  const Eigen::VectorXd A = face_areas(P, F);
  // Standardise: one common scale for the three centroid coordinates (keeps distances
  // isotropic), area by its own standard deviation; otherwise, in a unit box, areas
  // (~1e-5) would not count at all (NOTES reading 6).
  const Eigen::RowVector3d c_mean = C.colwise().mean();
  const double c_scale = std::sqrt((C.rowwise() - c_mean).squaredNorm() / (3.0 * static_cast<double>(nf)));
  const double a_mean = A.mean();
  const double a_scale = std::sqrt((A.array() - a_mean).square().sum() / static_cast<double>(nf));
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> X(static_cast<Eigen::Index>(nf), 4);
  X.leftCols<3>() = (C.rowwise() - c_mean) / (c_scale > 0 ? c_scale : 1.0);
  X.col(3) = (A.array() - a_mean) / (a_scale > 0 ? a_scale : 1.0);

  // k-means++ seeding with a fixed seed: deterministic.
  std::mt19937_64 rng(seed);
  auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> centers(k, 4);
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

  // Lloyd iterations until no label changes.
  std::vector<std::int64_t> count(static_cast<std::size_t>(k));
  for (int it = 0; it < max_iterations; ++it) {
    bool changed = false;
    for (std::size_t i = 0; i < nf; ++i) {
      int best = 0;
      double best_d = std::numeric_limits<double>::infinity();
      for (int c = 0; c < k; ++c) {
        const double d = (X.row(static_cast<Eigen::Index>(i)) - centers.row(c)).squaredNorm();
        if (d < best_d) best_d = d, best = c;
      }
      if (out.label[i] != best) {
        out.label[i] = best;
        changed = true;
      }
    }
    if (!changed && it > 0) break;
    centers.setZero();
    std::fill(count.begin(), count.end(), 0);
    for (std::size_t i = 0; i < nf; ++i) {
      centers.row(out.label[i]) += X.row(static_cast<Eigen::Index>(i));
      ++count[static_cast<std::size_t>(out.label[i])];
    }
    for (int c = 0; c < k; ++c)
      if (count[static_cast<std::size_t>(c)] > 0) centers.row(c) /= static_cast<double>(count[static_cast<std::size_t>(c)]);
  }

  std::fill(count.begin(), count.end(), 0);
  for (std::size_t i = 0; i < nf; ++i) {
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
  return out;
}

// Eq. 2 on the vertices of `faces`; all other vertices are fixed and enter the
// Laplacian rows of their unknown neighbours as constants.
Vertices region_prefilter(const Vertices& P, const Triangles& F, const Topology& topo,
                          const std::vector<std::int32_t>& faces, double beta, std::int64_t* num_unknowns) {
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

  // L_U: one row per unknown u: x_u - mean of its one-ring; fixed neighbours go to c.
  const auto m = static_cast<Eigen::Index>(vertices.size());
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(m, 3);
  Eigen::MatrixXd P_u(m, 3);
  for (Eigen::Index r = 0; r < m; ++r) {
    const auto v = static_cast<std::size_t>(vertices[static_cast<std::size_t>(r)]);
    P_u.row(r) = P.row(static_cast<Eigen::Index>(v));
    const std::int32_t begin = topo.vv_offsets[v], end = topo.vv_offsets[v + 1];
    if (begin == end) continue;  // isolated: no Laplacian row
    const double inv_deg = 1.0 / static_cast<double>(end - begin);
    triplets.emplace_back(r, r, 1.0);
    for (std::int32_t s = begin; s < end; ++s) {
      const auto j = static_cast<std::size_t>(topo.vv_vertices[static_cast<std::size_t>(s)]);
      if (unknown[j] >= 0)
        triplets.emplace_back(r, unknown[j], -inv_deg);
      else
        c.row(r) -= inv_deg * P.row(static_cast<Eigen::Index>(j));
    }
  }
  SparseMatrix L(m, m);
  L.setFromTriplets(triplets.begin(), triplets.end());
  SparseMatrix I(m, m);
  I.setIdentity();
  // argmin ||X - P_U||^2 + beta ||L X + c||^2  <=>  (I + beta L^T L) X = P_U - beta L^T c.
  const SparseMatrix M = I + beta * SparseMatrix(L.transpose() * L);
  Eigen::SimplicialLDLT<SparseMatrix> ldlt(M);
  if (ldlt.info() != Eigen::Success) throw SolverError("LDLT factorisation of the region pre-filter (Eq. 2) failed");
  const Eigen::MatrixXd X = ldlt.solve(Eigen::MatrixXd(P_u - beta * (L.transpose() * c)));
  if (!X.allFinite()) throw SolverError("region pre-filter (Eq. 2) produced non-finite positions");
  for (Eigen::Index r = 0; r < m; ++r) out.row(vertices[static_cast<std::size_t>(r)]) = X.row(r);
  return out;
}

}  // namespace mdn
