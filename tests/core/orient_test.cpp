#include "core/orient.h"

#include <gtest/gtest.h>

#include <random>

#include "core/auto/denoise.h"
#include "core/metrics.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

// Every third face of m turned (two corners swapped), and the list of them.
TriMesh turn_every_third(const TriMesh& m, std::vector<std::int32_t>& turned) {
  TriMesh out = m;
  for (std::int32_t f = 1; f < out.F.rows(); f += 3) {
    std::swap(out.F(f, 1), out.F(f, 2));
    turned.push_back(f);
  }
  return out;
}

TEST(Orientation, AConsistentlyWoundMeshNeedsNothing) {
  for (const TriMesh& m : {test::sphere(3), test::torus(32, 16, 0.3), test::plane(8)})
    EXPECT_TRUE(faces_to_turn(m.F, static_cast<std::int32_t>(m.V.rows())).empty());
}

TEST(Orientation, FindsExactlyTheFacesWoundAgainstMostOfTheirPiece) {
  const TriMesh sphere = test::sphere(3);
  std::vector<std::int32_t> turned;
  const TriMesh mixed = turn_every_third(sphere, turned);
  EXPECT_EQ(faces_to_turn(mixed.F, static_cast<std::int32_t>(mixed.V.rows())), turned);
  // Two pieces, one of them wound inside out entirely: a piece keeps its own majority.
  TriMesh inverted = test::plane(6);
  for (std::int64_t f = 0; f < inverted.F.rows(); ++f) std::swap(inverted.F(f, 1), inverted.F(f, 2));
  EXPECT_TRUE(faces_to_turn(inverted.F, static_cast<std::int32_t>(inverted.V.rows())).empty());
}

TEST(Orientation, AMoebiusStripIsWalkedWithoutLoopingOrFailing) {
  const TriMesh strip = test::parametric(48, 2, true, false, [](double u, double v) {
    const double t = 2 * M_PI * u, w = v - 0.5;
    return Vec3((1 + w * std::cos(t / 2)) * std::cos(t), (1 + w * std::cos(t / 2)) * std::sin(t), w * std::sin(t / 2));
  });
  const std::vector<std::int32_t> turn = faces_to_turn(strip.F, static_cast<std::int32_t>(strip.V.rows()));
  EXPECT_LT(turn.size(), static_cast<std::size_t>(strip.F.rows()));
}

// Decision 34: the method sees the faces wound one way; the output keeps the input's faces.
TEST(Orientation, DenoisingAMixedWindingGivesTheConsistentResultAndKeepsTheInputFaces) {
  const TriMesh noisy = test::with_noise(test::sphere(4), 0.3);
  std::vector<std::int32_t> turned;
  const TriMesh mixed = turn_every_third(noisy, turned);
  for (const ParamMode mode : {ParamMode::Manual, ParamMode::Auto}) {
    DenoiseParams p;
    p.mode = mode;
    const DenoiseResult consistent = denoise(noisy, p), got = denoise(mixed, p);
    EXPECT_TRUE(got.mesh.V == consistent.mesh.V);
    EXPECT_TRUE(got.mesh.F == mixed.F);
    ASSERT_EQ(got.report.notes.size(), 1u);
    EXPECT_NE(got.report.notes[0].find(std::to_string(turned.size()) + " of "), std::string::npos);
    EXPECT_TRUE(consistent.report.notes.empty());
  }
  // Mode None filters nothing: no note, the input as it came.
  DenoiseParams none;
  none.mode = ParamMode::None;
  const DenoiseResult converted = denoise(mixed, none);
  EXPECT_TRUE(converted.report.notes.empty());
  EXPECT_TRUE(converted.mesh.V == mixed.V && converted.mesh.F == mixed.F);
  // A clean surface with mixed winding is left alone, as the consistent one is.
  std::vector<std::int32_t> ignored;
  const TriMesh clean = turn_every_third(test::sphere(4), ignored);
  EXPECT_TRUE(denoise(clean, test::automatic()).mesh.V == clean.V);
}


// Decision 53 with decision 34: a guidance normal belongs to its face as the caller wound it, so
// a turned face's guidance turns with it; the mixed winding then gives the consistent result.
TEST(Orientation, GuidanceTurnsWithTheFacesItGuides) {
  const TriMesh clean = test::sphere(4);
  const TriMesh noisy = test::with_noise(clean, 0.3);
  std::vector<std::int32_t> turned;
  const TriMesh mixed = turn_every_third(noisy, turned);
  const Vertices guidance = face_normals(clean.V, clean.F);
  Vertices mixed_guidance = guidance;  // the clean normals as the mixed winding sees them
  for (const std::int32_t f : turned) mixed_guidance.row(f) *= -1;
  RunOptions consistent_run, mixed_run;
  consistent_run.guidance = &guidance;
  mixed_run.guidance = &mixed_guidance;
  const DenoiseResult consistent = denoise(noisy, {}, consistent_run), got = denoise(mixed, {}, mixed_run);
  EXPECT_TRUE(got.mesh.V == consistent.mesh.V);
  EXPECT_FALSE(got.mesh.V == denoise(noisy, {}).mesh.V);  // the guidance did change the result
}

}  // namespace
}  // namespace mdn
