#include "core/auto/descriptors.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "core/auto/surface_sample.h"
#include "core/params.h"
#include "core/parallel.h"

namespace mdn {

namespace {

// Decision 33: what the noise reading reads at most.
constexpr std::int64_t kNoiseVertices = 1500;
constexpr int kMargin = 4;  // rings left out along a sample's cut (measure_input smooths 4 steps)

// q-quantile of v (sorted copy; 0 for an empty list).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
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

// Area-weighted mean of the normals of the faces sharing a vertex with f (and f itself).
Vec3 ring_mean(const Topology& topo, const Vertices& N, const Eigen::VectorXd& A, std::int64_t f) {
  Vec3 s = A(f) * N.row(f).transpose();
  for (std::int32_t k = topo.ff_offsets[static_cast<std::size_t>(f)]; k < topo.ff_offsets[static_cast<std::size_t>(f) + 1]; ++k) {
    const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(k)];
    s += A(g) * N.row(g).transpose();
  }
  const double n = s.norm();
  return n > 0 ? Vec3(s / n) : Vec3::Zero();
}

}  // namespace

const std::vector<std::string>& descriptor_names() {
  static const std::vector<std::string> names = {
      "log_faces",        "noise_sigma",      "noise_gaussian",   "noise_one_pass",   "ring_noise",
      "ring_tail",        "ring_feature_share", "smooth_residual", "smooth_tail",     "log_cluster_ratio",
      "dev_mean",         "dev_median",       "dev_p90",          "dev_p99",          "dev2_median",
      "dev2_p90",         "dihedral_median",  "dihedral_p75",     "dihedral_p90",     "dihedral_p99",
      "dihedral_over20",  "dihedral_over60",  "dihedral_over130", "edge_cv",          "edge_log_p90_p10",
      "min_angle_median", "sliver_share",     "boundary_share",   "dev_over_dihedral",
      "dihedral_flat_share", "dihedral_p10",  "dev_p10"};
  return names;
}

Descriptors describe_input(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor,
                           std::int64_t max_faces) {
  const auto t0 = std::chrono::steady_clock::now();
  Descriptors d;
  const std::int64_t nf = F.rows();

  // Decision 33: a surface of more than max_faces faces is read on patches of it (the sample
  // of decision 21, with a margin as deep as the smoothing below), its cut left out of the
  // statistics; a smaller one whole.
  std::optional<SurfaceSample> sample;
  if (nf > max_faces) sample = sample_surface(P, F, topo, max_faces, 16, kMargin);
  const Vertices& SP = sample ? sample->P : P;
  const Triangles& SF = sample ? sample->F : F;
  const Topology& ST = sample ? sample->topo : topo;
  const std::vector<std::int32_t> inner = sample ? sample->scored_vertices : std::vector<std::int32_t>{};
  const auto scored = [&](std::int64_t f) { return !sample || sample->scored[static_cast<std::size_t>(f)] != 0; };

  // The noise's quick reading (decision 33) at up to kNoiseVertices vertices, a fixed stride.
  const std::int64_t nv = sample ? static_cast<std::int64_t>(inner.size()) : SP.rows();
  std::vector<std::int32_t> where;
  const std::int64_t vstride = (nv + kNoiseVertices - 1) / kNoiseVertices;
  for (std::int64_t k = 0; k < nv; k += std::max<std::int64_t>(1, vstride))
    where.push_back(sample ? inner[static_cast<std::size_t>(k)] : static_cast<std::int32_t>(k));
  d.noise = estimate_noise_quick(SP, SF, ST, where, &executor);
  d.measures = measure_input(SP, SF, ST, DenoiseParams{}, &executor, inner);

  // Per face: the angle to its ring's mean normal (noise with no recorruption), the same after
  // one more mean filter (what survives smoothing: features), and the shape of the triangle.
  const Vertices N = face_normals(SP, SF);
  const Eigen::VectorXd A = face_areas(SP, SF);
  const std::int64_t sf = SF.rows();
  Vertices M(sf, 3);  // mean-filtered normals (every face: the second filter reads neighbours)
  executor.parallel_for(sf, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t f = b; f < e; ++f) M.row(f) = ring_mean(ST, N, A, f).transpose();
  });
  std::vector<std::int32_t> faces;
  for (std::int64_t f = 0; f < sf; ++f)
    if (scored(f)) faces.push_back(static_cast<std::int32_t>(f));
  const auto ns = static_cast<std::int64_t>(faces.size());
  std::vector<double> dev(static_cast<std::size_t>(ns)), dev2(static_cast<std::size_t>(ns)), min_angle(static_cast<std::size_t>(ns));
  executor.parallel_for(ns, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t k = b; k < e; ++k) {
      const std::int64_t f = faces[static_cast<std::size_t>(k)];
      const auto i = static_cast<std::size_t>(k);
      dev[i] = angle(N.row(f).transpose(), M.row(f).transpose());
      dev2[i] = angle(M.row(f).transpose(), ring_mean(ST, M, A, f));
      double smallest = M_PI;
      for (int c = 0; c < 3; ++c) {
        const Vec3 a = SP.row(SF(f, c)).transpose(), b2 = SP.row(SF(f, (c + 1) % 3)).transpose(), c2 = SP.row(SF(f, (c + 2) % 3)).transpose();
        const Vec3 u = b2 - a, w = c2 - a;
        if (u.norm() > 0 && w.norm() > 0) smallest = std::min(smallest, angle(u, w));
      }
      min_angle[i] = smallest;
    }
  });

  // Dihedral angles over the interior edges between scored faces.
  std::vector<double> dihedral;
  for (std::int64_t e = 0; e < ST.num_interior_edges(); ++e)
    if (scored(ST.edge_faces(e, 0)) && scored(ST.edge_faces(e, 1)))
      dihedral.push_back(angle(N.row(ST.edge_faces(e, 0)).transpose(), N.row(ST.edge_faces(e, 1)).transpose()));

  // Edge lengths of the scored faces (each face's three edges).
  std::vector<double> edges;
  edges.reserve(static_cast<std::size_t>(3 * ns));
  for (const std::int32_t f : faces)
    for (int c = 0; c < 3; ++c) edges.push_back((SP.row(SF(f, c)) - SP.row(SF(f, (c + 1) % 3))).norm());
  const double emean = mean(edges);
  double evar = 0;
  for (const double x : edges) evar += (x - emean) * (x - emean);
  evar = edges.empty() ? 0 : evar / static_cast<double>(edges.size());
  const double p10 = quantile(edges, 0.1), p90 = quantile(edges, 0.9);

  // The boundary's share is the whole surface's (the sample's cut is not a boundary).
  const std::int64_t ne = topo.num_interior_edges();
  const double edges_total = static_cast<double>(ne + topo.boundary_edges.rows() + topo.nonmanifold_edges.rows());
  const double dev_median = quantile(dev, 0.5), dih_median = quantile(dihedral, 0.5);
  const double deg = M_PI / 180;
  const InputMeasures& m = d.measures;
  // Scale-like readings enter as logarithms (they span decades from clean to 0.8 l of noise);
  // shares and angles as they are.
  const auto lg = [](double x) { return std::log(std::max(x, 0.0) + 1e-4); };
  d.values = {std::log10(std::max<double>(1, static_cast<double>(nf))),
              lg(d.noise.sigma_edges),
              lg(d.noise.edge_length > 0 ? d.noise.gaussian_sigma / d.noise.edge_length : 0),
              lg(d.noise.one_pass_edges),
              lg(m.noise),
              std::log(std::max(1.0, m.tail)),
              m.feature_share,
              lg(m.smooth_residual),
              std::log(std::max(1.0, m.smooth_tail)),
              std::log(std::max(1.0, m.cluster_area_ratio)),
              lg(mean(dev)),
              lg(dev_median),
              lg(quantile(dev, 0.9)),
              lg(quantile(dev, 0.99)),
              lg(quantile(dev2, 0.5)),
              lg(quantile(dev2, 0.9)),
              lg(dih_median),
              lg(quantile(dihedral, 0.75)),
              lg(quantile(dihedral, 0.9)),
              lg(quantile(dihedral, 0.99)),
              share_above(dihedral, 20 * deg),
              share_above(dihedral, 60 * deg),
              share_above(dihedral, 130 * deg),
              emean > 0 ? std::sqrt(evar) / emean : 0,
              p10 > 0 && p90 > 0 ? std::log(p90 / p10) : 0,
              quantile(min_angle, 0.5),
              1 - share_above(min_angle, 10 * deg),
              edges_total > 0 ? static_cast<double>(topo.boundary_edges.rows()) / edges_total : 0,
              dih_median > 0 ? std::log(std::max(dev_median, 1e-6) / dih_median) : 0,
              // Decision 33: exactly flat neighbours (a clean CAD surface's planes; noise of
              // 0.05 l already tilts them by degrees) and the low tails.
              1 - share_above(dihedral, 0.01 * deg),
              lg(quantile(dihedral, 0.1)),
              lg(quantile(dev, 0.1))};
  d.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace mdn
