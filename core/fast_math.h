// Small inline math kernels for the hot loops (internal to the core).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

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

}  // namespace mdn::detail
