// JSON <-> JobParams. Names, ranges and defaults of the numeric method parameters come from
// mdn::param_specs() (core/params.h), so they are defined once; this file only adds the JSON
// typing rules and the enumerations; the "output" object's fields, ranges and choices come from
// io::output_settings() (core/io/output_settings.h, decision 69).
#include "service/params_json.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/io/output_settings.h"

namespace mdn::service {
namespace {

using nlohmann::json;

// Integral doubles print without a fraction ("500", not "500.0"); others print shortest
// round-trip ("0.1"), which is what nlohmann's dump() does for doubles.
std::string number_text(double value) {
  if (std::isfinite(value) && value == std::floor(value) && std::abs(value) < 1e15) {
    return std::to_string(static_cast<std::int64_t>(value));
  }
  return json(value).dump();
}

// What the caller sent, for messages: numbers and short strings verbatim, other types by kind.
std::string describe(const json& value) {
  switch (value.type()) {
    case json::value_t::string: {
      const auto& s = value.get_ref<const std::string&>();
      if (s.size() <= 40) return "the string " + json(s).dump();
      return "a string";
    }
    case json::value_t::boolean:
      return value.get<bool>() ? "true" : "false";
    case json::value_t::null:
      return "null";
    case json::value_t::object:
      return "an object";
    case json::value_t::array:
      return "an array";
    case json::value_t::number_float:
      return number_text(value.get<double>());
    default:
      return value.dump();  // integers
  }
}

std::string range_text(double min, double max) {
  // Appended piecewise: GCC 12's -Wrestrict misfires on "[" + std::string&& (a known false positive).
  std::string text = "[";
  text += number_text(min);
  text += ", ";
  text += number_text(max);
  text += "]";
  return text;
}

[[noreturn]] void fail(const std::string& path, const std::string& requirement, const json& got) {
  throw InvalidParamsError(path, path + " must be " + requirement + ", got " + describe(got));
}

// JSON numbers only (booleans are not numbers here, unlike in some JSON libraries' casts).
// An integral float such as 2.0 counts as an integer, as JSON Schema's "integer" type does.
double real_in_range(const json& value, const std::string& path, double min, double max) {
  const std::string requirement = "a number in " + range_text(min, max);
  if (!value.is_number()) fail(path, requirement, value);
  const double x = value.get<double>();
  if (!std::isfinite(x) || x < min || x > max) fail(path, requirement, value);
  return x;
}

std::int64_t integer_in_range(const json& value, const std::string& path, double min, double max) {
  const std::string requirement = "an integer in " + range_text(min, max);
  if (!value.is_number()) fail(path, requirement, value);
  if (value.is_number_integer()) {
    // number_unsigned above int64 cannot be in any range we accept.
    if (value.is_number_unsigned() &&
        value.get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
      fail(path, requirement, value);
    }
    const auto n = value.get<std::int64_t>();
    if (static_cast<double>(n) < min || static_cast<double>(n) > max) fail(path, requirement, value);
    return n;
  }
  const double x = value.get<double>();
  if (!std::isfinite(x) || x != std::floor(x) || x < min || x > max) fail(path, requirement, value);
  return static_cast<std::int64_t>(x);
}

// A seed: any non-negative integer that fits 64 bits. Integral floats are accepted only up to
// 2^53, where every integer is still exactly representable.
std::uint64_t seed_value(const json& value, const std::string& path) {
  const std::string requirement = "a non-negative integer below 2^64";
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (value.is_number_integer()) fail(path, requirement, value);  // negative
  if (value.is_number_float()) {
    const double x = value.get<double>();
    if (std::isfinite(x) && x >= 0 && x == std::floor(x) && x <= 9007199254740992.0) {
      return static_cast<std::uint64_t>(x);
    }
  }
  fail(path, requirement, value);
}

bool boolean_value(const json& value, const std::string& path) {
  if (!value.is_boolean()) fail(path, "true or false", value);
  return value.get<bool>();
}

const std::string& string_value(const json& value, const std::string& path, const std::string& choices) {
  if (!value.is_string()) fail(path, "one of " + choices, value);
  return value.get_ref<const std::string&>();
}

// The "output" object's fields, ranges and choices: io::output_settings() (decision 69).
// "\"off\", \"obj\", ... or null": the choices as a message lists them.
std::string choices_text(const io::OutputSetting& s) {
  std::string text;
  for (std::size_t i = 0; i < s.choices.size(); ++i) {
    const bool last = i + 1 == s.choices.size() && !s.nullable;
    text += (i == 0 ? "" : last ? " or " : ", ") + json(s.choices[i]).dump();
  }
  if (s.nullable) text += " or null (same as the input)";
  return text;
}

std::vector<std::string> top_level_names() {
  std::vector<std::string> names;
  for (const auto& spec : param_specs()) names.emplace_back(spec.name);
  names.insert(names.end(), {"mode", "region_mode", "kmeans_seed", "solver", "output"});
  return names;
}

std::vector<std::string> output_names() {
  std::vector<std::string> names;
  for (const auto& s : io::output_settings()) names.emplace_back(s.name);
  return names;
}

[[noreturn]] void unknown_field(const std::string& path, const std::vector<std::string>& accepted) {
  std::ostringstream out;
  out << "unknown field \"" << path << "\"; accepted fields:";
  for (std::size_t i = 0; i < accepted.size(); ++i) out << (i ? ", " : " ") << accepted[i];
  throw InvalidParamsError(path, out.str());
}

// "compression" names the glTF output compression; "draco" (the older switch) still overrides
// it: true is "draco", false is "none". Both given, they must agree.
void parse_output(const json& j, io::EncodeOptions& out) {
  if (!j.is_object()) fail("output", "an object", j);
  std::optional<io::Compression> compression;
  std::optional<bool> draco;
  for (const auto& [key, value] : j.items()) {
    const std::string path = "output." + key;
    const io::OutputSetting* s = io::find_output_setting(key);
    if (!s) unknown_field(path, output_names());
    if (s->kind == io::SettingKind::Integer) {
      out.*s->field = static_cast<int>(integer_in_range(value, path, s->min, s->max));
    } else if (s->kind == io::SettingKind::Flag) {
      draco = boolean_value(value, path);
    } else if (key == "format") {
      if (value.is_null()) {
        out.format.reset();
        continue;
      }
      const auto format = io::format_from_string(string_value(value, path, choices_text(*s)));
      if (!format) fail(path, "one of " + choices_text(*s), value);
      out.format = *format;
    } else {
      compression = io::compression_from_string(string_value(value, path, choices_text(*s)));
      if (!compression) fail(path, "one of " + choices_text(*s), value);
    }
  }
  if (draco) {
    const io::Compression by_draco = *draco ? io::Compression::Draco : io::Compression::None;
    if (compression && *compression != by_draco)
      fail("output.draco",
           std::string("consistent with output.compression \"") + std::string(io::to_string(*compression)) +
               "\" (or left out)",
           json(*draco));
    compression = by_draco;
  }
  if (compression) {
    out.compression = *compression;
  }
}

// Parses JSON text; a syntax error becomes InvalidParamsError(field) with nlohmann's message,
// which carries the byte position of the error.
json parse_text(std::string_view text, const std::string& field) {
  try {
    return json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {
    std::string what = e.what();
    if (const auto pos = what.find("] "); pos != std::string::npos) what = what.substr(pos + 2);
    throw InvalidParamsError(field, field + " is not valid JSON: " + what);
  }
}

}  // namespace

void validate(const JobParams& params) {
  params.denoise.validate();
  io::check_output_options(params.output);
}

JobParams job_params_from_json(const nlohmann::json& j) {
  if (!j.is_object()) {
    throw InvalidParamsError("params", "params must be a JSON object, got " + describe(j));
  }
  JobParams p;
  for (const auto& [key, value] : j.items()) {
    if (const auto field = auto_field_from_string(key)) p.denoise.pin(*field);  // explicit: kept in auto mode
    if (key == "mode") {
      constexpr const char* kModes = "\"auto\", \"search\", \"manual\" or \"none\"";
      const auto mode = param_mode_from_string(string_value(value, key, kModes));
      if (!mode) fail(key, std::string("one of ") + kModes, value);
      p.denoise.mode = *mode;
    } else if (key == "region_mode") {
      const auto& text = string_value(value, key, "\"auto\", \"on\" or \"off\"");
      const auto mode = region_mode_from_string(text);
      if (!mode) fail(key, "one of \"auto\", \"on\" or \"off\"", value);
      p.denoise.region_mode = *mode;
    } else if (key == "solver") {
      const auto& text = string_value(value, key, "\"ldlt\" or \"cg\"");
      const auto solver = linear_solver_from_string(text);
      if (!solver) fail(key, "one of \"ldlt\" or \"cg\"", value);
      p.denoise.solver = *solver;
    } else if (key == "kmeans_seed") {
      p.denoise.kmeans_seed = seed_value(value, key);
    } else if (key == "output") {
      parse_output(value, p.output);
    } else {
      const ParamSpec* spec = nullptr;
      for (const auto& s : param_specs()) {
        if (s.name == key) {
          spec = &s;
          break;
        }
      }
      if (!spec) unknown_field(key, top_level_names());
      if (spec->int_field) {
        p.denoise.*spec->int_field = static_cast<int>(integer_in_range(value, key, spec->min, spec->max));
      } else {
        p.denoise.*spec->real_field = real_in_range(value, key, spec->min, spec->max);
      }
    }
  }
  // Cross-field rules (if core has any) and a second check of every range, in core's words.
  validate(p);
  return p;
}

JobParams job_params_from_text(std::string_view text) { return job_params_from_json(parse_text(text, "params")); }

nlohmann::json to_json(const JobParams& p) {
  json j = json::object();
  const bool automatic = p.denoise.mode != ParamMode::Manual;
  j["mode"] = std::string(to_string(p.denoise.mode));
  for (const auto& spec : param_specs()) {
    if (const auto field = auto_field_from_string(spec.name); automatic && field && !p.denoise.is_pinned(*field))
      continue;
    if (spec.int_field) {
      j[std::string(spec.name)] = p.denoise.*spec.int_field;
    } else {
      j[std::string(spec.name)] = p.denoise.*spec.real_field;
    }
  }
  if (!automatic || p.denoise.is_pinned(AutoField::RegionMode))
    j["region_mode"] = std::string(to_string(p.denoise.region_mode));
  j["kmeans_seed"] = p.denoise.kmeans_seed;
  j["solver"] = std::string(to_string(p.denoise.solver));
  json out = json::object();
  out["format"] = p.output.format ? json(std::string(io::to_string(*p.output.format))) : json(nullptr);
  out["compression"] = std::string(io::to_string(p.output.compression));
  for (const auto& s : io::output_settings())
    if (s.kind == io::SettingKind::Integer) out[std::string(s.name)] = p.output.*s.field;
  j["output"] = std::move(out);
  return j;
}

}  // namespace mdn::service

namespace mdn::service {

// Sigma is in mean edge lengths; 10 already moves vertices far past their neighbours, so
// larger values are more likely a unit mistake than an experiment.
constexpr double kMaxNoiseSigma = 10;

NoiseSpec noise_spec_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw InvalidParamsError("noise", "the noise spec must be a JSON object, got " + describe(j));
  NoiseSpec spec;
  constexpr const char* kKinds = "\"along_normal\", \"per_coordinate\" or \"random_direction\"";
  for (const auto& [key, value] : j.items()) {
    if (key == "kind") {
      const auto kind = noise_kind_from_string(string_value(value, key, kKinds));
      if (!kind) fail(key, std::string("one of ") + kKinds, value);
      spec.kind = *kind;
    } else if (key == "sigma") {
      spec.sigma = real_in_range(value, key, 0, kMaxNoiseSigma);
    } else if (key == "seed") {
      spec.seed = seed_value(value, key);
    } else if (key == "impulse_fraction") {
      spec.impulse_fraction = real_in_range(value, key, 0, 1);
    } else {
      unknown_field(key, {"kind", "sigma", "seed", "impulse_fraction"});
    }
  }
  return spec;
}

NoiseSpec noise_spec_from_text(std::string_view text) { return noise_spec_from_json(parse_text(text, "noise")); }

nlohmann::json to_json(const NoiseSpec& spec) {
  return {{"kind", std::string(to_string(spec.kind))},
          {"sigma", spec.sigma},
          {"seed", spec.seed},
          {"impulse_fraction", spec.impulse_fraction}};
}

nlohmann::json method_params_json(const DenoiseParams& p) {
  return {{"mode", "manual"},
          {"alpha", p.alpha},
          {"sigma_theta", p.sigma_theta},
          {"n_aniso", p.n_aniso},
          {"sigma_gamma", p.sigma_gamma},
          {"n_normal", p.n_normal},
          {"n_vertex", p.n_vertex},
          {"region_mode", std::string(to_string(p.region_mode))}};
}

}  // namespace mdn::service
