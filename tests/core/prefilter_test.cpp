#include "core/prefilter.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <random>

#include "core/noise.h"
#include "core/parallel.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

Topology topology_of(const TriMesh& m) { return Topology::build(m.F, static_cast<std::int32_t>(m.V.rows())); }

// Eq. 1 fixed point: on a grid split along one diagonal every edge's quad is a
// parallelogram, so S(e) = 0 everywhere and the minimiser is the input itself.
TEST(InitialPrefilter, ParallelogramGridIsAFixedPoint) {
  const TriMesh m = test::plane(6, 1.0, /*alternate=*/false);
  const Topology t = topology_of(m);
  for (LinearSolver kind : {LinearSolver::Ldlt, LinearSolver::ConjugateGradient}) {
    const Vertices out = initial_prefilter(m.V, t, 0.2, kind);
    EXPECT_LT((out - m.V).cwiseAbs().maxCoeff(), 1e-9) << to_string(kind);
  }
}

// Eq. 1 is linear and acts per coordinate: a planar input (z = 0) stays exactly planar.
TEST(InitialPrefilter, PlaneStaysAPlaneAndNoiseInPlaneShrinks) {
  TriMesh m = test::plane(10);
  const Topology t = topology_of(m);
  NoiseSpec spec;
  spec.kind = NoiseKind::PerCoordinate;
  spec.sigma = 0.3;
  Vertices noisy = add_noise(m, spec);
  noisy.col(2).setZero();
  const Vertices out = initial_prefilter(noisy, t, 0.1);
  EXPECT_EQ(out.col(2).cwiseAbs().maxCoeff(), 0.0);
}

// CG at 1e-10 solves the LDLT's system to 1e-8; at the default tolerance (1e-8, decision 41)
// the positions stay within 1e-7 of it (measured 1.8e-8).
TEST(ShapingSolver, LdltAndConjugateGradientAgree) {
  const TriMesh clean = test::sphere(3);
  NoiseSpec spec;
  spec.sigma = 0.4;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = topology_of(clean);
  DenoiseParams p;
  p.n_aniso = 3;
  p.solver = LinearSolver::Ldlt;
  const Vertices a = anisotropic_prefilter(initial_prefilter(noisy, t, p.alpha, p.solver), clean.F, t, p);
  p.solver = LinearSolver::ConjugateGradient;
  const Vertices b_default = anisotropic_prefilter(initial_prefilter(noisy, t, p.alpha, p.solver), clean.F, t, p);
  EXPECT_LT((a - b_default).cwiseAbs().maxCoeff(), 1e-7);
  p.cg_tolerance = 1e-10;
  const Vertices b = anisotropic_prefilter(initial_prefilter(noisy, t, p.alpha, p.solver), clean.F, t, p);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-8);
}

// P - (I + alpha D^T D) x, formed from the edges in double.
Vertices shaping_residual(const Vertices& P, const Topology& t, double alpha, const Vertices& x) {
  Vertices residual = P - x;
  for (Eigen::Index e = 0; e < t.num_interior_edges(); ++e) {
    const Eigen::RowVector3d s = alpha * (x.row(t.interior_edges(e, 0)) - x.row(t.interior_edges(e, 1)) +
                                          x.row(t.interior_edges(e, 2)) - x.row(t.interior_edges(e, 3)));
    for (int a = 0; a < 4; ++a) residual.row(t.interior_edges(e, a)) -= (a % 2 == 0 ? 1.0 : -1.0) * s;
  }
  return residual;
}

// CG runs in single precision and is checked and polished in double (decision 37): above the
// size where its passes go parallel (32768 rows) the result is the same for any thread count,
// and its residual, recomputed here from the edges in double, meets the tolerance.
TEST(ShapingSolver, ConjugateGradientMeetsItsToleranceForAnyThreadCount) {
  const TriMesh clean = test::sphere(6);  // 40962 vertices
  NoiseSpec spec;
  spec.sigma = 0.3;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = topology_of(clean);
  const double alpha = 0.1, tolerance = 1e-10;
  Executor one(1);
  ShapingSolver serial(t, LinearSolver::ConjugateGradient, tolerance, &one);
  const Vertices x = serial.solve(noisy, alpha, {});
  for (int threads : {2, 3}) {
    Executor ex(threads);
    ShapingSolver parallel(t, LinearSolver::ConjugateGradient, tolerance, &ex);
    EXPECT_TRUE((parallel.solve(noisy, alpha, {}).array() == x.array()).all()) << threads << " threads";
  }
  const Vertices residual = shaping_residual(noisy, t, alpha, x);
  for (int c = 0; c < 3; ++c) EXPECT_LE(residual.col(c).norm(), tolerance * noisy.col(c).norm()) << "column " << c;
}

// A given start (Eq. 3's from the second pass on, decision 42) is taken as CG's first iterate:
// the tolerance still holds, from a start near the solution and from one far from it, and for
// any thread count.
TEST(ShapingSolver, ConjugateGradientFromAGivenStartMeetsItsTolerance) {
  const TriMesh clean = test::sphere(6);  // 40962 vertices: the passes go parallel
  NoiseSpec spec;
  spec.sigma = 0.3;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = topology_of(clean);
  const double alpha = 0.1, tolerance = 1e-8;
  Executor one(1), two(2);
  ShapingSolver serial(t, LinearSolver::ConjugateGradient, tolerance, &one);
  const Vertices step = serial.solve(noisy, alpha, {}) - noisy;
  for (const Vertices& start : {Vertices(noisy + step), Vertices(noisy - step), Vertices(clean.V)}) {
    const Vertices x = serial.solve(noisy, alpha, {}, start);
    const Vertices residual = shaping_residual(noisy, t, alpha, x);
    for (int c = 0; c < 3; ++c) EXPECT_LE(residual.col(c).norm(), tolerance * noisy.col(c).norm()) << "column " << c;
    ShapingSolver parallel(t, LinearSolver::ConjugateGradient, tolerance, &two);
    EXPECT_TRUE((parallel.solve(noisy, alpha, {}, start).array() == x.array()).all());
  }
}

// Eq. 4: w_e = 1 for coplanar faces, b^-1 at theta = sigma_theta, decreasing in theta.
TEST(AnisotropicWeights, FollowEquation4) {
  for (double opening : {180.0, 150.0, 90.0}) {
    const TriMesh m = test::fold(4, opening);
    const Topology t = topology_of(m);
    const Eigen::VectorXd w = anisotropic_edge_weights(m.V, m.F, t, 30.0, std::sqrt(3.0));
    const double theta = (180.0 - opening) * M_PI / 180.0;
    const double expected = std::pow(std::sqrt(3.0), -(1 - std::cos(theta)) / (1 - std::cos(M_PI / 6)));
    EXPECT_NEAR(w.maxCoeff(), 1.0, 1e-12);
    EXPECT_NEAR(w.minCoeff(), expected, 1e-9) << "opening " << opening;
  }
}

TEST(AnisotropicPrefilter, KeepsACreaseBetterThanTheIsotropicFilter) {
  const TriMesh clean = test::fold(16, 90);
  NoiseSpec spec;
  spec.sigma = 0.1;
  const Vertices noisy = add_noise(clean, spec);
  const Topology t = topology_of(clean);
  DenoiseParams p;
  p.alpha = 0.2;
  p.n_aniso = 6;
  p.sigma_theta = 20;
  const Vertices aniso = anisotropic_prefilter(noisy, clean.F, t, p);
  ShapingSolver iso(t, p.solver, p.cg_tolerance);
  Vertices isotropic = noisy;
  for (int i = 0; i < p.n_aniso; ++i) isotropic = iso.solve(isotropic, p.alpha, {});
  // Height of the crease line (x = 0): the true value is 0.
  double aniso_err = 0, iso_err = 0;
  for (Eigen::Index v = 0; v < clean.V.rows(); ++v)
    if (std::abs(clean.V(v, 0)) < 1e-12) {
      aniso_err += std::abs(aniso(v, 2) - clean.V(v, 2));
      iso_err += std::abs(isotropic(v, 2) - clean.V(v, 2));
    }
  EXPECT_LT(aniso_err, 0.7 * iso_err);
}

TEST(FoldRatio, CountsEdgesFoldedBeyondTheThreshold) {
  const TriMesh flat = test::plane(5);
  const Topology t = topology_of(flat);
  EXPECT_EQ(fold_ratio(flat.V, flat.F, t, 130), 0.0);
  const TriMesh sharp = test::fold(6, 30);  // normals differ by 150 degrees along the crease
  const Topology ts = topology_of(sharp);
  EXPECT_NEAR(fold_ratio(sharp.V, sharp.F, ts, 130), 6.0 / ts.num_interior_edges(), 1e-12);
  EXPECT_EQ(fold_ratio(sharp.V, sharp.F, ts, 160), 0.0);
}

TEST(ClusterFaces, SeparatesTheDenselySampledHalf) {
  const TriMesh m = test::irregular_plane(6, 8);
  const FaceClusters c = cluster_faces(m.V, m.F, 2, 1);
  EXPECT_GT(c.area_ratio, 4.0);
  const Vertices C = face_centroids(m.V, m.F);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    EXPECT_EQ(c.label[static_cast<std::size_t>(f)] == c.smallest, C(f, 0) < 0.5) << "face " << f;
  // A regular mesh shows no such contrast.
  const TriMesh regular = test::sphere(3);
  EXPECT_LT(cluster_faces(regular.V, regular.F, 2, 1).area_ratio, 2.0);
}

// Lloyd's sums are taken per block of faces and added in block order (decision 39): the same
// clusters for any thread count (in parallel from 32768 faces).
TEST(ClusterFaces, SameForAnyThreadCount) {
  const TriMesh m = test::irregular_sphere(5);
  ASSERT_GT(m.F.rows(), 32768);
  const FaceClusters serial = cluster_faces(m.V, m.F, 2, 1);
  EXPECT_GT(serial.area_ratio, 4.0);
  for (int threads : {2, 3}) {
    Executor ex(threads);
    const FaceClusters c = cluster_faces(m.V, m.F, 2, 1, 100, &ex);
    EXPECT_EQ(c.label, serial.label) << threads;
    EXPECT_EQ(c.area_ratio, serial.area_ratio) << threads;
  }
}

// Decision 49: Lloyd skips the faces whose label the centres' drift cannot have changed and
// keeps the sums of blocks without a change. Against plain Lloyd, written out here (every
// label measured, every centre summed afresh), on clouds that take many iterations: the same
// labels, the same centres, and as many iterations.
TEST(ClusterFaces, LloydWithBoundsEqualsPlainLloyd) {
  using detail::ClusterFeatures;
  const auto plain = [](const ClusterFeatures& X, ClusterFeatures& centers, std::vector<std::int32_t>& label) {
    int iterations = 0;
    for (int it = 0; it < 100; ++it, ++iterations) {
      std::int64_t changed = 0;
      ClusterFeatures sum = ClusterFeatures::Zero(centers.rows(), 4);
      std::vector<std::int64_t> count(static_cast<std::size_t>(centers.rows()), 0);
      for (Eigen::Index i = 0; i < X.rows(); ++i) {
        Eigen::Index best = 0;
        for (Eigen::Index c = 1; c < centers.rows(); ++c)
          if ((X.row(i) - centers.row(c)).squaredNorm() < (X.row(i) - centers.row(best)).squaredNorm()) best = c;
        changed += label[static_cast<std::size_t>(i)] != best;
        label[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(best);
        sum.row(best) += X.row(i);
        ++count[static_cast<std::size_t>(best)];
      }
      if (changed == 0 && it > 0) break;
      for (Eigen::Index c = 0; c < centers.rows(); ++c)
        if (count[static_cast<std::size_t>(c)] > 0) centers.row(c) = sum.row(c) / static_cast<double>(count[static_cast<std::size_t>(c)]);
    }
    return iterations;
  };
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss;
  for (const int k : {1, 2, 3, 6}) {
    // Overlapping blobs: a slow, long convergence with few faces moving late.
    const Eigen::Index n = 40000;
    ClusterFeatures X(n, 4);
    for (Eigen::Index i = 0; i < n; ++i)
      for (int a = 0; a < 4; ++a) X(i, a) = gauss(rng) + (i % 3 == 0 && a == 3 ? 1.5 : 0.0);
    ClusterFeatures seeds(k, 4);
    for (int c = 0; c < k; ++c) seeds.row(c) = X.row(97 * c + 11);
    ClusterFeatures want_centers = seeds;
    std::vector<std::int32_t> want(static_cast<std::size_t>(n), 0);
    const int iterations = plain(X, want_centers, want);
    if (k > 1) {
      EXPECT_GT(iterations, 10) << k;
    }
    for (int threads : {1, 2}) {
      Executor ex(threads);
      ClusterFeatures centers = seeds;
      std::vector<std::int32_t> got(static_cast<std::size_t>(n), 0);
      detail::lloyd_iterations(X, centers, 100, &ex, got);
      EXPECT_EQ(got, want) << k << " clusters, " << threads << " threads";
      EXPECT_LT((centers - want_centers).cwiseAbs().maxCoeff(), 1e-12) << k;
    }
  }
}

// The faces of m whose centroid c satisfies keep(c).
template <class Keep>
std::vector<std::int32_t> faces_where(const TriMesh& m, const Keep& keep) {
  std::vector<std::int32_t> faces;
  const Vertices C = face_centroids(m.V, m.F);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    if (keep(Eigen::RowVector3d(C.row(f)))) faces.push_back(static_cast<std::int32_t>(f));
  return faces;
}

// Noise along the normal with NoiseSpec's default seed (1).
Vertices with_noise_v(const TriMesh& m, double sigma) { return test::with_noise(m, sigma, NoiseKind::AlongNormal, 1).V; }

TEST(RegionPrefilter, SmoothsOnlyTheClusterAndKeepsOthersFixed) {
  const TriMesh clean = test::irregular_plane(6, 8);
  const Vertices noisy = with_noise_v(clean, 0.5);
  const Topology t = topology_of(clean);
  const std::vector<std::int32_t> left = faces_where(clean, [](const Eigen::RowVector3d& c) { return c(0) < 0.25; });
  std::int64_t unknowns = 0;
  const Vertices out = region_prefilter(noisy, clean.F, t, left, 6.0, &unknowns);
  EXPECT_GT(unknowns, 0);
  double before = 0, after = 0;
  for (Eigen::Index v = 0; v < clean.V.rows(); ++v) {
    if (clean.V(v, 0) > 0.26) {
      EXPECT_EQ(out.row(v), noisy.row(v)) << "vertex " << v << " outside the cluster moved";
    } else if (clean.V(v, 0) < 0.2 && clean.V(v, 1) > 0.05 && clean.V(v, 1) < 0.95) {
      before += std::abs(noisy(v, 2));
      after += std::abs(out(v, 2));
    }
  }
  EXPECT_LT(after, 0.5 * before);
}

// Eq. 2 matrix-free (decision 38) against the system assembled and factored: (I + beta L^T L) X
// = P_U - beta L^T c, L the uniform Laplacian rows of the unknowns, fixed neighbours in c.
TEST(RegionPrefilter, MatchesTheAssembledSystem) {
  const TriMesh clean = test::irregular_sphere(3);
  const Vertices noisy = with_noise_v(clean, 0.3);
  const Topology t = topology_of(clean);
  const std::vector<std::int32_t> faces = faces_where(clean, [](const Eigen::RowVector3d& c) { return c(2) > 0.1; });
  const double beta = 6;
  const Vertices out = region_prefilter(noisy, clean.F, t, faces, beta);

  std::vector<std::int32_t> row(static_cast<std::size_t>(noisy.rows()), -1), vertices;
  for (std::int32_t f : faces)
    for (int k = 0; k < 3; ++k) row[static_cast<std::size_t>(clean.F(f, k))] = 0;
  for (std::int32_t v = 0; v < noisy.rows(); ++v)
    if (row[static_cast<std::size_t>(v)] == 0) {
      row[static_cast<std::size_t>(v)] = static_cast<std::int32_t>(vertices.size());
      vertices.push_back(v);
    }
  const auto m = static_cast<Eigen::Index>(vertices.size());
  ASSERT_GT(m, 100);
  ASSERT_LT(m, noisy.rows());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(m, 3), P_u(m, 3);
  for (Eigen::Index r = 0; r < m; ++r) {
    const auto v = static_cast<std::size_t>(vertices[static_cast<std::size_t>(r)]);
    P_u.row(r) = noisy.row(static_cast<Eigen::Index>(v));
    const double inv_deg = 1.0 / (t.vv_offsets[v + 1] - t.vv_offsets[v]);
    entries.emplace_back(r, r, 1.0);
    for (std::int32_t s = t.vv_offsets[v]; s < t.vv_offsets[v + 1]; ++s) {
      const auto j = static_cast<std::size_t>(t.vv_vertices[static_cast<std::size_t>(s)]);
      if (row[j] >= 0)
        entries.emplace_back(r, row[j], -inv_deg);
      else
        c.row(r) -= inv_deg * noisy.row(static_cast<Eigen::Index>(j));
    }
  }
  Eigen::SparseMatrix<double> L(m, m), I(m, m);
  L.setFromTriplets(entries.begin(), entries.end());
  I.setIdentity();
  const Eigen::SparseMatrix<double> M = I + beta * Eigen::SparseMatrix<double>(L.transpose() * L);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(M);
  const Eigen::MatrixXd X = ldlt.solve(Eigen::MatrixXd(P_u - beta * (L.transpose() * c)));
  double worst = 0;
  for (Eigen::Index r = 0; r < m; ++r) worst = std::max(worst, (out.row(vertices[static_cast<std::size_t>(r)]) - X.row(r)).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT((X - P_u).cwiseAbs().maxCoeff(), 1e-3);  // the solve did move the region
}

// Eq. 2 over threads (decision 38): the same positions bit for bit for any thread count (the
// passes run in parallel from 32768 unknowns).
TEST(RegionPrefilter, SameForAnyThreadCount) {
  const TriMesh m = test::plane(200);
  const Vertices noisy = with_noise_v(m, 0.3);
  const Topology t = topology_of(m);
  std::vector<std::int32_t> faces(static_cast<std::size_t>(m.F.rows()));
  for (std::size_t f = 0; f < faces.size(); ++f) faces[f] = static_cast<std::int32_t>(f);
  const Vertices serial = region_prefilter(noisy, m.F, t, faces, 6.0);
  for (int threads : {2, 3}) {
    Executor ex(threads);
    EXPECT_TRUE((region_prefilter(noisy, m.F, t, faces, 6.0, nullptr, &ex).array() == serial.array()).all()) << threads;
  }
}

}  // namespace
}  // namespace mdn
