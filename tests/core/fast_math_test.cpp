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

}  // namespace
}  // namespace mdn::detail
