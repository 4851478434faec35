// The JSON shape of the parameters: defaults come from core, every kind of bad field is
// refused with InvalidParamsError naming its JSON path, and to_json round-trips.
#include "service/params_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/errors.h"

namespace mdn::service {
namespace {

using nlohmann::json;

// Runs the parser and returns the error, failing the test if none is thrown.
InvalidParamsError parse_error(const json& j) {
  try {
    job_params_from_json(j);
  } catch (const InvalidParamsError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted " << j.dump();
  return InvalidParamsError("", "");
}

InvalidParamsError text_error(std::string_view text) {
  try {
    job_params_from_text(text);
  } catch (const InvalidParamsError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted " << text;
  return InvalidParamsError("", "");
}

const ParamSpec& spec_named(std::string_view name) {
  for (const auto& spec : param_specs())
    if (spec.name == name) return spec;
  throw std::logic_error("no spec " + std::string(name));
}

TEST(ParamsJson, EmptyObjectGivesCoreDefaults) {
  const JobParams p = job_params_from_json(json::object());
  const DenoiseParams d;
  for (const auto& spec : param_specs()) {
    if (spec.int_field) {
      EXPECT_EQ(p.denoise.*spec.int_field, d.*spec.int_field) << spec.name;
    } else {
      EXPECT_EQ(p.denoise.*spec.real_field, d.*spec.real_field) << spec.name;
    }
    EXPECT_EQ(spec.default_value(), spec.int_field ? d.*spec.int_field : d.*spec.real_field) << spec.name;
  }
  EXPECT_EQ(p.denoise.region_mode, d.region_mode);
  EXPECT_EQ(p.denoise.solver, d.solver);
  EXPECT_EQ(p.denoise.kmeans_seed, d.kmeans_seed);
  const io::EncodeOptions o;
  EXPECT_FALSE(p.output.format.has_value());
  EXPECT_EQ(p.output.compression, io::Compression::AsInput);  // the input's, issue 18
  EXPECT_EQ(p.output.position_bits, o.position_bits);
  EXPECT_EQ(p.output.compression_level, o.compression_level);
}

TEST(ParamsJson, ToJsonEmitsEveryFieldWithItsDefault) {
  JobParams manual;
  manual.denoise.mode = ParamMode::Manual;
  const json j = to_json(manual);
  EXPECT_EQ(j["mode"], "manual");
  for (const auto& spec : param_specs()) {
    ASSERT_TRUE(j.contains(std::string(spec.name))) << spec.name;
    EXPECT_EQ(j[std::string(spec.name)].get<double>(), spec.default_value()) << spec.name;
    if (spec.int_field) {
      EXPECT_TRUE(j[std::string(spec.name)].is_number_integer()) << spec.name;
    }
  }
  const DenoiseParams d;
  EXPECT_EQ(j["region_mode"], std::string(to_string(d.region_mode)));
  EXPECT_EQ(j["solver"], std::string(to_string(d.solver)));
  EXPECT_EQ(j["kmeans_seed"], d.kmeans_seed);
  ASSERT_TRUE(j["output"].is_object());
  EXPECT_TRUE(j["output"]["format"].is_null());
  EXPECT_EQ(j["output"]["compression"], "as_input");
  EXPECT_FALSE(j["output"].contains("draco"));  // accepted, not echoed
  for (const char* key : {"compression", "position_bits", "normal_bits", "texcoord_bits", "color_bits", "generic_bits",
                          "compression_level"}) {
    EXPECT_TRUE(j["output"].contains(key)) << key;
  }
}

TEST(ParamsJson, ParsesEveryKindOfField) {
  const JobParams p = job_params_from_text(R"({
    "alpha": 0.15, "sigma_theta": 20, "n_aniso": 1, "sigma_gamma": 40.5, "n_normal": 100,
    "n_vertex": 100.0, "region_mode": "on", "kmeans_seed": 18446744073709551615, "solver": "cg",
    "output": {"format": "glb", "draco": false, "position_bits": 20, "normal_bits": 8,
               "texcoord_bits": 14, "color_bits": 9, "generic_bits": 11, "compression_level": 0}})");
  EXPECT_EQ(p.denoise.alpha, 0.15);
  EXPECT_EQ(p.denoise.sigma_theta, 20);
  EXPECT_EQ(p.denoise.n_aniso, 1);
  EXPECT_EQ(p.denoise.sigma_gamma, 40.5);
  EXPECT_EQ(p.denoise.n_normal, 100);
  EXPECT_EQ(p.denoise.n_vertex, 100);  // 100.0 is an integer, as in JSON Schema
  EXPECT_EQ(p.denoise.region_mode, RegionMode::On);
  EXPECT_EQ(p.denoise.kmeans_seed, std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(p.denoise.solver, LinearSolver::ConjugateGradient);
  EXPECT_EQ(p.output.format, io::Format::Glb);
  EXPECT_EQ(p.output.compression, io::Compression::None);  // draco false overrides the default
  EXPECT_EQ(p.output.position_bits, 20);
  EXPECT_EQ(p.output.normal_bits, 8);
  EXPECT_EQ(p.output.texcoord_bits, 14);
  EXPECT_EQ(p.output.color_bits, 9);
  EXPECT_EQ(p.output.generic_bits, 11);
  EXPECT_EQ(p.output.compression_level, 0);
}

TEST(ParamsJson, AutoIsTheDefaultAndExplicitFieldsArePinned) {
  const JobParams empty = job_params_from_json(json::object());
  EXPECT_EQ(empty.denoise.mode, ParamMode::Auto);
  EXPECT_EQ(empty.denoise.pinned, 0);
  // The echo leaves out what the rule chooses, so it parses back to the same request.
  const json echo = to_json(empty);
  EXPECT_EQ(echo["mode"], "auto");
  for (const char* key : {"alpha", "sigma_theta", "n_aniso", "sigma_gamma", "n_normal", "n_vertex", "region_mode"})
    EXPECT_FALSE(echo.contains(key)) << key;
  EXPECT_TRUE(echo.contains("beta"));  // not chosen by the rule: always echoed

  const JobParams some = job_params_from_text(R"({"n_normal": 40, "region_mode": "off", "beta": 3})");
  EXPECT_EQ(some.denoise.mode, ParamMode::Auto);
  EXPECT_TRUE(some.denoise.is_pinned(AutoField::NNormal));
  EXPECT_TRUE(some.denoise.is_pinned(AutoField::RegionMode));
  EXPECT_FALSE(some.denoise.is_pinned(AutoField::Alpha));
  EXPECT_EQ(some.denoise.n_normal, 40);
  const json some_echo = to_json(some);
  EXPECT_EQ(some_echo["n_normal"], 40);
  EXPECT_EQ(some_echo["region_mode"], "off");
  EXPECT_FALSE(some_echo.contains("alpha"));
  const JobParams again = job_params_from_text(some_echo.dump());
  EXPECT_EQ(again.denoise.pinned, some.denoise.pinned);
  EXPECT_EQ(to_json(again), some_echo);

  const JobParams manual = job_params_from_text(R"({"mode": "manual", "alpha": 0.2})");
  EXPECT_EQ(manual.denoise.mode, ParamMode::Manual);
  EXPECT_EQ(manual.denoise.alpha, 0.2);
  EXPECT_EQ(manual.denoise.n_normal, DenoiseParams{}.n_normal);

  const auto e = parse_error({{"mode", "automatic"}});
  EXPECT_EQ(e.field(), "mode");
  EXPECT_NE(std::string(e.what()).find("\"auto\", \"search\", \"manual\" or \"none\""), std::string::npos) << e.what();
  EXPECT_EQ(parse_error({{"mode", 1}}).field(), "mode");
}

TEST(ParamsJson, MethodParamsJsonIsAManualRequestForTheSameParameters) {
  DenoiseParams d;
  d.alpha = 0.4;
  d.n_aniso = 16;
  d.region_mode = RegionMode::On;
  const JobParams q = job_params_from_json(method_params_json(d));
  EXPECT_EQ(q.denoise.mode, ParamMode::Manual);
  EXPECT_EQ(q.denoise.alpha, 0.4);
  EXPECT_EQ(q.denoise.n_aniso, 16);
  EXPECT_EQ(q.denoise.region_mode, RegionMode::On);
  EXPECT_EQ(q.denoise.sigma_gamma, d.sigma_gamma);
}

TEST(ParamsJson, RoundTripThroughToJson) {
  JobParams p;
  p.denoise.mode = ParamMode::Manual;
  p.denoise.alpha = 0.2;
  p.denoise.sigma_theta = 47.25;
  p.denoise.n_aniso = 12;
  p.denoise.n_normal = 7;
  p.denoise.region_mode = RegionMode::Off;
  p.denoise.kmeans_seed = 123456789012345ull;
  p.denoise.solver = LinearSolver::ConjugateGradient;
  p.denoise.cg_tolerance = 1e-12;
  p.output.format = io::Format::Ply;
  p.output.compression = mdn::io::Compression::None;
  p.output.position_bits = 11;
  p.output.compression_level = 10;
  const json j = to_json(p);
  // Through text, as the API sees it.
  const JobParams q = job_params_from_text(j.dump());
  EXPECT_EQ(to_json(q), j);
  EXPECT_EQ(q.denoise.sigma_theta, 47.25);
  EXPECT_EQ(q.denoise.cg_tolerance, 1e-12);
  EXPECT_EQ(q.denoise.kmeans_seed, 123456789012345ull);
  EXPECT_EQ(q.output.format, io::Format::Ply);
  // Every numeric spec survives the round trip, including the non-Table-1 ones.
  for (const auto& spec : param_specs()) {
    if (spec.int_field) {
      EXPECT_EQ(q.denoise.*spec.int_field, p.denoise.*spec.int_field) << spec.name;
    } else {
      EXPECT_EQ(q.denoise.*spec.real_field, p.denoise.*spec.real_field) << spec.name;
    }
  }
}

TEST(ParamsJson, FractionalIterationCountNamesFieldAndRange) {
  const auto e = parse_error({{"n_normal", 2.5}});
  EXPECT_EQ(e.field(), "n_normal");
  const auto& spec = spec_named("n_normal");
  const std::string expected = "n_normal must be an integer in [" + std::to_string(static_cast<int>(spec.min)) + ", " +
                               std::to_string(static_cast<int>(spec.max)) + "], got 2.5";
  EXPECT_EQ(std::string(e.what()), expected);
}

TEST(ParamsJson, WrongTypesAreRefusedWithTheirField) {
  EXPECT_EQ(parse_error({{"alpha", "0.1"}}).field(), "alpha");
  EXPECT_EQ(parse_error({{"alpha", true}}).field(), "alpha");  // a bool is not a number
  EXPECT_EQ(parse_error({{"n_aniso", false}}).field(), "n_aniso");
  EXPECT_EQ(parse_error({{"n_vertex", nullptr}}).field(), "n_vertex");
  EXPECT_EQ(parse_error({{"sigma_gamma", json::array({30})}}).field(), "sigma_gamma");
  EXPECT_EQ(parse_error({{"region_mode", 1}}).field(), "region_mode");
  EXPECT_EQ(parse_error({{"solver", true}}).field(), "solver");
  EXPECT_EQ(parse_error({{"kmeans_seed", "7"}}).field(), "kmeans_seed");
  EXPECT_EQ(parse_error({{"output", "glb"}}).field(), "output");
  EXPECT_EQ(parse_error({{"output", {{"draco", 1}}}}).field(), "output.draco");
  EXPECT_EQ(parse_error({{"output", {{"format", 3}}}}).field(), "output.format");
  EXPECT_EQ(parse_error({{"output", {{"position_bits", "16"}}}}).field(), "output.position_bits");
  EXPECT_EQ(parse_error({{"output", {{"compression_level", 7.5}}}}).field(), "output.compression_level");
  const std::string message = parse_error({{"alpha", "0.1"}}).what();
  EXPECT_NE(message.find("alpha must be a number in ["), std::string::npos) << message;
  EXPECT_NE(message.find("the string \"0.1\""), std::string::npos) << message;
}

TEST(ParamsJson, OutOfRangeValuesNameTheAcceptedRange) {
  for (const auto& spec : param_specs()) {
    const std::string name(spec.name);
    for (const double bad : {spec.min - 1, spec.max * 2 + 1}) {
      json value = spec.int_field ? json(static_cast<std::int64_t>(bad)) : json(bad);
      const auto e = parse_error({{name, value}});
      EXPECT_EQ(e.field(), name);
      EXPECT_NE(std::string(e.what()).find(spec.int_field ? "must be an integer in [" : "must be a number in ["),
                std::string::npos)
          << e.what();
    }
    // The bounds themselves are accepted.
    for (const double good : {spec.min, spec.max}) {
      json value = spec.int_field ? json(static_cast<std::int64_t>(good)) : json(good);
      EXPECT_NO_THROW(job_params_from_json({{name, value}})) << name << " = " << good;
    }
  }
  const auto bits = parse_error({{"output", {{"position_bits", 7}}}});
  EXPECT_EQ(bits.field(), "output.position_bits");
  EXPECT_EQ(std::string(bits.what()), "output.position_bits must be an integer in [8, 30], got 7");
  EXPECT_EQ(parse_error({{"output", {{"normal_bits", 31}}}}).field(), "output.normal_bits");
  EXPECT_EQ(parse_error({{"output", {{"texcoord_bits", -1}}}}).field(), "output.texcoord_bits");
  EXPECT_EQ(parse_error({{"output", {{"color_bits", -1}}}}).field(), "output.color_bits");
  EXPECT_EQ(parse_error({{"output", {{"position_bits", 0}}}}).field(), "output.position_bits");
  // 0 = stored losslessly, for every attribute but positions (io::EncodeOptions).
  EXPECT_EQ(job_params_from_json({{"output", {{"texcoord_bits", 0}, {"color_bits", 0}, {"generic_bits", 0}}}})
                .output.texcoord_bits,
            0);
  EXPECT_EQ(parse_error({{"output", {{"normal_bits", 0}}}}).field(), "output.normal_bits");  // recomputed anyway
  EXPECT_EQ(parse_error({{"output", {{"generic_bits", 100}}}}).field(), "output.generic_bits");
  EXPECT_EQ(parse_error({{"output", {{"compression_level", 11}}}}).field(), "output.compression_level");
  EXPECT_EQ(parse_error({{"kmeans_seed", -1}}).field(), "kmeans_seed");
  EXPECT_EQ(parse_error({{"kmeans_seed", 1.5}}).field(), "kmeans_seed");
  EXPECT_EQ(parse_error({{"n_normal", 1e30}}).field(), "n_normal");
  EXPECT_EQ(parse_error({{"n_normal", 18446744073709551615ull}}).field(), "n_normal");
}

TEST(ParamsJson, NonFiniteNumbersAreRefused) {
  // JSON text cannot spell them, but a json built in code (or by another parser) can hold them.
  EXPECT_EQ(parse_error({{"alpha", std::nan("")}}).field(), "alpha");
  EXPECT_EQ(parse_error({{"sigma_theta", std::numeric_limits<double>::infinity()}}).field(), "sigma_theta");
  EXPECT_EQ(parse_error({{"n_normal", -std::numeric_limits<double>::infinity()}}).field(), "n_normal");
  // In text, overflowing literals are a JSON error.
  EXPECT_EQ(text_error(R"({"alpha": 1e400})").field(), "params");
  EXPECT_EQ(text_error(R"({"alpha": NaN})").field(), "params");
}

TEST(ParamsJson, UnknownFieldsAndEnumerationValues) {
  const auto e = parse_error({{"n_normals", 20}});
  EXPECT_EQ(e.field(), "n_normals");
  EXPECT_NE(std::string(e.what()).find("n_normal"), std::string::npos);  // lists what is accepted
  EXPECT_EQ(parse_error({{"output", {{"quality", 3}}}}).field(), "output.quality");
  EXPECT_EQ(parse_error({{"region_mode", "sometimes"}}).field(), "region_mode");
  EXPECT_EQ(parse_error({{"solver", "LDLT"}}).field(), "solver");
  EXPECT_EQ(parse_error({{"output", {{"format", "xyz"}}}}).field(), "output.format");
  EXPECT_NO_THROW(job_params_from_json({{"output", {{"format", nullptr}}}}));  // null: like the input
}

TEST(ParamsJson, CompressionByNameAndTheDracoOverride) {
  const auto compression = [](const json& output) { return job_params_from_json({{"output", output}}).output.compression; };
  EXPECT_EQ(compression(json::object()), io::Compression::AsInput);
  EXPECT_EQ(compression({{"compression", "none"}}), io::Compression::None);
  EXPECT_EQ(compression({{"compression", "DRACO"}}), io::Compression::Draco);
  EXPECT_EQ(compression({{"compression", "as_input"}}), io::Compression::AsInput);
  EXPECT_EQ(compression({{"compression", "meshopt"}}), io::Compression::Meshopt);  // refused when the job runs (422)
  EXPECT_EQ(compression({{"draco", true}}), io::Compression::Draco);
  EXPECT_EQ(compression({{"draco", false}}), io::Compression::None);
  EXPECT_EQ(compression({{"draco", true}, {"compression", "draco"}}), io::Compression::Draco);
  EXPECT_EQ(parse_error({{"output", {{"draco", false}, {"compression", "draco"}}}}).field(), "output.draco");
  EXPECT_EQ(parse_error({{"output", {{"draco", true}, {"compression", "as_input"}}}}).field(), "output.draco");
  EXPECT_EQ(parse_error({{"output", {{"compression", "zip"}}}}).field(), "output.compression");
  EXPECT_EQ(parse_error({{"output", {{"compression", true}}}}).field(), "output.compression");
  // The echo names the compression, and parses back to it.
  for (const char* name : {"as_input", "none", "draco"}) {
    const json echo = to_json(job_params_from_json({{"output", {{"compression", name}}}}));
    EXPECT_EQ(echo["output"]["compression"], name);
    EXPECT_EQ(to_json(job_params_from_json(echo)), echo);
  }
}

TEST(ParamsJson, ModeNoneAndStlByName) {
  const JobParams p = job_params_from_json({{"mode", "none"}, {"output", {{"format", "stl"}}}});
  EXPECT_EQ(p.denoise.mode, ParamMode::None);
  EXPECT_EQ(p.output.format, io::Format::Stl);
  const json echo = to_json(p);
  EXPECT_EQ(echo["mode"], "none");
  EXPECT_EQ(echo["output"]["format"], "stl");
  EXPECT_EQ(to_json(job_params_from_json(echo)), echo);
  EXPECT_NE(std::string(parse_error({{"mode", "convert"}}).what()).find("\"none\""), std::string::npos);
}

TEST(ParamsJson, NonObjectsAndBadTextNameParams) {
  EXPECT_EQ(parse_error(json::array()).field(), "params");
  EXPECT_EQ(parse_error(json(3)).field(), "params");
  EXPECT_EQ(text_error("").field(), "params");
  EXPECT_EQ(text_error("{\"alpha\": 0.1").field(), "params");
  EXPECT_EQ(text_error("[1, 2]").field(), "params");
  EXPECT_EQ(text_error("{\"alpha\": 0.1} trailing").field(), "params");
}

TEST(ParamsJson, ValidateChecksOptionsBuiltInCode) {
  JobParams p;
  EXPECT_NO_THROW(validate(p));
  p.output.compression_level = 12;
  try {
    validate(p);
    FAIL() << "accepted compression_level 12";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "output.compression_level");
  }
  p = JobParams{};
  p.denoise.n_normal = -1;
  try {
    validate(p);
    FAIL() << "accepted n_normal -1";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "n_normal");
  }
}

TEST(NoiseSpecJson, ParsesAndRefuses) {
  const NoiseSpec s = noise_spec_from_text(R"({"kind":"per_coordinate","sigma":0.3,"seed":9,"impulse_fraction":0.25})");
  EXPECT_EQ(s.kind, NoiseKind::PerCoordinate);
  EXPECT_EQ(s.sigma, 0.3);
  EXPECT_EQ(s.seed, 9u);
  EXPECT_EQ(s.impulse_fraction, 0.25);
  const NoiseSpec d = noise_spec_from_text("{}");
  EXPECT_EQ(d.kind, NoiseSpec{}.kind);
  EXPECT_EQ(d.sigma, NoiseSpec{}.sigma);
  EXPECT_EQ(to_json(noise_spec_from_json(to_json(s))), to_json(s));

  auto field_of = [](std::string_view text) -> std::string {
    try {
      noise_spec_from_text(text);
    } catch (const InvalidParamsError& e) {
      return e.field();
    }
    return "(accepted)";
  };
  EXPECT_EQ(field_of(R"({"kind":"gaussian"})"), "kind");
  EXPECT_EQ(field_of(R"({"sigma":-0.1})"), "sigma");
  EXPECT_EQ(field_of(R"({"sigma":"0.1"})"), "sigma");
  EXPECT_EQ(field_of(R"({"seed":-3})"), "seed");
  EXPECT_EQ(field_of(R"({"impulse_fraction":1.5})"), "impulse_fraction");
  EXPECT_EQ(field_of(R"({"amplitude":1})"), "amplitude");
  EXPECT_EQ(field_of("not json"), "noise");
  EXPECT_EQ(field_of("[]"), "noise");
}

}  // namespace
}  // namespace mdn::service
