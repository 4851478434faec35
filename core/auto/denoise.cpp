#include "core/auto/denoise.h"

#include <memory>

#include "core/auto/choose.h"

namespace mdn {

DenoiseResult denoise(const TriMesh& input, const DenoiseParams& params, const RunOptions& options) {
  return run_pipeline(input, params, options,
                      [&params](const Vertices& P, const Triangles& F, const Topology& topo, double box_scale, Executor& executor,
                                ProgressObserver* progress, DenoiseReport& report) {
                        DenoiseParams chosen;
                        auto choice = std::make_shared<ParameterChoice>(
                            choose_parameters(P, F, topo, params, box_scale, executor, progress, chosen));
                        report.choice = std::move(choice);
                        return chosen;
                      });
}

}  // namespace mdn
