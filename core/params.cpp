#include "core/params.h"

#include <array>
#include <cmath>
#include <sstream>

#include "core/errors.h"

namespace mdn {

std::string_view to_string(RegionMode mode) {
  switch (mode) {
    case RegionMode::Auto: return "auto";
    case RegionMode::On: return "on";
    case RegionMode::Off: return "off";
  }
  return "auto";
}

std::optional<RegionMode> region_mode_from_string(std::string_view text) {
  if (text == "auto") return RegionMode::Auto;
  if (text == "on") return RegionMode::On;
  if (text == "off") return RegionMode::Off;
  return std::nullopt;
}

std::string_view to_string(ParamMode mode) {
  switch (mode) {
    case ParamMode::Auto: return "auto";
    case ParamMode::Search: return "search";
    case ParamMode::None: return "none";
    case ParamMode::Manual: break;
  }
  return "manual";
}

std::optional<ParamMode> param_mode_from_string(std::string_view text) {
  if (text == "auto") return ParamMode::Auto;
  if (text == "search") return ParamMode::Search;
  if (text == "manual") return ParamMode::Manual;
  if (text == "none") return ParamMode::None;
  return std::nullopt;
}

namespace {
constexpr std::array<std::string_view, kAutoFieldCount> kAutoFieldNames{
    "alpha", "sigma_theta", "n_aniso", "sigma_gamma", "n_normal", "n_vertex", "region_mode"};
}

std::string_view to_string(AutoField field) { return kAutoFieldNames[static_cast<std::size_t>(field)]; }

std::optional<AutoField> auto_field_from_string(std::string_view name) {
  for (std::size_t i = 0; i < kAutoFieldNames.size(); ++i)
    if (kAutoFieldNames[i] == name) return static_cast<AutoField>(i);
  return std::nullopt;
}

std::string_view to_string(LinearSolver solver) {
  return solver == LinearSolver::Ldlt ? "ldlt" : "cg";
}

std::optional<LinearSolver> linear_solver_from_string(std::string_view text) {
  if (text == "ldlt") return LinearSolver::Ldlt;
  if (text == "cg") return LinearSolver::ConjugateGradient;
  return std::nullopt;
}

namespace {
using P = DenoiseParams;
// Accepted ranges are wider than the paper's where a wider value is meaningful (the best
// parameters per mesh often sit at the edges of the paper's ranges).
const std::array<ParamSpec, 15> kSpecs{{
    {"alpha", false, 0, 10, 0.05, 0.2, "", "Eq. 1, Eq. 3", "weight of the shaping term in the pre-filters", &P::alpha, nullptr},
    {"sigma_theta", false, 1, 180, 20, 50, "degrees", "Eq. 4", "angle scale of the anisotropic edge weight w_e", &P::sigma_theta, nullptr},
    {"n_aniso", true, 0, 100, 0, 12, "iterations", "Eq. 3", "iterations of the anisotropic pre-filter", nullptr, &P::n_aniso},
    {"sigma_gamma", false, 1, 180, 20, 50, "degrees", "Eq. 6-7", "angle scale of the L1-median normal filter", &P::sigma_gamma, nullptr},
    {"n_normal", true, 0, 1000, 5, 100, "iterations", "Eq. 7", "iterations of the L1-median normal filter", nullptr, &P::n_normal},
    {"n_vertex", true, 0, 1000, 5, 100, "iterations", "Eq. 8", "iterations of the vertex update", nullptr, &P::n_vertex},
    {"beta", false, 0, 1000, 6, 6, "", "Eq. 2", "smoothness of the region-based Laplacian pre-filter", &P::beta, nullptr},
    {"kmeans_k", true, 2, 16, 2, 2, "clusters", "Sec. 4.2", "number of K-means clusters over (centroid, area)", nullptr, &P::kmeans_k},
    {"fold_angle", false, 0, 180, 130, 130, "degrees", "Sec. 4.2", "angle between face normals above which an edge counts as folded", &P::fold_angle, nullptr},
    {"fold_ratio", false, 0, 1, 0.1, 0.1, "fraction", "Sec. 4.2", "fraction of folded edges (angle > fold_angle) also required before auto runs the region pre-filter", &P::fold_ratio, nullptr},
    {"irregular_area_ratio", false, 1, 1e6, 4, 4, "ratio", "Sec. 4.2", "cluster mean-area ratio that marks irregular sampling", &P::irregular_area_ratio, nullptr},
    {"b", false, 1, 100, 1.7320508075688772, 1.7320508075688772, "", "Eq. 4", "base of the exponential edge weight", &P::b, nullptr},
    {"bilateral_switch", false, 0, 2, 1e-3, 1e-3, "", "Eq. 7", "||n_i - n_j|| below which bilateral weights are used", &P::bilateral_switch, nullptr},
    {"sigma_c_factor", false, 0.01, 100, 1.5, 1.5, "", "Eq. 6", "sigma_c in multiples of the mean centroid distance of adjacent faces", &P::sigma_c_factor, nullptr},
    {"cg_tolerance", false, 1e-16, 1e-2, 1e-8, 1e-8, "", "", "relative residual of the conjugate-gradient solver", &P::cg_tolerance, nullptr},
}};

std::string format_number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}
}  // namespace

double ParamSpec::default_value() const {
  static const DenoiseParams defaults{};
  return real_field ? defaults.*real_field : static_cast<double>(defaults.*int_field);
}

std::span<const ParamSpec> param_specs() { return {kSpecs.data(), kSpecs.size()}; }

void DenoiseParams::validate() const {
  for (const ParamSpec& spec : param_specs()) {
    const double value = spec.real_field ? this->*spec.real_field : static_cast<double>(this->*spec.int_field);
    if (!std::isfinite(value) || value < spec.min || value > spec.max)
      throw InvalidParamsError(std::string(spec.name),
                               std::string(spec.name) + " must be in [" + format_number(spec.min) + ", " +
                                   format_number(spec.max) + "], got " + format_number(value));
  }
}

}  // namespace mdn
