// The true MSAE of every set of the label grid (label_grid.h) on one noisy/clean pair: the
// corpus labels (train_corpus label) and the ground-truth best of tune_bench's validation.
#pragma once

#include <vector>

#include "core/mesh.h"
#include "core/params.h"
#include "core/topology.h"

namespace mdn::train {

// A noisy input in the unit-box frame, as denoise() sees it, with the clean face normals.
struct Prepared {
  Vertices P;
  Triangles F;
  Topology topo;
  Vertices truth_normals;
};
Prepared prepare(const TriMesh& clean, const Vertices& noisy);

// The region mode auto would run (decision 6: the K-means area ratio of the input).
RegionMode auto_region_mode(const Prepared& c);

// Identity's MSAE first, then every set of label_sets() in order (one thread).
std::vector<double> label_case(const Prepared& c, RegionMode region);

}  // namespace mdn::train
