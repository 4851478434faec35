#include "core/fast_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace mdn::detail {
namespace {

TEST(FastMath, ExpNonPositiveMatchesStdExpWithinTwoUlp) {
  double worst = 0;
  for (double y = 0; y > -707; y -= 0.000731) {
    const double a = exp_nonpositive(y), b = std::exp(y);
    worst = std::max(worst, std::abs(a - b) / b);
  }
  EXPECT_LT(worst, 4.5e-16);  // 2 ulp
  EXPECT_EQ(exp_nonpositive(0.0), 1.0);
  EXPECT_EQ(exp_nonpositive(-800.0), 0.0);
  EXPECT_EQ(exp_nonpositive(-std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_EQ(exp_nonpositive(std::numeric_limits<double>::quiet_NaN()), 0.0);
}

// The single-precision exp of the normal filter's range weights (decision 36).
TEST(FastMath, ExpNonPositiveFloatMatchesStdExpWithinTwoUlp) {
  double worst = 0;
  for (float y = 0; y > -87.0f; y -= 0.000731f) {
    const double a = exp_nonpositive_f(y), b = std::exp(static_cast<double>(y));
    worst = std::max(worst, std::abs(a - b) / b);
  }
  EXPECT_LT(worst, 2.4e-7);  // 2 ulp of a float
  EXPECT_EQ(exp_nonpositive_f(0.0f), 1.0f);
  EXPECT_EQ(exp_nonpositive_f(-100.0f), 0.0f);
  EXPECT_EQ(exp_nonpositive_f(-std::numeric_limits<float>::infinity()), 0.0f);
  EXPECT_EQ(exp_nonpositive_f(std::numeric_limits<float>::quiet_NaN()), 0.0f);
}

}  // namespace
}  // namespace mdn::detail
