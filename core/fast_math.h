// Small inline math kernels for the hot loops (internal to the core).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

// Before a loop function: compile it for AVX2 as well and pick the version at run time (GCC on
// x86-64; not under ASan, which does not support the resolver). Without FMA contraction both
// versions do the same IEEE operations.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
#define MDN_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define MDN_AVX2_CLONE
#endif

namespace mdn::detail {

// exp(y) for y <= 0, within 2 ulp of std::exp (tested), inlined and branch-light so the
// filters' inner loops do not pay a libm call per neighbour pair. Identical results on
// every platform with IEEE doubles (no table, no FMA contraction assumed).
inline double exp_nonpositive(double y) {
  constexpr double kLog2e = 1.4426950408889634;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;  // Cody-Waite split of ln 2
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  // Round y / ln2 to the nearest integer k with the 1.5 * 2^52 trick (no libm call): the
  // sum's bit pattern is that of the shifter plus k, so k and 2^k come from integer adds.
  // Everything below is branch-free, so loops over arrays of y vectorise.
  constexpr double kShifter = 6755399441055744.0;  // 1.5 * 2^52
  const double yc = y > -708.0 ? y : -708.0;        // clamp (NaN too); the result is zeroed below
  const double t = yc * kLog2e + kShifter;
  const double k = t - kShifter;
  const double r = (yc - k * kLn2Hi) - k * kLn2Lo;  // |r| <= ln2 / 2
  // Taylor polynomial of degree 12: truncation error < 2e-17 on |r| <= 0.347.
  double p = 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // 2^k as a normal double (k >= -1022 after the clamp).
  const std::uint64_t k_bits = std::bit_cast<std::uint64_t>(t) - std::bit_cast<std::uint64_t>(kShifter);
  const double scale = std::bit_cast<double>((k_bits + 1023) << 52);
  return y > -708.0 ? p * scale : 0.0;  // underflow and NaN -> 0
}

// exp(y) for y <= 0 in single precision, within 2 ulp of std::exp(float) (tested): the same
// Cody-Waite reduction and 2^k by integer adds, a degree-7 Taylor polynomial (truncation
// < 5e-9 on |r| <= 0.347). For the normal filter's range weights (decision 36). Results under
// 2^-126 (y < -87) are flushed to 0; branch-free, so loops over arrays of y vectorise.
inline float exp_nonpositive_f(float y) {
  constexpr float kLog2e = 1.44269504f;
  constexpr float kLn2Hi = 0.693359375f;  // exact in 9 bits: k * kLn2Hi is exact
  constexpr float kLn2Lo = -2.12194440e-4f;
  constexpr float kShifter = 12582912.0f;  // 1.5 * 2^23
  const float yc = y > -87.0f ? y : -87.0f;
  const float t = yc * kLog2e + kShifter;
  const float k = t - kShifter;
  const float r = (yc - k * kLn2Hi) - k * kLn2Lo;
  float p = 1.0f / 5040.0f;
  p = p * r + 1.0f / 720.0f;
  p = p * r + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  const std::uint32_t k_bits = std::bit_cast<std::uint32_t>(t) - std::bit_cast<std::uint32_t>(kShifter);
  const float scale = std::bit_cast<float>((k_bits + 127u) << 23);
  return y > -87.0f ? p * scale : 0.0f;  // underflow and NaN -> 0
}

}  // namespace mdn::detail
