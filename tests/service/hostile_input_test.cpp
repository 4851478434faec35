// Hostile inputs through the whole job path (decode, denoise, encode), as the server and the CLI
// run it: valid files of every format, mutated thousands of times in deterministic, seeded ways
// (bit flips, boundary integers over length and count fields, truncations, cut and repeated
// slices, and in text formats numbers swapped for nan, inf, -1 or huge values). Every mutant must
// either give a result that decodes again with finite coordinates, or throw one of the errors
// the server answers with a 4xx. Anything else (another exception, a crash, a sanitizer report
// in a sanitizer build) is a bug; the failure names the seed file and the mutant's number.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/io/document.h"
#include "io/gltf_fixtures.h"
#include "service/job_runner.h"
#include "service/params_json.h"
#include "support/mutate.h"
#include "support/noisy.h"
#include "support/shapes.h"

namespace mdn {
namespace {

struct Seed {
  std::string name;
  io::Format format;
  std::string bytes;
};

// Valid files: a small noisy sphere in every format the service reads (converted by the io layer
// itself), and the glTF fixture scene (two primitives, textures, instancing, quantized and sparse
// variants).
std::vector<Seed> seeds() {
  const std::string off = test::off_text(test::with_noise(test::sphere(1), 0.2));  // 80 faces
  std::vector<Seed> out = {{"sphere.off", io::Format::Off, off}};
  const auto convert = [&](const char* name, io::Format format, bool draco) {
    io::EncodeOptions options;
    options.format = format;
    options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
    out.push_back({name, format, io::decode(off, io::Format::Off)->encode(options).bytes});
  };
  convert("sphere.obj", io::Format::Obj, false);
  convert("sphere.ply", io::Format::Ply, false);
  convert("sphere.drc", io::Format::Drc, true);
  convert("sphere.glb", io::Format::Glb, false);
  convert("sphere-draco.glb", io::Format::Glb, true);
  convert("sphere.gltf", io::Format::Gltf, false);
  const test_io::SphereFixture fixture = test_io::make_sphere();
  out.push_back({"scene.glb", io::Format::Glb, test_io::sphere_scene_glb(fixture)});
  out.push_back({"scene-quantized.glb", io::Format::Glb, test_io::sphere_scene_glb(fixture, test_io::Variant::Quantized)});
  out.push_back({"scene-sparse.glb", io::Format::Glb, test_io::sphere_scene_glb(fixture, test_io::Variant::Sparse)});
  return out;
}

bool is_text(io::Format f) {
  return f == io::Format::Off || f == io::Format::Obj || f == io::Format::Gltf;
}

// The outcome of one mutant.
struct Outcome {
  bool result = false;  // a result came back (else a client error was thrown)
  std::string problem;  // "" when acceptable, else what went wrong
};

Outcome run_one(const std::string& bytes, io::Format format, const service::JobParams& params) {
  io::Limits limits;
  limits.max_faces = 200'000;
  limits.max_vertices = 200'000;
  limits.max_decoded_bytes = std::int64_t{256} << 20;
  service::JobInput input{bytes, format, params, 1, std::nullopt};
  try {
    const service::JobOutput out = service::run_job(input, limits);
    // A result: it must read back, every coordinate finite.
    const auto doc = io::decode(out.bytes, out.format, limits);
    for (const TriMesh& m : doc->surfaces())
      if (!m.V.allFinite()) return {true, "the result has a non-finite coordinate"};
    return {true, ""};
  } catch (const io::FormatError&) {  // 400
  } catch (const InvalidMeshError&) {  // 400
  } catch (const io::UnsupportedError&) {  // 422
  } catch (const io::LimitError&) {  // 413
  } catch (const SolverError&) {  // 422
  } catch (const std::exception& e) {
    return {false, std::string("unexpected exception (the server would answer 500): ") + e.what()};
  } catch (...) {
    return {false, "unexpected non-standard exception"};
  }
  return {false, ""};
}

TEST(HostileInput, MutatedFilesOfEveryFormatGiveAResultOrAClientError) {
  // Auto mode measures the input; cheap iteration counts keep each run to about a millisecond.
  const service::JobParams params = service::job_params_from_json({{"n_normal", 3}, {"n_vertex", 3}, {"n_aniso", 1}});
  const int kMutantsPerSeed = test::mutants_per_seed(400);
  double slowest_ms = 0;
  std::string slowest;
  for (const Seed& seed : seeds()) {
    SCOPED_TRACE(seed.name);
    const Outcome original = run_one(seed.bytes, seed.format, params);
    ASSERT_TRUE(original.result && original.problem.empty()) << original.problem;
    std::mt19937_64 rng(std::hash<std::string>{}(seed.name));
    int results = 0, refused = 0;
    for (int i = 0; i < kMutantsPerSeed; ++i) {
      const std::string bytes = test::mutate(seed.bytes, is_text(seed.format), rng);
      const auto t0 = std::chrono::steady_clock::now();
      const Outcome o = run_one(bytes, seed.format, params);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (ms > slowest_ms) slowest_ms = ms, slowest = seed.name + " #" + std::to_string(i);
      EXPECT_EQ(o.problem, "") << seed.name << " mutant #" << i << " (" << bytes.size() << " bytes)";
      ++(o.result ? results : refused);
    }
    // Both kinds of outcome occur: the mutants reach past the first check and also break things.
    EXPECT_GT(results, 0);
    EXPECT_GT(refused, 0);
    std::printf("%-20s %3d results, %3d refused\n", seed.name.c_str(), results, refused);
  }
  std::printf("slowest mutant: %s, %.1f ms\n", slowest.c_str(), slowest_ms);
}

// The parameters text (?params=, X-Denoise-Params, the form field, --params) mutated the same
// way: each mutant parses to parameters that pass validate(), or throws InvalidParamsError naming
// a field (a 400 problem with "field"), nothing else.
TEST(HostileInput, MutatedParametersParseOrNameTheBadField) {
  const std::string valid =
      R"({"mode":"manual","alpha":0.2,"sigma_theta":40,"n_aniso":6,"sigma_gamma":30,"n_normal":50,"n_vertex":40,)"
      R"("region_mode":"auto","output":{"format":"glb","draco":true,"position_bits":14,"normal_bits":10}})";
  ASSERT_NO_THROW(service::job_params_from_text(valid));
  std::mt19937_64 rng(20261123);
  int parsed = 0, refused = 0;
  for (int i = 0; i < 4000; ++i) {
    const std::string text = test::mutate(valid, /*text=*/true, rng);
    try {
      service::validate(service::job_params_from_text(text));
      ++parsed;
    } catch (const InvalidParamsError& e) {
      // The field is named; "" only when the text has an empty key (an unknown field called "").
      EXPECT_TRUE(!e.field().empty() || text.find("\"\":") != std::string::npos) << "mutant #" << i << ": " << text;
      EXPECT_NE(std::string(e.what()), "") << "mutant #" << i;
      ++refused;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "mutant #" << i << " threw " << e.what() << " (the server would answer 500): " << text;
    }
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(refused, 0);
  std::printf("parameters: %d parsed, %d refused\n", parsed, refused);
}

}  // namespace
}  // namespace mdn
