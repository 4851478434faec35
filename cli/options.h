// The command line of meshdenoise: its options, the usage text (which documents the exit codes)
// and the parser, both from one table of options (options.cpp). Parsing only: what the options mean is main.cpp's.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "service/job_runner.h"

namespace mdn::cli {

// A bad command line (exit code 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the tool reads, bounded (decision 61): by default the server's limits, each settable.
// Every input (a file, a FIFO, /dev/zero, standard input, a --params file) is read up to
// max_input_bytes (a regular file's size is checked before reading), and decoded under `decode`.
struct InputLimits {
  std::int64_t max_input_bytes = service::kDefaultMaxInputBytes;  // --max-input
  io::Limits decode;                                              // --max-decoded-bytes, --max-faces, --max-vertices
};

struct CliOptions {
  std::vector<std::string> positional;
  std::optional<std::string> params;     // --params: inline JSON or a file name
  std::optional<std::string> add_noise;  // --add-noise: inline JSON or a file name
  std::optional<std::string> metrics;    // --metrics: ground-truth mesh file
  std::optional<std::string> tune;       // --tune: ground-truth mesh file
  std::optional<std::string> out_dir;    // --out-dir: batch mode, every positional is an input
  std::optional<std::string> mode;       // --mode: "mode" of the parameters (auto, search, manual, none)
  InputLimits limits;                    // --max-input, --max-decoded-bytes, --max-faces, --max-vertices
  int threads = 0;                       // 0: hardware concurrency
  bool in_place = false;                 // --in-place: OUT may be IN (replaced through a temporary file)
  bool report = false;
  bool progress = true;
  bool help = false;
  bool version = false;
};

std::string usage();
// --threads: an integer in [1, 1024]. Throws UsageError.
int parse_threads(const std::string& text);
// --max-input and the other limits: an integer in [1, 2^40]. Throws UsageError naming `option`.
std::int64_t parse_limit(const std::string& option, const std::string& text);
// Options anywhere among the positionals ("--" ends them); --name value or --name=value.
// Throws UsageError for an unknown option or a missing value.
CliOptions parse_command_line(int argc, char** argv);

}  // namespace mdn::cli
