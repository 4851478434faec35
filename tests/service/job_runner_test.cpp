// The shared job runner: bytes in, denoised bytes out, deterministic across thread counts,
// typed errors from every stage.
#include "service/job_runner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include "core/errors.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "service/job_json.h"
#include "support/shapes.h"

namespace mdn::service {
namespace {

TriMesh decode_single(const std::string& bytes, io::Format format) {
  auto document = io::decode(bytes, format);
  EXPECT_EQ(document->surfaces().size(), 1u);
  return document->surfaces().front();
}

// A noisy sphere (642 vertices): small enough to be fast, curved enough to be a real test.
struct NoisySphere {
  TriMesh clean = test::sphere(3);
  TriMesh noisy = clean;
  NoisySphere() { noisy.V = add_noise(clean, {NoiseKind::AlongNormal, 0.3, 7, 0}); }
};

JobInput off_job(const TriMesh& mesh, int threads = 1) {
  JobInput input;
  input.bytes = test::off_text(mesh);
  input.format = io::Format::Off;
  input.threads = threads;
  return input;
}

TEST(JobRunner, OffInOffOutDenoises) {
  const NoisySphere s;
  const JobOutput out = run_job(off_job(s.noisy), io::Limits{});
  EXPECT_EQ(out.format, io::Format::Off);
  EXPECT_EQ(out.media_type, std::string(io::media_type(io::Format::Off)));
  ASSERT_EQ(out.effective.output.format, io::Format::Off);  // the default is echoed as resolved
  EXPECT_EQ(out.vertices, s.clean.num_vertices());
  EXPECT_EQ(out.faces, s.clean.num_faces());
  ASSERT_EQ(out.reports.size(), 1u);
  EXPECT_GE(out.reports[0].fold_ratio, 0.0);
  // The pipeline's stages run inside the denoise step: together they cannot take longer.
  const JobTimings& t = out.timings;
  EXPECT_GT(t.denoise_ms, 0.0);
  EXPECT_LE(t.setup_ms + t.measure_ms + t.initial_ms + t.region_ms + t.anisotropic_ms + t.normal_ms + t.vertex_ms,
            t.denoise_ms * 1.001 + 0.01);

  const TriMesh result = decode_single(out.bytes, io::Format::Off);
  ASSERT_EQ(result.F, s.clean.F);  // connectivity untouched
  const double before = msae(s.noisy, s.clean);
  const double after = msae(result, s.clean);
  EXPECT_LT(after, before / 4) << "before " << before << " after " << after;
}

// Decision 34: faces wound against their neighbours are filtered turned, written back as they
// came, and the job's notes say so.
TEST(JobRunner, MixedWindingIsDenoisedLikeTheConsistentMeshAndNamedInTheNotes) {
  const NoisySphere s;
  TriMesh mixed = s.noisy;
  for (std::int64_t f = 0; f < mixed.F.rows(); f += 4) std::swap(mixed.F(f, 1), mixed.F(f, 2));
  const JobOutput consistent = run_job(off_job(s.noisy), io::Limits{}), out = run_job(off_job(mixed), io::Limits{});
  const TriMesh a = decode_single(consistent.bytes, io::Format::Off), b = decode_single(out.bytes, io::Format::Off);
  EXPECT_EQ(b.F, mixed.F);
  EXPECT_TRUE(a.V == b.V);
  EXPECT_TRUE(consistent.notes.empty());
  ASSERT_EQ(out.notes.size(), 1u);
  EXPECT_NE(out.notes[0].find("wound against their neighbours"), std::string::npos) << out.notes[0];
}

TEST(JobRunner, SameBytesWhateverTheThreadCount) {
  const NoisySphere s;
  const JobOutput one = run_job(off_job(s.noisy, 1), io::Limits{});
  const JobOutput two = run_job(off_job(s.noisy, 2), io::Limits{});
  const JobOutput four = run_job(off_job(s.noisy, 4), io::Limits{});
  EXPECT_EQ(one.bytes, two.bytes);
  EXPECT_EQ(one.bytes, four.bytes);
  EXPECT_NE(one.bytes, off_job(s.noisy).bytes);  // and it did change something
}

// The CLI hands its input over: the bytes are freed once decoded (a 4.8M-face GLB's 87 MB are
// not held through the denoising), and the job gives what the const overload gives.
TEST(JobRunner, AnInputHandedOverIsFreedOnceDecoded) {
  const NoisySphere s;
  const JobInput kept = off_job(s.noisy);
  JobInput handed = kept;
  const JobOutput a = run_job(kept, io::Limits{});
  const JobOutput b = run_job(std::move(handed), io::Limits{});
  EXPECT_EQ(a.bytes, b.bytes);
  EXPECT_EQ(kept.bytes, test::off_text(s.noisy));  // the const overload leaves its input alone
  EXPECT_TRUE(handed.bytes.empty());               // NOLINT(bugprone-use-after-move): emptied, not moved
  EXPECT_LT(handed.bytes.capacity(), 64u);         // and its memory given back
}

TEST(JobRunner, ParametersReachThePipeline) {
  const NoisySphere s;
  JobInput input = off_job(s.noisy);
  const JobOutput defaults = run_job(input, io::Limits{});
  input.params.denoise.n_normal = 0;
  input.params.denoise.n_vertex = 0;
  input.params.denoise.n_aniso = 0;
  // Auto mode (the service's default) keeps only pinned fields: pin them, as the JSON parser does.
  for (const AutoField f : {AutoField::NNormal, AutoField::NVertex, AutoField::NAniso}) input.params.denoise.pin(f);
  const JobOutput light = run_job(input, io::Limits{});
  EXPECT_NE(light.bytes, defaults.bytes);
  EXPECT_EQ(light.effective.denoise.n_normal, 0);
  EXPECT_EQ(output_to_json(light)["params"]["n_normal"], 0);
  EXPECT_EQ(light.reports.at(0).params.n_normal, 0);  // what ran
  EXPECT_EQ(output_to_json(light)["reports"][0]["params"]["n_vertex"], 0);
  // Manual mode uses the values as set.
  input.params.denoise.mode = ParamMode::Manual;
  input.params.denoise.pinned = 0;
  const JobOutput manual = run_job(input, io::Limits{});
  EXPECT_EQ(manual.reports.at(0).params.n_normal, 0);
  EXPECT_EQ(manual.reports.at(0).params.alpha, DenoiseParams{}.alpha);
}

TEST(JobRunner, OutputFormatCanDifferFromInput) {
  const NoisySphere s;
  JobInput input = off_job(s.noisy);
  input.params.output.format = io::Format::Ply;
  const JobOutput out = run_job(input, io::Limits{});
  EXPECT_EQ(out.format, io::Format::Ply);
  const TriMesh result = decode_single(out.bytes, io::Format::Ply);
  EXPECT_EQ(result.F, s.clean.F);
  EXPECT_EQ(result.num_vertices(), s.clean.num_vertices());
}

TEST(JobRunner, SummaryJsonHasTheDocumentedShape) {
  const NoisySphere s;
  const JobOutput out = run_job(off_job(s.noisy), io::Limits{});
  const nlohmann::json j = output_to_json(out);
  EXPECT_EQ(j["format"], "off");
  EXPECT_EQ(j["vertices"], s.clean.num_vertices());
  EXPECT_EQ(j["faces"], s.clean.num_faces());
  EXPECT_EQ(j["bytes"], out.bytes.size());
  EXPECT_EQ(j["params"]["output"]["format"], "off");
  for (const char* key : {"decode", "setup", "measure", "initial_prefilter", "region_prefilter",
                          "anisotropic_prefilter", "normal_filter", "vertex_update", "denoise", "encode"}) {
    EXPECT_TRUE(j["timings_ms"][key].is_number()) << key;
  }
  ASSERT_EQ(j["reports"].size(), 1u);
  EXPECT_TRUE(j["reports"][0]["region_prefilter_applied"].is_boolean());
  EXPECT_TRUE(j["reports"][0]["fold_ratio"].is_number());
}

TEST(JobRunner, MalformedBytesThrowFormatError) {
  JobInput input;
  input.format = io::Format::Off;
  input.bytes = "OFF\n3 1 0\n0 0 0\n1 0 0\n";  // truncated: a vertex and the face are missing
  EXPECT_THROW(run_job(input, io::Limits{}), io::FormatError);
  input.bytes = "this is not a mesh";
  EXPECT_THROW(run_job(input, io::Limits{}), io::FormatError);
}

TEST(JobRunner, InvalidMeshThrowsInvalidMeshError) {
  TriMesh mesh = test::plane(3);
  mesh.V(4, 1) = std::numeric_limits<double>::quiet_NaN();
  JobInput input = off_job(mesh);
  // The adapter or the pipeline may be the one to notice; both throw an InvalidMeshError.
  EXPECT_THROW(run_job(input, io::Limits{}), InvalidMeshError);
}

TEST(JobRunner, LimitsAreEnforced) {
  const NoisySphere s;
  io::Limits limits;
  limits.max_faces = 100;
  EXPECT_THROW(run_job(off_job(s.noisy), limits), io::LimitError);
}

TEST(JobRunner, BadParamsAreRefusedBeforeDecoding) {
  JobInput input;
  input.format = io::Format::Off;
  input.bytes = "garbage that would be a FormatError";
  input.params.denoise.alpha = -1;
  try {
    run_job(input, io::Limits{});
    FAIL() << "accepted alpha -1";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "alpha");
  }
  input.params = JobParams{};
  input.params.output.position_bits = 40;
  try {
    run_job(input, io::Limits{});
    FAIL() << "accepted position_bits 40";
  } catch (const InvalidParamsError& e) {
    EXPECT_EQ(e.field(), "output.position_bits");
  }
}

class CancelAtOnce : public ProgressObserver {
 public:
  void on_progress(Stage, double) override { ++calls; }
  bool cancel_requested() override { return true; }
  int calls = 0;
};

class Recorder : public ProgressObserver {
 public:
  void on_progress(Stage stage, double fraction) override {
    ++calls;
    if (fraction < 0 || fraction > 1) bad = true;
    last_stage = stage;
  }
  int calls = 0;
  bool bad = false;
  Stage last_stage = Stage::InitialPrefilter;
};

TEST(JobRunner, ProgressIsReportedAndCancellationIsTyped) {
  const NoisySphere s;
  Recorder recorder;
  run_job(off_job(s.noisy), io::Limits{}, &recorder);
  EXPECT_GT(recorder.calls, 0);
  EXPECT_FALSE(recorder.bad);
  EXPECT_EQ(recorder.last_stage, Stage::VertexUpdate);

  CancelAtOnce cancel;
  EXPECT_THROW(run_job(off_job(s.noisy), io::Limits{}, &cancel), CancelledError);
}

}  // namespace
}  // namespace mdn::service
