#include "core/auto/descriptors.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "core/auto/face_features.h"
#include "core/auto/surface_sample.h"
#include "core/params.h"
#include "core/parallel.h"

namespace mdn {

namespace {

// Decision 33: what the noise reading reads at most.
constexpr std::int64_t kNoiseVertices = 1500;
constexpr int kMargin = 4;  // rings left out along a sample's cut (measure_input smooths 4 steps)

// The q-quantiles of v for ascending qs (0 for an empty list): the element of rank
// round(q (n - 1)). One copy; each selection runs on what the one before left above its rank.
std::vector<double> quantiles(std::vector<double> v, const std::vector<double>& qs) {
  std::vector<double> out;
  std::size_t lo = 0;
  for (const double q : qs) {
    if (v.empty()) {
      out.push_back(0);
      continue;
    }
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
    if (k >= lo) {  // else k is the last rank selected
      std::nth_element(v.begin() + static_cast<std::ptrdiff_t>(lo), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
      lo = k + 1;
    }
    out.push_back(v[k]);
  }
  return out;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (const double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

double share_above(const std::vector<double>& v, double t) {
  std::size_t n = 0;
  for (const double x : v) n += x > t;
  return v.empty() ? 0 : static_cast<double>(n) / static_cast<double>(v.size());
}

double angle(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

}  // namespace

const std::vector<std::string>& descriptor_names() {
  static const std::vector<std::string> names = {
      "log_faces",        "noise_sigma",      "noise_gaussian",   "noise_one_pass",   "ring_noise",
      "ring_tail",        "ring_feature_share", "smooth_residual", "smooth_tail",     "log_cluster_ratio",
      "dev_mean",         "dev_median",       "dev_p90",          "dev_p99",          "dev2_median",
      "dev2_p90",         "dihedral_median",  "dihedral_p75",     "dihedral_p90",     "dihedral_p99",
      "dihedral_over20",  "dihedral_over60",  "dihedral_over130", "edge_cv",          "edge_log_p90_p10",
      "min_angle_median", "sliver_share",     "boundary_share",   "dev_over_dihedral",
      "dihedral_flat_share", "dihedral_p10",  "dev_p10",  "devl_median", "devl_p90", "devl_over_dev",
      "vdist_median",     "vdist_p99",        "vdist_tail",       "vdist_outliers",
      "spike_share",      "spike_p999"};
  return names;
}

namespace {

// What the descriptors read (decision 33): the surface itself, or patches of it with the
// faces and vertices near the cut left out of the statistics.
struct Read {
  std::optional<SurfaceSample> sample;
  const Vertices* P;
  const Triangles* F;
  const Topology* topo;

  Read(const Vertices& P0, const Triangles& F0, const Topology& topo0, std::int64_t max_faces) : P(&P0), F(&F0), topo(&topo0) {
    if (F0.rows() <= max_faces) return;
    sample = sample_surface(P0, F0, topo0, max_faces, 16, kMargin);
    P = &sample->P;
    F = &sample->F;
    topo = &sample->topo;
  }
  Read(const Read&) = delete;  // P, F and topo may point into `sample`
  Read& operator=(const Read&) = delete;
  bool scored(std::int64_t f) const { return !sample || sample->scored[static_cast<std::size_t>(f)] != 0; }
  // The sample's scored vertices (empty: all of the surface).
  const std::vector<std::int32_t>& inner() const {
    static const std::vector<std::int32_t> all;
    return sample ? sample->scored_vertices : all;
  }
  std::int64_t vertex_count() const { return sample ? static_cast<std::int64_t>(inner().size()) : P->rows(); }
  std::int32_t vertex(std::int64_t k) const { return sample ? inner()[static_cast<std::size_t>(k)] : static_cast<std::int32_t>(k); }
};

// Per scored face: the angle to its ring's mean normal (noise with no recorruption), the same
// after one more mean filter (what survives smoothing: features), the same between one and four
// mean filters (decision 45), the triangle's smallest angle; per scored vertex, its distance to
// its ring's plane (decision 46).
struct FaceReadings {
  std::vector<double> dev, dev2, devl, min_angle, dihedral, edges;
  std::vector<double> vdist;  // per scored vertex: distance to its ring's plane / ring radius
  std::vector<double> spike;  // per scored vertex: vdist over the largest of its ring's (decision 50)
};

// The per-vertex readings of decisions 46 and 50 into out.vdist and out.spike.
void vertex_readings(const Read& r, Executor& executor, FaceReadings& out) {
  // Decision 46: each vertex's distance to the plane through its ring's centroid, along the
  // area-weighted vertex normal, over the ring's mean radius (measure_input's r_i, scale-free
  // per vertex; 0 where undefined). Impulses are a heavy upper tail of it that the face angles
  // (bounded by 180 degrees) read only in part.
  std::vector<double> all = ring_plane_distances(*r.P, *r.F, *r.topo, {}, executor, true);
  for (double& d : all)
    if (std::isnan(d)) d = 0;
  // Decision 50: a spike (one vertex thrown off a surface that is otherwise clean) stands out
  // of every reading around it: its neighbours' rings hold it, so they read about a valence's
  // share of it. A crease's or a corner's vertex has neighbours along the feature that read as
  // much, and Gaussian noise rarely leaves all of a ring at a third of its centre. The floor
  // keeps exactly flat rings (readings ~1e-17) from dividing by rounding.
  const std::int64_t n = r.vertex_count();
  out.vdist.resize(static_cast<std::size_t>(n));
  out.spike.resize(static_cast<std::size_t>(n));
  for (std::int64_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(r.vertex(k));
    double ring = 0;
    for (std::int32_t a = r.topo->vv_offsets[i]; a < r.topo->vv_offsets[i + 1]; ++a)
      ring = std::max(ring, all[static_cast<std::size_t>(r.topo->vv_vertices[static_cast<std::size_t>(a)])]);
    out.vdist[static_cast<std::size_t>(k)] = all[i];
    out.spike[static_cast<std::size_t>(k)] = all[i] / std::max(ring, 1e-4);
  }
}

FaceReadings read_faces(const Read& r, Executor& executor) {
  const Vertices& P = *r.P;
  const Triangles& F = *r.F;
  const Vertices N = face_normals(P, F);
  const Eigen::VectorXd A = face_areas(P, F);
  Vertices M(F.rows(), 3);  // mean-filtered normals (every face: the second filter reads neighbours)
  executor.parallel_for(F.rows(), [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t f = b; f < e; ++f) M.row(f) = ring_mean(*r.topo, N, A, f).transpose();
  });
  // Decision 45: three more mean filters; the angle between M and that (devl) is what survives
  // heavy smoothing, a feature's reading at a scale the noise no longer reaches.
  Vertices L = M, L2(F.rows(), 3);
  for (int pass = 0; pass < 3; ++pass) {
    executor.parallel_for(F.rows(), [&](std::int64_t b, std::int64_t e) {
      for (std::int64_t f = b; f < e; ++f) L2.row(f) = ring_mean(*r.topo, L, A, f).transpose();
    });
    L.swap(L2);
  }
  std::vector<std::int32_t> faces;
  for (std::int64_t f = 0; f < F.rows(); ++f)
    if (r.scored(f)) faces.push_back(static_cast<std::int32_t>(f));
  FaceReadings out;
  out.dev.resize(faces.size());
  out.dev2.resize(faces.size());
  out.devl.resize(faces.size());
  out.min_angle.resize(faces.size());
  executor.parallel_for(static_cast<std::int64_t>(faces.size()), [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t k = b; k < e; ++k) {
      const std::int64_t f = faces[static_cast<std::size_t>(k)];
      const auto i = static_cast<std::size_t>(k);
      out.dev[i] = angle(N.row(f).transpose(), M.row(f).transpose());
      out.dev2[i] = angle(M.row(f).transpose(), ring_mean(*r.topo, M, A, f));
      out.devl[i] = angle(M.row(f).transpose(), L.row(f).transpose());
      double smallest = M_PI;
      for (int c = 0; c < 3; ++c) {
        const Vec3 a = P.row(F(f, c)).transpose(), b2 = P.row(F(f, (c + 1) % 3)).transpose(), c2 = P.row(F(f, (c + 2) % 3)).transpose();
        const Vec3 u = b2 - a, w = c2 - a;
        if (u.norm() > 0 && w.norm() > 0) smallest = std::min(smallest, angle(u, w));
      }
      out.min_angle[i] = smallest;
    }
  });
  // Dihedral angles over the interior edges between scored faces; the scored faces' edges.
  const Topology& topo = *r.topo;
  std::vector<std::int64_t> inner_edges;
  for (std::int64_t e = 0; e < topo.num_interior_edges(); ++e)
    if (r.scored(topo.edge_faces(e, 0)) && r.scored(topo.edge_faces(e, 1))) inner_edges.push_back(e);
  out.dihedral.resize(inner_edges.size());
  executor.parallel_for(static_cast<std::int64_t>(inner_edges.size()), [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t k = b; k < e; ++k) {
      const std::int64_t edge = inner_edges[static_cast<std::size_t>(k)];
      out.dihedral[static_cast<std::size_t>(k)] =
          angle(N.row(topo.edge_faces(edge, 0)).transpose(), N.row(topo.edge_faces(edge, 1)).transpose());
    }
  });
  vertex_readings(r, executor, out);
  out.edges.reserve(3 * faces.size());
  for (const std::int32_t f : faces)
    for (int c = 0; c < 3; ++c) out.edges.push_back((P.row(F(f, c)) - P.row(F(f, (c + 1) % 3))).norm());
  return out;
}

// Decision 26's values, in the order of descriptor_names(). Scale-like readings enter as
// logarithms (they span decades from clean to 0.8 l of noise); shares and angles as they are.
std::vector<double> values_of(std::int64_t faces, double boundary_share, const NoiseEstimate& noise, const InputMeasures& m,
                              const FaceReadings& r, Executor& executor) {
  const auto lg = [](double x) { return std::log(std::max(x, 0.0) + 1e-4); };
  const double emean = mean(r.edges);
  double evar = 0;
  for (const double x : r.edges) evar += (x - emean) * (x - emean);
  evar = r.edges.empty() ? 0 : evar / static_cast<double>(r.edges.size());
  // Every reading's quantiles, the readings in parallel.
  const std::vector<std::pair<const std::vector<double>*, std::vector<double>>> asked = {
      {&r.edges, {0.1, 0.9}},     {&r.dev, {0.1, 0.5, 0.9, 0.99}}, {&r.dev2, {0.5, 0.9}},
      {&r.dihedral, {0.1, 0.5, 0.75, 0.9, 0.99}}, {&r.min_angle, {0.5}}, {&r.devl, {0.5, 0.9}},
      {&r.vdist, {0.5, 0.99}},    {&r.spike, {0.999}}};
  std::vector<std::vector<double>> qv(asked.size());
  executor.parallel_for(static_cast<std::int64_t>(asked.size()), 1, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t i = b; i < e; ++i)
      qv[static_cast<std::size_t>(i)] = quantiles(*asked[static_cast<std::size_t>(i)].first, asked[static_cast<std::size_t>(i)].second);
  });
  const auto &edge_q = qv[0], &dev_q = qv[1], &dev2_q = qv[2], &dih_q = qv[3];
  const auto &angle_q = qv[4], &devl_q = qv[5], &vd_q = qv[6], &spike_q = qv[7];
  const double p10 = edge_q[0], p90 = edge_q[1];
  const double dev_median = dev_q[1], dih_median = dih_q[1];
  const double deg = M_PI / 180;
  const double vd_median = vd_q[0], vd_p99 = vd_q[1];
  return {std::log10(std::max<double>(1, static_cast<double>(faces))),
          lg(noise.sigma_edges),
          lg(noise.edge_length > 0 ? noise.gaussian_sigma / noise.edge_length : 0),
          lg(noise.one_pass_edges),
          lg(m.noise),
          std::log(std::max(1.0, m.tail)),
          m.feature_share,
          lg(m.smooth_residual),
          std::log(std::max(1.0, m.smooth_tail)),
          std::log(std::max(1.0, m.cluster_area_ratio)),
          lg(mean(r.dev)),
          lg(dev_median),
          lg(dev_q[2]),
          lg(dev_q[3]),
          lg(dev2_q[0]),
          lg(dev2_q[1]),
          lg(dih_median),
          lg(dih_q[2]),
          lg(dih_q[3]),
          lg(dih_q[4]),
          share_above(r.dihedral, 20 * deg),
          share_above(r.dihedral, 60 * deg),
          share_above(r.dihedral, 130 * deg),
          emean > 0 ? std::sqrt(evar) / emean : 0,
          p10 > 0 && p90 > 0 ? std::log(p90 / p10) : 0,
          angle_q[0],
          1 - share_above(r.min_angle, 10 * deg),
          boundary_share,
          dih_median > 0 ? std::log(std::max(dev_median, 1e-6) / dih_median) : 0,
          // Decision 33: exactly flat neighbours (a clean CAD surface's planes; noise of 0.05 l
          // already tilts them by degrees) and the low tails.
          1 - share_above(r.dihedral, 0.01 * deg),
          lg(dih_q[0]),
          lg(dev_q[0]),
          lg(devl_q[0]),
          lg(devl_q[1]),
          dev_median > 0 ? std::log(std::max(devl_q[1], 1e-6) / dev_median) : 0,
          lg(vd_median),
          lg(vd_p99),
          vd_median > 0 ? std::log(std::max(vd_p99, 1e-6) / vd_median) : 0,
          share_above(r.vdist, 4 * vd_median),
          share_above(r.spike, 3),
          lg(spike_q[0])};
}

}  // namespace

Descriptors describe_input(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor,
                           std::int64_t max_faces) {
  const auto t0 = std::chrono::steady_clock::now();
  Descriptors d;
  // Decision 33: a surface of more than max_faces faces is read on patches of it (the sample of
  // decision 21, with a margin as deep as measure_input's smoothing), its cut left out of the
  // statistics; a smaller one whole. The noise's quick reading takes kNoiseVertices of a stride.
  const Read r(P, F, topo, max_faces);
  std::vector<std::int32_t> where;
  const std::int64_t nv = r.vertex_count();
  const std::int64_t stride = std::max<std::int64_t>(1, (nv + kNoiseVertices - 1) / kNoiseVertices);
  for (std::int64_t k = 0; k < nv; k += stride) where.push_back(r.vertex(k));
  d.noise = estimate_noise_quick(*r.P, *r.F, *r.topo, where, &executor);
  d.measures = measure_input(*r.P, *r.F, *r.topo, DenoiseParams{}, &executor, r.inner());
  // The boundary's share is the whole surface's (the sample's cut is not a boundary).
  const double edges = static_cast<double>(topo.num_interior_edges() + topo.boundary_edges.rows() + topo.nonmanifold_edges.rows());
  const double boundary_share = edges > 0 ? static_cast<double>(topo.boundary_edges.rows()) / edges : 0;
  d.values = values_of(F.rows(), boundary_share, d.noise, d.measures, read_faces(r, executor), executor);
  d.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace mdn
