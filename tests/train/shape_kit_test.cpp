// The corpus's retessellations (tools/train/shape_kit.h, decision 38): a new tessellation of
// the same closed, consistently oriented surface.
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

}  // namespace
}  // namespace mdn::train::kit
