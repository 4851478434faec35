#include "core/mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/errors.h"
#include "support/shapes.h"

namespace mdn {
namespace {

TEST(Mesh, ValidateRejectsEmptyNonFiniteAndOutOfRange) {
  TriMesh empty;
  EXPECT_THROW(validate_mesh(empty), InvalidMeshError);

  TriMesh no_faces;
  no_faces.V = Vertices::Zero(3, 3);
  EXPECT_THROW(validate_mesh(no_faces), InvalidMeshError);

  TriMesh m = test::plane(2);
  EXPECT_NO_THROW(validate_mesh(m));
  m.V(3, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(validate_mesh(m), InvalidMeshError);
  m.V(3, 1) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(validate_mesh(m), InvalidMeshError);

  TriMesh bad = test::plane(2);
  bad.F(1, 2) = static_cast<std::int32_t>(bad.V.rows());
  EXPECT_THROW(validate_mesh(bad), InvalidMeshError);
  bad.F(1, 2) = -1;
  EXPECT_THROW(validate_mesh(bad), InvalidMeshError);
}

TEST(Mesh, ToTriMeshRejectsPolygonsAndNamesTheFace) {
  PolygonMesh poly;
  poly.V = Vertices::Zero(4, 3);
  poly.offsets = {0, 3, 7};
  poly.indices = {0, 1, 2, 0, 1, 2, 3};
  try {
    to_tri_mesh(poly);
    FAIL() << "a quad must be refused";
  } catch (const InvalidMeshError& e) {
    EXPECT_NE(std::string(e.what()).find("face 1 has 4 vertices"), std::string::npos) << e.what();
  }
  poly.offsets = {0, 3};
  poly.indices = {0, 1, 9};
  EXPECT_THROW(to_tri_mesh(poly), InvalidMeshError);
  poly.indices = {0, 1, 2};
  const TriMesh m = to_tri_mesh(poly);
  EXPECT_EQ(m.F.rows(), 1);
}

TEST(Mesh, UnitBoxRoundTripsAndHasUnitLongestSide) {
  TriMesh m = test::sphere(1);
  m.V.col(0) *= 3.0;
  m.V.col(2) += Eigen::VectorXd::Constant(m.V.rows(), 7.0);
  const UnitBox box = UnitBox::of(m.V);
  const Vertices in = box.apply(m.V);
  const Eigen::RowVector3d extent = in.colwise().maxCoeff() - in.colwise().minCoeff();
  EXPECT_NEAR(extent.maxCoeff(), 1.0, 1e-12);
  EXPECT_NEAR((in.colwise().maxCoeff() + in.colwise().minCoeff()).norm(), 0.0, 1e-12);
  EXPECT_LT((box.undo(in) - m.V).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Mesh, DegenerateFaceHasZeroNormalAndArea) {
  Vertices V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0;  // collinear
  Triangles F(1, 3);
  F << 0, 1, 2;
  EXPECT_EQ(face_normals(V, F).row(0).norm(), 0.0);
  EXPECT_EQ(face_areas(V, F)(0), 0.0);
}

TEST(Mesh, MeanEdgeLengthOfUnitGrid) {
  const TriMesh m = test::plane(4, 4.0, /*alternate=*/false);
  // 40 axis edges of length 1 and 16 diagonals of length sqrt(2).
  EXPECT_NEAR(mean_edge_length(m.V, m.F), (40.0 + 16.0 * std::sqrt(2.0)) / 56.0, 1e-12);
}

}  // namespace
}  // namespace mdn
