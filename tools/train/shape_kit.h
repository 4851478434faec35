// Building blocks of the corpus's shapes made in code (tools/train/corpus.cpp), and the seeded
// families of generated shapes that widen the corpus (generated_shapes.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace mdn::train::kit {

inline constexpr double kPi = std::numbers::pi;

// Flips every face if the closed mesh's signed volume is negative (outward normals).
void orient_outward(TriMesh& m);
// Samples a closed polyline: each corner exactly, each side split into pieces of at most `step`.
std::vector<Eigen::Vector2d> sample_loop(const std::vector<Eigen::Vector2d>& corners, double step);
// An arc from angle a0 to a1 around c with radius r, n segments, end excluded.
void arc(std::vector<Eigen::Vector2d>& out, Eigen::Vector2d c, double r, double a0, double a1, int n);
// A closed profile loop in the (r, z) half-plane (r > 0) revolved around z.
TriMesh revolve(const std::vector<Eigen::Vector2d>& corners, double step, int around);
// A star-shaped outline extruded to height h: `rows` rows of side quads, caps of `rings` rings.
TriMesh extrude(const std::vector<Eigen::Vector2d>& outline, double h, int rows, int rings);
std::vector<Eigen::Vector2d> gear_outline(int teeth, double root, double tip, int per_arc);
std::vector<Eigen::Vector2d> rounded_rect(double w, double h, double r, int per_arc, double step);
// A cube of n x n quads per side pushed onto the p-norm ball scaled by `axes`.
TriMesh superquadric(int n, double p, const Vec3& axes);
// An icosphere of `level` displaced by seeded low-order harmonics.
TriMesh bumpy(int level, std::uint64_t seed, double amplitude, int max_freq);
// A seeded height field of n x n quads.
TriMesh terrain(std::uint64_t seed, int n);
// A closed curve around the z axis, radius 1, lifted by lift * sin(turns * t): tube()'s and the
// ropes' (decision 96). around(t, b, r) is the point at distance r from the curve's point at t,
// at angle b in the plane normal to the curve.
struct LoopCurve {
  double lift;
  int turns;
  Vec3 around(double t, double b, double r) const;
};
// A tube of radius 0.18 + swell * sin(3t) along LoopCurve{lift, turns}.
TriMesh tube(double swell, double lift, int turns, int nu, int nv);
// Refines the slab x < min + 0.3 extent twice (16x denser): an irregular tessellation.
TriMesh irregular(const TriMesh& m);
// Splits at its midpoint every edge within about `max_angle_deg` of the line `dir`, and
// re-triangulates each face to match (the surface is unchanged): faces become shorter along
// `dir` only, an anisotropic tessellation.
TriMesh split_along(const TriMesh& m, const Vec3& dir, double max_angle_deg);
// Flips, in a seeded random order, each edge with probability `p` where its two faces are
// within `max_dihedral_deg` of coplanar and both new faces keep an angle over 2 degrees and a
// normal within `max_dihedral_deg` of the old ones: irregular valences on nearly the same
// surface.
TriMesh flip_random(const TriMesh& m, std::uint64_t seed, double p, double max_dihedral_deg);
// One of four seeded retessellations of `m` (decision 44): split along a random direction once
// or twice, random flips, or both. The tag names the one chosen ("aniso1", "aniso2", "flip",
// "aniso1+flip").
TriMesh retessellate(const TriMesh& m, std::uint64_t seed, std::string* tag = nullptr);

struct Generated {
  std::string name;
  std::string family;  // "cad", "organic" or "rough" (decision 96)
  std::function<TriMesh()> make;
};
// Seeded random members of the corpus's families (revolved and extruded parts, filleted boxes,
// folds, blobs, terrains, tubes, tori), named gen_<kind>_<k>: the same list on every machine.
std::vector<Generated> generated_shapes();

}  // namespace mdn::train::kit
