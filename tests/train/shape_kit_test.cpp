// The corpus's retessellations (tools/train/shape_kit.h, decision 38): a new tessellation of
// the same closed, consistently oriented surface. The rough generated shapes (decision 96) are
// seeded, valid and small enough for every noise kind.
#include <gtest/gtest.h>

#include <map>
#include <utility>

#include "train/shape_kit.h"
#include "support/shapes.h"

namespace mdn::train::kit {
namespace {

double area(const TriMesh& m) {
  double a = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Vec3 p = m.V.row(m.F(f, 0)).transpose(), q = m.V.row(m.F(f, 1)).transpose(), r = m.V.row(m.F(f, 2)).transpose();
    a += 0.5 * (q - p).cross(r - p).norm();
  }
  return a;
}

// Every directed edge appears once and its reverse once: closed, manifold, consistently oriented.
void expect_closed_and_oriented(const TriMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++directed[{m.F(f, k), m.F(f, (k + 1) % 3)}];
  for (const auto& [e, count] : directed) {
    ASSERT_EQ(count, 1) << "edge " << e.first << "-" << e.second << " used twice in one direction";
    ASSERT_TRUE(directed.count({e.second, e.first})) << "edge " << e.first << "-" << e.second << " has one face";
  }
}

int valence_spread(const TriMesh& m) {
  std::vector<int> valence(static_cast<std::size_t>(m.V.rows()), 0);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++valence[static_cast<std::size_t>(m.F(f, k))];
  return *std::max_element(valence.begin(), valence.end()) - *std::min_element(valence.begin(), valence.end());
}

TEST(ShapeKit, SplitAlongKeepsTheSurfaceAndRefinesOnlyAlongTheDirection) {
  const TriMesh box = test::cube(6);
  const TriMesh split = split_along(box, Vec3::UnitX(), 30);
  expect_closed_and_oriented(split);
  EXPECT_GT(split.F.rows(), box.F.rows());
  EXPECT_NEAR(area(split), area(box), 1e-9 * area(box));
  // Within 1 degree of x, only the cube's edges parallel to x split: 7 lattice lines of 6
  // segments on each of the four sides along x, the 4 rims shared, 144 edges; each splits its
  // two faces in two.
  EXPECT_EQ(split_along(box, Vec3::UnitX(), 1).F.rows(), box.F.rows() + 2 * (4 * 7 * 6 - 4 * 6));
}

TEST(ShapeKit, FlipRandomKeepsTheFlatSurfaceAndMakesValencesIrregular) {
  const TriMesh box = test::cube(8);
  const TriMesh flipped = flip_random(box, 7, 0.6, 8);
  expect_closed_and_oriented(flipped);
  EXPECT_EQ(flipped.F.rows(), box.F.rows());
  EXPECT_NEAR(area(flipped), area(box), 1e-9 * area(box));  // only coplanar pairs flip on a cube
  EXPECT_GT(valence_spread(flipped), valence_spread(box));
  // Seeded: the same seed gives the same mesh.
  EXPECT_EQ(flip_random(box, 7, 0.6, 8).F, flipped.F);
}

TEST(ShapeKit, RetessellateIsSeededAndKeepsACurvedSurfaceClosed) {
  const TriMesh torus = test::torus(40, 16, 0.4);
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    std::string tag;
    const TriMesh t = retessellate(torus, seed, &tag);
    SCOPED_TRACE(tag);
    expect_closed_and_oriented(t);
    EXPECT_NEAR(area(t), area(torus), 0.01 * area(torus));
    EXPECT_EQ(retessellate(torus, seed).F, t.F);
  }
}

// Every directed edge at most once: manifold and consistently oriented, borders allowed.
void expect_oriented(const TriMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::pair<int, int> edge{m.F(f, k), m.F(f, (k + 1) % 3)};
      ASSERT_EQ(++directed[edge], 1) << "edge " << edge.first << "-" << edge.second;
    }
}

TEST(ShapeKit, RoughShapesAreSeededValidAndGetEveryNoiseKind) {
  std::map<std::string, int> kinds;
  for (const Generated& g : generated_shapes()) {
    if (g.family != "rough") continue;
    SCOPED_TRACE(g.name);
    const std::string kind = g.name.substr(4, g.name.rfind('_') - 4);
    ++kinds[kind];
    const TriMesh m = g.make();
    EXPECT_LE(m.F.rows(), 12000);  // the corpus gives every noise kind to shapes this small
    const Vertices n = face_normals(m.V, m.F);
    for (Eigen::Index f = 0; f < n.rows(); ++f) ASSERT_GT(n.row(f).squaredNorm(), 0.5) << "degenerate face " << f;
    expect_oriented(m);
    if (kind != "knurl") expect_closed_and_oriented(m);  // a knurl is an open sleeve
    EXPECT_EQ(g.make().V, m.V);
  }
  EXPECT_EQ(kinds, (std::map<std::string, int>{{"knurl", 4}, {"relief", 4}, {"rope", 4}, {"sliced", 4}}));
}

}  // namespace
}  // namespace mdn::train::kit
