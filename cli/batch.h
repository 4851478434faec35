// meshdenoise --out-dir DIR [--params P] [--threads N] [--report] IN...
// Files run side by side, one pipeline thread each while there are more files than threads
// (the output never depends on the thread count). A file that fails is reported on stderr and
// in the report, and the others go on; Ctrl-C cancels the running files and starts no more.
#pragma once

#include "cli/options.h"

namespace mdn::cli {

// 0, or the exit code of the first input (in order) that failed (130 after Ctrl-C).
int run_batch(const CliOptions& options);

}  // namespace mdn::cli
