// The one JSON view of a job's output: the timings table, and output_to_json / output_from_json
// as inverses (the Redis store relies on it to answer for a job another replica ran).
#include "service/job_json.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "support/shapes.h"

namespace mdn::service {
namespace {

using nlohmann::json;

TEST(JobTimings, EveryFieldHasItsOwnNameAndMember) {
  std::set<std::string_view> names;
  JobTimings t;
  double value = 1;
  for (const TimingField& f : kTimingFields) {
    EXPECT_TRUE(names.insert(f.name).second) << f.name;
    EXPECT_EQ(t.*f.member, 0.0) << f.name << " shares a member with an earlier field";
    t.*f.member = value++;
  }
  EXPECT_EQ(sizeof(JobTimings), std::size(kTimingFields) * sizeof(double)) << "a member is missing from the table";
}

TEST(JobTimings, StageTimingsAddUpPerSurface) {
  StageTimings a;
  a.setup_ms = 1, a.measure_ms = 2, a.initial_ms = 3, a.region_ms = 4, a.anisotropic_ms = 5, a.normal_ms = 6,
  a.vertex_ms = 7, a.total_ms = 100;
  JobTimings sum;
  add_stage_timings(sum, a);
  add_stage_timings(sum, a);
  int from_stages = 0;
  for (const TimingField& f : kTimingFields) {
    // decode, denoise and encode are measured by run_job around the pipelines, not summed.
    EXPECT_EQ(sum.*f.member, f.stage ? 2 * (a.*f.stage) : 0.0) << f.name;
    from_stages += f.stage != nullptr;
  }
  EXPECT_EQ(from_stages, 7);  // every StageTimings member but total_ms
  EXPECT_EQ(sum.vertex_ms, 14);
}

TEST(JobTimings, JsonUsesTheTableNamesAndReadsMissingAsZero) {
  JobTimings t;
  t.normal_ms = 12.5;
  t.decode_ms = 3;
  const json j = timings_to_json(t);
  EXPECT_EQ(j.size(), std::size(kTimingFields));
  EXPECT_EQ(j["normal_filter"], 12.5);
  EXPECT_EQ(j["decode"], 3.0);
  const JobTimings back = timings_from_json(json{{"vertex_update", 4.0}});
  EXPECT_EQ(back.vertex_ms, 4.0);
  EXPECT_EQ(back.normal_ms, 0.0);
  EXPECT_THROW(timings_from_json(json{{"vertex_update", "slow"}}), json::exception);
}

JobOutput sample_output() {
  JobInput input;
  input.format = io::Format::Off;
  input.bytes = test::off_text(test::sphere(1));
  input.params.denoise.mode = ParamMode::Manual;
  return run_job(input, io::Limits{});
}

TEST(JobJson, OutputRoundTripsThroughJson) {
  const JobOutput out = sample_output();
  const json j = output_to_json(out);
  EXPECT_EQ(j["bytes"], out.bytes.size());
  ASSERT_EQ(j["reports"].size(), 1u);
  EXPECT_EQ(j["reports"][0]["mode"], "manual");

  json reports;
  std::int64_t bytes = 0;
  const JobOutput back = output_from_json(j, reports, bytes);
  EXPECT_EQ(bytes, std::int64_t(out.bytes.size()));
  EXPECT_EQ(reports, j["reports"]);
  EXPECT_TRUE(back.bytes.empty());
  EXPECT_TRUE(back.reports.empty());
  EXPECT_EQ(back.format, out.format);
  EXPECT_EQ(back.media_type, out.media_type);
  EXPECT_EQ(back.vertices, out.vertices);
  EXPECT_EQ(back.faces, out.faces);
  EXPECT_EQ(to_json(back.effective), to_json(out.effective));
  EXPECT_EQ(back.notes, out.notes);
  EXPECT_EQ(timings_to_json(back.timings), timings_to_json(out.timings));
  // And written again, the same document.
  EXPECT_EQ(output_to_json(back, bytes, reports), j);
}

// What the Redis store keeps: an STL result and a Draco glTF one read back with their format
// and compression (format_from_string names STL since issue 18).
TEST(JobJson, StlAndCompressionRoundTrip) {
  for (const char* output : {R"({"mode":"none","output":{"format":"stl"}})",
                             R"({"mode":"none","output":{"format":"glb","compression":"draco"}})"}) {
    JobInput input;
    input.format = io::Format::Off;
    input.bytes = test::off_text(test::sphere(1));
    input.params = job_params_from_text(output);
    const JobOutput out = run_job(input, io::Limits{});
    const json j = output_to_json(out);
    json reports;
    std::int64_t bytes = 0;
    const JobOutput back = output_from_json(j, reports, bytes);
    EXPECT_EQ(back.format, out.format) << output;
    EXPECT_EQ(back.compression, out.compression) << output;
    EXPECT_EQ(output_to_json(back, bytes, reports), j) << output;
  }
}

TEST(JobJson, ADocumentWithoutARequiredPartIsRefused) {
  json j = output_to_json(sample_output());
  j.erase("params");
  json reports;
  std::int64_t bytes = 0;
  EXPECT_THROW(output_from_json(j, reports, bytes), json::exception);
}

}  // namespace
}  // namespace mdn::service
