#include "core/progress.h"

#include "core/errors.h"

namespace mdn {

std::string_view to_string(Stage stage) {
  switch (stage) {
    case Stage::SelectParameters: return "select_parameters";
    case Stage::InitialPrefilter: return "initial_prefilter";
    case Stage::RegionPrefilter: return "region_prefilter";
    case Stage::AnisotropicPrefilter: return "anisotropic_prefilter";
    case Stage::NormalFilter: return "normal_filter";
    case Stage::VertexUpdate: return "vertex_update";
  }
  return "unknown";
}

void checkpoint(ProgressObserver* progress, Stage stage, double fraction) {
  if (!progress) return;
  if (progress->cancel_requested()) throw CancelledError();
  progress->on_progress(stage, fraction);
}

}  // namespace mdn
