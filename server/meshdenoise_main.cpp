// meshdenoise: the command-line tool. Denoises a mesh file, or a batch of them into a folder,
// with the shared job runner (the same bytes as the HTTP server for the same input and
// parameters), adds synthetic noise for experiments, and measures MSAE / E_v against a ground
// truth. See usage() for the shapes.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/parallel.h"
#include "core/params.h"
#include "core/progress.h"
#include "core/tune.h"
#include "server/cli_options.h"
#include "server/job_json.h"
#include "server/job_runner.h"
#include "server/params_json.h"

#ifndef MDN_VERSION
#define MDN_VERSION "unknown"
#endif

namespace {

using nlohmann::json;
namespace io = mdn::io;
namespace service = mdn::service;
using mdn::cli::CliOptions;
using mdn::cli::UsageError;
using mdn::cli::parse_command_line;
using mdn::cli::usage;

// Exit codes (documented in usage()).
constexpr int kExitOk = 0;
constexpr int kExitUsage = 2;      // bad command line or bad parameters
constexpr int kExitFile = 3;       // a file cannot be read or written, is malformed or not a valid mesh
constexpr int kExitInternal = 4;   // solver failure or anything unexpected
constexpr int kExitCancelled = 130;

class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Failure {
  int exit_code;
  std::string message;
};

// The exit code and message for an exception; one mapping for the whole tool and for each
// file of a batch.
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


// "-" names standard input where a file is read (IN, GT, a --params file) and standard output
// where OUT is written, as Unix filters do; a file called "-" is "./-".
constexpr std::string_view kStdio = "-";

std::string read_stdin() {
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(STDIN_FILENO, buffer, sizeof buffer);
    if (n == 0) return bytes;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw FileError(std::string("cannot read standard input: ") + std::strerror(errno));
    }
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
}

std::string read_file(const std::string& path) {
  if (path == kStdio) return read_stdin();
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
  if (path == kStdio) {
    std::cout.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    std::cout.flush();
    if (!std::cout) throw FileError("cannot write standard output");
    return;
  }
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
  throw FileError("cannot tell the format of " + (path == kStdio ? std::string("standard input") : path) +
                  " from its extension or its contents (supported: off, obj, ply, stl, drc, glb, gltf)");
}

// The extensions an OUT may have ("out.off", ..., "out.gltf").
std::string accepted_extensions() {
  std::string out;
  for (io::Format f : {io::Format::Off, io::Format::Obj, io::Format::Ply, io::Format::Stl, io::Format::Drc,
                       io::Format::Glb, io::Format::Gltf})
    out += (out.empty() ? "." : ", .") + std::string(io::to_string(f));
  return out;
}

// OUT's format by its extension; none if it has no extension (then output.format or IN's).
// An extension that names no format is refused rather than written as IN's format.
std::optional<io::Format> output_format_by_name(const std::string& path) {
  if (path == kStdio) return std::nullopt;
  const std::filesystem::path name = std::filesystem::path(path).filename();
  if (!name.has_extension() || name.stem().empty()) return std::nullopt;
  if (auto format = io::format_from_extension(name.string())) return format;
  throw UsageError("cannot write " + path + ": the extension " + name.extension().string() +
                   " names no format this tool writes (accepted: " + accepted_extensions() + ")");
}

// The job's parameters: --params (inline JSON or a file, read once), then --mode. `fields`
// receives the --params object as given (empty without --params).
service::JobParams job_params(const CliOptions& options, json& fields) {
  service::JobParams params;
  fields = json::object();
  if (options.params) {
    const std::string text = json_argument("--params", *options.params);
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

// A .gltf read from a file may reference buffers and images beside it (relative URIs inside
// its folder); from standard input, or in any other format, nothing outside the bytes is read.
std::optional<std::string> resource_dir(const std::string& path, io::Format format) {
  if (format != io::Format::Gltf || path == kStdio) return std::nullopt;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

// Whether a .gltf references files (a buffer or image uri that is not a data: URI).
bool has_external_uris(const std::string& gltf_text) {
  const json j = json::parse(gltf_text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return false;
  for (const char* key : {"buffers", "images"})
    for (const auto& item : j.value(key, json::array()))
      if (item.is_object() && item.contains("uri") && item["uri"].is_string() &&
          !item["uri"].get<std::string>().starts_with("data:"))
        return true;
  return false;
}

std::string base64_decode(std::string_view text) {
  static constexpr std::string_view kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    const std::size_t v = kAlphabet.find(c);
    if (v == std::string_view::npos) continue;  // '=' padding
    bits = (bits << 6) | static_cast<std::uint32_t>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out += static_cast<char>((bits >> count) & 0xFF);
    }
  }
  return out;
}

// The files a .gltf output writes beside itself when its input had its data beside it: each
// embedded buffer and image becomes OUT's stem + "_<i>.bin" / "_image<i>.<ext>" in OUT's
// folder, referenced by that relative name. Returns the rewritten .gltf and the files.
std::string externalize(const std::string& gltf_text, const std::string& out_path,
                        std::vector<std::pair<std::string, std::string>>& files) {
  namespace fs = std::filesystem;
  json j = json::parse(gltf_text);
  const fs::path out(out_path);
  const std::string stem = out.stem().string();
  for (const char* key : {"buffers", "images"}) {
    if (!j.contains(key)) continue;
    for (std::size_t i = 0; i < j[key].size(); ++i) {
      json& item = j[key][i];
      if (!item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      const std::size_t comma = uri.find(',');
      if (!uri.starts_with("data:") || comma == std::string::npos) continue;
      const std::string mime = uri.substr(5, uri.find(';') - 5);
      std::string name = stem + (std::string(key) == "buffers" ? "_" + std::to_string(i) + ".bin"
                                                                : "_image" + std::to_string(i) +
                                                                      (mime == "image/jpeg" ? ".jpg" : mime == "image/webp" ? ".webp" : ".png"));
      files.emplace_back((out.parent_path() / name).string(), base64_decode(std::string_view(uri).substr(comma + 1)));
      item["uri"] = name;
    }
  }
  return j.dump(2);
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
    loaded.document = io::decode(bytes, format, io::DecodeOptions{cli_limits(), resource_dir(path, format)});
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

// Denoises one input with the shared job runner; a problem with the input is blamed on its file.
// The progress bar (if any) is cleared whatever happens.
service::JobOutput denoise_input(const std::string& in_path, const std::string& in_bytes, io::Format in_format,
                                 const service::JobParams& params, int threads, CliProgress& progress) {
  const service::JobInput job{.bytes = in_bytes,
                              .format = in_format,
                              .params = params,
                              .threads = threads,
                              .resource_dir = resource_dir(in_path, in_format)};
  try {
    service::JobOutput output = blame_file(in_path, [&] { return service::run_job(job, cli_limits(), &progress); });
    progress.clear();
    return output;
  } catch (...) {
    progress.clear();
    throw;
  }
}

// Where a --report summary came from and went.
void add_paths(json& summary, const std::string& in_path, io::Format in_format, const std::string& out_path) {
  summary["input"] = {{"path", in_path}, {"format", std::string(io::to_string(in_format))}};
  summary["output"] = out_path;
}

int default_threads(const CliOptions& options) {
  return options.threads > 0 ? options.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Where each input of a batch goes: DIR / its file name, with the extension of the requested
// output format if there is one. Refused before any work: an input without a file name, two
// inputs with one output, an output that is its own input (it would be overwritten).
std::vector<std::string> batch_outputs(const std::vector<std::string>& inputs, const std::filesystem::path& dir,
                                       const std::optional<io::Format>& format) {
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
    fs::path name = fs::path(in).filename();
    if (name.empty() || name == "." || name == "..") throw UsageError("--out-dir: the input \"" + in + "\" has no file name");
    if (format) name.replace_extension(std::string(io::to_string(*format)));
    const fs::path out = dir / name;
    const fs::path out_key = key(out);
    if (out_key == key(in)) {
      throw UsageError("--out-dir: " + out.string() + " would overwrite its input " + in + "; choose another folder");
    }
    if (const auto [it, fresh] = taken.emplace(out_key, in); !fresh) {
      throw UsageError("--out-dir: " + it->second + " and " + in + " would both be written to " + out.string());
    }
    outputs.push_back(out.string());
  }
  return outputs;
}

// meshdenoise --out-dir DIR [--params P] [--threads N] [--report] IN...
// Files run side by side, one pipeline thread each while there are more files than threads
// (the output never depends on the thread count). A file that fails is reported on stderr and
// in the report, and the others go on; Ctrl-C cancels the running files and starts no more.
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
  const std::vector<std::string> outputs = batch_outputs(inputs, dir, params.output.format);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) {
    throw FileError("cannot use " + dir.string() + " as the output folder: " +
                    (ec ? ec.message() : std::string("it is not a directory")));
  }

  const std::size_t n = inputs.size();
  const int threads = default_threads(options);
  const int jobs = static_cast<int>(std::min<std::size_t>(n, static_cast<std::size_t>(threads)));
  const int threads_per_job = std::max(1, threads / jobs);
  std::vector<json> reports(n);
  std::vector<int> codes(n, kExitCancelled);  // a file never started counts as cancelled
  std::atomic<std::size_t> next{0};
  std::mutex stderr_mutex;
  std::size_t finished = 0;
  // The report entry of a file that failed (or never started).
  auto error_report = [&](std::size_t i, int exit_code, const std::string& message) {
    return json{{"input", {{"path", inputs[i]}}},
                {"output", outputs[i]},
                {"error", {{"exit_code", exit_code}, {"message", message}}}};
  };
  install_sigint_handler();
  auto work = [&] {
    CliProgress cancel(false);  // no bar: several files run at once; Ctrl-C still cancels
    for (std::size_t i = next++; i < n && !g_interrupted; i = next++) {
      const auto start = std::chrono::steady_clock::now();
      std::string line;
      try {
        const std::string in_bytes = read_file(inputs[i]);
        const io::Format in_format = input_format(inputs[i], in_bytes);
        service::JobOutput output = denoise_input(inputs[i], in_bytes, in_format, params, threads_per_job, cancel);
        reports[i] = service::output_to_json(output);
        add_paths(reports[i], inputs[i], in_format, outputs[i]);
        write_file(outputs[i], output.bytes);
        codes[i] = kExitOk;
        if (options.progress) {
          const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          std::ostringstream text;
          text.precision(3);
          text << inputs[i] << " -> " << outputs[i] << " (" << output.faces << " faces, " << seconds << " s)";
          line = text.str();
        }
      } catch (...) {
        const Failure failure = describe_failure(std::current_exception());
        codes[i] = failure.exit_code;
        // Most messages name the file already; the rest get it in front.
        const std::string message =
            failure.message.find(inputs[i]) == std::string::npos ? inputs[i] + ": " + failure.message : failure.message;
        reports[i] = error_report(i, failure.exit_code, message);
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

  std::size_t failed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (codes[i] == kExitOk) continue;
    ++failed;
    if (reports[i].is_null()) {
      reports[i] = error_report(i, kExitCancelled, "cancelled before it started");
    }
  }
  if (options.report) {
    std::cout << json{{"files", reports}, {"succeeded", n - failed}, {"failed", failed}}.dump(2) << "\n";
  }
  if (g_interrupted) {
    print_error("cancelled");
    return kExitCancelled;
  }
  for (int code : codes)
    if (code != kExitOk) return code;
  return kExitOk;
}

// meshdenoise --tune GT [--params START] [--threads N] NOISY
int run_tune(const CliOptions& options) {
  if (options.positional.size() != 1)
    throw UsageError("--tune GT takes exactly one file, the noisy mesh, got " + std::to_string(options.positional.size()));
  if (options.add_noise || options.metrics) throw UsageError("--tune cannot be combined with --add-noise or --metrics");
  service::JobParams start;
  if (options.params) start = service::job_params_from_text(json_argument("--params", *options.params));
  const int threads = default_threads(options);
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
  if (options.metrics) truth = load_truth(*options.metrics);

  if (measure_only) {
    const LoadedMesh loaded = decode_mesh(in_path, in_bytes, in_format);
    std::cout << measure(*truth, *options.metrics, loaded.merged, in_path, threads).dump(2) << "\n";
    return kExitOk;
  }

  const std::string& out_path = pos[1];
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
    service::JobOutput output = denoise_input(in_path, in_bytes, in_format, params, threads, progress);
    summary = service::output_to_json(output);  // before the bytes move out
    out_bytes = std::move(output.bytes);
    if (truth) result = merge_surfaces(output.surfaces);
  }
  add_paths(summary, in_path, in_format, out_path);

  // Metrics before writing: a failed comparison leaves no OUT behind (non-zero exit, no file).
  // They measure the computed surface, so every output format gives the same figures; the
  // file's own quantisation (Draco) can be measured afterwards with --metrics GT OUT.
  std::optional<json> metrics;
  if (truth) metrics = measure(*truth, *options.metrics, result, in_path, threads);
  // A .gltf whose data sat beside it gets its output's data beside the output (the same layout).
  const io::Format out_format = io::format_from_string(summary.value("format", std::string())).value_or(in_format);
  if (out_format == io::Format::Gltf && in_format == io::Format::Gltf && out_path != kStdio && has_external_uris(in_bytes)) {
    std::vector<std::pair<std::string, std::string>> files;
    out_bytes = externalize(out_bytes, out_path, files);
    for (const auto& [file, bytes] : files) write_file(file, bytes);
  }
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
  try {
    return run(argc, argv);
  } catch (...) {
    const Failure failure = describe_failure(std::current_exception());
    print_error(failure.message);
    return failure.exit_code;
  }
}
