// The entry point for every parameter mode: Manual and None run the pipeline (core/pipeline.h)
// as given; Auto and Search first choose the parameters per input (core/auto/choose.h).
#pragma once

#include "core/auto/choice.h"
#include "core/pipeline.h"

namespace mdn {

// Throws InvalidMeshError, InvalidParamsError, SolverError or CancelledError.
DenoiseResult denoise(const TriMesh& input, const DenoiseParams& params, const RunOptions& options = {});

}  // namespace mdn
