// Building blocks of the corpus's shapes made in code (see shape_kit.h).
#include "shape_kit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <numbers>
#include <random>

#include "support/shapes.h"

namespace mdn::train::kit {

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

Vec3 LoopCurve::around(double t, double b, double r) const {
  const Vec3 c(std::cos(t), std::sin(t), lift * std::sin(turns * t));
  const Vec3 tangent = Vec3(-std::sin(t), std::cos(t), lift * turns * std::cos(turns * t)).normalized();
  const Vec3 n1 = tangent.cross(Vec3(0, 0, 1)).normalized(), n2 = tangent.cross(n1);
  return Vec3(c + r * (std::cos(b) * n1 + std::sin(b) * n2));
}

TriMesh tube(double swell, double lift, int turns, int nu, int nv) {
  const LoopCurve curve{lift, turns};
  return test::parametric(nu, nv, false, true, [&](double u, double v) {
    const double t = 2 * kPi * u, b = 2 * kPi * v, r = 0.18 + swell * std::sin(3 * t);
    return curve.around(t, b, r);
  });
}

// Refines the slab x < min + 0.3 extent twice (16x denser): an irregular tessellation.
TriMesh irregular(const TriMesh& m) {
  const double lo = m.V.col(0).minCoeff(), hi = m.V.col(0).maxCoeff();
  const double cut = lo + 0.3 * (hi - lo);
  const auto slab = [cut](const Vec3& c) { return c.x() < cut; };
  return test::refine_where(test::refine_where(m, slab), slab);
}

namespace {

using Edge = std::pair<int, int>;
Edge edge_key(int a, int b) { return {std::min(a, b), std::max(a, b)}; }
Vec3 vertex(const TriMesh& m, int i) { return m.V.row(i).transpose(); }
Vec3 face_cross(const Vec3& a, const Vec3& b, const Vec3& c) { return (b - a).cross(c - a); }

double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const auto angle = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    return std::atan2((q - p).cross(r - p).norm(), (q - p).dot(r - p));
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

}  // namespace

TriMesh split_along(const TriMesh& m, const Vec3& dir, double max_angle_deg) {
  const Vec3 d = dir.normalized();
  const double cos_min = std::cos(max_angle_deg * kPi / 180);
  std::vector<Vec3> v;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) v.push_back(vertex(m, static_cast<int>(i)));
  std::map<Edge, int> mid;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
      const Vec3 e = v[static_cast<std::size_t>(b)] - v[static_cast<std::size_t>(a)];
      if (std::abs(e.dot(d)) >= cos_min * e.norm() && !mid.count(edge_key(a, b))) {
        mid[edge_key(a, b)] = static_cast<int>(v.size());
        v.push_back(0.5 * (v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]));
      }
    }
  std::vector<std::array<int, 3>> out;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const int c[3] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
    int s[3];  // s[k]: the midpoint of edge c[k] c[k+1], or -1
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      const auto it = mid.find(edge_key(c[k], c[(k + 1) % 3]));
      s[k] = it == mid.end() ? -1 : it->second;
      count += s[k] >= 0;
    }
    if (count == 0) {
      out.push_back({c[0], c[1], c[2]});
    } else if (count == 3) {
      out.push_back({c[0], s[0], s[2]});
      out.push_back({c[1], s[1], s[0]});
      out.push_back({c[2], s[2], s[1]});
      out.push_back({s[0], s[1], s[2]});
    } else {
      // Rotate so that edge 0 is split (count 1) or edge 2 is the unsplit one (count 2).
      int r = 0;
      if (count == 1) while (s[r] < 0) ++r;
      else while (s[(r + 2) % 3] >= 0) ++r;
      const int a = c[r], b = c[(r + 1) % 3], e = c[(r + 2) % 3];
      const int ab = s[r], bc = s[(r + 1) % 3];
      if (count == 1) {
        out.push_back({a, ab, e});
        out.push_back({ab, b, e});
      } else {
        out.push_back({ab, b, bc});
        // The quad a, ab, bc, e: the shorter diagonal.
        const auto len = [&](int p, int q) { return (v[static_cast<std::size_t>(p)] - v[static_cast<std::size_t>(q)]).norm(); };
        if (len(a, bc) <= len(ab, e)) {
          out.push_back({a, ab, bc});
          out.push_back({a, bc, e});
        } else {
          out.push_back({a, ab, e});
          out.push_back({ab, bc, e});
        }
      }
    }
  }
  return tri_mesh_from_lists(v, out);
}

TriMesh flip_random(const TriMesh& m, std::uint64_t seed, double p, double max_dihedral_deg) {
  std::vector<std::array<int, 3>> f(static_cast<std::size_t>(m.F.rows()));
  for (std::size_t i = 0; i < f.size(); ++i)
    for (int k = 0; k < 3; ++k) f[i][static_cast<std::size_t>(k)] = m.F(static_cast<Eigen::Index>(i), k);
  std::map<Edge, std::vector<int>> faces_of;
  for (std::size_t i = 0; i < f.size(); ++i)
    for (int k = 0; k < 3; ++k) faces_of[edge_key(f[i][static_cast<std::size_t>(k)], f[i][static_cast<std::size_t>((k + 1) % 3)])].push_back(static_cast<int>(i));
  std::vector<Edge> edges;
  for (const auto& [e, fs] : faces_of)
    if (fs.size() == 2) edges.push_back(e);
  std::mt19937_64 rng(seed);
  std::shuffle(edges.begin(), edges.end(), rng);
  std::set<Edge> existing;
  for (const auto& [e, _] : faces_of) existing.insert(e);
  std::vector<bool> touched(f.size(), false);
  const double cos_max = std::cos(max_dihedral_deg * kPi / 180), min_new = 2 * kPi / 180;
  std::uniform_real_distribution<double> u(0, 1);
  for (const Edge& e : edges) {
    if (u(rng) >= p) continue;
    const std::vector<int>& fs = faces_of[e];
    const int f1 = fs[0], f2 = fs[1];
    if (touched[static_cast<std::size_t>(f1)] || touched[static_cast<std::size_t>(f2)]) continue;
    // Orient so that f1 holds a -> b and f2 holds b -> a; c and d are the opposite corners.
    const auto& t1 = f[static_cast<std::size_t>(f1)];
    const auto& t2 = f[static_cast<std::size_t>(f2)];
    int k1 = 0;
    while (!((t1[static_cast<std::size_t>(k1)] == e.first || t1[static_cast<std::size_t>(k1)] == e.second) &&
             (t1[static_cast<std::size_t>((k1 + 1) % 3)] == e.first || t1[static_cast<std::size_t>((k1 + 1) % 3)] == e.second)))
      ++k1;
    const int a = t1[static_cast<std::size_t>(k1)], b = t1[static_cast<std::size_t>((k1 + 1) % 3)], c = t1[static_cast<std::size_t>((k1 + 2) % 3)];
    int d = -1;
    for (int k = 0; k < 3; ++k)
      if (t2[static_cast<std::size_t>(k)] != a && t2[static_cast<std::size_t>(k)] != b) d = t2[static_cast<std::size_t>(k)];
    if (d < 0 || c == d || existing.count(edge_key(c, d))) continue;
    const Vec3 A = vertex(m, a), B = vertex(m, b), C = vertex(m, c), D = vertex(m, d);
    const Vec3 n1 = face_cross(A, B, C).normalized(), n2 = face_cross(B, A, D).normalized();
    if (n1.dot(n2) < cos_max) continue;
    // The new faces (c, a, d) and (c, d, b) keep the orientation (shape_kit.h).
    const Vec3 m1 = face_cross(C, A, D), m2 = face_cross(C, D, B);
    if (m1.norm() <= 0 || m2.norm() <= 0) continue;
    const Vec3 old_n = (n1 + n2).normalized();
    if (m1.normalized().dot(old_n) < cos_max || m2.normalized().dot(old_n) < cos_max) continue;
    if (min_angle(C, A, D) < min_new || min_angle(C, D, B) < min_new) continue;
    f[static_cast<std::size_t>(f1)] = {c, a, d};
    f[static_cast<std::size_t>(f2)] = {c, d, b};
    touched[static_cast<std::size_t>(f1)] = touched[static_cast<std::size_t>(f2)] = true;
    existing.erase(e);
    existing.insert(edge_key(c, d));
  }
  std::vector<Vec3> v;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) v.push_back(vertex(m, static_cast<int>(i)));
  return tri_mesh_from_lists(v, f);
}

TriMesh retessellate(const TriMesh& m, std::uint64_t seed, std::string* tag) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const int style = std::uniform_int_distribution<int>(0, 3)(rng);
  Vec3 dir(u(rng), u(rng), u(rng));
  if (dir.norm() < 1e-3) dir = Vec3::UnitX();
  const double spread = std::uniform_real_distribution<double>(25, 40)(rng);
  const std::uint64_t flip_seed = rng();
  static const char* const kTags[] = {"aniso1", "aniso2", "flip", "aniso1+flip"};
  if (tag) *tag = kTags[style];
  switch (style) {
    case 0: return split_along(m, dir, spread);
    case 1: return split_along(split_along(m, dir, spread), dir, spread);
    case 2: return flip_random(m, flip_seed, 0.6, 8);
    default: return flip_random(split_along(m, dir, spread), flip_seed, 0.6, 8);
  }
}

}  // namespace mdn::train::kit
