#include "core/auto/denoise.h"

#include <memory>
#include <string>
#include <utility>

#include "core/auto/choose.h"
#include "core/normal_filter.h"
#include "core/orient.h"

namespace mdn {

namespace {

DenoiseResult run(const TriMesh& input, const DenoiseParams& params, const RunOptions& options) {
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

}  // namespace

DenoiseResult denoise(const TriMesh& input, const DenoiseParams& params, const RunOptions& options) {
  // Decision 34: faces wound against their neighbours are filtered turned to their piece's
  // winding; the result keeps the input's faces as they were. Nothing is filtered in mode
  // None. The pipeline's own checks come first, in its order, so that faces_to_turn reads
  // only valid indices.
  if (params.mode == ParamMode::None) return run(input, params, options);
  params.validate();
  validate_mesh(input);
  const std::vector<std::int32_t> turn = faces_to_turn(input.F, static_cast<std::int32_t>(input.V.rows()));
  if (turn.empty()) return run(input, params, options);
  TriMesh wound = input;
  for (const std::int32_t f : turn) std::swap(wound.F(f, 1), wound.F(f, 2));
  // Guidance normals (decision 53) follow their faces: a turned face's guidance turns with it.
  RunOptions turned_options = options;
  Vertices turned_guidance;
  if (options.guidance) {
    check_guidance(*options.guidance, input.F.rows());
    turned_guidance = *options.guidance;
    for (const std::int32_t f : turn) turned_guidance.row(f) *= -1;
    turned_options.guidance = &turned_guidance;
  }
  DenoiseResult result = run(wound, params, turned_options);
  result.mesh.F = input.F;
  result.report.notes.push_back(std::to_string(turn.size()) + " of " + std::to_string(input.F.rows()) +
                                " faces are wound against their neighbours; they were filtered turned to match (decision 34)");
  return result;
}

}  // namespace mdn
