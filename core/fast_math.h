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
  if (!(y > -708.0)) return 0.0;  // underflow (and NaN) -> 0
  constexpr double kLog2e = 1.4426950408889634;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;  // Cody-Waite split of ln 2
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  // Round y / ln2 to the nearest integer with the 1.5 * 2^52 trick (no libm call): the sum's
  // low mantissa bits then hold k in two's complement.
  constexpr double kShifter = 6755399441055744.0;  // 1.5 * 2^52
  const double t = y * kLog2e + kShifter;
  const double k = t - kShifter;
  const auto ki = static_cast<std::int32_t>(static_cast<std::uint32_t>(std::bit_cast<std::uint64_t>(t)));
  const double r = (y - k * kLn2Hi) - k * kLn2Lo;  // |r| <= ln2 / 2
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
  // Scale by 2^k; k >= -1022 here, so 2^k is a normal double.
  return p * std::bit_cast<double>(static_cast<std::uint64_t>(ki + 1023) << 52);
}

}  // namespace mdn::detail
