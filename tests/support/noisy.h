// A noisy copy of a test mesh (same faces), for tests that denoise.
#pragma once

#include <cstdint>

#include "core/mesh.h"
#include "core/noise.h"
#include "core/params.h"

namespace mdn::test {

inline TriMesh with_noise(const TriMesh& clean, double sigma, NoiseKind kind = NoiseKind::AlongNormal,
                          std::uint64_t seed = 7) {
  NoiseSpec spec;
  spec.kind = kind;
  spec.sigma = sigma;
  spec.seed = seed;
  return TriMesh{add_noise(clean, spec), clean.F};
}

// The largest distance any vertex moved between two copies of one mesh.
inline double max_displacement(const TriMesh& a, const TriMesh& b) { return (a.V - b.V).rowwise().norm().maxCoeff(); }

// The default parameters with ParamMode::Auto, as the CLI and the service send them.
inline DenoiseParams automatic() {
  DenoiseParams p;
  p.mode = ParamMode::Auto;
  return p;
}

}  // namespace mdn::test
