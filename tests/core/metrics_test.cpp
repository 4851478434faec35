// Tests of core/metrics.h: MSAE, the AABB-tree distance and E_v.
#include "core/metrics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/errors.h"
#include "core/parallel.h"
#include "support/shapes.h"

namespace mdn {
namespace {

using test::plane;
using test::sphere;


// Independent reference for the point-triangle distance: project onto the plane and test
// the projection with edge half-spaces; outside (or degenerate) take the nearest edge.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}
double reference_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double edges = std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
  if (n.norm() < 1e-300) return edges;
  const Vec3 u = n.normalized();
  const Vec3 q = p - u.dot(p - a) * u;
  const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                      (a - c).cross(q - c).dot(n) >= 0;
  return inside ? std::abs(u.dot(p - a)) : edges;
}
double brute_force(const TriMesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    best = std::min(best, reference_distance(p, m.V.row(m.F(f, 0)), m.V.row(m.F(f, 1)), m.V.row(m.F(f, 2))));
  return best;
}

void expect_matches_brute_force(const TriMesh& surface, int queries, double spread, std::uint64_t seed) {
  const SurfaceDistance tree(surface);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-spread, spread);
  for (int q = 0; q < queries; ++q) {
    const Vec3 p(coord(rng), coord(rng), coord(rng));
    const double expected = brute_force(surface, p);
    ASSERT_NEAR(tree.distance(p), expected, 1e-12 * (1 + expected)) << "query " << q;
  }
  // Points on the surface itself (the corners) are at distance 0.
  for (Eigen::Index v = 0; v < std::min<Eigen::Index>(surface.V.rows(), 200); ++v)
    EXPECT_NEAR(tree.distance(surface.V.row(v).transpose()), 0.0, 1e-12);
}

TEST(Msae, MeshAgainstItselfIsZero) {
  const TriMesh m = sphere(3);
  EXPECT_EQ(msae(m, m), 0.0);
}

TEST(Msae, PlaneTiltedAboutAnInPlaneAxisGivesTheAngleSquared) {
  const TriMesh truth = plane(8);
  for (const double angle : {0.05, 0.3, 1.2, 3.0}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Vec3(1, 2, 0).normalized()).toRotationMatrix();
    TriMesh tilted = truth;
    tilted.V = truth.V * R.transpose();
    EXPECT_NEAR(msae(tilted, truth), angle * angle, 1e-12) << "angle " << angle;
  }
}

TEST(Msae, RigidRotationOfASphereMatchesTheRotationGeometry) {
  // A rotation by theta about the unit axis a turns a unit normal n by phi with
  // sin(phi / 2) = sin(theta / 2) |n x a|.
  const TriMesh truth = sphere(3);
  const Vertices normals = face_normals(truth.V, truth.F);
  const Vec3 axis = Vec3(1, 2, 3).normalized();
  for (const double angle : {0.05, 0.3, 1.2}) {
    TriMesh rotated = truth;
    rotated.V = truth.V * Eigen::AngleAxisd(angle, axis).toRotationMatrix().transpose();
    double expected = 0;
    for (Eigen::Index f = 0; f < normals.rows(); ++f) {
      const double phi = 2 * std::asin(std::sin(angle / 2) * normals.row(f).cross(axis.transpose()).norm());
      expected += phi * phi / static_cast<double>(normals.rows());
    }
    EXPECT_NEAR(msae(rotated, truth), expected, 1e-12) << "angle " << angle;
    EXPECT_LT(msae(rotated, truth), angle * angle);
  }
}

TEST(Msae, FacesRotatedByDifferentAnglesGiveTheMeanSquaredAngle) {
  // A soup of separate triangles, each turned about its own centroid by a known angle.
  const std::vector<double> angles = {0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 3.0};
  const auto n = static_cast<int>(angles.size());
  TriMesh truth, result;
  truth.V.resize(3 * n, 3);
  truth.F.resize(n, 3);
  for (int f = 0; f < n; ++f) {
    truth.V.row(3 * f) << 3.0 * f, 0, 0;
    truth.V.row(3 * f + 1) << 3.0 * f + 1, 0.2, 0;
    truth.V.row(3 * f + 2) << 3.0 * f + 0.3, 1, 0.1 * f;
    truth.F.row(f) << 3 * f, 3 * f + 1, 3 * f + 2;
  }
  result = truth;
  double expected = 0;
  for (int f = 0; f < n; ++f) {
    // The rotation axis lies in the face's plane, so the normal turns by the full angle.
    const Vec3 a = truth.V.row(3 * f), b = truth.V.row(3 * f + 1);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angles[f], (b - a).normalized()).toRotationMatrix();
    for (int j = 0; j < 3; ++j) result.V.row(3 * f + j) = (R * (truth.V.row(3 * f + j).transpose() - a) + a).transpose();
    expected += angles[f] * angles[f] / n;
  }
  EXPECT_NEAR(msae(result, truth), expected, 1e-12);
}

TEST(Msae, DegenerateFacesAreSkipped) {
  TriMesh truth = plane(4);
  // Append a zero-area face (a repeated vertex index).
  truth.F.conservativeResize(truth.F.rows() + 1, 3);
  truth.F.row(truth.F.rows() - 1) << 0, 0, 2;
  const double angle = 0.2;
  TriMesh tilted = truth;
  tilted.V = truth.V * Eigen::AngleAxisd(angle, Vec3::UnitY()).toRotationMatrix().transpose();
  const double value = msae(tilted, truth);
  EXPECT_TRUE(std::isfinite(value));
  EXPECT_NEAR(value, angle * angle, 1e-12);
  // All faces degenerate: no mean to take.
  TriMesh flat = truth;
  flat.V.setZero();
  EXPECT_THROW(msae(flat, truth), InvalidMeshError);
}

TEST(Msae, DifferentConnectivityIsRejected) {
  const TriMesh a = plane(4);
  TriMesh b = a;
  b.F.row(0) << b.F(0, 1), b.F(0, 0), b.F(0, 2);
  EXPECT_THROW(msae(a, b), InvalidMeshError);
  const TriMesh c = plane(5);
  EXPECT_THROW(msae(a, c), InvalidMeshError);
}

TEST(SurfaceDistance, MatchesBruteForceOnASphere) {
  expect_matches_brute_force(sphere(3), 1000, 1.6, 7);
}

TEST(SurfaceDistance, MatchesBruteForceOnARandomSoupWithDegenerateTriangles) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_real_distribution<double> size(0.001, 0.4);
  const int n = 400;
  TriMesh soup;
  soup.V.resize(3 * n, 3);
  soup.F.resize(n, 3);
  for (int f = 0; f < n; ++f) {
    const Vec3 centre(u(rng), u(rng), u(rng));
    const double s = size(rng);
    for (int j = 0; j < 3; ++j) soup.V.row(3 * f + j) = (centre + s * Vec3(u(rng), u(rng), u(rng))).transpose();
    soup.F.row(f) << 3 * f, 3 * f + 1, 3 * f + 2;
  }
  // Degenerate triangles: collinear corners, two coincident corners, all three coincident.
  for (int f = 0; f < 30; ++f) {  // 30 of the 400
    const Vec3 a = soup.V.row(3 * f).transpose();
    const Vec3 b = soup.V.row(3 * f + 1).transpose();
    if (f % 3 == 0) soup.V.row(3 * f + 2) = (a + 0.37 * (b - a)).transpose();
    if (f % 3 == 1) soup.V.row(3 * f + 2) = a.transpose();
    if (f % 3 == 2) soup.V.row(3 * f + 1) = soup.V.row(3 * f + 2) = a.transpose();
  }
  expect_matches_brute_force(soup, 2000, 1.5, 13);
}

TEST(SurfaceDistance, OnlyDegenerateTrianglesGiveSegmentAndPointDistances) {
  TriMesh m;
  m.V.resize(5, 3);
  m.V << 0, 0, 0, 2, 0, 0, 1, 0, 0,  // collinear: covers the segment [0, 2] on x
      50, 50, 50, 50, 50, 50;         // a point, twice
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 3, 4, 3;
  const SurfaceDistance d(m);
  EXPECT_NEAR(d.distance(Vec3(1.5, 3, 4)), 5.0, 1e-12);  // above the segment's interior
  EXPECT_NEAR(d.distance(Vec3(-3, 0, 4)), 5.0, 1e-12);   // beyond its end at the origin
  EXPECT_NEAR(d.distance(Vec3(50, 50, 52)), 2.0, 1e-12);    // near the point
}

TEST(SurfaceDistance, BadInputThrows) {
  EXPECT_THROW(SurfaceDistance(TriMesh{}), InvalidMeshError);
  const SurfaceDistance d(plane(2));
  EXPECT_THROW(d.distance(Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0)), InvalidMeshError);
}

TEST(VertexError, OffsetAlongThePlaneNormalIsTheOffset) {
  const double offset = 0.0123;
  const TriMesh truth = plane(20);  // 1 x 1: the unit box frame has the same scale
  TriMesh result = truth;
  result.V.col(2).array() += offset;
  EXPECT_NEAR(vertex_error(result, truth), offset, 1e-9);
  EXPECT_NEAR(vertex_error(truth, truth), 0.0, 1e-15);
}

TEST(VertexError, IsMeasuredInTheGroundTruthsUnitBox) {
  const double offset = 0.03;
  const TriMesh truth = plane(10, 4.0);  // longest side 4: distances shrink by 4
  TriMesh result = truth;
  result.V.col(2).array() -= offset;
  EXPECT_NEAR(vertex_error(result, truth), offset / 4.0, 1e-9);
}

TEST(VertexError, IsAreaWeighted) {
  // Only one corner vertex is displaced; its weight is the (result) area of its faces.
  const TriMesh truth = plane(2);
  TriMesh result = truth;
  const double h = 0.01;
  result.V(0, 2) = h;
  const Eigen::VectorXd areas = face_areas(result.V, result.F);
  double weight = 0;
  for (Eigen::Index f = 0; f < result.F.rows(); ++f)
    if ((result.F.row(f).array() == 0).any()) weight += areas[f];
  ASSERT_GT(weight, 0.0);
  ASSERT_LT(weight, areas.sum());
  const double expected = std::sqrt(weight * h * h / (3 * areas.sum()));
  EXPECT_NEAR(vertex_error(result, truth), expected, 1e-12);
}

TEST(VertexError, DoesNotDependOnTheThreadCount) {
  const TriMesh truth = sphere(5);
  TriMesh result = truth;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0, 0.01);
  for (Eigen::Index i = 0; i < result.V.rows(); ++i)
    for (int k = 0; k < 3; ++k) result.V(i, k) += g(rng);
  const double serial = vertex_error(result, truth);
  Executor one(1), three(3);
  EXPECT_EQ(vertex_error(result, truth, &one), serial);
  EXPECT_EQ(vertex_error(result, truth, &three), serial);
  EXPECT_GT(serial, 0.0);
}

TEST(VertexError, DegenerateResultFacesStayFinite) {
  const TriMesh truth = plane(5);
  TriMesh result = truth;
  // Collapse one face onto a line and one vertex onto another.
  result.V.row(result.F(3, 2)) = result.V.row(result.F(3, 0));
  const double value = vertex_error(result, truth);
  EXPECT_TRUE(std::isfinite(value));
  TriMesh flat = truth;
  flat.V.setZero();  // every face collapsed: no area to weight by
  EXPECT_THROW(vertex_error(flat, truth), InvalidMeshError);
}

}  // namespace
}  // namespace mdn
