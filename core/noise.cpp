// Seeded synthetic noise (Sec. 7). Everything random comes from one std::mt19937_64, whose
// output sequence the C++ standard fixes; the uniform, integer and Gaussian draws are
// written out here because std::*_distribution algorithms differ between libraries.
#include "core/noise.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/errors.h"

namespace mdn {

namespace {

class Sampler {
 public:
  explicit Sampler(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  // Uniform integer in [0, n), n > 0, without modulo bias (rejection of the top remainder).
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
    std::uint64_t x;
    do x = engine_();
    while (x >= limit);
    return x % n;
  }

  // Standard normal by Marsaglia's polar method; the second value of each pair is kept.
  double gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2.0 * uniform() - 1.0;
      v = 2.0 * uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double factor = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * factor;
    has_spare_ = true;
    return u * factor;
  }

  // Uniform direction on the unit sphere: a normalised isotropic Gaussian vector.
  Vec3 direction() {
    for (;;) {
      const Vec3 g(gaussian(), gaussian(), gaussian());
      const double n = g.norm();
      if (n > 1e-12) return g / n;
    }
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0;
  bool has_spare_ = false;
};

}  // namespace

std::vector<double> gaussian_draws(std::size_t n, std::uint64_t seed) {
  Sampler rng(seed);
  std::vector<double> out(n);
  for (double& x : out) x = rng.gaussian();
  return out;
}

std::string_view to_string(NoiseKind kind) {
  switch (kind) {
    case NoiseKind::PerCoordinate: return "per_coordinate";
    case NoiseKind::AlongNormal: return "along_normal";
    case NoiseKind::RandomDirection: return "random_direction";
  }
  return "unknown";
}

std::optional<NoiseKind> noise_kind_from_string(std::string_view text) {
  for (NoiseKind kind : {NoiseKind::PerCoordinate, NoiseKind::AlongNormal, NoiseKind::RandomDirection})
    if (to_string(kind) == text) return kind;
  return std::nullopt;
}

Vertices add_noise(const TriMesh& mesh, const NoiseSpec& spec) {
  validate_mesh(mesh);
  if (!std::isfinite(spec.sigma) || spec.sigma < 0)
    throw InvalidParamsError("sigma", "noise sigma must be a finite number >= 0, got " + std::to_string(spec.sigma));
  if (!std::isfinite(spec.impulse_fraction) || spec.impulse_fraction < 0 || spec.impulse_fraction > 1)
    throw InvalidParamsError("impulse_fraction",
                             "impulse_fraction must lie in [0, 1], got " + std::to_string(spec.impulse_fraction));
  if (to_string(spec.kind) == "unknown") throw InvalidParamsError("kind", "unknown noise kind");

  const std::int64_t nv = mesh.num_vertices();
  const double s = spec.sigma * mean_edge_length(mesh.V, mesh.F);
  Sampler rng(spec.seed);

  // Vertices to displace: all, or exactly round(fraction x #V) chosen by a partial
  // Fisher-Yates shuffle (each subset of that size equally likely), then sorted so the
  // Gaussian draws below are consumed in vertex order.
  std::vector<std::int64_t> chosen(nv);
  std::iota(chosen.begin(), chosen.end(), 0);
  if (spec.impulse_fraction > 0) {
    const auto k = static_cast<std::int64_t>(std::llround(spec.impulse_fraction * static_cast<double>(nv)));
    for (std::int64_t i = 0; i < k; ++i) {
      const auto j = i + static_cast<std::int64_t>(rng.below(static_cast<std::uint64_t>(nv - i)));
      std::swap(chosen[i], chosen[j]);
    }
    chosen.resize(k);
    std::sort(chosen.begin(), chosen.end());
  }

  Vertices out = mesh.V;
  Vertices normals;
  if (spec.kind == NoiseKind::AlongNormal) normals = vertex_normals(mesh.V, mesh.F);
  for (const std::int64_t v : chosen) {
    switch (spec.kind) {
      case NoiseKind::PerCoordinate:
        for (int k = 0; k < 3; ++k) out(v, k) += s * rng.gaussian();
        break;
      case NoiseKind::AlongNormal:
        // An isolated vertex has the zero normal and stays in place.
        out.row(v) += s * rng.gaussian() * normals.row(v);
        break;
      case NoiseKind::RandomDirection: {
        const Vec3 dir = rng.direction();
        out.row(v) += (s * rng.gaussian()) * dir.transpose();
        break;
      }
    }
  }
  return out;
}

}  // namespace mdn
