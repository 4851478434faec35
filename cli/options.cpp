#include "cli/options.h"

#include <algorithm>
#include <cctype>
#include <iterator>
#include <sstream>
#include <string_view>

#include "core/io/output_settings.h"
#include "core/params.h"
#include "service/params_json.h"

namespace mdn::cli {

namespace service = mdn::service;

namespace {

// One option: its name (and short alias), the name of its value (none: a flag), the help text
// (lines of at most 71 columns) and what it sets. usage() and the parser both read this table.
struct OptionSpec {
  std::string_view name, alias, value, help;
  void (*set)(CliOptions& options, const std::string& value);
};

// clang-format off
const OptionSpec kOptions[] = {
    {"--params", "", "JSON|FILE",
     "parameters as a JSON object (inline, or the name of a file holding it),\n"
     "the same shape as the HTTP API; missing fields keep their defaults.",
     [](CliOptions& o, const std::string& v) { o.params = v; }},
    {"--mode", "", "MODE",
     "the parameters' \"mode\": auto (default), search, manual, or none to\n"
     "convert only (decode IN, encode OUT, no denoising); the same as\n"
     "--params '{\"mode\": MODE}'",
     [](CliOptions& o, const std::string& v) { o.mode = v; }},
    {"--add-noise", "", "SPEC",
     "add Gaussian noise instead of denoising (--params may then only hold\n"
     "\"output\"); SPEC is JSON (inline or a file):\n"
     "{\"kind\": \"along_normal\"|\"per_coordinate\"|\"random_direction\",\n"
     " \"sigma\": 0.2 (x mean edge length, [0, 10]), \"seed\": 1,\n"
     " \"impulse_fraction\": 0 ([0, 1]; > 0 displaces only that fraction)}",
     [](CliOptions& o, const std::string& v) { o.add_noise = v; }},
    {"--metrics", "", "GT",
     "print {\"msae\": ..., \"msae_deg2\": ..., \"ev\": ...} on stdout: MSAE (mean\n"
     "squared face-normal angle, radians^2; msae_deg2 in degrees^2) and E_v\n"
     "(in GT's unit-box frame) of OUT (or of IN when there is no OUT) against\n"
     "GT, which must have the same faces in the same order. Both are\n"
     "measured as their scene shows them (a glTF's node transforms applied,\n"
     "an instanced mesh once per node), so a glTF compares with the same\n"
     "mesh written in world coordinates. With OUT it\n"
     "measures the computed surface (any OUT format gives the same figures);\n"
     "without OUT it measures the file IN as it is.",
     [](CliOptions& o, const std::string& v) { o.metrics = v; }},
    {"--tune", "", "GT",
     "for users with a clean scan of a calibration object: searches the six\n"
     "parameters and region_mode (coordinate descent over a grid that goes\n"
     "beyond the paper's ranges) for the lowest MSAE of IN against GT (same\n"
     "faces in the same order). Prints {\"params\": {...}, \"msae\": ...,\n"
     "\"start\": {\"params\", \"msae\"}, \"improvement\": start/best, ...}; \"params\"\n"
     "can be passed to --params as it is. --params sets the starting point\n"
     "(default: what auto mode chooses). Minutes on large meshes.",
     [](CliOptions& o, const std::string& v) { o.tune = v; }},
    {"--out-dir", "", "DIR",
     "batch mode: DIR (created if missing) receives each IN under its own\n"
     "file name, with the extension of params.output.format if one is given.\n"
     "Files run side by side (--threads of them at once); a file that fails is\n"
     "reported and the others go on. Two inputs that would land on one output,\n"
     "or an output that would overwrite its input (unless --in-place), are\n"
     "refused before any work. The files are those that IN DIR/NAME writes.",
     [](CliOptions& o, const std::string& v) { o.out_dir = v; }},
    {"--in-place", "", "",
     "allow OUT to be IN (with one file argument, OUT is IN; with --out-dir,\n"
     "an output may be its input): the result is written to a temporary file\n"
     "beside it and renamed over it. Without it, writing over the input is\n"
     "refused (exit 2). OUT's folder is created if missing.",
     [](CliOptions& o, const std::string&) { o.in_place = true; }},
    {"--report", "", "",
     "print a JSON summary on stdout: effective parameters, per-stage timings\n"
     "(ms), fold ratio and region pre-filter decision per surface; with\n"
     "--metrics the metrics go into it under \"metrics\". With --out-dir:\n"
     "{\"files\": [one summary, or {\"input\", \"output\", \"error\"}, per IN, in\n"
     "order], \"succeeded\": N, \"failed\": N}.",
     [](CliOptions& o, const std::string&) { o.report = true; }},
    {"--max-input", "", "BYTES",
     "read at most BYTES of any input (a file, a FIFO, standard input, a\n"
     "--params file; default 268435456, the server's --max-body); beyond it\n"
     "the input is refused (exit 3) before it is decoded.",
     [](CliOptions& o, const std::string& v) { o.limits.max_input_bytes = parse_limit("--max-input", v); }},
    {"--max-decoded-bytes", "", "BYTES",
     "bytes a decoder may allocate for one input (default 1073741824, the\n"
     "server's); sizes a file declares are checked before allocating.",
     [](CliOptions& o, const std::string& v) {
       o.limits.decode.max_decoded_bytes = parse_limit("--max-decoded-bytes", v);
     }},
    {"--max-faces", "", "N",
     "faces per surface (default 5000000, the server's)",
     [](CliOptions& o, const std::string& v) { o.limits.decode.max_faces = parse_limit("--max-faces", v); }},
    {"--max-vertices", "", "N",
     "vertices per surface (default 5000000, the server's)",
     [](CliOptions& o, const std::string& v) { o.limits.decode.max_vertices = parse_limit("--max-vertices", v); }},
    {"--threads", "", "N",
     "worker threads, [1, 1024] (default: hardware concurrency); the output\n"
     "does not depend on it.",
     [](CliOptions& o, const std::string& v) { o.threads = parse_threads(v); }},
    {"--no-progress", "", "",
     "no progress bar (it is drawn only when stderr is a terminal anyway); with\n"
     "--out-dir, no line per finished file on stderr (errors are still shown).",
     [](CliOptions& o, const std::string&) { o.progress = false; }},
    {"--help", "-h", "", "print this text", [](CliOptions& o, const std::string&) { o.help = true; }},
    {"--version", "", "", "print the version", [](CliOptions& o, const std::string&) { o.version = true; }},
};
// clang-format on

std::string usage_head() {
  return R"(Usage:
  meshdenoise [options] IN OUT                 denoise IN, write OUT
  meshdenoise [options] --out-dir DIR IN...    denoise every IN into the folder DIR
  meshdenoise [options] --in-place IN          denoise IN and replace it
  meshdenoise --add-noise SPEC [options] IN OUT
                                               write a noisy copy of the clean mesh IN to OUT
  meshdenoise --metrics GT IN                  only measure IN against the ground truth GT
  meshdenoise --metrics GT [options] IN OUT    denoise (or add noise), write OUT, measure OUT
  meshdenoise --tune GT [options] IN           search the parameters that denoise IN closest
                                               to the ground truth GT; print them as JSON

Robust mesh denoising via vertex pre-filtering and L1-median normal filtering (Lu, Chen,
Schaefer). Formats: off, obj, ply, stl, drc, glb, gltf, chosen by file extension, else by
content. OUT's format is its extension's (another extension is refused), else
params.output.format, else IN's. glTF output keeps IN's compression (Draco in, Draco out;
otherwise none) unless params.output.compression says otherwise. "-" as IN (or GT, or a
--params file) reads standard input, and as OUT writes standard output; "./-" is a file.

Options:
)";
}

// The options, from kOptions: "  --name VALUE" in 21 columns, then the help's lines.
std::string options_text() {
  std::ostringstream out;
  for (const OptionSpec& option : kOptions) {
    std::string head = "  ";
    head += option.name;
    if (!option.alias.empty()) head.append(", ").append(option.alias);
    if (!option.value.empty()) head.append(" ").append(option.value);
    head.resize(std::max<std::size_t>(head.size() + 1, 23), ' ');
    std::string_view help = option.help;
    for (std::size_t line = 0; !help.empty() || line == 0; ++line) {
      const std::size_t end = std::min(help.find('\n'), help.size());
      out << (line == 0 ? head : std::string(23, ' ')) << help.substr(0, end) << "\n";
      help.remove_prefix(std::min(end + 1, help.size()));
    }
  }
  return out.str();
}

// Words of `text` in lines of at most `width` columns, each indented by `indent` spaces.
std::string wrapped(std::string_view text, std::size_t indent, std::size_t width) {
  std::string out, line;
  std::istringstream words{std::string(text)};
  for (std::string word; words >> word;) {
    if (!line.empty() && indent + line.size() + 1 + word.size() > width) {
      out += std::string(indent, ' ') + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out += std::string(indent, ' ') + line + "\n";
  return out;
}

// The "output" object's settings from io::output_settings() (decision 69): name, range,
// default, meaning. tests/io/output_settings_test checks this text against the table.
std::string output_settings_text() {
  std::ostringstream out;
  for (const io::OutputSetting& s : io::output_settings()) {
    out << "    output." << s.name << " " << s.range_text();
    if (s.kind == io::SettingKind::Integer) out << ", default " << s.default_integer();
    else if (s.kind == io::SettingKind::Choice && s.default_choice().empty()) out << ", default null";
    else if (s.kind == io::SettingKind::Choice) out << ", default \"" << s.default_choice() << "\"";
    out << (s.deprecated ? " (deprecated)" : "") << "\n" << wrapped(s.meaning, 8, 96);
  }
  return out.str();
}

// The parameters, from core's param_specs() and the output settings' table.
std::string parameters_text() {
  std::ostringstream out;
  out << R"(Parameters (--params). By default ("mode": "auto") the six parameters of Table 1 (alpha ...
n_vertex) and region_mode are chosen per surface by a model trained offline: it reads cheap
statistics of the surface and runs the parameter set of lowest predicted error (a clean surface
is left alone); a field given explicitly keeps its value. "mode": "search" refines the pick by a
coordinate descent on an error estimated from recorrupted copies (several times slower).
"mode": "manual" uses the values as given and the defaults below (Table 1's Fandisk row) for
the others. "mode": "none" denoises nothing (a format or compression conversion). --report
shows what ran and the choice: the model, what it read, the noise estimate and the pick.
  mode "auto"|"search"|"manual"|"none", default "auto"
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
  output {...}  the output container, glTF compression and encoder settings (core/io's one table):
)";
  out << output_settings_text() << "\n";
  return out.str();
}

std::string exit_codes_text() {
  return R"(Exit codes: 0 ok; 2 bad command line or parameters (OUT that is IN without --in-place); 3 a file cannot be read or written, is
malformed or is not a valid mesh; 4 solver failure or internal error; 130 cancelled (Ctrl-C).
On any error OUT is not written. With --out-dir: the code of the first IN (in the order given)
that failed, 130 if cancelled; each OUT that was written is complete.
)";
}

}  // namespace

std::string usage() { return usage_head() + options_text() + "\n" + parameters_text() + exit_codes_text(); }

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

std::int64_t parse_limit(const std::string& option, const std::string& text) {
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || !std::isdigit(static_cast<unsigned char>(text[0])) || value < 1 ||
      value > (1LL << 40)) {
    throw UsageError(option + " must be an integer in [1, 2^40], got \"" + text + "\"");
  }
  return static_cast<std::int64_t>(value);
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
    const auto spec = std::find_if(std::begin(kOptions), std::end(kOptions), [&](const OptionSpec& o) {
      return arg == o.name || (!o.alias.empty() && arg == o.alias);
    });
    if (spec == std::end(kOptions)) throw UsageError("unknown option " + arg);
    if (spec->value.empty()) flag();
    spec->set(options, spec->value.empty() ? std::string() : value());
  }
  return options;
}

}  // namespace mdn::cli
