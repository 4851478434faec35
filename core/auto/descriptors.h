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

// P in the unit-box frame. The face statistics are taken over at most 60,000 faces (a fixed
// stride) and the noise estimate's fits over at most 20,000 vertices. The smoothed normals,
// measure_input's residuals and the ring-mean normals still cover the whole mesh: 3.8 s of a
// 14.6 s auto run at 1.2M faces (docs/measurements/trained-choice.md). Deterministic for any
// thread count.
Descriptors describe_input(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor);

}  // namespace mdn
