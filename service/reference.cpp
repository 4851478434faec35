#include "service/reference.h"

#include <cmath>
#include <cstdint>
#include <numbers>

#include "core/metrics.h"
#include "core/parallel.h"

namespace mdn::service {

TriMesh merge_surfaces(const std::vector<TriMesh>& surfaces) {
  std::int64_t nv = 0, nf = 0;
  for (const auto& s : surfaces) {
    nv += s.num_vertices();
    nf += s.num_faces();
  }
  TriMesh merged;
  merged.V.resize(nv, 3);
  merged.F.resize(nf, 3);
  std::int64_t v0 = 0, f0 = 0;
  for (const auto& s : surfaces) {
    merged.V.middleRows(v0, s.num_vertices()) = s.V;
    merged.F.middleRows(f0, s.num_faces()) = s.F.array() + static_cast<std::int32_t>(v0);
    v0 += s.num_vertices();
    f0 += s.num_faces();
  }
  return merged;
}

TriMesh scene_mesh(const std::vector<TriMesh>& surfaces, const std::vector<std::vector<Eigen::Matrix4d>>& placements) {
  static const std::vector<Eigen::Matrix4d> kAsIs = {Eigen::Matrix4d::Identity()};
  std::vector<TriMesh> shown;
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const auto& where = i < placements.size() && !placements[i].empty() ? placements[i] : kAsIs;
    for (const Eigen::Matrix4d& m : where) {
      TriMesh copy = surfaces[i];
      // Rows are points: V * A^T + t^T.
      copy.V = (surfaces[i].V * m.topLeftCorner<3, 3>().transpose()).rowwise() + m.topRightCorner<3, 1>().transpose();
      shown.push_back(std::move(copy));
    }
  }
  return merge_surfaces(shown);
}

bool same_faces(const TriMesh& a, const TriMesh& b) { return a.num_faces() == b.num_faces() && a.F == b.F; }

namespace {

// Area-weighted vertex normals (#V by 3; unit rows, or zero for a vertex of degenerate faces only).
Vertices vertex_normals(const TriMesh& m) {
  Vertices n = Vertices::Zero(m.num_vertices(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Vec3 a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    const Vec3 area2 = (b - a).cross(c - a);  // twice the face's area along its normal
    for (int k = 0; k < 3; ++k) n.row(m.F(f, k)) += area2.transpose();
  }
  for (Eigen::Index i = 0; i < n.rows(); ++i) {
    const double length = n.row(i).norm();
    if (length > 0) n.row(i) /= length;
  }
  return n;
}

double mean_edge_length(const TriMesh& m) {
  double sum = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (m.V.row(m.F(f, k)) - m.V.row(m.F(f, (k + 1) % 3))).norm();
  return m.F.rows() ? sum / (3.0 * static_cast<double>(m.F.rows())) : 0.0;
}

}  // namespace

ReferenceComparison compare_with_reference(const TriMesh& reference, const TriMesh& mesh, Executor* executor) {
  ReferenceComparison out;
  out.ev = vertex_error(mesh, reference, executor);  // validates both meshes
  out.mean_edge_length = mean_edge_length(reference);
  out.deviation.resize(static_cast<std::size_t>(mesh.num_vertices()));
  if (same_faces(reference, mesh) && reference.num_vertices() == mesh.num_vertices()) {
    out.msae = msae(mesh, reference);
    out.deviation_signed = true;
    const Vertices normals = vertex_normals(reference);
    for (Eigen::Index i = 0; i < mesh.num_vertices(); ++i)
      out.deviation[static_cast<std::size_t>(i)] = static_cast<float>((mesh.V.row(i) - reference.V.row(i)).dot(normals.row(i)));
  } else {
    const SurfaceDistance surface(reference);
    for (Eigen::Index i = 0; i < mesh.num_vertices(); ++i)
      out.deviation[static_cast<std::size_t>(i)] = static_cast<float>(surface.distance(mesh.V.row(i).transpose()));
  }
  return out;
}

nlohmann::json comparison_json(const ReferenceComparison& c) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  nlohmann::json out = {{"same_faces", c.msae.has_value()},
                        {"msae", c.msae ? nlohmann::json(*c.msae) : nlohmann::json(nullptr)},
                        {"msae_deg2", c.msae ? nlohmann::json(*c.msae * kDeg * kDeg) : nlohmann::json(nullptr)},
                        {"ev", c.ev},
                        {"mean_edge_length", c.mean_edge_length},
                        {"deviation_signed", c.deviation_signed},
                        {"deviation", c.deviation}};
  return out;
}

}  // namespace mdn::service
