#include "core/params.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/errors.h"

namespace mdn {
namespace {

TEST(Params, DefaultsAreTheFandiskRowAndValid) {
  const DenoiseParams p;
  EXPECT_EQ(p.alpha, 0.1);
  EXPECT_EQ(p.sigma_theta, 30);
  EXPECT_EQ(p.n_aniso, 2);
  EXPECT_EQ(p.sigma_gamma, 30);
  EXPECT_EQ(p.n_normal, 20);
  EXPECT_EQ(p.n_vertex, 10);
  EXPECT_EQ(p.beta, 6);
  EXPECT_NO_THROW(p.validate());
}

TEST(Params, SpecsListTable1First) {
  const auto specs = param_specs();
  const char* table1[] = {"alpha", "sigma_theta", "n_aniso", "sigma_gamma", "n_normal", "n_vertex"};
  ASSERT_GE(specs.size(), 6u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(specs[static_cast<std::size_t>(i)].name, table1[i]);
  for (const ParamSpec& s : specs) {
    EXPECT_LE(s.min, s.paper_min) << s.name;
    EXPECT_GE(s.max, s.paper_max) << s.name;
    EXPECT_GE(s.default_value(), s.min) << s.name;
    EXPECT_LE(s.default_value(), s.max) << s.name;
  }
}

TEST(Params, ValidateNamesTheOffendingField) {
  for (const ParamSpec& s : param_specs()) {
    DenoiseParams p;
    if (s.real_field)
      p.*s.real_field = s.max + 1;
    else
      p.*s.int_field = static_cast<int>(s.max) + 1;
    try {
      p.validate();
      FAIL() << s.name << " above its range was accepted";
    } catch (const InvalidParamsError& e) {
      EXPECT_EQ(e.field(), s.name);
      EXPECT_NE(std::string(e.what()).find(std::string(s.name)), std::string::npos);
    }
  }
  DenoiseParams nan;
  nan.alpha = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(nan.validate(), InvalidParamsError);
}

TEST(Params, EnumerationsRoundTrip) {
  for (RegionMode m : {RegionMode::Auto, RegionMode::On, RegionMode::Off})
    EXPECT_EQ(region_mode_from_string(to_string(m)), m);
  EXPECT_FALSE(region_mode_from_string("maybe").has_value());
  for (LinearSolver s : {LinearSolver::Ldlt, LinearSolver::ConjugateGradient})
    EXPECT_EQ(linear_solver_from_string(to_string(s)), s);
}

}  // namespace
}  // namespace mdn
