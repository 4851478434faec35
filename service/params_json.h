// The JSON shape of the parameters, shared by the command-line tool and the HTTP API.
// proto/params.schema.json documents the same shape; tests check that they agree.
//
//   { "alpha": 0.1, "sigma_theta": 30, "n_aniso": 2, "sigma_gamma": 30, "n_normal": 20,
//     "n_vertex": 10, "region_mode": "auto", "beta": 6, ... ,
//     "output": { "format": "glb", "compression": "as_input", "position_bits": 16, ... } }
#pragma once

#include <nlohmann/json.hpp>

#include "core/io/document.h"
#include "core/io/output_settings.h"
#include "core/noise.h"
#include "core/params.h"

namespace mdn::service {

// The service and the CLI default to ParamMode::Auto (issue 7): a field given explicitly in the
// JSON (alpha ... n_vertex, region_mode) is pinned and keeps its value; "mode": "manual" uses
// every value as given, missing ones from core's defaults (the paper's Fandisk row).
struct JobParams {
  DenoiseParams denoise = [] {
    DenoiseParams d;
    d.mode = ParamMode::Auto;
    return d;
  }();  // method parameters (defaults from core, mode auto)
  // Output container and compression (glTF: as the input's by default, issue 18) and the
  // Draco settings.
  io::EncodeOptions output = io::request_defaults();
};

// Parses a JSON object; missing fields keep their defaults. Throws InvalidParamsError naming
// the field for: a non-object, an unknown field, a wrong type, a non-integer where an integer
// is required, an out-of-range value, an unknown enumeration value.
JobParams job_params_from_json(const nlohmann::json& j);
// Parses text (the body of --params, ?params= or X-Denoise-Params). Bad JSON gives
// InvalidParamsError with field "params".
JobParams job_params_from_text(std::string_view text);
// Every field with its effective value (what the CLI prints and the server echoes). In auto
// mode the fields the rule chooses are left out unless pinned, so the echo parses back to the
// same request; what auto chose is in each surface's report (report_to_json).
nlohmann::json to_json(const JobParams& p);
// The six parameters of Table 1 and region_mode as JSON (a "params" object that --params and
// the API accept in manual mode, with "mode": "manual").
nlohmann::json method_params_json(const DenoiseParams& p);

// For JobParams built rather than parsed: DenoiseParams::validate() and the "output" ranges of
// io::output_settings() (io::check_output_options). Throws InvalidParamsError with the JSON
// path, e.g. "output.position_bits". job_params_from_json() already calls it; run_job() calls
// it before decoding.
void validate(const JobParams& params);

// Synthetic noise for experiments (meshdenoise --add-noise),
//   { "kind": "along_normal" | "per_coordinate" | "random_direction", "sigma": 0.2,
//     "seed": 1, "impulse_fraction": 0 }
// Missing fields keep NoiseSpec's defaults; sigma in [0, 10] mean edge lengths, impulse_fraction
// in [0, 1], seed a non-negative integer. Same error rules as job_params_from_json (field() is
// "sigma", "kind", ...). Text that is not JSON gives field "noise".
NoiseSpec noise_spec_from_json(const nlohmann::json& j);
NoiseSpec noise_spec_from_text(std::string_view text);
nlohmann::json to_json(const NoiseSpec& spec);

}  // namespace mdn::service
