// Automatic parameters (ParamMode::Auto): measure the noisy input, then choose the six
// parameters of Table 1 and the region mode from the measurements with a rule fitted on
// data by tests/bench/tune_bench.cpp (see core/README.md, "Automatic parameters").
#pragma once

#include "core/mesh.h"
#include "core/params.h"
#include "core/topology.h"

namespace mdn {

class Executor;

// What ParamMode::Auto measures on the noisy input (unit-box frame). Distances are in mean
// edge lengths l. r_i below is the distance of vertex i from the plane through the centroid
// of its 1-ring neighbours, normal to the area-weighted vertex normal: noise moves it by
// about the noise level, smooth curvature by O(l^2 kappa), sharp features by O(l).
struct InputMeasures {
  double noise = 0;               // median r_i / l: noise level (Gaussian sigma ~ 0.68 x this on a plane)
  double tail = 0;                // 90th percentile of r_i / median r_i: > 2.4 when features stand out of the noise
  double feature_share = 0;       // share of vertices with r_i > 4 x median r_i (features and impulses)
  // The same after 4 umbrella smoothing steps (lambda 1/2), which remove most of the noise but
  // keep curvature and creases: flat-and-crease (CAD) shapes get a long tail even at high
  // noise, smooth organic shapes do not.
  double smooth_residual = 0;     // median r_i / l after smoothing
  double smooth_tail = 0;         // 90th / 50th percentile of r_i after smoothing
  double cluster_area_ratio = 1;  // Sec. 4.2: K-means area ratio on the input's faces (sampling irregularity)
  double measure_ms = 0;          // time taken by measure_input
};

// Measures the input. P in the unit-box frame; K-means uses params.kmeans_k and kmeans_seed
// on at most 4000 faces (a fixed-stride sample: the area ratio does not need them all).
InputMeasures measure_input(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& params,
                            Executor* executor = nullptr);

// The rule: returns `requested` with every non-pinned AutoField replaced by the value the
// fitted rule gives for these measurements, and mode Manual (the result is what runs).
// region_mode is On iff cluster_area_ratio >= requested.irregular_area_ratio.
DenoiseParams choose_parameters(const InputMeasures& measures, const DenoiseParams& requested);

// --- The rule's form, shared with its fitting (tests/bench/tune_fit.cpp) ---
// Features: (1, ln noise, ln tail, ln smooth_tail, ln(smooth_residual / noise), feature_share,
// irregular 0/1). The rule takes the k training cases nearest in standardised feature space
// and the prototype parameter set with the least summed log-MSAE excess over them.
inline constexpr int kAutoFeatures = 7;
using AutoFeatures = Eigen::Matrix<double, kAutoFeatures, 1>;
AutoFeatures auto_features(const InputMeasures& measures, double irregular_area_ratio = DenoiseParams{}.irregular_area_ratio);
int choose_prototype(const InputMeasures& measures, double irregular_area_ratio);  // index into the rule's table
int rule_prototype_count();
// `requested` with prototype p (0 <= p < rule_prototype_count()) filled in as choose_parameters
// does; choose_parameters is this with p = choose_prototype. tune_bench uses it to show what
// the best choice among the prototypes would give (the ceiling of the rule's form).
DenoiseParams prototype_parameters(int p, const InputMeasures& measures, const DenoiseParams& requested);

}  // namespace mdn
