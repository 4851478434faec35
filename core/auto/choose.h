// ParamMode::Auto and Search: the parameters per input, without ground truth (issue 31;
// core/auto/README.md). Auto: the descriptors (descriptors.h) go through the trained model
// (model.h), which predicts the error of every shipped set; the lowest runs. Inputs outside
// the model's training range get no filtering or the paper's Table 1 row, whichever the
// recorrupted score prefers, named in the notes. Search: the
// model's pick, then the coordinate descent driven by the recorrupted score (recorrupted.h).
#pragma once

#include "core/auto/choice.h"
#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

class Executor;
class ProgressObserver;

// P in the unit-box frame whose scale (UnitBox::scale) is `box_scale`: the report's lengths are
// converted back to the input's units. Returns the choice (choice.search is set in Search mode)
// and stores the parameters to run in `chosen` (mode Manual, pinned fields kept).
ParameterChoice choose_parameters(const Vertices& P, const Triangles& F, const Topology& topo, const DenoiseParams& requested,
                                  double box_scale, Executor& executor, ProgressObserver* progress, DenoiseParams& chosen);

}  // namespace mdn
