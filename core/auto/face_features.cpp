#include "core/auto/face_features.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "core/auto/measures.h"
#include "core/parallel.h"

namespace mdn {

namespace {

constexpr std::int64_t kGrain = 2048;  // faces per block of the parallel passes

double angle(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// Eigenvalues (descending, over their sum) and the middle eigenvector of the area-weighted
// normal tensor sum_g A_g n_g n_g^T over f's ring, f included.
void tensor_reading(const Topology& topo, const Vertices& N, const Eigen::VectorXd& A, std::int64_t f, Vec3& values,
                    Vec3& middle) {
  Eigen::Matrix3d T = A(f) * N.row(f).transpose() * N.row(f);
  for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(f)]; k < topo.ff_offsets[static_cast<std::size_t>(f) + 1]; ++k) {
    const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(k)];
    T += A(g) * N.row(g).transpose() * N.row(g);
  }
  const double trace = T.trace();
  if (!(trace > 0)) {
    values.setZero();
    middle.setZero();
    return;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(T / trace);  // ascending
  values = Vec3(es.eigenvalues()(2), es.eigenvalues()(1), es.eigenvalues()(0));
  middle = es.eigenvectors().col(1);
}

}  // namespace

const std::vector<const char*>& face_feature_names() {
  static const std::vector<const char*> names = {
      "noisy_x",   "noisy_y",   "noisy_z",   "mean1_x",   "mean1_y",    "mean1_z",    "mean4_x",    "mean4_y",   "mean4_z",
      "bilat_x",   "bilat_y",   "bilat_z",   "edge0_x",   "edge0_y",    "edge0_z",    "edge1_x",    "edge1_y",   "edge1_z",
      "edge2_x",   "edge2_y",   "edge2_z",   "tensor_l1", "tensor_l2",  "tensor_l3",  "tensor_e2x", "tensor_e2y", "tensor_e2z",
      "tensor1_l1", "tensor1_l2", "tensor1_l3", "mean1_max_angle", "log_vdist", "log_spike", "log_area_ratio", "ring_size",
      "ring_max_angle", "patch_x", "patch_y", "patch_z", "patch_inconsistency", "own_inconsistency"};
  return names;
}

Vec3 ring_mean(const Topology& topo, const Vertices& N, const Eigen::VectorXd& A, std::int64_t f) {
  Vec3 s = A(f) * N.row(f).transpose();
  for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(f)]; k < topo.ff_offsets[static_cast<std::size_t>(f) + 1]; ++k) {
    const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(k)];
    s += A(g) * N.row(g).transpose();
  }
  const double n = s.norm();
  return n > 0 ? Vec3(s / n) : Vec3::Zero();
}

Vec3 to_frame(const FaceFeatures& ff, std::int64_t f, const Vec3& v) {
  const auto r = ff.frame.row(f);
  return {r.segment<3>(0).dot(v), r.segment<3>(3).dot(v), r.segment<3>(6).dot(v)};
}

Vec3 from_frame(const FaceFeatures& ff, std::int64_t f, const Vec3& v) {
  const auto r = ff.frame.row(f);
  return (v.x() * r.segment<3>(0) + v.y() * r.segment<3>(3) + v.z() * r.segment<3>(6)).transpose();
}

Vec3 frame_to_world(const Eigen::Matrix3d& frame, const Vec3& v) {
  return (v.x() * frame.row(0) + v.y() * frame.row(1) + v.z() * frame.row(2)).transpose();
}

FaceReader::FaceReader(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor)
    : P_(P), F_(F), topo_(topo) {
  const std::int64_t nf = F.rows();
  face_normals(P, F, N0_, &executor);
  A_ = face_areas(P, F);
  C_ = face_centroids(P, F);
  // Decision 87: ring means at radii 1, 2 and 4 (each pass reaches one ring further).
  const auto pass = [&](const Vertices& in, Vertices& next) {
    next.resize(nf, 3);
    executor.parallel_for(nf, kGrain, [&](std::int64_t b, std::int64_t e) {
      for (std::int64_t f = b; f < e; ++f) next.row(f) = ring_mean(topo, in, A_, f).transpose();
    });
  };
  Vertices M3;
  pass(N0_, M1_);
  pass(M1_, M2_);
  pass(M2_, M3);
  pass(M3, M4_);
  // Decision 87: each face's ring inconsistency, the largest 1 - cos between its once-filtered
  // normal and its ring's (small inside a smooth patch, large where the ring straddles a crease).
  inconsistency_.resize(static_cast<std::size_t>(nf));
  executor.parallel_for(nf, kGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t f = b; f < e; ++f) {
      double worst = 0;
      for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(f)]; k < topo.ff_offsets[static_cast<std::size_t>(f) + 1]; ++k)
        worst = std::max(worst, 1 - M1_.row(f).dot(M1_.row(topo.ff_faces[static_cast<std::size_t>(k)])));
      inconsistency_[static_cast<std::size_t>(f)] = worst;
    }
  });
  // Per vertex: decision 46's distance to the ring's plane over the ring's radius, and decision
  // 50's spike reading (that over the largest of its ring's).
  vdist_ = ring_plane_distances(P, F, topo, {}, executor, true);
  for (double& d : vdist_)
    if (std::isnan(d)) d = 0;
  spike_.resize(vdist_.size());
  executor.parallel_for(static_cast<std::int64_t>(vdist_.size()), kGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t v = b; v < e; ++v) {
      const auto i = static_cast<std::size_t>(v);
      double ring = 0;
      for (std::int32_t a = topo.vv_offsets[i]; a < topo.vv_offsets[i + 1]; ++a)
        ring = std::max(ring, vdist_[static_cast<std::size_t>(topo.vv_vertices[static_cast<std::size_t>(a)])]);
      spike_[i] = vdist_[i] / std::max(ring, 1e-4);
    }
  });
  // Edge neighbours: the faces across each of f's interior manifold edges.
  across_.assign(static_cast<std::size_t>(nf), {-1, -1, -1});
  for (std::int64_t e = 0; e < topo.num_interior_edges(); ++e) {
    const std::int32_t a = topo.edge_faces(e, 0), b = topo.edge_faces(e, 1);
    for (const auto& [f, g] : {std::pair{a, b}, std::pair{b, a}}) {
      auto& slots = across_[static_cast<std::size_t>(f)];
      for (std::int32_t& slot : slots)
        if (slot < 0) {
          slot = g;
          break;
        }
    }
  }
}

Vec3 FaceReader::axis(std::int64_t f) const {
  const Vec3 n0 = N0_.row(f).transpose();
  Vec3 z = M2_.row(f).transpose();
  if (z.squaredNorm() == 0) z = n0.squaredNorm() > 0 ? n0 : Vec3::UnitZ();
  return z;
}

bool FaceReader::flat(std::int64_t f) const {
  const double flat_cos = std::cos(kFlatDegrees * M_PI / 180);
  const Vec3 z = axis(f);
  double ring_cos = 1;
  for (std::int32_t k = topo_.ff_offsets[static_cast<std::size_t>(f)]; k < topo_.ff_offsets[static_cast<std::size_t>(f) + 1]; ++k)
    ring_cos = std::min(ring_cos, N0_.row(topo_.ff_faces[static_cast<std::size_t>(k)]).dot(z));
  return ring_cos >= flat_cos && N0_.row(f).dot(z) >= flat_cos;
}

void FaceReader::read(std::int64_t f, double* out_row, Eigen::Matrix3d& frame) const {
  const Vertices& P = P_;
  const Triangles& F = F_;
  const Topology& topo = topo_;
  const Vertices &N0 = N0_, &M1 = M1_, &M4 = M4_, &C = C_;
  const Eigen::VectorXd& A = A_;
  const double range_scale = 1 - std::cos(M_PI / 6);  // the bilateral pass's 30 degrees
  const auto fi = static_cast<std::size_t>(f);
  const Vec3 n0 = N0.row(f).transpose();
  const Vec3 z = axis(f);
  // x: the noisy normal's tilt from z, else the once-filtered normal's, else the first edge.
  Vec3 x = n0 - n0.dot(z) * z;
  if (x.norm() < 1e-9) x = Vec3(M1.row(f).transpose()) - M1.row(f).dot(z) * z;
  if (x.norm() < 1e-9) {
    const Vec3 edge = (P.row(F(f, 1)) - P.row(F(f, 0))).transpose();
    x = edge - edge.dot(z) * z;
  }
  if (x.norm() < 1e-9) x = z.cross(std::abs(z.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY());
  x.normalize();
  const Vec3 y = z.cross(x);
  frame.row(0) = x.transpose();
  frame.row(1) = y.transpose();
  frame.row(2) = z.transpose();
  const auto local = [&](const Vec3& v) { return Vec3(x.dot(v), y.dot(v), z.dot(v)); };
  Eigen::Map<Eigen::Matrix<double, 1, kFaceFeatures>> row(out_row);
  row.segment<3>(0) = local(n0).transpose();
  row.segment<3>(3) = local(M1.row(f).transpose()).transpose();
  row.segment<3>(6) = local(M4.row(f).transpose()).transpose();
  // One bilateral pass on the noisy normals over the ring: spatial weight on the centroid
  // distance (scale: the ring's mean distance), range weight on the angle to the
  // once-filtered normal (decision 87).
  const std::int32_t r0 = topo.ff_offsets[fi], r1 = topo.ff_offsets[fi + 1];
  double sigma_c = 0, ring_cos = 1, mean_area = A(f);
  double m1_min_cos = 1;
  for (std::int32_t k = r0; k < r1; ++k) {
    const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(k)];
    sigma_c += (C.row(g) - C.row(f)).norm();
    ring_cos = std::min(ring_cos, N0.row(g).dot(z));
    mean_area += A(g);
    m1_min_cos = std::min(m1_min_cos, M1.row(f).dot(M1.row(g)));
  }
  const int ring = r1 - r0;
  sigma_c = ring > 0 ? sigma_c / ring : 1;
  mean_area /= (ring + 1);
  Vec3 bsum = A(f) * n0;
  const Vec3 m1 = M1.row(f).transpose();
  for (std::int32_t k = r0; k < r1; ++k) {
    const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(k)];
    const double d = (C.row(g) - C.row(f)).norm() / std::max(sigma_c, 1e-300);
    const double t = (1 - N0.row(g).dot(m1)) / range_scale;
    bsum += A(g) * std::exp(-(0.5 * d * d + t * t)) * N0.row(g).transpose();
  }
  const Vec3 bn = bsum.norm() > 0 ? Vec3(bsum.normalized()) : n0;
  row.segment<3>(9) = local(bn).transpose();
  // The three faces across f's edges (f's own normal where an edge has none), the one
  // turned furthest from f first.
  std::array<Vec3, 3> nb;
  for (int s = 0; s < 3; ++s) nb[s] = across_[fi][s] >= 0 ? Vec3(N0.row(across_[fi][s]).transpose()) : n0;
  std::sort(nb.begin(), nb.end(), [&](const Vec3& a, const Vec3& c) { return a.dot(n0) < c.dot(n0); });
  for (int s = 0; s < 3; ++s) row.segment<3>(12 + 3 * s) = local(nb[s]).transpose();
  Vec3 values, middle;
  tensor_reading(topo, N0, A, f, values, middle);
  if (middle.dot(x) < 0) middle = -middle;
  row.segment<3>(21) = values.transpose();
  row.segment<3>(24) = local(middle).transpose();
  tensor_reading(topo, M1, A, f, values, middle);
  row.segment<3>(27) = values.transpose();
  row(30) = std::acos(std::clamp(m1_min_cos, -1.0, 1.0));
  double vd = 0, sp = 0;
  for (int c = 0; c < 3; ++c) {
    vd = std::max(vd, vdist_[static_cast<std::size_t>(F(f, c))]);
    sp = std::max(sp, spike_[static_cast<std::size_t>(F(f, c))]);
  }
  row(31) = std::log(vd + 1e-4);
  row(32) = std::log(sp + 1e-4);
  row(33) = mean_area > 0 && A(f) > 0 ? std::log(A(f) / mean_area) : -10;
  row(34) = ring / 12.0;
  row(35) = std::acos(std::clamp(ring_cos, -1.0, 1.0));
  // The most consistent patch around f (after guided normal filtering's patch choice): the
  // face of f's ring, f included, whose ring is the least inconsistent; its once-filtered
  // normal and inconsistency, and f's own.
  std::int64_t best = f;
  for (std::int32_t k = r0; k < r1; ++k) {
    const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(k)];
    if (inconsistency_[static_cast<std::size_t>(g)] < inconsistency_[static_cast<std::size_t>(best)]) best = g;
  }
  row.segment<3>(36) = local(M1.row(best).transpose()).transpose();
  row(39) = inconsistency_[static_cast<std::size_t>(best)];
  row(40) = inconsistency_[fi];
}

FaceFeatures face_features(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor) {
  const std::int64_t nf = F.rows();
  const FaceReader reader(P, F, topo, executor);
  FaceFeatures out;
  out.noisy = reader.noisy();
  out.smoothed = reader.smoothed();
  out.X.resize(nf, kFaceFeatures);
  out.frame.resize(nf, 9);
  out.flat.assign(static_cast<std::size_t>(nf), 0);
  executor.parallel_for(nf, kGrain, [&](std::int64_t b, std::int64_t e) {
    Eigen::Matrix3d frame;
    for (std::int64_t f = b; f < e; ++f) {
      reader.read(f, out.X.row(f).data(), frame);
      out.frame.row(f) << frame.row(0), frame.row(1), frame.row(2);
      out.flat[static_cast<std::size_t>(f)] = reader.flat(f);
    }
  });
  return out;
}

}  // namespace mdn

namespace mdn {

const char* face_class_name(FaceClass c) {
  static const char* names[] = {"flat", "curved", "crease", "corner"};
  return names[static_cast<int>(c)];
}

std::vector<FaceClass> face_classes(const Vertices& V, const Triangles& F, const Topology& topo, Executor& executor) {
  const Vertices N = face_normals(V, F);
  const Eigen::VectorXd A = face_areas(V, F);
  std::vector<FaceClass> out(static_cast<std::size_t>(F.rows()), FaceClass::Flat);
  const double deg = M_PI / 180;
  executor.parallel_for(F.rows(), kGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t f = b; f < e; ++f) {
      double largest = 0;
      for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(f)]; k < topo.ff_offsets[static_cast<std::size_t>(f) + 1]; ++k)
        largest = std::max(largest, angle(N.row(f).transpose(), N.row(topo.ff_faces[static_cast<std::size_t>(k)]).transpose()));
      FaceClass c = FaceClass::Flat;
      if (largest >= 20 * deg) {
        Vec3 values, middle;
        tensor_reading(topo, N, A, f, values, middle);
        c = values(2) > 0.01 ? FaceClass::Corner : FaceClass::Crease;
      } else if (largest >= 2 * deg) {
        c = FaceClass::Curved;
      }
      out[static_cast<std::size_t>(f)] = c;
    }
  });
  return out;
}

}  // namespace mdn
