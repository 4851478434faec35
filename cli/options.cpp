#include "cli/options.h"

#include <sstream>

#include "core/params.h"
#include "service/params_json.h"

namespace mdn::cli {

namespace service = mdn::service;

std::string usage() {
  std::ostringstream out;
  out << R"(Usage:
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
  --params JSON|FILE   parameters as a JSON object (inline, or the name of a file holding it),
                       the same shape as the HTTP API; missing fields keep their defaults.
  --mode MODE          the parameters' "mode": auto (default), search, manual, or none to
                       convert only (decode IN, encode OUT, no denoising); the same as
                       --params '{"mode": MODE}'
  --add-noise SPEC     add Gaussian noise instead of denoising (--params may then only hold
                       "output"); SPEC is JSON (inline or a file):
                       {"kind": "along_normal"|"per_coordinate"|"random_direction",
                        "sigma": 0.2 (x mean edge length, [0, 10]), "seed": 1,
                        "impulse_fraction": 0 ([0, 1]; > 0 displaces only that fraction)}
  --metrics GT         print {"msae": ..., "msae_deg2": ..., "ev": ...} on stdout: MSAE (mean
                       squared face-normal angle, radians^2; msae_deg2 in degrees^2) and E_v
                       (in GT's unit-box frame) of OUT (or of IN when there is no OUT) against
                       GT, which must have the same faces in the same order. Both are
                       measured as their scene shows them (a glTF's node transforms applied,
                       an instanced mesh once per node), so a glTF compares with the same
                       mesh written in world coordinates. With OUT it
                       measures the computed surface (any OUT format gives the same figures);
                       without OUT it measures the file IN as it is.
  --tune GT            for users with a clean scan of a calibration object: searches the six
                       parameters and region_mode (coordinate descent over a grid that goes
                       beyond the paper's ranges) for the lowest MSAE of IN against GT (same
                       faces in the same order). Prints {"params": {...}, "msae": ...,
                       "start": {"params", "msae"}, "improvement": start/best, ...}; "params"
                       can be passed to --params as it is. --params sets the starting point
                       (default: what auto mode chooses). Minutes on large meshes.
  --out-dir DIR        batch mode: DIR (created if missing) receives each IN under its own
                       file name, with the extension of params.output.format if one is given.
                       Files run side by side (--threads of them at once); a file that fails is
                       reported and the others go on. Two inputs that would land on one output,
                       or an output that would overwrite its input (unless --in-place), are
                       refused before any work. The files are those that IN DIR/NAME writes.
  --in-place           allow OUT to be IN (with one file argument, OUT is IN; with --out-dir,
                       an output may be its input): the result is written to a temporary file
                       beside it and renamed over it. Without it, writing over the input is
                       refused (exit 2). OUT's folder is created if missing.
  --report             print a JSON summary on stdout: effective parameters, per-stage timings
                       (ms), fold ratio and region pre-filter decision per surface; with
                       --metrics the metrics go into it under "metrics". With --out-dir:
                       {"files": [one summary, or {"input", "output", "error"}, per IN, in
                       order], "succeeded": N, "failed": N}.
  --threads N          worker threads, [1, 1024] (default: hardware concurrency); the output
                       does not depend on it.
  --no-progress        no progress bar (it is drawn only when stderr is a terminal anyway); with
                       --out-dir, no line per finished file on stderr (errors are still shown).
  --help, --version

Parameters (--params). By default ("mode": "auto") the six parameters of Table 1 (alpha ...
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
  output {...}  output container, glTF compression and Draco settings, defaults:
         )" << service::to_json(service::JobParams{})["output"].dump()
      << R"(
         format: "off"|"obj"|"ply"|"stl"|"drc"|"glb"|"gltf", null = IN's;
         compression: "as_input" (IN's: Draco if IN used it, else none; meshopt input
         gives none)|"none"|"draco" ("meshopt" is not written yet); "draco": true|false
         is still accepted (= "draco"|"none"); position_bits [8, 30];
         normal_bits [1, 30]; texcoord_bits, color_bits, generic_bits [0, 30], 0 = lossless;
         compression_level [0, 10] (10 = smallest)

Exit codes: 0 ok; 2 bad command line or parameters (OUT that is IN without --in-place); 3 a file cannot be read or written, is
malformed or is not a valid mesh; 4 solver failure or internal error; 130 cancelled (Ctrl-C).
On any error OUT is not written. With --out-dir: the code of the first IN (in the order given)
that failed, 130 if cancelled; each OUT that was written is complete.
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
    } else if (arg == "--mode") {
      options.mode = value();
    } else if (arg == "--out-dir") {
      options.out_dir = value();
    } else if (arg == "--threads") {
      options.threads = parse_threads(value());
    } else if (arg == "--in-place") {
      flag();
      options.in_place = true;
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

}  // namespace mdn::cli
