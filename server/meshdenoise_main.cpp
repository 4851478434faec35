// meshdenoise: the command-line tool. Denoises a mesh file with the shared job runner (the
// same bytes as the HTTP server for the same input and parameters), adds synthetic noise for
// experiments, and measures MSAE / E_v against a ground truth. See usage() for the shapes.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/parallel.h"
#include "core/params.h"
#include "core/progress.h"
#include "core/tune.h"
#include "server/job_runner.h"
#include "server/params_json.h"

#ifndef MDN_VERSION
#define MDN_VERSION "unknown"
#endif

namespace {

using nlohmann::json;
namespace io = mdn::io;
namespace service = mdn::service;

// Exit codes (documented in usage()).
constexpr int kExitOk = 0;
constexpr int kExitUsage = 2;      // bad command line or bad parameters
constexpr int kExitFile = 3;       // a file cannot be read or written, is malformed or not a valid mesh
constexpr int kExitInternal = 4;   // solver failure or anything unexpected
constexpr int kExitCancelled = 130;

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The only process-wide state: set by the SIGINT handler, polled by the progress observer.
// A signal handler can do nothing else safely.
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_sigint(int) { g_interrupted = 1; }

void install_sigint_handler() {
  struct sigaction action {};
  action.sa_handler = on_sigint;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: a second Ctrl-C kills the process at once if cancellation is slow.
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
}

// Cooperative cancellation on SIGINT, and a one-line progress bar on stderr when it is a
// terminal: "normal filter  [##########..........]  50%". Redraws only when the stage or
// the whole percentage changes.
class CliProgress : public mdn::ProgressObserver {
 public:
  explicit CliProgress(bool draw) : draw_(draw) {}
  ~CliProgress() override { clear(); }

  void on_progress(mdn::Stage stage, double fraction) override {
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

  bool cancel_requested() override { return g_interrupted != 0; }

  void clear() {
    if (drawn_) {
      std::fputs("\r\033[K", stderr);
      std::fflush(stderr);
      drawn_ = false;
    }
  }

 private:
  bool draw_;
  bool drawn_ = false;
  mdn::Stage stage_{};
  int percent_ = -1;
};

struct CliOptions {
  std::vector<std::string> positional;
  std::optional<std::string> params;     // --params: inline JSON or a file name
  std::optional<std::string> add_noise;  // --add-noise: inline JSON or a file name
  std::optional<std::string> metrics;    // --metrics: ground-truth mesh file
  std::optional<std::string> tune;       // --tune: ground-truth mesh file
  int threads = 0;                       // 0: hardware concurrency
  bool report = false;
  bool progress = true;
  bool help = false;
  bool version = false;
};

std::string usage() {
  std::ostringstream out;
  out << R"(Usage:
  meshdenoise [options] IN OUT                 denoise IN, write OUT
  meshdenoise --add-noise SPEC [options] IN OUT
                                               write a noisy copy of the clean mesh IN to OUT
  meshdenoise --metrics GT IN                  only measure IN against the ground truth GT
  meshdenoise --metrics GT [options] IN OUT    denoise (or add noise), write OUT, measure OUT
  meshdenoise --tune GT [options] IN           search the parameters that denoise IN closest
                                               to the ground truth GT; print them as JSON

Robust mesh denoising via vertex pre-filtering and L1-median normal filtering (Lu, Chen,
Schaefer). Formats: off, obj, ply, drc, glb, gltf, chosen by file extension, else by content.
OUT's format is its extension's, else params.output.format, else IN's.

Options:
  --params JSON|FILE   parameters as a JSON object (inline, or the name of a file holding it),
                       the same shape as the HTTP API; missing fields keep their defaults.
  --add-noise SPEC     add Gaussian noise instead of denoising (--params may then only hold
                       "output"); SPEC is JSON (inline or a file):
                       {"kind": "along_normal"|"per_coordinate"|"random_direction",
                        "sigma": 0.2 (x mean edge length, [0, 10]), "seed": 1,
                        "impulse_fraction": 0 ([0, 1]; > 0 displaces only that fraction)}
  --metrics GT         print {"msae": ..., "msae_deg2": ..., "ev": ...} on stdout: MSAE (mean
                       squared face-normal angle, radians^2; msae_deg2 in degrees^2) and E_v
                       (in GT's unit-box frame) of OUT (or of IN when there is no OUT) against
                       GT, which must have the same faces in the same order. With OUT it
                       measures the computed surface (any OUT format gives the same figures);
                       without OUT it measures the file IN as it is.
  --tune GT            for users with a clean scan of a calibration object: searches the six
                       parameters and region_mode (coordinate descent over a grid that goes
                       beyond the paper's ranges) for the lowest MSAE of IN against GT (same
                       faces in the same order). Prints {"params": {...}, "msae": ...,
                       "start": {"params", "msae"}, "improvement": start/best, ...}; "params"
                       can be passed to --params as it is. --params sets the starting point
                       (default: what auto mode chooses). Minutes on large meshes.
  --report             print a JSON summary on stdout: effective parameters, per-stage timings
                       (ms), fold ratio and region pre-filter decision per surface; with
                       --metrics the metrics go into it under "metrics".
  --threads N          worker threads, [1, 1024] (default: hardware concurrency); the output
                       does not depend on it.
  --no-progress        no progress bar (it is drawn only when stderr is a terminal anyway).
  --help, --version

Parameters (--params). By default ("mode": "auto") the six parameters of Table 1 (alpha ...
n_vertex) and region_mode are chosen from measurements of each input surface by a rule fitted
on data; a field given explicitly keeps its value. "mode": "manual" uses the values as given
and the defaults below (Table 1's Fandisk row) for the others. --report shows what ran.
  mode "auto"|"manual", default "auto"
[accepted range], default:
)";
  const mdn::DenoiseParams defaults;
  for (const auto& spec : mdn::param_specs()) {
    std::ostringstream line;
    line << "  " << spec.name << " [" << spec.min << ", " << spec.max << "] " << spec.default_value();
    std::string text = line.str();
    text.resize(std::max<std::size_t>(text.size() + 1, 38), ' ');
    out << text << spec.description;
    if (!spec.unit.empty() && spec.description.find(spec.unit) == std::string_view::npos) {
      out << " (" << spec.unit << ")";
    }
    if (!spec.equation.empty()) out << ", " << spec.equation;
    out << "\n";
  }
  out << R"(  region_mode "auto"|"on"|"off", default ")" << mdn::to_string(defaults.region_mode)
      << R"("  region pre-filter of Sec. 4.2
  kmeans_seed  integer >= 0, default )"
      << defaults.kmeans_seed << R"(
  solver "ldlt"|"cg", default ")"
      << mdn::to_string(defaults.solver) << R"("
  output {...}  output container and Draco settings, defaults:
         )" << service::to_json(service::JobParams{})["output"].dump()
      << R"(
         format: "off"|"obj"|"ply"|"drc"|"glb"|"gltf", null = IN's; position_bits [8, 30];
         normal_bits [1, 30]; texcoord_bits, color_bits, generic_bits [0, 30], 0 = lossless;
         compression_level [0, 10] (10 = smallest)

Exit codes: 0 ok; 2 bad command line or parameters; 3 a file cannot be read or written, is
malformed or is not a valid mesh; 4 solver failure or internal error; 130 cancelled (Ctrl-C).
On any error OUT is not written.
)";
  return out.str();
}

int parse_threads(const std::string& text) {
  std::size_t used = 0;
  long value = 0;
  try {
    value = std::stol(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || value < 1 || value > 1024) {
    throw UsageError("--threads must be an integer in [1, 1024], got \"" + text + "\"");
  }
  return static_cast<int>(value);
}

CliOptions parse_command_line(int argc, char** argv) {
  CliOptions options;
  bool options_done = false;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (options_done || arg.size() < 2 || arg[0] != '-') {
      options.positional.push_back(arg);
      continue;
    }
    if (arg == "--") {
      options_done = true;
      continue;
    }
    // --name=value or --name value
    std::optional<std::string> inline_value;
    if (const auto eq = arg.find('='); arg.starts_with("--") && eq != std::string::npos) {
      inline_value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
    }
    auto value = [&]() -> std::string {
      if (inline_value) return *inline_value;
      if (i + 1 >= argc) throw UsageError(arg + " needs a value");
      return argv[++i];
    };
    auto flag = [&]() {
      if (inline_value) throw UsageError(arg + " takes no value");
    };
    if (arg == "--params") {
      options.params = value();
    } else if (arg == "--add-noise") {
      options.add_noise = value();
    } else if (arg == "--metrics") {
      options.metrics = value();
    } else if (arg == "--tune") {
      options.tune = value();
    } else if (arg == "--threads") {
      options.threads = parse_threads(value());
    } else if (arg == "--report") {
      flag();
      options.report = true;
    } else if (arg == "--no-progress") {
      flag();
      options.progress = false;
    } else if (arg == "--help" || arg == "-h") {
      flag();
      options.help = true;
    } else if (arg == "--version") {
      flag();
      options.version = true;
    } else {
      throw UsageError("unknown option " + arg);
    }
  }
  return options;
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw FileError("cannot read " + path + ": it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot read " + path + ": " + std::strerror(errno));
  try {
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw FileError("cannot read " + path + ": " + std::strerror(errno));
    return bytes;
  } catch (const std::ios_base::failure& e) {  // libstdc++ throws from underflow on read errors
    throw FileError("cannot read " + path + ": " + e.what());
  }
}

void write_bytes(const std::string& path, const std::string& bytes, const std::string& shown) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError("cannot write " + shown + ": " + std::strerror(errno));
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw FileError("cannot write " + shown + ": " + std::strerror(errno));
}

// Writes OUT through a temporary file in the same folder and a rename, so a failure (disk
// full, Ctrl-C) never leaves a truncated OUT behind or clobbers an existing one. Special files
// (/dev/stdout, pipes) and symbolic links are written in place.
void write_file(const std::string& path, const std::string& bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(path, ec);
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    if (fs::is_directory(status)) throw FileError("cannot write " + path + ": it is a directory");
    write_bytes(path, bytes, path);
    return;
  }
  const std::string partial = path + ".partial-" + std::to_string(::getpid());
  try {
    write_bytes(partial, bytes, path);
    fs::rename(partial, path);
  } catch (const fs::filesystem_error& e) {
    fs::remove(partial, ec);
    throw FileError("cannot write " + path + ": " + e.code().message());
  } catch (...) {
    fs::remove(partial, ec);
    throw;
  }
}

// --params / --add-noise take inline JSON (anything starting with '{' after blanks) or a file.
std::string json_argument(const std::string& option, const std::string& value) {
  const auto first = value.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && value[first] == '{') return value;
  try {
    return read_file(value);
  } catch (const FileError& e) {
    throw UsageError(option + ": not inline JSON, and " + e.what());
  }
}

// The CLI runs on the user's own machine: the server's request limits would only get in the
// way, but declared sizes are still checked so a corrupt header cannot exhaust memory.
io::Limits cli_limits() {
  io::Limits limits;
  limits.max_faces = 100'000'000;
  limits.max_vertices = 100'000'000;
  limits.max_decoded_bytes = std::int64_t{16} << 30;
  return limits;
}

io::Format input_format(const std::string& path, const std::string& bytes) {
  if (auto format = io::format_from_extension(path)) return *format;
  if (auto format = io::sniff_format(bytes)) return *format;
  throw FileError("cannot tell the format of " + path +
                  " from its extension or its contents (supported: off, obj, ply, drc, glb, gltf)");
}

// Runs fn; a mesh or format problem is reported against the file it came from (exit 3).
template <typename Fn>
auto blame_file(const std::string& path, Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const mdn::InvalidParamsError&) {
    throw;  // InvalidParamsError is an invalid_argument too, but it is the user's parameters
  } catch (const mdn::InvalidMeshError& e) {
    throw FileError(path + ": " + e.what());
  } catch (const io::UnsupportedError& e) {
    throw FileError(path + ": unsupported: " + e.what());
  } catch (const io::LimitError& e) {
    throw FileError(path + ": too large: " + e.what());
  }
}

struct LoadedMesh {
  std::unique_ptr<io::MeshDocument> document;
  mdn::TriMesh merged;  // all surfaces in one mesh, for the metrics
};

// All surfaces of a document as one mesh (indices offset), so MSAE and E_v cover a whole
// multi-mesh glTF the same way they cover a single OFF.
mdn::TriMesh merge_surfaces(const std::vector<mdn::TriMesh>& surfaces) {
  std::int64_t nv = 0, nf = 0;
  for (const auto& s : surfaces) {
    nv += s.num_vertices();
    nf += s.num_faces();
  }
  mdn::TriMesh merged;
  merged.V.resize(nv, 3);
  merged.F.resize(nf, 3);
  std::int64_t v0 = 0, f0 = 0;
  for (const auto& s : surfaces) {
    merged.V.middleRows(v0, s.num_vertices()) = s.V;
    merged.F.middleRows(f0, s.num_faces()) = s.F.array() + static_cast<std::int32_t>(v0);
    v0 += s.num_vertices();
    f0 += s.num_faces();
  }
  return merged;
}

LoadedMesh decode_mesh(const std::string& path, const std::string& bytes, io::Format format) {
  return blame_file(path, [&] {
    LoadedMesh loaded;
    loaded.document = io::decode(bytes, format, cli_limits());
    loaded.merged = merge_surfaces(loaded.document->surfaces());
    mdn::validate_mesh(loaded.merged);
    return loaded;
  });
}

mdn::TriMesh load_truth(const std::string& path) {
  const std::string bytes = read_file(path);
  return decode_mesh(path, bytes, input_format(path, bytes)).merged;
}

// MSAE and E_v of `result` against the ground truth (Sec. 7). Both need the same faces in the
// same order; formats that renumber them (Draco) cannot be compared after the fact.
json measure(const mdn::TriMesh& truth, const std::string& truth_path, const mdn::TriMesh& result,
             const std::string& result_path, int threads) {
  if (truth.num_faces() != result.num_faces() || truth.F != result.F) {
    throw FileError(result_path + " and the ground truth " + truth_path +
                    " do not have the same faces in the same order (MSAE compares face by face; "
                    "Draco-compressed files renumber faces: measure while writing, or use another format)");
  }
  mdn::Executor executor(threads);
  const double msae = mdn::msae(result, truth);
  const double ev = mdn::vertex_error(result, truth, &executor);
  constexpr double kDeg = 180.0 / std::numbers::pi;
  return {{"msae", msae}, {"msae_deg2", msae * kDeg * kDeg}, {"ev", ev}};
}

// meshdenoise --tune GT [--params START] [--threads N] NOISY
int run_tune(const CliOptions& options) {
  if (options.positional.size() != 1)
    throw UsageError("--tune GT takes exactly one file, the noisy mesh, got " + std::to_string(options.positional.size()));
  if (options.add_noise || options.metrics) throw UsageError("--tune cannot be combined with --add-noise or --metrics");
  service::JobParams start;
  if (options.params) start = service::job_params_from_text(json_argument("--params", *options.params));
  const int threads =
      options.threads > 0 ? options.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const std::string& in_path = options.positional[0];
  const std::string in_bytes = read_file(in_path);
  const mdn::TriMesh truth = load_truth(*options.tune);
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
  const auto& pos = options.positional;
  if (options.tune) return run_tune(options);
  const bool measure_only = pos.size() == 1 && options.metrics;
  if (!(pos.size() == 2 || measure_only)) {
    throw UsageError(pos.size() == 1 ? "missing OUT (or give --metrics GT to only measure IN)"
                                     : "expected IN and OUT, got " + std::to_string(pos.size()) + " file arguments");
  }
  if (measure_only && (options.params || options.add_noise)) {
    throw UsageError("--params and --add-noise need an OUT file");
  }
  const int threads =
      options.threads > 0 ? options.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));

  // Parse everything the user typed before touching any mesh.
  service::JobParams params;
  if (options.params) {
    const std::string text = json_argument("--params", *options.params);
    params = service::job_params_from_text(text);
    if (options.add_noise) {
      // Only the output settings apply when no denoising happens; anything else would be
      // silently ignored, so it is refused.
      const json fields = json::parse(text);  // valid: job_params_from_text accepted it
      for (const auto& [key, value] : fields.items()) {
        if (key != "output") throw UsageError("with --add-noise, --params may only hold \"output\", not \"" + key + "\"");
      }
    }
  }
  std::optional<mdn::NoiseSpec> noise;
  if (options.add_noise) noise = service::noise_spec_from_text(json_argument("--add-noise", *options.add_noise));

  const std::string& in_path = pos[0];
  const std::string in_bytes = read_file(in_path);
  const io::Format in_format = input_format(in_path, in_bytes);
  // The ground truth is read before any long work, so a bad GT fails fast.
  std::optional<mdn::TriMesh> truth;
  if (options.metrics) truth = load_truth(*options.metrics);

  if (measure_only) {
    const LoadedMesh loaded = decode_mesh(in_path, in_bytes, in_format);
    std::cout << measure(*truth, *options.metrics, loaded.merged, in_path, threads).dump(2) << "\n";
    return kExitOk;
  }

  const std::string& out_path = pos[1];
  if (auto by_extension = io::format_from_extension(out_path)) {
    if (params.output.format && *params.output.format != *by_extension) {
      throw UsageError("output.format is \"" + std::string(io::to_string(*params.output.format)) + "\" but " +
                       out_path + " has the extension of \"" + std::string(io::to_string(*by_extension)) + "\"");
    }
    params.output.format = by_extension;
  }

  json summary;
  std::string out_bytes;
  mdn::TriMesh result;  // all output surfaces, as computed (before the format's quantisation)
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
    out_bytes = blame_file(in_path, [&] { return loaded.document->encode(encode); });
    result = merge_surfaces(loaded.document->surfaces());
    summary = {{"noise", service::to_json(*noise)},
               {"format", std::string(io::to_string(*encode.format))},
               {"bytes", out_bytes.size()},
               {"vertices", result.num_vertices()},
               {"faces", result.num_faces()},
               {"notes", loaded.document->notes()}};
  } else {
    install_sigint_handler();
    CliProgress progress(options.progress && ::isatty(STDERR_FILENO));
    service::JobInput job{.bytes = in_bytes, .format = in_format, .params = params, .threads = threads};
    service::JobOutput output;
    try {
      output = blame_file(in_path, [&] { return service::run_job(job, cli_limits(), &progress); });
    } catch (...) {
      progress.clear();
      throw;
    }
    progress.clear();
    summary = service::job_summary_json(output);  // before the bytes move out
    out_bytes = std::move(output.bytes);
    if (truth) result = merge_surfaces(output.surfaces);
  }
  summary["input"] = {{"path", in_path}, {"format", std::string(io::to_string(in_format))}};
  summary["output"] = out_path;

  // Metrics before writing: a failed comparison leaves no OUT behind (non-zero exit, no file).
  // They measure the computed surface, so every output format gives the same figures; the
  // file's own quantisation (Draco) can be measured afterwards with --metrics GT OUT.
  std::optional<json> metrics;
  if (truth) metrics = measure(*truth, *options.metrics, result, in_path, threads);
  write_file(out_path, out_bytes);

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
  auto error = [](const std::string& message) { std::cerr << "meshdenoise: error: " << message << "\n"; };
  try {
    return run(argc, argv);
  } catch (const UsageError& e) {
    error(std::string(e.what()) + "\n(run meshdenoise --help for usage)");
    return kExitUsage;
  } catch (const mdn::InvalidParamsError& e) {
    error(e.what());
    return kExitUsage;
  } catch (const mdn::CancelledError& e) {
    error("cancelled");
    return kExitCancelled;
  } catch (const FileError& e) {
    error(e.what());
    return kExitFile;
  } catch (const mdn::InvalidMeshError& e) {
    error(e.what());
    return kExitFile;
  } catch (const io::UnsupportedError& e) {
    error(std::string("unsupported input: ") + e.what());
    return kExitFile;
  } catch (const io::LimitError& e) {
    error(std::string("input too large: ") + e.what());
    return kExitFile;
  } catch (const mdn::SolverError& e) {
    error(std::string("solver failed: ") + e.what());
    return kExitInternal;
  } catch (const std::bad_alloc&) {
    error("out of memory");
    return kExitInternal;
  } catch (const std::exception& e) {
    error(std::string("internal error: ") + e.what());
    return kExitInternal;
  } catch (...) {
    error("internal error (unknown exception)");
    return kExitInternal;
  }
}
