// meshdenoise: the command-line tool. A dispatcher by verb (the table kVerbs): denoise a mesh
// file, or a batch of them into a folder, with the shared job runner (the same bytes as the HTTP
// server for the same input and parameters); add synthetic noise for experiments; measure MSAE /
// E_v against a ground truth; search the parameters against one (--tune). See usage().
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/batch.h"
#include "cli/denoise.h"
#include "cli/files.h"
#include "cli/job.h"
#include "cli/mesh.h"
#include "cli/options.h"
#include "core/auto/tune.h"
#include "core/noise.h"
#include "service/job_json.h"
#include "service/params_json.h"
#include "service/process_memory.h"

#ifndef MDN_VERSION
#define MDN_VERSION "unknown"
#endif

namespace {

using nlohmann::json;
namespace io = mdn::io;
namespace service = mdn::service;
using namespace mdn::cli;

// The file arguments of a single run: --in-place IN means IN IN.
std::vector<std::string> single_files(const CliOptions& options) {
  std::vector<std::string> files = options.positional;
  if (options.in_place && files.size() == 1) files.push_back(files[0]);
  return files;
}

// Standard input can be read once: by IN (not in a batch), GT or a --params / --add-noise file.
void check_standard_input(const CliOptions& options) {
  int reads = !options.out_dir && !options.positional.empty() && options.positional[0] == kStdio ? 1 : 0;
  for (const auto* file : {&options.params, &options.add_noise, &options.metrics, &options.tune})
    if (*file && **file == kStdio) ++reads;
  if (reads > 1) throw UsageError("standard input (-) can be read only once");
}

int run_help(const CliOptions&) {
  std::cout << usage();
  return kExitOk;
}

int run_version(const CliOptions&) {
  std::cout << "meshdenoise " << MDN_VERSION << "\n";
  return kExitOk;
}

// meshdenoise --tune GT [--params START] [--threads N] NOISY
int run_tune(const CliOptions& options) {
  if (options.positional.size() != 1)
    throw UsageError("--tune GT takes exactly one file, the noisy mesh, got " +
                     std::to_string(options.positional.size()));
  if (options.add_noise || options.metrics || options.in_place)
    throw UsageError("--tune cannot be combined with --add-noise, --metrics or --in-place (it writes no mesh)");
  service::JobParams start;
  if (options.params)
    start = service::job_params_from_text(json_argument("--params", *options.params, options.limits.max_input_bytes));
  const int threads = default_threads(options);
  const InputFile in = read_input(options.positional[0], options.limits);
  const mdn::TriMesh truth =
      load_mesh(*options.tune, options.limits).merged;  // the search runs in the surfaces' own frame
  const LoadedMesh noisy = decode_mesh(in.path, in.bytes, in.format, options.limits.decode);
  if (truth.num_vertices() != noisy.merged.num_vertices() || truth.F != noisy.merged.F) {
    throw FileError(in.path + " and the ground truth " + *options.tune +
                    " do not have the same vertices and faces in the same order (the search compares face by face)");
  }
  install_sigint_handler();
  CliProgress cancel(false);
  mdn::TuneOptions tune;
  tune.threads = threads;
  tune.progress = &cancel;
  const mdn::TuneResult r = mdn::tune_parameters(truth, noisy.merged, start.denoise, tune);
  constexpr double kDeg = 180.0 / std::numbers::pi;
  const json out = {{"params", service::method_params_json(r.best)},
                    {"msae", r.best_msae},
                    {"msae_deg2", r.best_msae * kDeg * kDeg},
                    {"start",
                     {{"mode", std::string(mdn::to_string(start.denoise.mode))},
                      {"params", service::method_params_json(r.start)},
                      {"msae", r.start_msae}}},
                    {"improvement", r.start_msae / r.best_msae},
                    {"evaluations", r.evaluations},
                    {"seconds", r.seconds}};
  std::cout << out.dump(2) << "\n";
  return kExitOk;
}

// meshdenoise --metrics GT IN: measures the file IN as it is.
int run_measure(const CliOptions& options) {
  if (options.params || options.add_noise) throw UsageError("--params and --add-noise need an OUT file");
  const int threads = default_threads(options);
  const InputFile in = read_input(single_files(options)[0], options.limits);
  const GroundTruth truth = load_truth(*options.metrics, options.limits);
  const LoadedMesh loaded = decode_mesh(in.path, in.bytes, in.format, options.limits.decode);
  std::cout << measure(truth.scene, truth.path, loaded.scene, in.path, threads).dump(2) << "\n";
  return kExitOk;
}

// A single run's IN, OUT, parameters and threads, with every usage error found before any
// file is read.
struct SingleRun {
  std::string in_path, out_path;
  service::JobParams params;
  json fields;  // --params as given
  int threads = 1;
};

SingleRun single_run(const CliOptions& options) {
  const std::vector<std::string> files = single_files(options);
  if (files.size() != 2) {
    throw UsageError(files.size() == 1
                         ? "missing OUT (or give --metrics GT to only measure IN)"
                         : "expected IN and OUT, got " + std::to_string(files.size()) + " file arguments");
  }
  SingleRun run;
  run.in_path = files[0];
  run.out_path = files[1];
  run.threads = default_threads(options);
  if (options.add_noise && options.mode) throw UsageError("--mode cannot be combined with --add-noise");
  run.params = job_params(options, run.fields);
  return run;
}

// OUT, checked once IN and GT are read: not IN (unless --in-place), not standard output when
// something else prints there, and its extension agreeing with output.format (which it sets).
void check_output(const CliOptions& options, SingleRun& run) {
  check_not_input(run.in_path, run.out_path, options.in_place);
  if (run.out_path == kStdio && (options.report || options.metrics)) {
    throw UsageError("OUT is standard output (-): --report and --metrics would print into the mesh");
  }
  if (auto by_extension = output_format_by_name(run.out_path)) {
    if (run.params.output.format && *run.params.output.format != *by_extension) {
      throw UsageError("output.format is \"" + std::string(io::to_string(*run.params.output.format)) + "\" but " +
                       run.out_path + " has the extension of \"" + std::string(io::to_string(*by_extension)) + "\"");
    }
    run.params.output.format = by_extension;
  }
}

std::optional<GroundTruth> truth_of(const CliOptions& options) {
  if (!options.metrics) return std::nullopt;
  return load_truth(*options.metrics, options.limits);  // read before any long work, so a bad GT fails fast
}

// --report prints the summary (the metrics inside); otherwise the metrics alone, if any.
void print_result(const CliOptions& options, json summary, const std::optional<json>& metrics) {
  if (options.report) {
    if (metrics) summary["metrics"] = *metrics;
    std::cout << summary.dump(2) << "\n";
  } else if (metrics) {
    std::cout << metrics->dump(2) << "\n";
  }
}

// meshdenoise [options] IN OUT: the one denoise path (denoise_file), as each file of a batch.
int run_denoise(const CliOptions& options) {
  SingleRun run = single_run(options);
  InputFile in = read_input(run.in_path, options.limits);
  const std::optional<GroundTruth> truth = truth_of(options);
  check_output(options, run);
  install_sigint_handler();
  CliProgress progress(options.progress && ::isatty(STDERR_FILENO));
  const DenoisedFile file = denoise_file(std::move(in), run.out_path, run.params, run.threads, options.limits.decode,
                                         progress, truth ? &*truth : nullptr);
  print_result(options, file.summary, file.metrics);
  return kExitOk;
}

// meshdenoise --add-noise SPEC [options] IN OUT: a noisy copy, each surface its own stream.
int run_add_noise(const CliOptions& options) {
  SingleRun run = single_run(options);
  // Only the output settings apply when no denoising happens; anything else would be silently
  // ignored, so it is refused.
  for (const auto& [key, value] : run.fields.items()) {
    if (key != "output") throw UsageError("with --add-noise, --params may only hold \"output\", not \"" + key + "\"");
  }
  const mdn::NoiseSpec noise =
      service::noise_spec_from_text(json_argument("--add-noise", *options.add_noise, options.limits.max_input_bytes));
  const InputFile in = read_input(run.in_path, options.limits);
  const std::optional<GroundTruth> truth = truth_of(options);
  check_output(options, run);
  LoadedMesh loaded = decode_mesh(in.path, in.bytes, in.format, options.limits.decode);
  std::uint64_t index = 0;
  for (mdn::TriMesh& surface : loaded.document->surfaces()) {
    mdn::NoiseSpec spec = noise;  // seed + index: identical meshes get different noise
    spec.seed += index++;
    surface.V = blame_file(in.path, [&] { return mdn::add_noise(surface, spec); });
  }
  io::EncodeOptions encode = run.params.output;
  if (!encode.format) encode.format = in.format;
  std::string out_bytes = blame_file(in.path, [&] { return loaded.document->encode(encode).bytes; });
  std::int64_t vertices = 0, faces = 0;  // of the asset (an instanced mesh counts once)
  for (const mdn::TriMesh& surface : loaded.document->surfaces()) {
    vertices += surface.num_vertices();
    faces += surface.num_faces();
  }
  json summary = {{"noise", service::to_json(noise)},
                  {"format", std::string(io::to_string(*encode.format))},
                  {"bytes", out_bytes.size()},
                  {"vertices", vertices},
                  {"faces", faces},
                  {"notes", loaded.document->notes()}};
  add_paths(summary, in.path, in.format, run.out_path);
  std::optional<json> metrics;  // before writing: a failed comparison leaves no OUT behind
  if (truth) {
    metrics = measure(truth->scene, truth->path, scene_mesh(loaded.document->surfaces(), loaded.document->placements()),
                      in.path, run.threads);
  }
  write_output(in.path, in.data_beside, run.out_path, std::move(out_bytes), *encode.format);
  print_result(options, std::move(summary), metrics);
  return kExitOk;
}

// The verbs, the first that applies runs. Help and version first; a batch or --tune whatever
// else is given (they refuse what they cannot combine with); --metrics GT IN only measures.
struct Verb {
  bool (*applies)(const CliOptions&);
  int (*run)(const CliOptions&);
};
constexpr Verb kVerbs[] = {
    {[](const CliOptions& o) { return o.help; }, run_help},
    {[](const CliOptions& o) { return o.version; }, run_version},
    {[](const CliOptions& o) { return o.out_dir.has_value(); }, run_batch},
    {[](const CliOptions& o) { return o.tune.has_value(); }, run_tune},
    {[](const CliOptions& o) { return o.metrics && single_files(o).size() == 1; }, run_measure},
    {[](const CliOptions& o) { return o.add_noise.has_value(); }, run_add_noise},
    {[](const CliOptions&) { return true; }, run_denoise},
};

// Decision 100: with kHugePagesMinInputBytes of input files or more (the meshes and the ground
// truth; standard input does not count), the process starts again at once with glibc's huge
// pages for its heap, if the kernel gives them on request and GLIBC_TUNABLES does not already
// say. Nothing has been read or written yet, so the new process does the whole run; if the
// restart fails this one does it.
void restart_with_huge_pages(const CliOptions& options, char** argv) {
  std::uintmax_t bytes = 0;
  std::vector<std::string> files = options.positional;
  for (const auto* file : {&options.metrics, &options.tune})
    if (*file) files.push_back(**file);
  for (const std::string& file : files) {
    std::error_code error;
    if (file != kStdio && std::filesystem::is_regular_file(file, error)) {
      const std::uintmax_t size = std::filesystem::file_size(file, error);
      if (!error) bytes += size;
    }
  }
  if (bytes < service::kHugePagesMinInputBytes) return;
  if (!service::kernel_gives_huge_pages_on_request()) return;
  const std::optional<std::string> tunables = service::tunables_with_huge_pages(std::getenv("GLIBC_TUNABLES"));
  if (!tunables || ::setenv("GLIBC_TUNABLES", tunables->c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
}

int run(int argc, char** argv) {
  service::keep_freed_memory();  // decision 52: a process that ends after its files
  const CliOptions options = parse_command_line(argc, argv);
  restart_with_huge_pages(options, argv);
  if (!options.help && !options.version) check_standard_input(options);
  for (const Verb& verb : kVerbs)
    if (verb.applies(options)) return verb.run(options);
  return kExitInternal;  // not reached: run_denoise always applies
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (...) {
    const Failure failure = describe_failure(std::current_exception());
    print_error(failure.message);
    return failure.exit_code;
  }
}
