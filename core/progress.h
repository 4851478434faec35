// Progress reporting and cooperative cancellation, independent of any transport.
#pragma once

#include <string_view>

namespace mdn {

enum class Stage {
  SelectParameters,      // ParamMode::Auto / Search: scoring candidate parameters on a sample
  InitialPrefilter,      // Eq. 1
  RegionPrefilter,       // Sec. 4.2, K-means + Eq. 2
  AnisotropicPrefilter,  // Eq. 3-4
  NormalFilter,          // Eq. 6-7
  VertexUpdate,          // Eq. 8
};
std::string_view to_string(Stage stage);

// Implemented by callers. Both methods may be called from the thread running denoise()
// only (never concurrently); implementations must be cheap.
class ProgressObserver {
 public:
  virtual ~ProgressObserver() = default;
  // fraction in [0, 1] of the given stage.
  virtual void on_progress(Stage stage, double fraction) = 0;
  // Polled between iterations; returning true makes denoise() throw CancelledError.
  virtual bool cancel_requested() { return false; }
};

// Between iterations: throws CancelledError if cancellation was requested, else reports
// progress. A null observer does nothing.
void checkpoint(ProgressObserver* progress, Stage stage, double fraction);

}  // namespace mdn
