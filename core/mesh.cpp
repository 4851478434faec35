#include "core/mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/parallel.h"

namespace mdn {

void validate_mesh(const TriMesh& mesh) {
  if (mesh.V.rows() == 0) throw InvalidMeshError("mesh has no vertices");
  if (mesh.F.rows() == 0) throw InvalidMeshError("mesh has no faces");
  if (mesh.V.rows() > std::numeric_limits<std::int32_t>::max())
    throw InvalidMeshError("mesh has more vertices than 32-bit indices can address");
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(mesh.V(i, k)))
        throw InvalidMeshError("vertex " + std::to_string(i) + " has a non-finite coordinate");
  const auto n = static_cast<std::int64_t>(mesh.V.rows());
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = mesh.F(f, k);
      if (v < 0 || v >= n)
        throw InvalidMeshError("face " + std::to_string(f) + " references vertex " + std::to_string(v) +
                               ", outside [0, " + std::to_string(n) + ")");
    }
}

TriMesh to_tri_mesh(const PolygonMesh& poly) {
  if (poly.offsets.empty() || poly.offsets.front() != 0 ||
      poly.offsets.back() != static_cast<std::int64_t>(poly.indices.size()))
    throw InvalidMeshError("polygon mesh offsets are inconsistent with its index list");
  const std::size_t faces = poly.offsets.size() - 1;
  TriMesh mesh;
  mesh.V = poly.V;
  mesh.F.resize(static_cast<Eigen::Index>(faces), 3);
  const auto n = static_cast<std::int64_t>(poly.V.rows());
  for (std::size_t f = 0; f < faces; ++f) {
    const std::int64_t begin = poly.offsets[f], end = poly.offsets[f + 1];
    if (end - begin != 3)
      throw InvalidMeshError("face " + std::to_string(f) + " has " + std::to_string(end - begin) +
                             " vertices; only triangles are supported");
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = poly.indices[static_cast<std::size_t>(begin + k)];
      if (v < 0 || v >= n)
        throw InvalidMeshError("face " + std::to_string(f) + " references vertex " + std::to_string(v) +
                               ", outside [0, " + std::to_string(n) + ")");
      mesh.F(static_cast<Eigen::Index>(f), k) = static_cast<std::int32_t>(v);
    }
  }
  return mesh;
}

namespace {
inline Vec3 row(const Vertices& V, std::int32_t i) { return V.row(i).transpose(); }
}  // namespace

namespace {
void face_normals_range(const Vertices& V, const Triangles& F, Vertices& N, std::int64_t begin, std::int64_t end) {
  for (Eigen::Index f = begin; f < end; ++f) {
    const Vec3 a = row(V, F(f, 0)), b = row(V, F(f, 1)), c = row(V, F(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    const double len = n.norm();
    // A zero-area face has no orientation: the zero vector marks it for the filters.
    if (len > 0 && std::isfinite(len))
      N.row(f) = n.transpose() / len;
    else
      N.row(f).setZero();
  }
}
}  // namespace

TriMesh tri_mesh_from_lists(const std::vector<Vec3>& positions, const std::vector<std::array<int, 3>>& faces) {
  TriMesh m;
  m.V.resize(static_cast<Eigen::Index>(positions.size()), 3);
  for (std::size_t i = 0; i < positions.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = positions[i].transpose();
  m.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t i = 0; i < faces.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) << faces[i][0], faces[i][1], faces[i][2];
  return m;
}

Vertices face_normals(const Vertices& V, const Triangles& F) {
  Vertices N(F.rows(), 3);
  face_normals_range(V, F, N, 0, F.rows());
  return N;
}

void face_normals(const Vertices& V, const Triangles& F, Vertices& N, Executor* executor) {
  N.resize(F.rows(), 3);
  if (executor)
    executor->parallel_for(F.rows(), 8192, [&](std::int64_t b, std::int64_t e) { face_normals_range(V, F, N, b, e); });
  else
    face_normals_range(V, F, N, 0, F.rows());
}

Eigen::VectorXd face_areas(const Vertices& V, const Triangles& F) {
  Eigen::VectorXd A(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = row(V, F(f, 0)), b = row(V, F(f, 1)), c = row(V, F(f, 2));
    A(f) = 0.5 * (b - a).cross(c - a).norm();
  }
  return A;
}

Vertices face_centroids(const Vertices& V, const Triangles& F) {
  Vertices C(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    C.row(f) = (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))) / 3.0;
  return C;
}

Vertices vertex_normals(const Vertices& V, const Triangles& F) {
  Vertices N = Vertices::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = row(V, F(f, 0)), b = row(V, F(f, 1)), c = row(V, F(f, 2));
    const Vec3 n = (b - a).cross(c - a);  // length = 2 x area: area weighting
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
  }
  for (Eigen::Index i = 0; i < N.rows(); ++i) {
    const double len = N.row(i).norm();
    if (len > 0) N.row(i) /= len;
  }
  return N;
}

double mean_edge_length(const Vertices& V, const Triangles& F) {
  // Unique undirected edges: sort (min, max) pairs.
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  edges.reserve(static_cast<std::size_t>(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      std::int32_t a = F(f, k), b = F(f, (k + 1) % 3);
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      edges.emplace_back(a, b);
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  if (edges.empty()) return 0;
  double sum = 0;
  for (const auto& [a, b] : edges) sum += (V.row(a) - V.row(b)).norm();
  return sum / static_cast<double>(edges.size());
}

UnitBox UnitBox::of(const Vertices& V) {
  UnitBox box;
  if (V.rows() == 0) return box;
  const Vec3 lo = V.colwise().minCoeff().transpose();
  const Vec3 hi = V.colwise().maxCoeff().transpose();
  box.center = 0.5 * (lo + hi);
  const double extent = (hi - lo).maxCoeff();
  box.scale = extent > 0 ? 1.0 / extent : 1.0;  // a single point: translate only
  return box;
}

Vertices UnitBox::apply(const Vertices& V) const {
  return ((V.rowwise() - center.transpose()) * scale).eval();
}

Vertices UnitBox::undo(const Vertices& V) const {
  return ((V / scale).rowwise() + center.transpose()).eval();
}

}  // namespace mdn
