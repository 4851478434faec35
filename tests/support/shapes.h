// Small procedural test meshes with known geometry (header-only, namespace mdn::test).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "core/mesh.h"

namespace mdn::test {

// n x n quads over [0, size]^2 at z = 0, each split into two triangles; normal +z.
// alternate: alternate the diagonal per cell (no preferred direction); otherwise every
// cell is split along the same diagonal (every edge's quad is then a parallelogram).
inline TriMesh plane(int n, double size = 1.0, bool alternate = true) {
  TriMesh m;
  m.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.V.row(j * (n + 1) + i) << size * i / n, size * j / n, 0.0;
  m.F.resize(2 * n * n, 3);
  int f = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      // Alternate the diagonal so the triangulation has no preferred direction.
      if (!alternate || (i + j) % 2 == 0) {
        m.F.row(f++) << a, b, d;
        m.F.row(f++) << a, d, c;
      } else {
        m.F.row(f++) << a, b, c;
        m.F.row(f++) << b, d, c;
      }
    }
  return m;
}

// Axis-aligned cube [-0.5, 0.5]^3, each face an n x n grid, shared edge vertices welded;
// outward normals.
inline TriMesh cube(int n) {
  TriMesh m;
  std::map<std::array<long long, 3>, int> index;  // welding on the integer lattice
  std::vector<std::array<double, 3>> verts;
  std::vector<std::array<int, 3>> tris;
  auto vertex = [&](const std::array<int, 3>& g) {
    const std::array<long long, 3> key{g[0], g[1], g[2]};
    auto [it, inserted] = index.emplace(key, static_cast<int>(verts.size()));
    if (inserted) verts.push_back({double(g[0]) / n - 0.5, double(g[1]) / n - 0.5, double(g[2]) / n - 0.5});
    return it->second;
  };
  // For each of the 6 faces: axis, side (0 or n), and two tangent axes ordered for outward normals.
  const int faces[6][4] = {{0, n, 1, 2}, {0, 0, 2, 1}, {1, n, 2, 0}, {1, 0, 0, 2}, {2, n, 0, 1}, {2, 0, 1, 0}};
  for (const auto& fc : faces) {
    const int axis = fc[0], side = fc[1], u = fc[2], v = fc[3];
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        auto at = [&](int a, int b) {
          std::array<int, 3> g{};
          g[axis] = side;
          g[u] = a;
          g[v] = b;
          return vertex(g);
        };
        const int p00 = at(i, j), p10 = at(i + 1, j), p01 = at(i, j + 1), p11 = at(i + 1, j + 1);
        if ((i + j) % 2 == 0) {
          tris.push_back({p00, p10, p11});
          tris.push_back({p00, p11, p01});
        } else {
          tris.push_back({p00, p10, p01});
          tris.push_back({p10, p11, p01});
        }
      }
  }
  m.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (std::size_t i = 0; i < verts.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) << verts[i][0], verts[i][1], verts[i][2];
  m.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t i = 0; i < tris.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) << tris[i][0], tris[i][1], tris[i][2];
  return m;
}

// Unit sphere: icosahedron subdivided `levels` times (1-to-4), projected to the sphere.
inline TriMesh sphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto [it, inserted] = mid.emplace(key, static_cast<int>(v.size()));
      if (inserted) v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      return it->second;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f.swap(next);
  }
  return tri_mesh_from_lists(v, f);
}

// A folded sheet: two planar n x n wings meeting at the crease x = 0 with the given dihedral
// opening (180 = flat). Open boundary; normals of each wing are known exactly.
inline TriMesh fold(int n, double opening_deg) {
  TriMesh m = plane(n, 2.0);
  const double half = (180.0 - opening_deg) / 2.0 * std::numbers::pi / 180.0;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const double x = m.V(i, 0) - 1.0;  // crease at x = 0
    m.V(i, 0) = x * std::cos(half);
    m.V(i, 2) = std::abs(x) * std::sin(half);
  }
  return m;
}

// A (u, v) grid of nu x nv quads, each split along alternating diagonals, mapped through
// `at`; `wrap_u` / `wrap_v` close the grid into a tube or a torus.
inline TriMesh parametric(int nu, int nv, bool wrap_u, bool wrap_v, const std::function<Vec3(double, double)>& at) {
  const int cu = wrap_u ? nu : nu + 1, cv = wrap_v ? nv : nv + 1;
  TriMesh m;
  m.V.resize(cu * cv, 3);
  for (int i = 0; i < cu; ++i)
    for (int j = 0; j < cv; ++j) m.V.row(i * cv + j) = at(static_cast<double>(i) / nu, static_cast<double>(j) / nv).transpose();
  m.F.resize(2 * nu * nv, 3);
  int f = 0;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = i * cv + j, b = ((i + 1) % cu) * cv + j, c = ((i + 1) % cu) * cv + (j + 1) % cv, d = i * cv + (j + 1) % cv;
      if ((i + j) % 2) {
        m.F.row(f++) << a, b, c;
        m.F.row(f++) << a, c, d;
      } else {
        m.F.row(f++) << a, b, d;
        m.F.row(f++) << b, c, d;
      }
    }
  return m;
}

// A torus of radii 1 and `r` on an nu x nv grid.
inline TriMesh torus(int nu, int nv, double r) {
  return parametric(nu, nv, true, true, [r](double u, double v) {
    const double a = 2 * std::numbers::pi * u, b = 2 * std::numbers::pi * v, rho = 1 + r * std::cos(b);
    return Vec3(rho * std::cos(a), rho * std::sin(a), r * std::sin(b));
  });
}

// A closed unit-radius cylinder of the given height, as a low-poly exporter writes it:
// `around` segments, `rows` rings of quads split in two, flat caps fanned from their centres
// (long thin triangles; every ring vertex but the middle rows' lies on a 90-degree crease).
inline TriMesh closed_cylinder(int around, int rows, double height) {
  TriMesh m;
  const int ring = around * (rows + 1);
  m.V.resize(ring + 2, 3);
  for (int r = 0; r <= rows; ++r)
    for (int a = 0; a < around; ++a) {
      const double t = 2 * std::numbers::pi * a / around;
      m.V.row(r * around + a) << std::cos(t), std::sin(t), height * r / rows;
    }
  const int bottom = ring, top = ring + 1;
  m.V.row(bottom) << 0, 0, 0;
  m.V.row(top) << 0, 0, height;
  m.F.resize(2 * around * rows + 2 * around, 3);
  Eigen::Index f = 0;
  for (int r = 0; r < rows; ++r)
    for (int a = 0; a < around; ++a) {
      const int b = (a + 1) % around;
      m.F.row(f++) << r * around + a, r * around + b, (r + 1) * around + b;
      m.F.row(f++) << r * around + a, (r + 1) * around + b, (r + 1) * around + a;
    }
  for (int a = 0; a < around; ++a) {
    const int b = (a + 1) % around;
    m.F.row(f++) << bottom, b, a;
    m.F.row(f++) << top, rows * around + a, rows * around + b;
  }
  return m;
}

}  // namespace mdn::test

namespace mdn::test {

// A plane over [0, 1]^2 whose left half is sampled `density` times more finely in x than its
// right half: triangle areas differ by that factor (irregular sampling, Sec. 4.2).
inline TriMesh irregular_plane(int n, int density) {
  std::vector<double> xs;
  for (int i = 0; i < n * density; ++i) xs.push_back(0.5 * i / (n * density));
  for (int i = 0; i <= n; ++i) xs.push_back(0.5 + 0.5 * i / n);
  const int cols = static_cast<int>(xs.size()), rows = 2 * n + 1;
  TriMesh m;
  m.V.resize(cols * rows, 3);
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) m.V.row(j * cols + i) << xs[static_cast<std::size_t>(i)], double(j) / (rows - 1), 0.0;
  m.F.resize(2 * (cols - 1) * (rows - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < rows; ++j)
    for (int i = 0; i + 1 < cols; ++i) {
      const int a = j * cols + i, b = a + 1, c = a + cols, d = c + 1;
      m.F.row(f++) << a, b, d;
      m.F.row(f++) << a, d, c;
    }
  return m;
}

}  // namespace mdn::test

namespace mdn::test {

// One conforming red-green refinement step: faces whose centroid satisfies `select` are split
// 1-to-4; neighbours left with one split edge are bisected (green), neighbours with two or
// three split edges are split 1-to-4 as well, until the mesh has no hanging vertex.
template <class Select>
TriMesh refine_where(const TriMesh& in, Select select) {
  std::vector<Vec3> v;
  for (Eigen::Index i = 0; i < in.V.rows(); ++i) v.push_back(in.V.row(i).transpose());
  const auto nf = static_cast<std::size_t>(in.F.rows());
  std::vector<bool> red(nf, false);
  for (std::size_t f = 0; f < nf; ++f) {
    const Eigen::Index r = static_cast<Eigen::Index>(f);
    red[f] = select(((in.V.row(in.F(r, 0)) + in.V.row(in.F(r, 1)) + in.V.row(in.F(r, 2))) / 3.0).transpose().eval());
  }
  std::map<std::pair<int, int>, int> mid;
  auto key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  for (bool changed = true; changed;) {  // closure: no face may keep two split edges
    changed = false;
    mid.clear();
    for (std::size_t f = 0; f < nf; ++f)
      if (red[f])
        for (int k = 0; k < 3; ++k) mid[key(in.F(static_cast<Eigen::Index>(f), k), in.F(static_cast<Eigen::Index>(f), (k + 1) % 3))] = -1;
    for (std::size_t f = 0; f < nf; ++f) {
      if (red[f]) continue;
      int split = 0;
      for (int k = 0; k < 3; ++k) split += mid.count(key(in.F(static_cast<Eigen::Index>(f), k), in.F(static_cast<Eigen::Index>(f), (k + 1) % 3))) ? 1 : 0;
      if (split >= 2) red[f] = changed = true;
    }
  }
  for (auto& [edge, index] : mid) {
    index = static_cast<int>(v.size());
    v.push_back(0.5 * (v[static_cast<std::size_t>(edge.first)] + v[static_cast<std::size_t>(edge.second)]));
  }
  std::vector<std::array<int, 3>> out;
  for (std::size_t f = 0; f < nf; ++f) {
    const Eigen::Index r = static_cast<Eigen::Index>(f);
    const int a = in.F(r, 0), b = in.F(r, 1), c = in.F(r, 2);
    if (red[f]) {
      const int ab = mid[key(a, b)], bc = mid[key(b, c)], ca = mid[key(c, a)];
      out.push_back({a, ab, ca});
      out.push_back({b, bc, ab});
      out.push_back({c, ca, bc});
      out.push_back({ab, bc, ca});
      continue;
    }
    const int corners[3] = {a, b, c};
    bool done = false;
    for (int k = 0; k < 3 && !done; ++k) {
      const int p = corners[k], q = corners[(k + 1) % 3], o = corners[(k + 2) % 3];
      auto it = mid.find(key(p, q));
      if (it == mid.end()) continue;
      out.push_back({p, it->second, o});  // green: bisect the split edge
      out.push_back({it->second, q, o});
      done = true;
    }
    if (!done) out.push_back({a, b, c});
  }
  return tri_mesh_from_lists(v, out);
}

// A unit sphere whose upper cap (z > 0.2) is sampled 16 times more densely (two conforming
// refinement steps, vertices projected back to the sphere): irregular sampling, Sec. 4.2.
inline TriMesh irregular_sphere(int levels) {
  auto cap = [](const Vec3& c) { return c.z() > 0.2; };
  TriMesh m = refine_where(refine_where(sphere(levels), cap), cap);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i).normalize();
  return m;
}

}  // namespace mdn::test

namespace mdn::test {

// The mesh as OFF text, coordinates with 17 significant digits (round trips exactly).
inline std::string off_text(const TriMesh& mesh) {
  std::string out = "OFF\n" + std::to_string(mesh.num_vertices()) + " " + std::to_string(mesh.num_faces()) + " 0\n";
  char buffer[96];
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
    std::snprintf(buffer, sizeof buffer, "%.17g %.17g %.17g\n", mesh.V(i, 0), mesh.V(i, 1), mesh.V(i, 2));
    out += buffer;
  }
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    out += "3 " + std::to_string(mesh.F(f, 0)) + " " + std::to_string(mesh.F(f, 1)) + " " + std::to_string(mesh.F(f, 2)) + "\n";
  return out;
}

}  // namespace mdn::test
