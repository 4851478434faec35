#include "cli/job.h"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <thread>
#include <utility>

#include "core/errors.h"
#include "core/params.h"
#include "cli/files.h"
#include "cli/mesh.h"
#include "service/params_json.h"

namespace mdn::cli {
namespace {

using nlohmann::json;

// The only process-wide state: set by the SIGINT handler, polled by the progress observer.
// A signal handler can do nothing else safely.
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_sigint(int) { g_interrupted = 1; }

}  // namespace

Failure describe_failure(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const UsageError& e) {
    return {kExitUsage, std::string(e.what()) + "\n(run meshdenoise --help for usage)"};
  } catch (const mdn::InvalidParamsError& e) {
    return {kExitUsage, e.what()};
  } catch (const mdn::CancelledError&) {
    return {kExitCancelled, "cancelled"};
  } catch (const FileError& e) {
    return {kExitFile, e.what()};
  } catch (const mdn::InvalidMeshError& e) {
    return {kExitFile, e.what()};
  } catch (const io::UnsupportedError& e) {
    return {kExitFile, std::string("unsupported input: ") + e.what()};
  } catch (const io::LimitError& e) {
    return {kExitFile, std::string("input too large: ") + e.what()};
  } catch (const mdn::SolverError& e) {
    return {kExitInternal, std::string("solver failed: ") + e.what()};
  } catch (const std::bad_alloc&) {
    return {kExitInternal, "out of memory"};
  } catch (const std::exception& e) {
    return {kExitInternal, std::string("internal error: ") + e.what()};
  } catch (...) {
    return {kExitInternal, "internal error (unknown exception)"};
  }
}

void print_error(const std::string& message) { std::cerr << "meshdenoise: error: " << message << "\n"; }

void install_sigint_handler() {
  struct sigaction action {};
  action.sa_handler = on_sigint;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: a second Ctrl-C kills the process at once if cancellation is slow.
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
}

bool interrupted() { return g_interrupted != 0; }

void CliProgress::on_progress(mdn::Stage stage, double fraction) {
  if (!draw_) return;
  const int percent = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 100.0);
  if (drawn_ && stage == stage_ && percent == percent_) return;
  stage_ = stage;
  percent_ = percent;
  drawn_ = true;
  constexpr int kWidth = 30;
  const int filled = percent * kWidth / 100;
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.append(static_cast<std::size_t>(kWidth - filled), '.');
  std::string name(mdn::to_string(stage));
  name.resize(std::max<std::size_t>(name.size(), 22), ' ');
  std::fprintf(stderr, "\r\033[K%s [%s] %3d%%", name.c_str(), bar.c_str(), percent);
  std::fflush(stderr);
}

void CliProgress::clear() {
  if (drawn_) {
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    drawn_ = false;
  }
}

service::JobParams job_params(const CliOptions& options, json& fields) {
  service::JobParams params;
  fields = json::object();
  if (options.params) {
    const std::string text = json_argument("--params", *options.params, options.limits.max_input_bytes);
    params = service::job_params_from_text(text);
    fields = json::parse(text);  // valid: job_params_from_text accepted it
  }
  if (options.mode) {
    const auto mode = mdn::param_mode_from_string(*options.mode);
    if (!mode) throw UsageError("--mode must be auto, search, manual or none, got \"" + *options.mode + "\"");
    if (fields.contains("mode") && fields["mode"] != *options.mode)
      throw UsageError("--mode " + *options.mode + " disagrees with --params' \"mode\": " + fields["mode"].dump());
    params.denoise.mode = *mode;
  }
  return params;
}

service::JobOutput denoise_input(const std::string& in_path, std::string in_bytes, io::Format in_format,
                                 const service::JobParams& params, int threads, const io::Limits& limits,
                                 CliProgress& progress) {
  service::JobInput job{.bytes = std::move(in_bytes),
                        .format = in_format,
                        .params = params,
                        .threads = threads,
                        .resource_dir = resource_dir(in_path, in_format)};
  try {
    service::JobOutput output =
        blame_file(in_path, [&] { return service::run_job(std::move(job), limits, &progress); });
    progress.clear();
    return output;
  } catch (...) {
    progress.clear();
    throw;
  }
}

void add_paths(json& summary, const std::string& in_path, io::Format in_format, const std::string& out_path) {
  summary["input"] = {{"path", in_path}, {"format", std::string(io::to_string(in_format))}};
  summary["output"] = out_path;
}

int default_threads(const CliOptions& options) {
  return options.threads > 0 ? options.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace mdn::cli
