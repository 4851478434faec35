// Seeded synthetic noise for experiments and tests (Sec. 7). Deterministic for a given seed
// on every platform (own Gaussian sampler over std::mt19937_64).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "core/mesh.h"

namespace mdn {

enum class NoiseKind {
  PerCoordinate,    // each coordinate gets an independent N(0, s^2)
  AlongNormal,      // displacement N(0, s^2) along the area-weighted vertex normal
  RandomDirection,  // displacement N(0, s^2) along a uniformly random unit direction
};
std::string_view to_string(NoiseKind kind);
std::optional<NoiseKind> noise_kind_from_string(std::string_view text);

struct NoiseSpec {
  NoiseKind kind = NoiseKind::AlongNormal;
  double sigma = 0.2;            // standard deviation, in multiples of the mean edge length
  std::uint64_t seed = 1;
  // Impulse noise (Fig. 11): if > 0, only this fraction of the vertices, chosen at random,
  // is displaced (with the kind and sigma above); the others stay exactly in place.
  double impulse_fraction = 0;   // [0, 1]
};

// Returns the noisy positions (#V by 3); connectivity is unchanged. Throws InvalidMeshError
// for an invalid mesh and InvalidParamsError (field "sigma" or "impulse_fraction") for a
// negative or non-finite sigma or a fraction outside [0, 1].
Vertices add_noise(const TriMesh& mesh, const NoiseSpec& spec);

// n independent standard normal draws from `seed` (the sampler add_noise uses).
std::vector<double> gaussian_draws(std::size_t n, std::uint64_t seed);

}  // namespace mdn
