// Seeded random members of the corpus's families (shape_kit.h; decision 35). Each shape draws its
// parameters from its own generator, seeded by its kind and index, so adding a kind or
// changing one never changes another shape. Sizes stay under 12,000 faces, so every shape
// gets all the corpus's noise kinds.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/smoothing.h"
#include "core/topology.h"
#include "corpus.h"
#include "shape_kit.h"
#include "support/shapes.h"

namespace mdn::train::kit {

namespace {

struct Draw {
  std::mt19937_64 rng;
  double real(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  bool chance(double p) { return real(0, 1) < p; }
};

// A stepped profile (1-3 steps down from radius 1 to the bore), each outer corner sharp or
// chamfered, revolved.
TriMesh revolved_part(Draw d) {
  const double bore = d.real(0.15, 0.55), height = d.real(0.25, 1.2);
  const int steps = d.integer(1, 3);
  std::vector<Eigen::Vector2d> p{{bore, 0}};
  double r = 1, z = 0;
  const double chamfer = d.chance(0.5) ? std::min(d.real(0.02, 0.06), 0.3 * height / steps) : 0;
  for (int s = 0; s < steps; ++s) {
    const double top = height * (s + 1) / steps;
    if (chamfer > 0) {
      p.emplace_back(r - chamfer, z);
      p.emplace_back(r, z + chamfer);
      p.emplace_back(r, top - chamfer);
      p.emplace_back(r - chamfer, top);
    } else {
      p.emplace_back(r, z);
      p.emplace_back(r, top);
    }
    z = top;
    r = s + 1 < steps ? bore + (r - bore) * d.real(0.45, 0.8) : r;
  }
  p.emplace_back(bore, height);
  const double step = d.real(0.03, 0.09);
  const double perimeter = 2 * (1 - bore) + 2 * height;
  const int around = std::clamp(static_cast<int>(10000 / (2 * perimeter / step)), 20, 96);
  return revolve(p, step, around);
}

std::vector<Eigen::Vector2d> random_outline(Draw& d) {
  switch (d.integer(0, 3)) {
    case 0: {
      const int teeth = d.integer(6, 28);
      const double root = d.real(0.7, 0.92);
      return gear_outline(teeth, root, 1.0, d.integer(2, 4));
    }
    case 1: {
      const double w = d.real(0.6, 1.2), h = d.real(0.3, 1.0);
      const double r = d.chance(0.3) ? 0 : d.real(0.05, 0.9 * std::min(w, h));
      const int per_arc = d.integer(3, 6);
      return rounded_rect(w, h, r, per_arc, d.real(0.05, 0.12));
    }
    case 2: {
      std::vector<Eigen::Vector2d> o;
      const int points = d.integer(5, 9);
      const double inner = d.real(0.4, 0.8);
      for (int k = 0; k < 2 * points; ++k) {
        const double rad = k % 2 ? inner : 1.0, a = k * kPi / points;
        o.emplace_back(rad * std::cos(a), rad * std::sin(a));
      }
      return sample_loop(o, d.real(0.04, 0.1));
    }
    default: {
      std::vector<double> angles;
      const int corners = d.integer(3, 8);
      for (int k = 0; k < corners; ++k) angles.push_back(2 * kPi * (k + d.real(0.1, 0.9)) / corners);
      std::vector<Eigen::Vector2d> o;
      for (const double a : angles) o.push_back(d.real(0.7, 1.0) * Eigen::Vector2d(std::cos(a), std::sin(a)));
      return sample_loop(o, d.real(0.05, 0.12));
    }
  }
}

TriMesh extruded_part(Draw d) {
  const std::vector<Eigen::Vector2d> outline = random_outline(d);
  const int k = static_cast<int>(outline.size());
  const int rows = std::clamp(d.integer(2, 12), 1, std::max(1, 2500 / k));
  const int rings = std::clamp(d.integer(2, 10), 2, std::max(2, 2500 / k));
  const double height = d.real(0.15, 0.9);
  return extrude(outline, height, rows, rings);
}

TriMesh filleted_box(Draw d) {
  const double ps[] = {2.5, 3, 4, 6, 8, 12, 20};
  const double p = ps[d.integer(0, 6)];
  Vec3 axes;
  for (int c = 0; c < 3; ++c) axes(c) = d.real(0.4, 1.2);
  if (d.chance(0.3)) return irregular(superquadric(d.integer(6, 9), p, axes));
  return superquadric(d.integer(8, 22), p, axes);
}

// Shapes that are rough by construction (issue 48; decision 96): detail a few edges wide that a
// filter would take for noise, on clean assets users have. See
// docs/experiments/2026-12-05-rough-clean-shapes.md.

// A rope: a tube along a LoopCurve with `strands` helical strands, grooves between them
// (|cos| has a crease at each zero), 4-6 vertices across a strand.
TriMesh rope(Draw d) {
  const LoopCurve curve{d.real(0, 0.5), d.integer(1, 3)};
  const int strands = d.integer(3, 5), per_strand = d.integer(4, 6);
  const int nv = strands * per_strand;
  const double r0 = d.real(0.12, 0.2), depth = d.real(0.15, 0.3);
  // Twists along the curve: the strands' pitch 1-2.5 tube diameters.
  const int twists = std::max(1, static_cast<int>(std::lround(2 * kPi / (d.real(1, 2.5) * 2 * r0))));
  // Rows about as long as the vertices around are apart (the curve is about 2 pi long), at
  // most 11,000 faces.
  const int nu = std::clamp(static_cast<int>(nv / r0), 60, 11000 / (2 * nv));
  return test::parametric(nu, nv, true, true, [&](double u, double v) {
    const double t = 2 * kPi * u, b = 2 * kPi * v;
    return curve.around(t, b, r0 * (1 - depth + 2 * depth * std::abs(std::cos(0.5 * (strands * b + twists * t)))));
  });
}

// A knurled grip: an open cylinder whose radius carries a diamond knurl (two crossing
// triangle waves) or a straight one, sharp ridges, 4-6 vertices per period.
TriMesh knurl(Draw d) {
  const int periods = d.integer(10, 20), per_period = d.integer(4, 6);
  const int around = periods * per_period;
  const double height = d.real(0.4, 1.5), depth = d.real(0.015, 0.04);
  const bool diamond = d.chance(0.6);
  const double pitch = 2 * kPi / periods;  // the same pitch along the axis as around it
  const int rows = std::clamp(static_cast<int>(height / (pitch / per_period)), 8, 11000 / (2 * around));
  const auto tri = [](double x) { return std::abs(x - 2 * std::floor(0.5 * (x + 1))); };  // 0..1, period 2
  return test::parametric(around, rows, true, false, [&](double u, double v) {
    const double a = 2 * kPi * u, z = height * v;
    const double s = periods * u * 2, w = z / pitch * 2;
    const double ridge = diamond ? 0.5 * (tri(s + w) + tri(s - w)) : tri(s);
    return Vec3((1 + depth * ridge) * std::cos(a), (1 + depth * ridge) * std::sin(a), z);
  });
}

// A surface with relief: an icosphere displaced along its radius by many short waves, 3-10
// edges long and 0.15-0.5 edge lengths high.
TriMesh relief(Draw d) {
  TriMesh m = test::sphere(4);
  const double edge = mean_edge_length(m.V, m.F);
  const int count = d.integer(24, 48);
  const double height = d.real(0.15, 0.5) * edge;
  struct Wave { Vec3 dir; double k, phase; };
  std::vector<Wave> waves;
  for (int i = 0; i < count; ++i) {
    const Vec3 dir{d.real(-1, 1), d.real(-1, 1), d.real(-1, 1)};  // braces: drawn left to right
    const double k = 2 * kPi / (d.real(3, 10) * edge);
    waves.push_back({dir.normalized(), k, d.real(0, 2 * kPi)});
  }
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const Vec3 p = m.V.row(i).transpose();
    double r = 0;
    for (const Wave& w : waves) r += std::sin(w.k * p.dot(w.dir) + w.phase);
    m.V.row(i) = (p.normalized() * (1 + height * r * std::sqrt(2.0 / count))).transpose();
  }
  return m;
}

// A slice stack: a bumpy blob's height quantised to slices 0.8-2 edge lengths apart (the
// terraces of a segmentation's slices or a printer's layers), softened by 1-2 Laplacian passes.
TriMesh sliced(Draw d) {
  const std::uint64_t seed = d.rng();
  const double amplitude = d.real(0.3, 1.1);
  TriMesh m = bumpy(4, seed, amplitude, d.integer(2, 5));
  const Vec3 axis = Vec3{d.real(-1, 1), d.real(-1, 1), d.real(-1, 1)}.normalized();  // braces: in order
  const double step = d.real(0.8, 2.0) * mean_edge_length(m.V, m.F);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const double h = m.V.row(i).dot(axis);
    m.V.row(i) += (std::round(h / step) * step - h) * axis.transpose();
  }
  const Topology topo = Topology::build(m.F, static_cast<std::int32_t>(m.V.rows()));
  m.V = laplacian_smoothing(m.V, topo, d.integer(1, 2));
  return m;
}

}  // namespace

std::vector<Generated> generated_shapes() {
  std::vector<Generated> out;
  const auto add = [&](const std::string& kind, int count, const std::string& family,
                       const std::function<TriMesh(Draw)>& make) {
    for (int k = 0; k < count; ++k) {
      const std::uint64_t seed = hash_name("gen/" + kind) + static_cast<std::uint64_t>(k);
      out.push_back({"gen_" + kind + "_" + std::to_string(k), family, [make, seed] { return make(Draw{std::mt19937_64(seed)}); }});
    }
  };
  add("revolve", 10, "cad", revolved_part);
  add("extrude", 12, "cad", extruded_part);
  add("fillet", 10, "cad", filleted_box);
  // Every draw is its own statement: the order of a call's arguments is unspecified.
  add("fold", 5, "cad", [](Draw d) {
    const int n = d.integer(10, 36);
    return test::fold(n, d.real(30, 170));
  });
  add("blob", 10, "organic", [](Draw d) {
    const int level = d.chance(0.4) ? 3 : 4;
    const std::uint64_t seed = d.rng();
    const double amplitude = d.real(0.3, 1.3);
    return bumpy(level, seed, amplitude, d.integer(2, 7));
  });
  add("terrain", 6, "organic", [](Draw d) {
    const std::uint64_t seed = d.rng();
    return terrain(seed, d.integer(18, 60));
  });
  add("tube", 6, "organic", [](Draw d) {
    const double swell = d.real(0.02, 0.1), lift = d.real(0, 0.7);
    const int turns = d.integer(1, 4), nu = d.integer(48, 140);
    return tube(swell, lift, turns, nu, d.integer(10, 22));
  });
  add("torus", 5, "organic", [](Draw d) {
    const int nu = d.integer(30, 90), nv = d.integer(12, 36);
    return test::torus(nu, nv, d.real(0.15, 0.6));
  });
  add("rope", 4, "rough", rope);
  add("knurl", 4, "rough", knurl);
  add("relief", 4, "rough", relief);
  add("sliced", 4, "rough", sliced);
  return out;
}

}  // namespace mdn::train::kit
