#include "cli/batch.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/denoise.h"
#include "cli/files.h"
#include "cli/job.h"
#include "cli/mesh.h"
#include "service/job_json.h"
#include "service/output_files.h"

namespace mdn::cli {
namespace {

using nlohmann::json;

// Where each input of a batch goes: DIR / its file name, with the extension of the requested
// output format if there is one. Refused before any work: an input without a file name, two
// inputs with one output, an output that is its own input (it would be overwritten) unless
// --in-place.
std::vector<std::string> batch_outputs(const std::vector<std::string>& inputs, const std::filesystem::path& dir,
                                       const std::optional<io::Format>& format, bool in_place) {
  namespace fs = std::filesystem;
  auto key = [](const fs::path& path) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(fs::absolute(path), ec);
    return ec ? fs::absolute(path).lexically_normal() : canonical;
  };
  std::vector<std::string> outputs;
  std::map<fs::path, std::string> taken;  // output -> the input that goes there
  for (const std::string& in : inputs) {
    if (in == kStdio) throw UsageError("--out-dir: standard input (-) cannot be part of a batch");
    const fs::path name = fs::path(in).filename();
    if (name.empty() || name == "." || name == "..")
      throw UsageError("--out-dir: the input \"" + in + "\" has no file name");
    const fs::path out = dir / service::output_file_name(in, format);
    const fs::path out_key = key(out);
    check_not_input(in, out.string(), in_place, "--out-dir: ");
    if (const auto [it, fresh] = taken.emplace(out_key, in); !fresh) {
      throw UsageError("--out-dir: " + it->second + " and " + in + " would both be written to " + out.string());
    }
    outputs.push_back(out.string());
  }
  return outputs;
}

// The folder every output goes to, created if missing.
void make_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (!std::filesystem::is_directory(dir)) {
    throw FileError("cannot use " + dir.string() +
                    " as the output folder: " + (ec ? ec.message() : std::string("it is not a directory")));
  }
}

// The report entry of a file that failed (or never started).
json error_report(const std::string& input, const std::string& output, int exit_code, const std::string& message) {
  return json{
      {"input", {{"path", input}}}, {"output", output}, {"error", {{"exit_code", exit_code}, {"message", message}}}};
}

// The batch's end: --report's document, then the exit code (the first failure's, in the order
// given; 130 when cancelled).
int finish_batch(const CliOptions& options, const std::vector<std::string>& inputs,
                 const std::vector<std::string>& outputs, std::vector<json>& reports, const std::vector<int>& codes) {
  const std::size_t n = inputs.size();
  std::size_t failed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (codes[i] == kExitOk) continue;
    ++failed;
    if (reports[i].is_null())
      reports[i] = error_report(inputs[i], outputs[i], kExitCancelled, "cancelled before it started");
  }
  if (options.report) {
    std::cout << json{{"files", reports}, {"succeeded", n - failed}, {"failed", failed}}.dump(2) << "\n";
  }
  if (interrupted()) {
    print_error("cancelled");
    return kExitCancelled;
  }
  for (int code : codes)
    if (code != kExitOk) return code;
  return kExitOk;
}

}  // namespace

int run_batch(const CliOptions& options) {
  namespace fs = std::filesystem;
  const std::vector<std::string>& inputs = options.positional;
  if (inputs.empty()) throw UsageError("--out-dir DIR needs at least one input file");
  if (options.add_noise || options.metrics || options.tune) {
    throw UsageError("--out-dir cannot be combined with --add-noise, --metrics or --tune");
  }
  json fields;
  const service::JobParams params = job_params(options, fields);
  const fs::path dir = *options.out_dir;
  const std::vector<std::string> outputs = batch_outputs(inputs, dir, params.output.format, options.in_place);
  make_output_dir(dir);

  const std::size_t n = inputs.size();
  const int threads = default_threads(options);
  const int jobs = static_cast<int>(std::min<std::size_t>(n, static_cast<std::size_t>(threads)));
  const int threads_per_job = std::max(1, threads / jobs);
  std::vector<json> reports(n);
  std::vector<int> codes(n, kExitCancelled);  // a file never started counts as cancelled
  std::atomic<std::size_t> next{0};
  std::mutex stderr_mutex;
  std::size_t finished = 0;
  install_sigint_handler();
  auto work = [&] {
    CliProgress cancel(false);  // no bar: several files run at once; Ctrl-C still cancels
    for (std::size_t i = next++; i < n && !interrupted(); i = next++) {
      const auto start = std::chrono::steady_clock::now();
      std::string line;
      try {
        // The one denoise path, as a single run's (cli/denoise.h).
        const DenoisedFile file = denoise_file(read_input(inputs[i], options.limits), outputs[i], params,
                                               threads_per_job, options.limits.decode, cancel);
        reports[i] = file.summary;
        codes[i] = kExitOk;
        if (options.progress) {
          const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          std::ostringstream text;
          text.precision(3);
          text << inputs[i] << " -> " << outputs[i] << " (" << file.faces << " faces, " << seconds << " s)";
          line = text.str();
        }
      } catch (...) {
        const Failure failure = describe_failure(std::current_exception());
        codes[i] = failure.exit_code;
        // Most messages name the file already; the rest get it in front.
        const std::string message =
            failure.message.find(inputs[i]) == std::string::npos ? inputs[i] + ": " + failure.message : failure.message;
        reports[i] = error_report(inputs[i], outputs[i], failure.exit_code, message);
        line = "error: " + message;
      }
      const std::lock_guard lock(stderr_mutex);
      ++finished;
      if (!line.empty()) std::cerr << "meshdenoise: [" << finished << "/" << n << "] " << line << "\n";
    }
  };
  std::vector<std::thread> helpers;
  for (int j = 1; j < jobs; ++j) helpers.emplace_back(work);
  work();
  for (auto& t : helpers) t.join();

  return finish_batch(options, inputs, outputs, reports, codes);
}

}  // namespace mdn::cli
