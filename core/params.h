// Parameters of the method (Table 1 order), their defaults, meanings and ranges.
// Defaults are defined here once; the CLI and the server fill missing fields from them.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace mdn {

// Whether the region-based pre-filter of Sec. 4.2 (K-means + Eq. 2) runs.
enum class RegionMode {
  Auto,  // run it when the input is irregularly sampled (cluster area ratio) and fold_ratio is met
  On,    // always run it on the small-triangle cluster
  Off,   // never run it
};
std::string_view to_string(RegionMode mode);
std::optional<RegionMode> region_mode_from_string(std::string_view text);

// Sparse solver for the SPD systems of Eq. 1-3 (see core/README.md for the measurements).
enum class LinearSolver {
  Ldlt,               // Eigen SimplicialLDLT, symbolic analysis shared by Eq. 1 and all Eq. 3 steps
  ConjugateGradient,  // Jacobi-preconditioned CG warm-started from the previous iterate
};
std::string_view to_string(LinearSolver solver);
std::optional<LinearSolver> linear_solver_from_string(std::string_view text);

// Who sets the six parameters of Table 1 and the region mode.
enum class ParamMode {
  Manual,  // the values below, as given
  Auto,    // chosen per input by the trained model (core/auto/choose.h), except pinned fields
  Search,  // Auto, then a coordinate descent driven by a recorrupted estimate of the error (slower; core/auto/tune.h)
  None,    // no denoising: denoise() returns the input's positions unchanged (format conversion only)
};
std::string_view to_string(ParamMode mode);
std::optional<ParamMode> param_mode_from_string(std::string_view text);

// The fields ParamMode::Auto chooses; a pinned one keeps the caller's value.
enum class AutoField : std::uint8_t { Alpha, SigmaTheta, NAniso, SigmaGamma, NNormal, NVertex, RegionMode };
inline constexpr int kAutoFieldCount = 7;
std::string_view to_string(AutoField field);  // the JSON field name: "alpha", ..., "region_mode"
std::optional<AutoField> auto_field_from_string(std::string_view name);

struct DenoiseParams {
  // --- Who chooses: Manual uses the values below; Auto replaces every non-pinned AutoField ---
  ParamMode mode = ParamMode::Manual;
  std::uint8_t pinned = 0;  // bit i set: AutoField i keeps the value below in Auto mode
  void pin(AutoField f) { pinned = static_cast<std::uint8_t>(pinned | (1u << static_cast<int>(f))); }
  bool is_pinned(AutoField f) const { return (pinned >> static_cast<int>(f)) & 1u; }

  // --- The six parameters of Table 1 (defaults: the Fandisk row) ---
  double alpha = 0.1;        // weight of the shaping term, Eq. 1 and Eq. 3; paper [0.05, 0.2]
  double sigma_theta = 30;   // degrees; angle scale of the edge weight w_e, Eq. 4; paper [20, 50]
  int n_aniso = 2;           // iterations of the anisotropic pre-filter, Eq. 3; paper [0, 12]
  double sigma_gamma = 30;   // degrees; angle scale of the normal filter, Eq. 6-7; paper [20, 50]
  int n_normal = 20;         // iterations of the L1-median normal filter, Eq. 7; paper [5, 100]
  int n_vertex = 10;         // iterations of the vertex update, Eq. 8; paper [5, 100]

  // --- Region-based pre-filter (Sec. 4.2) ---
  RegionMode region_mode = RegionMode::Auto;
  double beta = 6;                  // smoothness of the cluster Laplacian, Eq. 2
  int kmeans_k = 2;                 // K of the K-means clustering
  double fold_angle = 130;          // degrees; an edge is folded if its face normals differ by more
  // Fraction of folded edges required (with irregular sampling) before Auto runs the region
  // pre-filter. The paper gates at 0.10; that gate misses irregular meshes at moderate noise,
  // where the pre-filter helps most, so the default is 0 (irregularity alone decides; see
  // core/README.md for the measurements). Set 0.1 to reproduce the paper's gate.
  double fold_ratio = 0.0;
  double irregular_area_ratio = 4;  // mean-area ratio between clusters that marks irregular sampling
  std::uint64_t kmeans_seed = 1;    // seed of the k-means++ initialisation

  // --- Constants ---
  double b = 1.7320508075688772;  // base of the exponential edge weight, Eq. 4 (sqrt 3)
  double bilateral_switch = 1e-3; // ||n_i - n_j|| below which Eq. 7 uses bilateral weights
  double sigma_c_factor = 1.5;    // sigma_c = factor x mean centroid distance of adjacent faces

  // --- Numerics (do not change the result beyond solver tolerance) ---
  LinearSolver solver = LinearSolver::ConjugateGradient;
  double cg_tolerance = 1e-8;     // relative residual for LinearSolver::ConjugateGradient (decision 41)

  // Throws InvalidParamsError naming the first field outside its accepted range.
  void validate() const;
};

// Description of one numeric parameter, for validation, help texts and the JSON Schema.
struct ParamSpec {
  std::string_view name;         // field name, identical in C++ and JSON
  bool integer;                  // true for iteration counts and K
  double min, max;               // accepted range, inclusive
  double paper_min, paper_max;   // range the paper used (Sec. 7); equal to min/max if none
  std::string_view unit;         // "degrees", "iterations", "" ...
  std::string_view equation;     // "Eq. 4", "Sec. 4.2" ...
  std::string_view description;  // one line
  double DenoiseParams::*real_field = nullptr;  // exactly one of the two is set
  int DenoiseParams::*int_field = nullptr;
  double default_value() const;
};
// All numeric parameters, Table 1's six first. (region_mode, kmeans_seed and solver are
// enumerations / seeds and are described separately by the adapters.)
std::span<const ParamSpec> param_specs();

}  // namespace mdn
