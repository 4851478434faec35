// meshdenoise: the command-line tool. Denoises a mesh file, or a batch of them into a folder,
// with the shared job runner (the same bytes as the HTTP server for the same input and
// parameters), adds synthetic noise for experiments, and measures MSAE / E_v against a ground
// truth. See usage() for the shapes.
#include <unistd.h>

#include <cstdint>
#include <iostream>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/noise.h"
#include "core/auto/tune.h"
#include "cli/batch.h"
#include "cli/files.h"
#include "cli/job.h"
#include "cli/mesh.h"
#include "cli/options.h"
#include "service/job_json.h"
#include "service/params_json.h"

#ifndef MDN_VERSION
#define MDN_VERSION "unknown"
#endif

namespace {

using nlohmann::json;
namespace io = mdn::io;
namespace service = mdn::service;
using namespace mdn::cli;

// meshdenoise --tune GT [--params START] [--threads N] NOISY
int run_tune(const CliOptions& options) {
  if (options.positional.size() != 1)
    throw UsageError("--tune GT takes exactly one file, the noisy mesh, got " + std::to_string(options.positional.size()));
  if (options.add_noise || options.metrics || options.in_place)
    throw UsageError("--tune cannot be combined with --add-noise, --metrics or --in-place (it writes no mesh)");
  service::JobParams start;
  if (options.params) start = service::job_params_from_text(json_argument("--params", *options.params));
  const int threads = default_threads(options);
  const std::string& in_path = options.positional[0];
  const std::string in_bytes = read_file(in_path);
  const mdn::TriMesh truth = load_mesh(*options.tune).merged;  // the search runs in the surfaces' own frame
  const LoadedMesh noisy = decode_mesh(in_path, in_bytes, input_format(in_path, in_bytes));
  if (truth.num_vertices() != noisy.merged.num_vertices() || truth.F != noisy.merged.F) {
    throw FileError(in_path + " and the ground truth " + *options.tune +
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
                    {"start", {{"mode", std::string(mdn::to_string(start.denoise.mode))},
                               {"params", service::method_params_json(r.start)},
                               {"msae", r.start_msae}}},
                    {"improvement", r.start_msae / r.best_msae},
                    {"evaluations", r.evaluations},
                    {"seconds", r.seconds}};
  std::cout << out.dump(2) << "\n";
  return kExitOk;
}

int run(int argc, char** argv) {
  const CliOptions options = parse_command_line(argc, argv);
  if (options.help) {
    std::cout << usage();
    return kExitOk;
  }
  if (options.version) {
    std::cout << "meshdenoise " << MDN_VERSION << "\n";
    return kExitOk;
  }
  // --in-place IN: OUT is IN.
  std::vector<std::string> pos = options.positional;
  if (options.in_place && !options.out_dir && !options.tune && pos.size() == 1) pos.push_back(pos[0]);
  int stdin_reads = !options.out_dir && !pos.empty() && pos[0] == kStdio ? 1 : 0;
  for (const auto* file : {&options.params, &options.add_noise, &options.metrics, &options.tune})
    if (*file && **file == kStdio) ++stdin_reads;
  if (stdin_reads > 1) throw UsageError("standard input (-) can be read only once");
  if (options.out_dir) return run_batch(options);
  if (options.tune) return run_tune(options);
  const bool measure_only = pos.size() == 1 && options.metrics;
  if (!(pos.size() == 2 || measure_only)) {
    throw UsageError(pos.size() == 1 ? "missing OUT (or give --metrics GT to only measure IN)"
                                     : "expected IN and OUT, got " + std::to_string(pos.size()) + " file arguments");
  }
  if (measure_only && (options.params || options.add_noise)) {
    throw UsageError("--params and --add-noise need an OUT file");
  }
  const int threads = default_threads(options);

  // Parse everything the user typed before touching any mesh.
  if (options.add_noise && options.mode) throw UsageError("--mode cannot be combined with --add-noise");
  json fields;
  service::JobParams params = job_params(options, fields);
  if (options.add_noise) {
    // Only the output settings apply when no denoising happens; anything else would be
    // silently ignored, so it is refused.
    for (const auto& [key, value] : fields.items()) {
      if (key != "output") throw UsageError("with --add-noise, --params may only hold \"output\", not \"" + key + "\"");
    }
  }
  std::optional<mdn::NoiseSpec> noise;
  if (options.add_noise) noise = service::noise_spec_from_text(json_argument("--add-noise", *options.add_noise));

  const std::string& in_path = pos[0];
  const std::string in_bytes = read_file(in_path);
  const io::Format in_format = input_format(in_path, in_bytes);
  // The ground truth is read before any long work, so a bad GT fails fast.
  std::optional<mdn::TriMesh> truth;
  if (options.metrics) truth = load_mesh(*options.metrics).scene;

  if (measure_only) {
    const LoadedMesh loaded = decode_mesh(in_path, in_bytes, in_format);
    std::cout << measure(*truth, *options.metrics, loaded.scene, in_path, threads).dump(2) << "\n";
    return kExitOk;
  }

  const std::string& out_path = pos[1];
  check_not_input(in_path, out_path, options.in_place);
  if (out_path == kStdio && (options.report || options.metrics)) {
    throw UsageError("OUT is standard output (-): --report and --metrics would print into the mesh");
  }
  if (auto by_extension = output_format_by_name(out_path)) {
    if (params.output.format && *params.output.format != *by_extension) {
      throw UsageError("output.format is \"" + std::string(io::to_string(*params.output.format)) + "\" but " +
                       out_path + " has the extension of \"" + std::string(io::to_string(*by_extension)) + "\"");
    }
    params.output.format = by_extension;
  }

  json summary;
  std::string out_bytes;
  mdn::TriMesh result;  // all output surfaces, as computed (before the format's quantisation), as the scene shows them
  if (noise) {
    LoadedMesh loaded = decode_mesh(in_path, in_bytes, in_format);
    std::uint64_t index = 0;
    for (mdn::TriMesh& surface : loaded.document->surfaces()) {
      // Each surface of a multi-mesh asset gets its own stream (seed + index), else identical
      // meshes would receive identical noise.
      mdn::NoiseSpec spec = *noise;
      spec.seed += index++;
      surface.V = blame_file(in_path, [&] { return mdn::add_noise(surface, spec); });
    }
    io::EncodeOptions encode = params.output;
    if (!encode.format) encode.format = in_format;
    out_bytes = blame_file(in_path, [&] { return loaded.document->encode(encode).bytes; });
    std::int64_t vertices = 0, faces = 0;  // of the asset (an instanced mesh counts once)
    for (const mdn::TriMesh& surface : loaded.document->surfaces()) {
      vertices += surface.num_vertices();
      faces += surface.num_faces();
    }
    result = scene_mesh(loaded.document->surfaces(), loaded.document->placements());
    summary = {{"noise", service::to_json(*noise)},
               {"format", std::string(io::to_string(*encode.format))},
               {"bytes", out_bytes.size()},
               {"vertices", vertices},
               {"faces", faces},
               {"notes", loaded.document->notes()}};
  } else {
    install_sigint_handler();
    CliProgress progress(options.progress && ::isatty(STDERR_FILENO));
    service::JobOutput output = denoise_input(in_path, in_bytes, in_format, params, threads, progress);
    summary = service::output_to_json(output);  // before the bytes move out
    out_bytes = std::move(output.bytes);
    if (truth) result = scene_mesh(output.surfaces, output.placements);
  }
  add_paths(summary, in_path, in_format, out_path);

  // Metrics before writing: a failed comparison leaves no OUT behind (non-zero exit, no file).
  // They measure the computed surface, so every output format gives the same figures; the
  // file's own quantisation (Draco) can be measured afterwards with --metrics GT OUT.
  std::optional<json> metrics;
  if (truth) metrics = measure(*truth, *options.metrics, result, in_path, threads);
  const io::Format out_format = io::format_from_string(summary.value("format", std::string())).value_or(in_format);
  write_output(in_path, in_bytes, in_format, out_path, std::move(out_bytes), out_format);

  if (options.report) {
    if (metrics) summary["metrics"] = *metrics;
    std::cout << summary.dump(2) << "\n";
  } else if (metrics) {
    std::cout << metrics->dump(2) << "\n";
  }
  return kExitOk;
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
