// One job of meshdenoise, as the single-file, batch and --tune runs share it: the exit codes and
// the one mapping of a failure to its code and message, Ctrl-C (cooperative cancellation) and
// the progress bar, the job's parameters from the command line, and the run itself on the
// shared job runner.
#pragma once

#include <exception>
#include <string>

#include <nlohmann/json.hpp>

#include "core/progress.h"
#include "cli/options.h"
#include "service/job_runner.h"

namespace mdn::cli {

// Exit codes (documented in usage()).
constexpr int kExitOk = 0;
constexpr int kExitUsage = 2;     // bad command line or bad parameters
constexpr int kExitFile = 3;      // a file cannot be read or written, is malformed or not a valid mesh
constexpr int kExitInternal = 4;  // solver failure or anything unexpected
constexpr int kExitCancelled = 130;

struct Failure {
  int exit_code;
  std::string message;
};

// The exit code and message for an exception; one mapping for the whole tool and for each
// file of a batch.
Failure describe_failure(const std::exception_ptr& error);
void print_error(const std::string& message);

// Ctrl-C: the handler sets a flag, interrupted() reads it (CliProgress polls it).
void install_sigint_handler();
bool interrupted();

// Cooperative cancellation on SIGINT, and a one-line progress bar on stderr when it is a
// terminal: "normal filter  [##########..........]  50%". Redraws only when the stage or
// the whole percentage changes.
class CliProgress : public mdn::ProgressObserver {
 public:
  explicit CliProgress(bool draw) : draw_(draw) {}
  ~CliProgress() override { clear(); }

  void on_progress(mdn::Stage stage, double fraction) override;
  bool cancel_requested() override { return interrupted(); }
  void clear();

 private:
  bool draw_;
  bool drawn_ = false;
  mdn::Stage stage_{};
  int percent_ = -1;
};

// The job's parameters: --params (inline JSON or a file, read once), then --mode. `fields`
// receives the --params object as given (empty without --params).
service::JobParams job_params(const CliOptions& options, nlohmann::json& fields);
int default_threads(const CliOptions& options);

// Denoises one input with the shared job runner; a problem with the input is blamed on its file.
// The progress bar (if any) is cleared whatever happens.
service::JobOutput denoise_input(const std::string& in_path, std::string in_bytes, io::Format in_format,
                                 const service::JobParams& params, int threads, const io::Limits& limits,
                                 CliProgress& progress);
// Where a --report summary came from and went.
void add_paths(nlohmann::json& summary, const std::string& in_path, io::Format in_format, const std::string& out_path);

}  // namespace mdn::cli
