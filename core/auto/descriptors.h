// What the trained parameter choice reads off a noisy surface at run time (issue 31, item 3):
// cheap, scale-free statistics, no ground truth, computed the same way for the training corpus
// (tools/train) and for a user's input. core/auto/README.md lists them.
#pragma once

#include <cstdint>
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

// P in the unit-box frame. Decision 33: a surface of more than `max_faces` faces is read on 16
// patches of max_faces / 16 faces (core/auto/surface_sample.h), so the cost does not grow with
// the mesh; the noise reading takes 1,500 vertices. Deterministic for any thread count.
constexpr std::int64_t kDescribedFaces = 20000;
Descriptors describe_input(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor,
                           std::int64_t max_faces = kDescribedFaces);

}  // namespace mdn
