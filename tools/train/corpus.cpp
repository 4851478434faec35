#include "corpus.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>

#include "bench/cgal_data.h"
#include "core/noise.h"
#include "range_scan.h"
#include "shape_kit.h"
#include "support/shapes.h"

namespace mdn::train {

namespace {

using namespace kit;

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
    // The second generation (2026-12-03): seeded random members of the same families.
    for (const Generated& g : generated_shapes()) add(g.name, g.family, g.make);
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

namespace {
// A retessellated copy of a shape is named PARENT~tess (decision 44); it is the parent's
// surface, so it follows the parent's split.
constexpr const char* kTessSuffix = "~tess";
std::string parent_of(const std::string& shape) { return shape.substr(0, shape.find('~')); }
bool gets_retessellated(const std::string& shape) { return hash_name("tess/" + shape) % 3 == 0; }
}  // namespace

std::string split_of(const std::string& shape) {
  return hash_name("split/" + parent_of(shape)) % 5 == 0 ? "holdout" : "train";
}

std::vector<std::string> shape_names(const std::filesystem::path& cgal_dir) {
  std::vector<std::string> names;
  for (const auto& [name, _] : procedural()) names.push_back(name);
  for (const std::string& name : kCgalTraining)
    if (!cgal_dir.empty() && std::filesystem::exists(cgal_dir / (name + ".off"))) names.push_back("cgal_" + name);
  const std::size_t parents = names.size();
  for (std::size_t i = 0; i < parents; ++i)
    if (gets_retessellated(names[i])) names.push_back(names[i] + kTessSuffix);
  return names;
}

Shape make_shape(const std::string& name, const std::filesystem::path& cgal_dir) {
  if (name.size() > std::string(kTessSuffix).size() && name.ends_with(kTessSuffix)) {
    const std::string parent = parent_of(name);
    if (parent + kTessSuffix != name || !gets_retessellated(parent)) throw std::invalid_argument("unknown shape: " + name);
    Shape s = make_shape(parent, cgal_dir);
    s.name = name;
    s.mesh = retessellate(s.mesh, hash_name("tess/" + parent));
    return s;
  }
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

namespace {
// The noise kinds on the shape's own mesh (before the depth-camera kinds).
std::vector<std::string> base_noise_names() {
  return {"clean",          "along:0.05",     "along:0.1",   "along:0.15",  "along:0.2",   "along:0.3",
          "along:0.4",      "along:0.5",      "along:0.6",   "along:0.7",   "along:0.8",   "iso:0.1",
          "iso:0.2",        "iso:0.3",        "iso:0.45",    "iso:0.6",     "dir:0.15",    "dir:0.35",
          "impulse:0.05:0.5", "impulse:0.1:0.6", "impulse:0.2:0.4", "impulse:0.3:0.3", "impulse:0.15:0.8",
          "scan:0.1",       "scan:0.2",       "scan:0.35",   "scan:0.5",    "mix:0.1:0.1", "mix:0.3:0.05",
          "mix:0.2:0.2",
          // Decision 50: scanner spikes, a few vertices far off (appended: the larger shapes'
          // every fifth kind stays the same, plus the first of these).
          "impulse:0.01:1", "impulse:0.02:0.6",
          // Decision 98: more of them, around the kind the choice left alone (appended at
          // indices 32-34, none a fifth: the larger shapes' list is unchanged).
          "impulse:0.005:1", "impulse:0.01:0.7", "impulse:0.015:1.5"};
}
}  // namespace

std::vector<std::string> scan_noise_names() {
  // Decision 60: per sensor, objects at three distances across the sensors' range (0.6, 1.2
  // and 2.2 m), each about a third (structured light) or a quarter (time of flight) of its
  // distance in size, so that a scan holds 800-32,000 faces like the rest of the corpus,
  // and a second pose of the middle one. The noise in mean edge lengths is set by the
  // distance (the footprint and sigma(z) both grow with it), the detail by the size. The
  // fused kinds ("fused_sl:SIZE:DIST", "fused_tof:SIZE:DIST") are built by name but not listed
  // (decision 60; decision 99: a model trained with them on the closed shapes failed its rule).
  //
  // Decision 93: structured light also sampled at its native 640x480 ("scan_sl640"), as real
  // scans are meshed, where neighbouring vertices' errors correlate at 8/9 and a ring reads a
  // noisy scan as nearly clean; half the object sizes keep the faces in the corpus's range.
  return {"scan_sl:0.2:0.6",   "scan_sl:0.4:1.2",  "scan_sl:0.7:2.2",   "scan_sl:0.4:1.2:1",
          "scan_tof:0.15:0.6", "scan_tof:0.3:1.2", "scan_tof:0.55:2.2", "scan_tof:0.3:1.2:1",
          "scan_sl640:0.2:1.2", "scan_sl640:0.35:2.2"};
}

std::vector<std::string> fused_noise_names() { return {"fused_sl:0.4:1.2", "fused_tof:0.3:1.2"}; }

bool is_scan_noise(const std::string& noise) {
  for (const char* kind : {"scan_sl:", "scan_sl640:", "scan_tof:", "fused_sl:", "fused_tof:"})
    if (noise.rfind(kind, 0) == 0) return true;
  return false;
}

std::vector<std::string> noise_names() {
  std::vector<std::string> all = base_noise_names();
  for (const std::string& n : scan_noise_names()) all.push_back(n);
  return all;
}

std::vector<std::string> noise_names_for(const Shape& shape) {
  if (shape.mesh.num_faces() <= 12000) return noise_names();
  std::vector<std::string> all = base_noise_names(), out;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (i % 5 == 0) out.push_back(all[i]);
  for (const std::string& n : scan_noise_names()) out.push_back(n);
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
  if (is_scan_noise(noise)) throw std::invalid_argument("a depth-camera case has its own mesh: make_noisy_case(" + noise + ")");
  if (kind == "mix") {  // Gaussian along the normal plus impulses of 0.6 l on a share of the vertices
    const Vertices a = gauss(NoiseKind::AlongNormal, v.at(0), 0, seed);
    const Vertices b = gauss(NoiseKind::AlongNormal, 0.6, v.at(1), seed ^ 0x1f3d);
    return a + (b - clean.V);
  }
  throw std::invalid_argument("unknown noise: " + noise);
}

NoisyCase scan_case(const TriMesh& mesh, const std::string& noise, std::uint64_t seed) {
  const std::string kind = noise.substr(0, noise.find(':'));
  const std::vector<double> v = parse_levels(noise);
  if (!is_scan_noise(noise) || v.size() < 2 || v.size() > 3) throw std::invalid_argument("unknown noise: " + noise);
  const bool native = kind == "scan_sl640";  // decision 93: every native pixel
  RangeSensor sensor = kind.ends_with("_sl") || native ? kinect_v1() : kinect_v2();
  if (native) sensor.stride = 1;
  const bool fused = kind.rfind("fused_", 0) == 0;
  // The pose is the seed's; a pose that sees fewer than 100 faces of the shape (a thin part
  // edge-on) is replaced by the next seed's, so that every name makes a case (decision 60).
  for (std::uint64_t attempt = 0;; ++attempt) {
    try {
      const ScanPose pose{v[0], v[1], seed + attempt};
      RangeScan s = fused ? fuse_scans(mesh, sensor, pose) : scan_shape(mesh, sensor, pose);
      return {std::move(s.clean), std::move(s.noisy)};
    } catch (const std::runtime_error&) {
      if (attempt == 7) throw;
    }
  }
}

NoisyCase make_noisy_case(const Shape& shape, const std::string& noise, std::uint64_t seed) {
  if (is_scan_noise(noise)) return scan_case(shape.mesh, noise, seed);
  return {shape.mesh, apply_noise(shape.mesh, noise, seed)};
}

}  // namespace mdn::train
