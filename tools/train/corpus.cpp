#include "corpus.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>

#include "../../tests/bench/cgal_data.h"
#include "core/noise.h"
#include "support/shapes.h"

namespace mdn::train {

namespace {

constexpr double kPi = std::numbers::pi;

// Flips every face if the closed mesh's signed volume is negative (outward normals).
void orient_outward(TriMesh& m) {
  double volume = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Vec3 a = m.V.row(m.F(f, 0)).transpose(), b = m.V.row(m.F(f, 1)).transpose(), c = m.V.row(m.F(f, 2)).transpose();
    volume += a.dot(b.cross(c));
  }
  if (volume < 0)
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) std::swap(m.F(f, 1), m.F(f, 2));
}

// Samples a closed polyline: each corner exactly, each side split into pieces of at most `step`.
std::vector<Eigen::Vector2d> sample_loop(const std::vector<Eigen::Vector2d>& corners, double step) {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const Eigen::Vector2d a = corners[k], b = corners[(k + 1) % corners.size()];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
    for (int i = 0; i < n; ++i) out.push_back(a + (b - a) * (double(i) / n));
  }
  return out;
}

// A quarter (or any) arc from angle a0 to a1 around c with radius r, n segments, end excluded.
void arc(std::vector<Eigen::Vector2d>& out, Eigen::Vector2d c, double r, double a0, double a1, int n) {
  for (int i = 0; i < n; ++i) {
    const double t = a0 + (a1 - a0) * i / n;
    out.push_back(c + r * Eigen::Vector2d(std::cos(t), std::sin(t)));
  }
}

// A closed profile loop in the (r, z) half-plane (r > 0) revolved around z: genus 1, sharp
// creases where the profile has corners (grid rows sit on them).
TriMesh revolve(const std::vector<Eigen::Vector2d>& corners, double step, int around) {
  const std::vector<Eigen::Vector2d> loop = sample_loop(corners, step);
  const int nu = static_cast<int>(loop.size());
  TriMesh m = test::parametric(nu, around, true, true, [&](double u, double v) {
    const Eigen::Vector2d p = loop[static_cast<std::size_t>(std::lround(u * nu)) % loop.size()];
    const double a = 2 * kPi * v;
    return Vec3(p.x() * std::cos(a), p.x() * std::sin(a), p.y());
  });
  orient_outward(m);
  return m;
}

// A star-shaped outline (counter-clockwise around the origin) extruded to height h with `rows`
// rows of side quads and caps made of `rings` rings around a centre vertex.
TriMesh extrude(const std::vector<Eigen::Vector2d>& outline, double h, int rows, int rings) {
  const int K = static_cast<int>(outline.size());
  std::vector<Vec3> V;
  std::vector<std::array<int, 3>> F;
  const auto side = [&](int k, int z) { return z * K + ((k % K) + K) % K; };
  for (int z = 0; z <= rows; ++z)
    for (int k = 0; k < K; ++k) V.emplace_back(outline[static_cast<std::size_t>(k)].x(), outline[static_cast<std::size_t>(k)].y(), h * z / rows);
  for (int z = 0; z < rows; ++z)
    for (int k = 0; k < K; ++k) {
      F.push_back({side(k, z), side(k + 1, z), side(k + 1, z + 1)});
      F.push_back({side(k, z), side(k + 1, z + 1), side(k, z + 1)});
    }
  for (const bool top : {false, true}) {
    const double zc = top ? h : 0;
    // ring j (1 .. rings - 1) at scale j / rings; ring `rings` is the side's rim.
    std::vector<int> ring_start(static_cast<std::size_t>(rings + 1));
    for (int j = 1; j < rings; ++j) {
      ring_start[static_cast<std::size_t>(j)] = static_cast<int>(V.size());
      for (int k = 0; k < K; ++k) {
        const Eigen::Vector2d p = outline[static_cast<std::size_t>(k)] * (double(j) / rings);
        V.emplace_back(p.x(), p.y(), zc);
      }
    }
    const int centre = static_cast<int>(V.size());
    V.emplace_back(0, 0, zc);
    const auto at = [&](int j, int k) {
      return j == rings ? side(k, top ? rows : 0) : ring_start[static_cast<std::size_t>(j)] + ((k % K) + K) % K;
    };
    const auto tri = [&](int a, int b, int c) {
      if (top) F.push_back({a, b, c});
      else F.push_back({a, c, b});
    };
    for (int k = 0; k < K; ++k) tri(centre, at(1, k), at(1, k + 1));
    for (int j = 1; j < rings; ++j)
      for (int k = 0; k < K; ++k) {
        tri(at(j, k), at(j + 1, k), at(j + 1, k + 1));
        tri(at(j, k), at(j + 1, k + 1), at(j, k + 1));
      }
  }
  TriMesh m;
  m.V.resize(static_cast<Eigen::Index>(V.size()), 3);
  for (std::size_t i = 0; i < V.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = V[i].transpose();
  m.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (std::size_t f = 0; f < F.size(); ++f) m.F.row(static_cast<Eigen::Index>(f)) << F[f][0], F[f][1], F[f][2];
  orient_outward(m);
  return m;
}

std::vector<Eigen::Vector2d> gear_outline(int teeth, double root, double tip, int per_arc) {
  std::vector<Eigen::Vector2d> out;
  const double pitch = 2 * kPi / teeth;
  for (int t = 0; t < teeth; ++t) {
    const double a = t * pitch;
    // root arc, flank up, tip arc, flank down (the flanks are single straight segments)
    for (int i = 0; i < per_arc; ++i) {
      const double ang = a + 0.5 * pitch * i / per_arc;
      out.emplace_back(root * std::cos(ang), root * std::sin(ang));
    }
    for (int i = 0; i < per_arc; ++i) {
      const double ang = a + 0.55 * pitch + 0.35 * pitch * i / per_arc;
      out.emplace_back(tip * std::cos(ang), tip * std::sin(ang));
    }
  }
  return out;
}

std::vector<Eigen::Vector2d> rounded_rect(double w, double h, double r, int per_arc, double step) {
  std::vector<Eigen::Vector2d> out;
  const Eigen::Vector2d c[4] = {{w - r, h - r}, {-w + r, h - r}, {-w + r, -h + r}, {w - r, -h + r}};
  for (int q = 0; q < 4; ++q) {
    if (r > 0) arc(out, c[q], r, q * kPi / 2, (q + 1) * kPi / 2, per_arc);
    else out.push_back(c[q]);
    // straight side to the next corner's arc start
    const Eigen::Vector2d from = c[q] + r * Eigen::Vector2d(std::cos((q + 1) * kPi / 2), std::sin((q + 1) * kPi / 2));
    const Eigen::Vector2d to = c[(q + 1) % 4] + r * Eigen::Vector2d(std::cos((q + 1) * kPi / 2), std::sin((q + 1) * kPi / 2));
    const int n = std::max(1, static_cast<int>(std::ceil((to - from).norm() / step)));
    for (int i = (r > 0 ? 0 : 1); i < n; ++i) out.push_back(from + (to - from) * (double(i) / n));
  }
  return out;
}

// A cube whose surface is pushed onto the p-norm ball scaled by `axes`: p = 2 an ellipsoid,
// large p a box with fillets whose radius shrinks as p grows.
TriMesh superquadric(int n, double p, const Vec3& axes) {
  TriMesh m = test::cube(n);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const Vec3 d = m.V.row(i).transpose().normalized();
    const double norm = std::pow(std::pow(std::abs(d.x()), p) + std::pow(std::abs(d.y()), p) + std::pow(std::abs(d.z()), p), 1.0 / p);
    m.V.row(i) = (d / norm).cwiseProduct(axes).transpose();
  }
  return m;
}

// A smooth random surface: an icosphere displaced by seeded low-order harmonics.
TriMesh bumpy(int level, std::uint64_t seed, double amplitude, int max_freq) {
  TriMesh m = test::sphere(level);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  struct Wave { Vec3 dir; double freq, phase, amp; };
  std::vector<Wave> waves;
  for (int k = 0; k < 6; ++k)
    waves.push_back({Vec3(U(rng), U(rng), U(rng)).normalized(), 1 + (max_freq - 1) * (U(rng) + 1) / 2, kPi * U(rng),
                     amplitude * (0.4 + 0.6 * (U(rng) + 1) / 2)});
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const Vec3 d = m.V.row(i).transpose().normalized();
    double r = 1;
    for (const Wave& w : waves) r += w.amp * std::sin(w.freq * d.dot(w.dir) * kPi + w.phase) / 6;
    m.V.row(i) = (r * d).transpose();
  }
  return m;
}

TriMesh terrain(std::uint64_t seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  std::vector<std::array<double, 5>> bumps;
  for (int k = 0; k < 5; ++k) bumps.push_back({U(rng) * 0.7, U(rng) * 0.7, 0.25 * U(rng), 4 + 10 * (U(rng) + 1), U(rng)});
  return test::parametric(n, n, false, false, [&](double u, double v) {
    const double x = 2 * u - 1, y = 2 * v - 1;
    double z = 0.08 * std::sin(2.5 * x + 3 * bumps[0][4]) * std::cos(2 * y + bumps[1][4]);
    for (const auto& b : bumps) z += b[2] * std::exp(-b[3] * ((x - b[0]) * (x - b[0]) + (y - b[1]) * (y - b[1])));
    return Vec3(x, y, z);
  });
}

TriMesh tube(double swell, double lift, int turns, int nu, int nv) {
  return test::parametric(nu, nv, false, true, [&](double u, double v) {
    const double t = 2 * kPi * u, b = 2 * kPi * v, r = 0.18 + swell * std::sin(3 * t);
    const Vec3 c(std::cos(t), std::sin(t), lift * std::sin(turns * t));
    const Vec3 tangent = Vec3(-std::sin(t), std::cos(t), lift * turns * std::cos(turns * t)).normalized();
    const Vec3 n1 = tangent.cross(Vec3(0, 0, 1)).normalized(), n2 = tangent.cross(n1);
    return Vec3(c + r * (std::cos(b) * n1 + std::sin(b) * n2));
  });
}

// Refines the slab x < min + 0.3 extent twice (16x denser): an irregular tessellation.
TriMesh irregular(const TriMesh& m) {
  const double lo = m.V.col(0).minCoeff(), hi = m.V.col(0).maxCoeff();
  const double cut = lo + 0.3 * (hi - lo);
  const auto slab = [cut](const Vec3& c) { return c.x() < cut; };
  return test::refine_where(test::refine_where(m, slab), slab);
}

using Maker = std::function<TriMesh()>;

const std::vector<std::pair<std::string, std::pair<std::string, Maker>>>& procedural() {
  static const std::vector<std::pair<std::string, std::pair<std::string, Maker>>> list = [] {
    std::vector<std::pair<std::string, std::pair<std::string, Maker>>> l;
    const auto add = [&](std::string name, std::string family, Maker m) { l.push_back({std::move(name), {std::move(family), std::move(m)}}); };
    // CAD: sharp boxes, folds, filleted boxes, revolved parts, extrusions, a low-poly cylinder.
    add("box_sharp", "cad", [] { return test::cube(16); });
    add("box_stretched", "cad", [] {  // anisotropic tessellation: long triangles on the long faces
      TriMesh m = test::cube(14);
      m.V.col(0) *= 2.2;
      m.V.col(2) *= 0.6;
      return m;
    });
    add("box_irregular", "cad", [] { return irregular(test::cube(10)); });
    for (const int angle : {60, 90, 120, 150})
      add("fold_" + std::to_string(angle), "cad", [angle] { return test::fold(30, angle); });
    add("rounded_box_p4", "cad", [] { return superquadric(16, 4, Vec3(1, 0.8, 0.6)); });
    add("rounded_box_p8", "cad", [] { return superquadric(16, 8, Vec3(1, 1, 0.7)); });
    add("rounded_box_p16", "cad", [] { return superquadric(16, 16, Vec3(1.2, 0.7, 0.7)); });
    add("rounded_box_p12_irregular", "cad", [] { return irregular(superquadric(10, 12, Vec3(1, 0.9, 0.8))); });
    add("washer", "cad", [] { return revolve({{0.5, 0}, {1, 0}, {1, 0.3}, {0.5, 0.3}}, 0.05, 64); });
    add("washer_chamfer", "cad", [] {
      return revolve({{0.5, 0}, {0.92, 0}, {1, 0.08}, {1, 0.22}, {0.92, 0.3}, {0.5, 0.3}}, 0.04, 64);
    });
    add("washer_fillet", "cad", [] {
      std::vector<Eigen::Vector2d> p{{0.5, 0}};
      arc(p, {0.88, 0.12}, 0.12, -kPi / 2, 0, 5);
      arc(p, {0.88, 0.28}, 0.12, 0, kPi / 2, 5);
      p.emplace_back(0.5, 0.4);
      return revolve(p, 0.04, 64);
    });
    add("pulley", "cad", [] {
      return revolve({{0.3, 0}, {1, 0}, {1, 0.1}, {0.75, 0.25}, {1, 0.4}, {1, 0.5}, {0.3, 0.5}}, 0.04, 72);
    });
    add("stepped_shaft", "cad", [] {
      return revolve({{0.15, 0}, {0.4, 0}, {0.4, 0.6}, {0.3, 0.6}, {0.3, 1.2}, {0.22, 1.25}, {0.22, 1.7}, {0.15, 1.7}}, 0.05,
                     48);
    });
    add("flange", "cad", [] {
      return revolve({{0.25, 0}, {1, 0}, {1, 0.12}, {0.45, 0.12}, {0.45, 0.5}, {0.25, 0.5}}, 0.04, 72);
    });
    add("boss_ring", "cad", [] {
      return revolve({{0.6, 0}, {1, 0}, {1, 0.15}, {0.85, 0.15}, {0.85, 0.35}, {0.7, 0.35}, {0.7, 0.15}, {0.6, 0.15}}, 0.04,
                     64);
    });
    add("gear_12", "cad", [] { return extrude(gear_outline(12, 0.8, 1.0, 4), 0.35, 5, 7); });
    add("gear_20", "cad", [] { return extrude(gear_outline(20, 0.88, 1.0, 3), 0.25, 4, 6); });
    add("plate_rounded", "cad", [] { return extrude(rounded_rect(1, 0.6, 0.2, 5, 0.08), 0.15, 2, 8); });
    add("plate_sharp", "cad", [] { return extrude(rounded_rect(1, 0.7, 0, 1, 0.07), 0.3, 4, 10); });
    add("star_prism", "cad", [] {
      std::vector<Eigen::Vector2d> o;
      for (int k = 0; k < 10; ++k) {
        const double r = k % 2 ? 0.5 : 1.0, a = k * kPi / 5;
        o.emplace_back(r * std::cos(a), r * std::sin(a));
      }
      return extrude(sample_loop(o, 0.06), 0.4, 6, 8);
    });
    add("hex_prism", "cad", [] {
      std::vector<Eigen::Vector2d> o;
      for (int k = 0; k < 6; ++k) o.emplace_back(std::cos(k * kPi / 3), std::sin(k * kPi / 3));
      return extrude(sample_loop(o, 0.06), 0.8, 12, 10);
    });
    add("cam", "cad", [] {
      std::vector<Eigen::Vector2d> o;
      for (int k = 0; k < 96; ++k) {
        const double a = 2 * kPi * k / 96;
        o.emplace_back(std::cos(a) * (1 + 0.3 * std::cos(a)), 0.8 * std::sin(a));
      }
      return extrude(o, 0.3, 4, 8);
    });
    add("cylinder_lowpoly", "cad", [] { return test::closed_cylinder(48, 10, 1.6); });
    // Organic: spheres, ellipsoids, bumpy blobs, tori, terrains, tubes.
    add("ico_sphere", "organic", [] { return test::sphere(4); });
    add("ellipsoid", "organic", [] { return superquadric(16, 2, Vec3(1, 0.6, 0.4)); });
    add("ellipsoid_irregular", "organic", [] { return irregular(superquadric(10, 2, Vec3(1, 0.7, 0.7))); });
    for (int k = 0; k < 5; ++k)
      add("blob_" + std::to_string(k), "organic",
          [k] { return bumpy(4, 1000 + std::uint64_t(k), 0.5 + 0.25 * k, 2 + k); });
    add("torus_thin", "organic", [] { return test::torus(80, 20, 0.2); });
    add("torus_mid", "organic", [] { return test::torus(64, 24, 0.35); });
    add("torus_fat", "organic", [] { return test::torus(48, 32, 0.55); });
    for (int k = 0; k < 4; ++k)
      add("terrain_" + std::to_string(k), "organic", [k] { return terrain(2000 + std::uint64_t(k), 40); });
    add("tube_a", "organic", [] { return tube(0.06, 0.4, 2, 96, 16); });
    add("tube_b", "organic", [] { return tube(0.09, 0.2, 3, 120, 14); });
    add("tube_c", "organic", [] { return tube(0.03, 0.6, 1, 80, 20); });
    // Coarser tessellations of the same kinds of surface (a few hundred to 1,500 faces).
    add("box_coarse", "cad", [] { return test::cube(7); });
    add("rounded_box_coarse", "cad", [] { return superquadric(8, 6, Vec3(1, 0.8, 0.8)); });
    add("washer_coarse", "cad", [] { return revolve({{0.5, 0}, {1, 0}, {1, 0.3}, {0.5, 0.3}}, 0.12, 32); });
    add("gear_coarse", "cad", [] { return extrude(gear_outline(10, 0.75, 1.0, 2), 0.4, 3, 3); });
    add("fold_coarse", "cad", [] { return test::fold(14, 100); });
    add("stepped_coarse", "cad", [] {
      return revolve({{0.15, 0}, {0.4, 0}, {0.4, 0.6}, {0.25, 0.6}, {0.25, 1.2}, {0.15, 1.2}}, 0.12, 24);
    });
    add("sphere_coarse", "organic", [] { return test::sphere(3); });
    add("blob_coarse_a", "organic", [] { return bumpy(3, 1100, 0.6, 2); });
    add("blob_coarse_b", "organic", [] { return bumpy(3, 1101, 0.9, 3); });
    add("torus_coarse", "organic", [] { return test::torus(36, 14, 0.4); });
    add("terrain_coarse", "organic", [] { return terrain(2100, 20); });
    add("tube_coarse", "organic", [] { return tube(0.05, 0.3, 2, 48, 10); });
    add("plate_coarse", "cad", [] { return extrude(rounded_rect(1, 0.5, 0.15, 3, 0.15), 0.2, 2, 4); });
    return l;
  }();
  return list;
}

// CGAL demo meshes that may train: not a standard test shape, not a validation mesh of
// tune_bench (1,000-20,000 triangles there), not a derivative of either.
const std::vector<std::string> kCgalTraining = {"cube-meshed", "anchor_dense", "rotor", "dino", "man", "pig", "cow",
                                                "bull", "camel", "bear", "bear_bis", "mannequin-devil", "oblong", "nefertiti",
                                                "part", "diplodocus", "polygon_mesh"};

}  // namespace

bool is_training_cgal_mesh(const std::string& name) {
  return std::find(kCgalTraining.begin(), kCgalTraining.end(), name) != kCgalTraining.end();
}

std::uint64_t hash_name(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const char ch : text) h = (h ^ static_cast<unsigned char>(ch)) * 1099511628211ull;
  return h;
}

std::string split_of(const std::string& shape) { return hash_name("split/" + shape) % 5 == 0 ? "holdout" : "train"; }

std::vector<std::string> shape_names(const std::filesystem::path& cgal_dir) {
  std::vector<std::string> names;
  for (const auto& [name, _] : procedural()) names.push_back(name);
  for (const std::string& name : kCgalTraining)
    if (!cgal_dir.empty() && std::filesystem::exists(cgal_dir / (name + ".off"))) names.push_back("cgal_" + name);
  return names;
}

Shape make_shape(const std::string& name, const std::filesystem::path& cgal_dir) {
  for (const auto& [n, entry] : procedural())
    if (n == name) return {name, entry.first, entry.second()};
  if (name.rfind("cgal_", 0) == 0) {
    const std::string file = name.substr(5);
    if (std::find(kCgalTraining.begin(), kCgalTraining.end(), file) == kCgalTraining.end())
      throw std::invalid_argument("not a training shape: " + name);
    return {name, "cgal", bench::load_off(cgal_dir / (file + ".off"))};
  }
  throw std::invalid_argument("unknown shape: " + name);
}

std::vector<std::string> noise_names() {
  return {"clean",          "along:0.05",     "along:0.1",   "along:0.15",  "along:0.2",   "along:0.3",
          "along:0.4",      "along:0.5",      "along:0.6",   "along:0.7",   "along:0.8",   "iso:0.1",
          "iso:0.2",        "iso:0.3",        "iso:0.45",    "iso:0.6",     "dir:0.15",    "dir:0.35",
          "impulse:0.05:0.5", "impulse:0.1:0.6", "impulse:0.2:0.4", "impulse:0.3:0.3", "impulse:0.15:0.8",
          "scan:0.1",       "scan:0.2",       "scan:0.35",   "scan:0.5",    "mix:0.1:0.1", "mix:0.3:0.05",
          "mix:0.2:0.2"};
}

std::vector<std::string> noise_names_for(const Shape& shape) {
  std::vector<std::string> all = noise_names(), out;
  if (shape.mesh.num_faces() <= 12000) return all;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (i % 5 == 0) out.push_back(all[i]);
  return out;
}

namespace {

std::vector<double> parse_levels(const std::string& noise) {
  std::vector<double> out;
  std::size_t at = noise.find(':');
  while (at != std::string::npos) {
    const std::size_t next = noise.find(':', at + 1);
    out.push_back(std::stod(noise.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1)));
    at = next;
  }
  return out;
}

// A scanner-like model: noise along one view direction whose deviation grows with depth,
// a low-frequency ripple, and the depth quantized to a step of sigma.
Vertices scanner_noise(const TriMesh& clean, double sigma_edges, std::uint64_t seed) {
  const double l = mean_edge_length(clean.V, clean.F);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0, 1);
  const Vec3 d = Vec3(N(rng), N(rng), N(rng)).normalized();
  const Vec3 wave = Vec3(N(rng), N(rng), N(rng)).normalized();
  const double phase = N(rng);
  const Eigen::VectorXd depth = clean.V * d;
  const double lo = depth.minCoeff(), span = std::max(1e-12, depth.maxCoeff() - lo);
  const double extent = (clean.V.colwise().maxCoeff() - clean.V.colwise().minCoeff()).norm();
  const std::vector<double> g = gaussian_draws(static_cast<std::size_t>(clean.V.rows()), seed ^ 0x5ca9);
  const double s = sigma_edges * l, step = s;
  Vertices out = clean.V;
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    const double t = (depth(i) - lo) / span;
    double z = depth(i) + s * (0.5 + t) * g[static_cast<std::size_t>(i)];
    z += 0.5 * s * std::sin(2 * kPi * (clean.V.row(i).dot(wave) / (0.3 * extent)) + phase);
    z = std::round(z / step) * step;
    out.row(i) += (z - depth(i)) * d.transpose();
  }
  return out;
}

}  // namespace

Vertices apply_noise(const TriMesh& clean, const std::string& noise, std::uint64_t seed) {
  const std::string kind = noise.substr(0, noise.find(':'));
  const std::vector<double> v = parse_levels(noise);
  const auto gauss = [&](NoiseKind k, double sigma, double fraction, std::uint64_t s) {
    return add_noise(clean, NoiseSpec{k, sigma, s, fraction});
  };
  if (kind == "clean") return clean.V;
  if (kind == "along") return gauss(NoiseKind::AlongNormal, v.at(0), 0, seed);
  if (kind == "iso") return gauss(NoiseKind::PerCoordinate, v.at(0), 0, seed);
  if (kind == "dir") return gauss(NoiseKind::RandomDirection, v.at(0), 0, seed);
  if (kind == "impulse") return gauss(NoiseKind::AlongNormal, v.at(1), v.at(0), seed);
  if (kind == "scan") return scanner_noise(clean, v.at(0), seed);
  if (kind == "mix") {  // Gaussian along the normal plus impulses of 0.6 l on a share of the vertices
    const Vertices a = gauss(NoiseKind::AlongNormal, v.at(0), 0, seed);
    const Vertices b = gauss(NoiseKind::AlongNormal, 0.6, v.at(1), seed ^ 0x1f3d);
    return a + (b - clean.V);
  }
  throw std::invalid_argument("unknown noise: " + noise);
}

}  // namespace mdn::train
