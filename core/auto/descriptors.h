// What the trained parameter choice reads off a noisy surface at run time (issue 31, item 3):
// cheap, scale-free statistics, no ground truth, computed the same way for the training corpus
// (tools/train) and for a user's input. core/auto/README.md lists them.
#pragma once

#include <string>
#include <vector>

#include "core/auto/measures.h"
#include "core/mesh.h"
#include "core/auto/noise_estimate.h"
#include "core/topology.h"

namespace mdn {

class Executor;

struct Descriptors {
  std::vector<double> values;  // in the order of descriptor_names()
  NoiseEstimate noise;         // the noise estimate among them (decision 19)
  InputMeasures measures;      // measure_input's readings among them (the region mode reads cluster_area_ratio)
  double ms = 0;               // time taken
};

// The names of Descriptors::values, in order; the model file lists the same names.
const std::vector<std::string>& descriptor_names();

// P in the unit-box frame. Statistics over faces read at most 60,000 faces (a fixed stride),
// the noise estimate at most 20,000 vertices, so the cost levels off on large scans.
// Deterministic for any thread count.
Descriptors describe_input(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor);

}  // namespace mdn
