// service/reference.h: a mesh against a reference, the figures from core/metrics and the
// per-vertex deviation, on small procedural meshes with known answers.
#include "service/reference.h"

#include <gtest/gtest.h>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/parallel.h"
#include "support/shapes.h"

namespace mdn::service {
namespace {

TEST(CompareWithReference, SameFacesGiveMsaeAndSignedDeviationAlongTheNormal) {
  const TriMesh reference = test::sphere(3);
  TriMesh mesh = reference;
  // Every vertex pushed out by 0.01 along the sphere's radius (its normal): deviation +0.01.
  for (Eigen::Index i = 0; i < mesh.num_vertices(); ++i) mesh.V.row(i) *= 1 + 0.01 / mesh.V.row(i).norm();
  Executor executor(2);
  const ReferenceComparison c = compare_with_reference(reference, mesh, &executor);
  ASSERT_TRUE(c.msae.has_value());
  EXPECT_NEAR(*c.msae, 0.0, 1e-12);  // a uniform scale keeps every face normal
  EXPECT_DOUBLE_EQ(c.ev, vertex_error(mesh, reference));
  EXPECT_TRUE(c.deviation_signed);
  ASSERT_EQ(c.deviation.size(), static_cast<std::size_t>(mesh.num_vertices()));
  for (float d : c.deviation) EXPECT_NEAR(d, 0.01, 2e-4);
  EXPECT_GT(c.mean_edge_length, 0);
  // Pushed in: the same deviation, negative.
  TriMesh inner = reference;
  for (Eigen::Index i = 0; i < inner.num_vertices(); ++i) inner.V.row(i) *= 1 - 0.01 / inner.V.row(i).norm();
  for (float d : compare_with_reference(reference, inner).deviation) EXPECT_NEAR(d, -0.01, 2e-4);
}

TEST(CompareWithReference, OtherFacesGiveEvAndTheDistanceToTheSurface) {
  const TriMesh reference = test::plane(8);
  TriMesh mesh = test::plane(5);  // another tessellation of the same square
  for (Eigen::Index i = 0; i < mesh.num_vertices(); ++i) mesh.V(i, 2) += 0.02;
  const ReferenceComparison c = compare_with_reference(reference, mesh);
  EXPECT_FALSE(c.msae.has_value());
  EXPECT_FALSE(c.deviation_signed);
  for (float d : c.deviation) EXPECT_NEAR(d, 0.02, 1e-6);
  EXPECT_DOUBLE_EQ(c.ev, vertex_error(mesh, reference));
  const nlohmann::json j = comparison_json(c);
  EXPECT_TRUE(j.at("msae").is_null());
  EXPECT_FALSE(j.at("same_faces").get<bool>());
  EXPECT_EQ(j.at("deviation").size(), c.deviation.size());
}

TEST(CompareWithReference, RefusesAnInvalidMesh) {
  TriMesh broken = test::plane(3);
  broken.F(0, 0) = 1000;
  EXPECT_THROW(compare_with_reference(test::plane(3), broken), InvalidMeshError);
}

TEST(SceneMesh, PlacesEachSurfaceOncePerPlacement) {
  const TriMesh s = test::plane(2);
  Eigen::Matrix4d shift = Eigen::Matrix4d::Identity();
  shift(0, 3) = 5;
  const TriMesh scene = scene_mesh({s}, {{Eigen::Matrix4d::Identity(), shift}});
  EXPECT_EQ(scene.num_vertices(), 2 * s.num_vertices());
  EXPECT_EQ(scene.num_faces(), 2 * s.num_faces());
  EXPECT_DOUBLE_EQ(scene.V(s.num_vertices(), 0), s.V(0, 0) + 5);
  EXPECT_TRUE(same_faces(merge_surfaces({s}), s));
}

}  // namespace
}  // namespace mdn::service
