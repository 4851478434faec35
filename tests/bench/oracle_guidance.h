// Issue 48's oracle guidance (decision 53): the clean face normals, each turned by a random angle
// of a given mean, a stand-in for a per-face regressor of that accuracy. tune_bench's `guided`
// and train_corpus's `guided` (the holdout shapes) both measure against it.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "core/mesh.h"

namespace mdn::bench {

// N's rows turned about random tangent axes: the tangent-plane offset is a 2D Gaussian, so the
// angle is Rayleigh distributed with mean mean_deg. Zero rows stay zero. Seeded.
inline Vertices perturbed_normals(const Vertices& N, double mean_deg, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, mean_deg * M_PI / 180 / std::sqrt(M_PI / 2));
  Vertices out = N;
  for (Eigen::Index f = 0; f < N.rows(); ++f) {
    const Vec3 n = N.row(f).transpose();
    const double gx = gauss(rng), gy = gauss(rng);
    if (n.squaredNorm() == 0) continue;
    const Vec3 t1 = n.cross(std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized(), t2 = n.cross(t1);
    const Vec3 d = gx * t1 + gy * t2;
    if (const double theta = d.norm(); theta > 0) out.row(f) = (std::cos(theta) * n + std::sin(theta) / theta * d).transpose();
  }
  return out;
}

}  // namespace mdn::bench
