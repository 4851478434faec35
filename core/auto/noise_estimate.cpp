#include "core/auto/noise_estimate.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>

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

Vertices patch_normals(const Vertices& P, const Topology& topo, const Vertices& normals, double spread, Executor* executor) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  constexpr int kMaxRings = 12;
  constexpr std::size_t kMaxVertices = 200;
  constexpr double kMaxTilt = 0.7;  // cosine: the patch's normal replaces the given one within ~45 degrees of it
  Vertices N = normals;
  ex.parallel_for(P.rows(), [&](std::int64_t begin, std::int64_t end) {
    std::vector<std::int32_t> seen(static_cast<std::size_t>(P.rows()), -1), patch;
    for (std::int64_t i = begin; i < end; ++i) {
      if (normals.row(i).squaredNorm() == 0) continue;
      const auto me = static_cast<std::int32_t>(i);
      patch.assign(1, me);
      seen[static_cast<std::size_t>(i)] = me;
      // Running sums of the patch's offsets from vertex i: mean and covariance without a rescan.
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      Eigen::Matrix3d squares = Eigen::Matrix3d::Zero();
      for (int ring = 0, first = 0; ring < kMaxRings; ++ring) {
        const auto last = static_cast<int>(patch.size());
        for (int q = first; q < last; ++q) {
          const auto j = static_cast<std::size_t>(patch[static_cast<std::size_t>(q)]);
          for (auto a = topo.vv_offsets[j]; a < topo.vv_offsets[j + 1]; ++a) {
            const std::int32_t v = topo.vv_vertices[static_cast<std::size_t>(a)];
            if (seen[static_cast<std::size_t>(v)] != me) {
              seen[static_cast<std::size_t>(v)] = me;
              patch.push_back(v);
              const Eigen::Vector3d d = (P.row(v) - P.row(i)).transpose();
              sum += d;
              squares += d * d.transpose();
            }
          }
        }
        first = last;
        const double count = static_cast<double>(patch.size());
        const Eigen::Vector3d mean = sum / count;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(squares / count - mean * mean.transpose());
        // The patch's principal spreads in its plane: across (the second) and along (the first).
        const double across = std::sqrt(std::max(0.0, eig.eigenvalues()(1))), along = std::sqrt(std::max(0.0, eig.eigenvalues()(2)));
        // A 1-ring `spread` wide across, or about as wide across as along: keep the given normal.
        if (ring == 0 && (across >= spread || across >= 0.5 * along)) break;
        if (across >= spread || patch.size() >= kMaxVertices || static_cast<int>(patch.size()) == last) {
          Eigen::Vector3d normal = eig.eigenvectors().col(0);
          if (normal.dot(normals.row(i).transpose()) < 0) normal = -normal;
          if (normal.dot(normals.row(i).transpose()) >= kMaxTilt) N.row(i) = normal.transpose();
          break;
        }
      }
    }
  });
  return N;
}

namespace {

// Vertex i's leave-one-out fit: the ring, the prediction weights w (prediction = w . h over the
// ring's heights in i's frame) and the error r = 0 - w . h; empty where no fit was possible.
// With `weights` false, w is not kept: only r and w2 = |w|^2 (the one-pass readings).
struct VertexFit {
  std::vector<std::int32_t> ring;
  std::vector<double> w;
  double r = 0, w2 = 0;
  bool weights = true;
};

void fit_vertex(const Vertices& P, const Topology& topo, const Vertices& N, LocalFit fit, double l, std::int32_t i, VertexFit& out) {
  out.ring.clear();
  out.w.clear();
  const Eigen::RowVector3d nrm = N.row(i);
  if (nrm.squaredNorm() == 0) return;
  // The k-ring of i, breadth first, without i; one ring more where a plane lacks its 5 points.
  std::vector<std::int32_t>& ring = out.ring;
  ring.assign(1, i);
  for (std::size_t begin_ring = 0, r = 0; r < static_cast<std::size_t>(fit.rings) || (r == static_cast<std::size_t>(fit.rings) && ring.size() < 6); ++r) {
    const std::size_t end_ring = ring.size();
    for (std::size_t q = begin_ring; q < end_ring; ++q) {
      const auto j = static_cast<std::size_t>(ring[q]);
      for (auto a = topo.vv_offsets[j]; a < topo.vv_offsets[j + 1]; ++a) {
        const std::int32_t v = topo.vv_vertices[static_cast<std::size_t>(a)];
        if (std::find(ring.begin(), ring.end(), v) == ring.end()) ring.push_back(v);
      }
    }
    begin_ring = end_ring;
  }
  ring.erase(ring.begin());
  const int m = static_cast<int>(ring.size());
  // The fit's degree, lowered until it has twice as many points as terms (a plane: 5 points).
  int terms = 0;
  for (int degree = fit.degree; degree >= 1 && terms == 0; --degree)
    if (const int t = (degree + 1) * (degree + 2) / 2; m >= (t == 3 ? 5 : 2 * t)) terms = t;
  if (terms == 0) return ring.clear();
  // Tangent frame at vertex i.
  const Eigen::Vector3d z = nrm.transpose();
  const Eigen::Vector3d x = (std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  const Eigen::RowVector3d o = P.row(i);
  // Rows of A: the monomials 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3 of each ring
  // vertex's tangent coordinates; h: its height.
  using Row = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, 10>;
  const auto row_of = [&](int r, double& height) {
    const Eigen::Vector3d d = (P.row(ring[static_cast<std::size_t>(r)]) - o).transpose() / l;
    const double u = d.dot(x), v = d.dot(y);
    height = d.dot(z);
    Row a(terms);
    a(0) = 1;
    a(1) = u;
    a(2) = v;
    if (terms >= 6) {
      a(3) = u * u;
      a(4) = u * v;
      a(5) = v * v;
    }
    if (terms >= 10) {
      a(6) = u * u * u;
      a(7) = u * u * v;
      a(8) = u * v * v;
      a(9) = v * v * v;
    }
    return a;
  };
  // The prediction at i (u = v = 0) is the constant term: w = first row of (A^T A)^-1 A^T, so
  // w . h = [(A^T A)^-1 A^T h]_0 and |w|^2 = [(A^T A)^-1]_00.
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 10, 10>;
  using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 10, 1>;
  Square AtA = Square::Zero(terms, terms);
  Column Ath = Column::Zero(terms);
  std::vector<Row> rows;
  if (out.weights) rows.reserve(static_cast<std::size_t>(m));
  for (int r = 0; r < m; ++r) {
    double height = 0;
    const Row a = row_of(r, height);
    AtA.noalias() += a.transpose() * a;
    Ath += height * a.transpose();
    if (out.weights) rows.push_back(a);
  }
  const Eigen::LDLT<Square> ldlt(AtA);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-10)) return ring.clear();
  const Column g = ldlt.solve(Column::Unit(terms, 0));  // (A^T A)^-1 e0
  out.w2 = g(0);
  out.r = (0 - g.dot(Ath)) * l;  // vertex i sits at height 0 in its own frame
  if (out.weights) {
    out.w.resize(static_cast<std::size_t>(m));
    for (int r = 0; r < m; ++r) out.w[static_cast<std::size_t>(r)] = rows[static_cast<std::size_t>(r)].dot(g);
  }
}

struct Reading {
  double sigma, core;
};

// The mean reads the RMS of any noise, impulses included, but also creases; the median only
// the Gaussian core. Impulses put the mean at most ~3.2x the median (measured), creases on a
// clean CAD surface at any multiple of a median of ~0: cap the mean at 4x (decision 19).
std::optional<Reading> read(std::vector<double> s) {
  std::erase_if(s, [](double v) { return std::isnan(v); });
  if (s.empty()) return std::nullopt;
  const auto mid = s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2);
  std::nth_element(s.begin(), mid, s.end());
  const double core = std::sqrt(*mid / 0.45493642311957);  // median of chi^2_1
  const double rms = std::sqrt(std::accumulate(s.begin(), s.end(), 0.0) / static_cast<double>(s.size()));
  return Reading{std::min(rms, 4 * core), core};
}

// The estimate from the kept reading and the quadric's one-pass reading.
NoiseEstimate finish(const std::optional<Reading>& best, const std::optional<Reading>& one_pass, double noisy_edge,
                     std::chrono::steady_clock::time_point t0) {
  NoiseEstimate est;
  if (best) {
    est.sigma = best->sigma;
    est.gaussian_sigma = best->core;
  }
  // Noise lengthens edges: |e + d|^2 = |e|^2 + 2 e.d + |d|^2 with E|d|^2 = 2 sigma^2 for the
  // difference d of two normal displacements, so the clean length is about
  // sqrt(l^2 - 2 sigma^2) (decision 19; at most halved, for estimates beyond the model).
  const double r = noisy_edge > 0 ? est.sigma / noisy_edge : 0;
  est.edge_length = noisy_edge * std::sqrt(std::max(0.25, 1 - 2 * r * r));
  est.sigma_edges = est.edge_length > 0 ? est.sigma / est.edge_length : 0;
  est.one_pass_edges = one_pass && est.edge_length > 0 ? one_pass->sigma / est.edge_length : 0;
  est.estimate_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return est;
}

// W, the fits' prediction weights, as compressed rows (a vertex without a fit has none and no
// defined error), and r = (I - W) h of every vertex.
struct FitOperator {
  std::vector<std::size_t> offsets;
  std::vector<std::int32_t> columns;
  std::vector<double> weights, r;

  // Row i of (I - W) applied to x; NaN propagates from undefined neighbours.
  double apply(std::size_t i, const std::vector<double>& x) const {
    if (offsets[i] == offsets[i + 1]) return std::nan("");
    double y = x[i];
    for (std::size_t a = offsets[i]; a < offsets[i + 1]; ++a) y -= weights[a] * x[static_cast<std::size_t>(columns[a])];
    return y;
  }
};

FitOperator fit_operator(const Vertices& P, const Topology& topo, const Vertices& N, LocalFit fit, double l, Executor& ex) {
  std::vector<VertexFit> fits(static_cast<std::size_t>(P.rows()));
  ex.parallel_for(P.rows(), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t v = begin; v < end; ++v) fit_vertex(P, topo, N, fit, l, static_cast<std::int32_t>(v), fits[static_cast<std::size_t>(v)]);
  });
  FitOperator W;
  W.offsets.assign(fits.size() + 1, 0);
  for (std::size_t v = 0; v < fits.size(); ++v) W.offsets[v + 1] = W.offsets[v] + fits[v].ring.size();
  W.columns.resize(W.offsets.back());
  W.weights.resize(W.offsets.back());
  W.r.resize(fits.size());
  for (std::size_t v = 0; v < fits.size(); ++v) {
    std::copy(fits[v].ring.begin(), fits[v].ring.end(), W.columns.begin() + static_cast<std::ptrdiff_t>(W.offsets[v]));
    std::copy(fits[v].w.begin(), fits[v].w.end(), W.weights.begin() + static_cast<std::ptrdiff_t>(W.offsets[v]));
    W.r[v] = fits[v].ring.empty() ? std::nan("") : fits[v].r;
  }
  return W;
}

// The squared norm of row i of (I - W)^passes. `coefficient` and `in_row` are a dense scratch
// of the vertex count, zero on entry and on return.
double row_norm2(const FitOperator& W, std::size_t i, int passes, std::vector<double>& coefficient, std::vector<std::uint8_t>& in_row) {
  std::vector<std::int32_t> row{static_cast<std::int32_t>(i)}, previous;
  std::vector<double> previous_c;
  coefficient[i] = 1;
  in_row[i] = 1;
  for (int pass = 0; pass < passes; ++pass) {  // row <- row (I - W)
    previous = row;
    previous_c.resize(previous.size());
    for (std::size_t q = 0; q < previous.size(); ++q) previous_c[q] = coefficient[static_cast<std::size_t>(previous[q])];
    for (std::size_t q = 0; q < previous.size(); ++q) {
      const auto v = static_cast<std::size_t>(previous[q]);
      for (std::size_t b = W.offsets[v]; b < W.offsets[v + 1]; ++b) {
        const auto u = static_cast<std::size_t>(W.columns[b]);
        if (!in_row[u]) {
          in_row[u] = 1;
          row.push_back(W.columns[b]);
        }
        coefficient[u] -= previous_c[q] * W.weights[b];
      }
    }
  }
  double norm2 = 0;
  for (const std::int32_t v : row) {
    norm2 += coefficient[static_cast<std::size_t>(v)] * coefficient[static_cast<std::size_t>(v)];
    coefficient[static_cast<std::size_t>(v)] = 0;
    in_row[static_cast<std::size_t>(v)] = 0;
  }
  return norm2;
}

}  // namespace

std::vector<double> local_fit_residuals(const Vertices& P, const Topology& topo, const Vertices& N, LocalFit fit,
                                        const std::vector<std::int32_t>& vertices, Executor* executor,
                                        std::vector<double>* first_pass) {
  Executor serial(1);
  Executor& ex = executor ? *executor : serial;
  const double l = std::max(topo.mean_edge_length(P), 1e-300);
  const std::int64_t n = vertices.empty() ? P.rows() : static_cast<std::int64_t>(vertices.size());
  const auto vertex = [&](std::int64_t k) {
    return static_cast<std::size_t>(vertices.empty() ? static_cast<std::int32_t>(k) : vertices[static_cast<std::size_t>(k)]);
  };
  std::vector<double> out(static_cast<std::size_t>(n), std::nan(""));
  if (fit.passes <= 1) {
    ex.parallel_for(n, [&](std::int64_t begin, std::int64_t end) {
      VertexFit f;
      f.weights = false;
      for (std::int64_t k = begin; k < end; ++k) {
        fit_vertex(P, topo, N, fit, l, static_cast<std::int32_t>(vertex(k)), f);
        if (!f.ring.empty()) out[static_cast<std::size_t>(k)] = f.r * f.r / (1 + f.w2);
      }
    });
    return out;
  }
  // Passes > 1: the errors r_1 = (I - W) h of every vertex, then r_{p+1} = (I - W) r_p, and at
  // the vertices asked for r_passes^2 over the squared norm of its row of (I - W)^passes (its
  // variance under white noise). The shape's share of r_1 varies slowly over the surface and
  // each pass removes most of it.
  const FitOperator W = fit_operator(P, topo, N, fit, l, ex);
  std::vector<double> r = W.r, next(r.size());
  if (first_pass) {
    first_pass->assign(static_cast<std::size_t>(n), std::nan(""));
    for (std::int64_t k = 0; k < n; ++k) {
      const std::size_t i = vertex(k);
      double w2 = 0;
      for (std::size_t a = W.offsets[i]; a < W.offsets[i + 1]; ++a) w2 += W.weights[a] * W.weights[a];
      if (W.offsets[i] < W.offsets[i + 1]) (*first_pass)[static_cast<std::size_t>(k)] = r[i] * r[i] / (1 + w2);
    }
  }
  for (int pass = 2; pass < fit.passes; ++pass) {
    ex.parallel_for(P.rows(), [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t v = begin; v < end; ++v) next[static_cast<std::size_t>(v)] = W.apply(static_cast<std::size_t>(v), r);
    });
    r.swap(next);
  }
  ex.parallel_for(n, [&](std::int64_t begin, std::int64_t end) {
    std::vector<double> coefficient(static_cast<std::size_t>(P.rows()), 0.0);
    std::vector<std::uint8_t> in_row(static_cast<std::size_t>(P.rows()), 0);
    for (std::int64_t k = begin; k < end; ++k) {
      const double y = W.apply(vertex(k), r);
      if (std::isnan(y)) continue;
      if (const double norm2 = row_norm2(W, vertex(k), fit.passes, coefficient, in_row); norm2 > 0)
        out[static_cast<std::size_t>(k)] = y * y / norm2;
    }
  });
  return out;
}

NoiseEstimate estimate_noise(const Vertices& P, const Triangles& F, const Topology& topo, const Vertices& smoothed,
                             const std::vector<std::int32_t>& vertices, Executor* executor) {
  const auto t0 = std::chrono::steady_clock::now();
  // Decision 19: planes over the 1-ring applied three times, quadrics over the 2-ring twice;
  // each reads the noise plus what is left of the shape, so the smaller is kept.
  // The smaller reading of the two fits in the given frames (decision 19).
  const auto smaller = [&](const Vertices& frames, std::optional<Reading>* one_pass) {
    std::optional<Reading> best;
    for (const LocalFit fit : {LocalFit{1, 1, 3}, LocalFit{2, 2, 2}}) {
      std::vector<double> first;
      const bool quadric = fit.rings == 2 && one_pass;
      const std::optional<Reading> r = read(local_fit_residuals(P, topo, frames, fit, vertices, executor, quadric ? &first : nullptr));
      if (r && (!best || r->sigma < best->sigma)) best = r;
      if (quadric) *one_pass = read(std::move(first));
    }
    return best;
  };
  std::optional<Reading> one_pass;
  std::optional<Reading> best = smaller(smoothed, &one_pass);
  const double noisy_edge = topo.mean_edge_length(P);
  // Decision 19: at high noise (a first reading above 0.3 noisy edge lengths, about 0.35 l) four
  // smoothing steps leave the frames tilted by the noise and the fits' linear terms absorb part
  // of it; read again in frames from 16 steps.
  constexpr double kHighNoiseEdges = 0.3;
  std::optional<Vertices> steadier;
  if (best && noisy_edge > 0 && best->sigma > kHighNoiseEdges * noisy_edge) {
    steadier = vertex_normals(umbrella_smooth(P, topo, 16, 0.5, executor), F);
    best = smaller(*steadier, nullptr);
  }
  const Vertices& normals = steadier ? *steadier : smoothed;
  // Decision 19: a second reading in frames from patches 3 sigma wide across slivers (none
  // where no frame changed: the same reading).
  if (best && best->sigma > 0) {
    const Vertices widened = patch_normals(P, topo, normals, 3 * best->sigma, executor);
    if ((widened.array() != normals.array()).any())
      if (const std::optional<Reading> second = smaller(widened, nullptr)) best = second;
  }
  return finish(best, one_pass, noisy_edge, t0);
}

NoiseEstimate estimate_noise_quick(const Vertices& P, const Triangles& F, const Topology& topo,
                                   const std::vector<std::int32_t>& vertices, Executor* executor) {
  const auto t0 = std::chrono::steady_clock::now();
  // Decision 33: one pass of each fit of decision 19 (planes over the 1-ring, quadrics over
  // the 2-ring) in the frames of smoothed_normals, the smaller reading kept; no re-reading at
  // high noise, no widened frames. Shape error is not filtered out, so a coarse curved surface
  // reads noisier than it is: a descriptor for the model, not a measurement.
  const Vertices frames = smoothed_normals(P, F, topo, executor);
  std::optional<Reading> best, one_pass;
  for (const LocalFit fit : {LocalFit{1, 1, 1}, LocalFit{2, 2, 1}}) {
    const std::optional<Reading> r = read(local_fit_residuals(P, topo, frames, fit, vertices, executor));
    if (r && (!best || r->sigma < best->sigma)) best = r;
    if (fit.rings == 2) one_pass = r;
  }
  return finish(best, one_pass, topo.mean_edge_length(P), t0);
}

}  // namespace mdn
