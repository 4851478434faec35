#include "core/noise_estimate.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "core/parallel.h"

namespace mdn {

Vertices umbrella_smooth(const Vertices& P, const Topology& topo, int steps, double lambda, Executor* executor) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  Vertices current = P, next(P.rows(), 3);
  for (int s = 0; s < steps; ++s) {
    ex.parallel_for(P.rows(), [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t i = begin; i < end; ++i) {
        const auto b = topo.vv_offsets[static_cast<std::size_t>(i)], e = topo.vv_offsets[static_cast<std::size_t>(i) + 1];
        if (b == e) {
          next.row(i) = current.row(i);
          continue;
        }
        Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
        for (auto k = b; k < e; ++k) c += current.row(topo.vv_vertices[static_cast<std::size_t>(k)]);
        next.row(i) = (1 - lambda) * current.row(i) + lambda * c / static_cast<double>(e - b);
      }
    });
    current.swap(next);
  }
  return current;
}

Vertices smoothed_normals(const Vertices& P, const Triangles& F, const Topology& topo, Executor* executor) {
  return vertex_normals(umbrella_smooth(P, topo, 4, 0.5, executor), F);
}

std::vector<double> quadric_residuals(const Vertices& P, const Triangles&, const Topology& topo, const Vertices& N,
                                      const std::vector<std::int32_t>& vertices, Executor* executor) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const double l = std::max(topo.mean_edge_length(P), 1e-300);
  const std::int64_t n = vertices.empty() ? P.rows() : static_cast<std::int64_t>(vertices.size());
  std::vector<double> out(static_cast<std::size_t>(n), std::nan(""));
  ex.parallel_for(n, [&](std::int64_t begin, std::int64_t end) {
    std::vector<std::int32_t> ring;
    std::vector<std::int32_t> mark;  // small linear-scan dedupe: 2-rings hold ~20 vertices
    for (std::int64_t k = begin; k < end; ++k) {
      const std::int32_t i = vertices.empty() ? static_cast<std::int32_t>(k) : vertices[static_cast<std::size_t>(k)];
      const Eigen::RowVector3d nrm = N.row(i);
      if (nrm.squaredNorm() == 0) continue;
      ring.clear();
      const auto add = [&](std::int32_t v) {
        if (v != i && std::find(ring.begin(), ring.end(), v) == ring.end()) ring.push_back(v);
      };
      for (auto a = topo.vv_offsets[static_cast<std::size_t>(i)]; a < topo.vv_offsets[static_cast<std::size_t>(i) + 1]; ++a) {
        const std::int32_t j = topo.vv_vertices[static_cast<std::size_t>(a)];
        add(j);
        for (auto b = topo.vv_offsets[static_cast<std::size_t>(j)]; b < topo.vv_offsets[static_cast<std::size_t>(j) + 1]; ++b)
          add(topo.vv_vertices[static_cast<std::size_t>(b)]);
      }
      const int m = static_cast<int>(ring.size());
      const int terms = m >= 12 ? 6 : (m >= 5 ? 3 : 0);  // quadric, else plane, else nothing
      if (terms == 0) continue;
      // Tangent frame at vertex i.
      const Eigen::Vector3d z = nrm.transpose();
      const Eigen::Vector3d x = (std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(z).normalized();
      const Eigen::Vector3d y = z.cross(x);
      const Eigen::RowVector3d o = P.row(i);
      Eigen::MatrixXd A(m, terms);
      Eigen::VectorXd h(m);
      for (int r = 0; r < m; ++r) {
        const Eigen::Vector3d d = (P.row(ring[static_cast<std::size_t>(r)]) - o).transpose() / l;
        const double u = d.dot(x), v = d.dot(y);
        h[r] = d.dot(z);
        A(r, 0) = 1;
        A(r, 1) = u;
        A(r, 2) = v;
        if (terms == 6) {
          A(r, 3) = u * u;
          A(r, 4) = u * v;
          A(r, 5) = v * v;
        }
      }
      // The prediction at i (u = v = 0) is the constant term: w = first row of (A^T A)^-1 A^T.
      const Eigen::MatrixXd AtA = A.transpose() * A;
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(AtA);
      if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-10)) continue;
      const Eigen::VectorXd e0 = Eigen::VectorXd::Unit(terms, 0);
      const Eigen::VectorXd g = ldlt.solve(e0);
      const Eigen::VectorXd w = A * g;  // prediction = w . h
      const double err = 0 - w.dot(h);  // vertex i sits at height 0 in its own frame
      out[static_cast<std::size_t>(k)] = err * err * l * l / (1 + w.squaredNorm());
    }
  });
  return out;
}

NoiseEstimate estimate_noise(const Vertices& P, const Triangles& F, const Topology& topo, const Vertices& normals,
                             const std::vector<std::int32_t>& vertices, Executor* executor) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<double> s = quadric_residuals(P, F, topo, normals, vertices, executor);
  std::erase_if(s, [](double v) { return std::isnan(v); });
  NoiseEstimate est;
  const double noisy_edge = topo.mean_edge_length(P);
  if (!s.empty()) {
    const auto mid = s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2);
    std::nth_element(s.begin(), mid, s.end());
    est.gaussian_sigma = std::sqrt(*mid / 0.45493642311957);  // median of chi^2_1
    // The mean reads the RMS of any noise, impulses included, but also creases; the median only
    // the Gaussian core. Impulses put the mean at most ~3.2x the median (measured), creases on a
    // clean CAD surface at any multiple of a median of ~0: cap the mean at 4x (decision 19).
    const double rms = std::sqrt(std::accumulate(s.begin(), s.end(), 0.0) / static_cast<double>(s.size()));
    // 0.84: the median of estimate / truth over the training cases was 1.19 (decision 19).
    est.sigma = 0.84 * std::min(rms, 4 * est.gaussian_sigma);
  }
  // Noise lengthens edges: |e + d|^2 = |e|^2 + 2 e.d + |d|^2 with E|d|^2 = 2 sigma^2 for the
  // difference d of two normal displacements, so the clean length is about
  // sqrt(l^2 - 2 sigma^2) (decision 19; at most halved, for estimates beyond the model).
  const double r = noisy_edge > 0 ? est.sigma / noisy_edge : 0;
  est.edge_length = noisy_edge * std::sqrt(std::max(0.25, 1 - 2 * r * r));
  est.sigma_edges = est.edge_length > 0 ? est.sigma / est.edge_length : 0;
  est.estimate_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return est;
}

}  // namespace mdn
