#include "core/auto/surface_sample.h"

#include <gtest/gtest.h>

#include <set>

#include "support/shapes.h"

namespace mdn {
namespace {

SurfaceSample sample_of(const TriMesh& m, std::int64_t max_faces) {
  return sample_surface(m.V, m.F, Topology::build(m.F, static_cast<std::int32_t>(m.V.rows())), max_faces);
}

TEST(SurfaceSample, ASmallSurfaceIsSampledWholeAndEveryFaceIsScored) {
  const TriMesh m = test::sphere(3);
  const SurfaceSample s = sample_of(m, m.num_faces());
  EXPECT_TRUE(s.whole);
  EXPECT_EQ(s.F, m.F);
  EXPECT_TRUE(s.P == m.V);
  EXPECT_EQ(std::count(s.scored.begin(), s.scored.end(), 1), m.num_faces());
  EXPECT_EQ(static_cast<std::int64_t>(s.scored_vertices.size()), m.num_vertices());
}

TEST(SurfaceSample, PatchesStayWithinTheBudgetKeepPositionsAndScoreOnlyAwayFromTheCut) {
  const TriMesh m = test::sphere(5);  // 20480 faces
  const Topology topo = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  const SurfaceSample s = sample_surface(m.V, m.F, topo, 4000, 8, 2);
  EXPECT_FALSE(s.whole);
  EXPECT_LE(s.F.rows(), 4000);
  EXPECT_GT(s.F.rows(), 3000);
  for (std::size_t v = 0; v < s.vertex.size(); ++v) EXPECT_TRUE(s.P.row(static_cast<Eigen::Index>(v)) == m.V.row(s.vertex[v]));
  // Every sampled face is a face of the surface.
  std::set<std::array<std::int32_t, 3>> faces;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) faces.insert({m.F(f, 0), m.F(f, 1), m.F(f, 2)});
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    EXPECT_TRUE(faces.count({s.vertex[static_cast<std::size_t>(s.F(f, 0))], s.vertex[static_cast<std::size_t>(s.F(f, 1))],
                             s.vertex[static_cast<std::size_t>(s.F(f, 2))]}));
  // A scored face's vertices keep all their faces of the surface in the sample (margin >= 1).
  std::vector<int> sampled_faces_of(static_cast<std::size_t>(s.vertex.size()), 0);
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) ++sampled_faces_of[static_cast<std::size_t>(s.F(f, c))];
  const auto scored = std::count(s.scored.begin(), s.scored.end(), 1);
  EXPECT_GT(scored, s.F.rows() / 3);
  EXPECT_LT(scored, s.F.rows());
  for (Eigen::Index f = 0; f < s.F.rows(); ++f) {
    if (!s.scored[static_cast<std::size_t>(f)]) continue;
    for (int c = 0; c < 3; ++c) {
      const auto v = s.F(f, c);
      const auto g = s.vertex[static_cast<std::size_t>(v)];
      EXPECT_EQ(sampled_faces_of[static_cast<std::size_t>(v)], topo.vf_offsets[g + 1] - topo.vf_offsets[g]);
    }
  }
  // Deterministic.
  const SurfaceSample again = sample_surface(m.V, m.F, topo, 4000, 8, 2);
  EXPECT_EQ(again.F, s.F);
  EXPECT_EQ(again.scored, s.scored);
}

}  // namespace
}  // namespace mdn
