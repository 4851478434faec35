// The Redis store's job codec without a Redis server: a job's hash -> JobSnapshot, and the
// stored forms of its error and output.
#include "server/http/jobs/redis/job_codec.h"

#include <gtest/gtest.h>

#include "service/job_json.h"
#include "support/shapes.h"

namespace mdn::http::redis {
namespace {

TEST(RedisJobCodec, AQueuedJobWaitsSinceItWasCreated) {
  const std::int64_t created = now_ms() - 1500;
  const JobSnapshot s = snapshot_from_hash("ab12", {{"state", "queued"}, {"created_ms", std::to_string(created)},
                                                    {"input_bytes", "42"}}, std::nullopt);
  EXPECT_EQ(s.id, "ab12");
  EXPECT_TRUE(s.asynchronous);
  EXPECT_EQ(s.state, JobState::Queued);
  EXPECT_EQ(s.stage, "queued");
  EXPECT_EQ(s.input_bytes, 42);
  EXPECT_NEAR(s.queue_wait_s, 1.5, 0.5);
  EXPECT_EQ(s.run_s, 0.0);
  EXPECT_FALSE(s.output);
}

TEST(RedisJobCodec, AFinishedJobsTimesComeFromItsHashAlone) {
  const JobSnapshot s = snapshot_from_hash(
      "cd34", {{"state", "failed"}, {"created_ms", "1000"}, {"started_ms", "1250"}, {"finished_ms", "4250"},
               {"stage", "normal_filter"}, {"fraction", "7"}, {"attempts", "2"}, {"cancel", "1"},
               {"error", problem_text(make_problem(ProblemType::SolverFailed, "not positive definite"))}},
      std::nullopt);
  EXPECT_EQ(s.state, JobState::Failed);
  EXPECT_DOUBLE_EQ(s.queue_wait_s, 0.25);
  EXPECT_DOUBLE_EQ(s.run_s, 3.0);
  EXPECT_EQ(s.fraction, 1.0);  // clamped
  EXPECT_EQ(s.attempts, 2);
  EXPECT_TRUE(s.cancel_requested);
  ASSERT_TRUE(s.error);
  EXPECT_EQ(s.error->type, "solver-failed");
  EXPECT_EQ(s.error->status, 422);
  EXPECT_EQ(s.error->detail, "not positive definite");
}

TEST(RedisJobCodec, UnknownStatesAndGarbageFailSafely) {
  const JobSnapshot s = snapshot_from_hash("x", {{"state", "exploded"}, {"attempts", "many"}}, std::nullopt);
  EXPECT_EQ(s.state, JobState::Failed);
  EXPECT_EQ(s.attempts, 0);
  EXPECT_EQ(to_int("12", -1), 12);
  EXPECT_EQ(to_int("", -1), -1);
  EXPECT_EQ(to_int("1e9x", -1), 1);  // stoll reads the leading digits
  EXPECT_EQ(to_double("nope"), 0.0);
  EXPECT_FALSE(problem_from_text(""));
  ASSERT_TRUE(problem_from_text("{not json"));
  EXPECT_EQ(problem_from_text("{not json")->type, "internal");
}

TEST(RedisJobCodec, ProblemsKeepTheirExtensions) {
  Problem p = make_problem(ProblemType::ResultTooLarge, "too big");
  p.extensions["maximum"] = 1024;
  const auto back = problem_from_text(problem_text(p));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->status, 422);
  EXPECT_EQ(back->title, p.title);
  EXPECT_EQ(back->extensions["maximum"], 1024);
}

TEST(RedisJobCodec, ASucceededJobCarriesItsOutputAndTheResultOnlyWhenAsked) {
  service::JobInput input;
  input.format = io::Format::Off;
  input.bytes = test::off_text(test::sphere(1));
  input.params.denoise.mode = ParamMode::Manual;
  const service::JobOutput out = service::run_job(input, io::Limits{});
  std::map<std::string, std::string> hash = {{"state", "succeeded"}, {"created_ms", "1"}, {"started_ms", "2"},
                                             {"finished_ms", "3"}, {"output", output_text(out)},
                                             {"output_bytes", std::to_string(out.bytes.size())}};
  const JobSnapshot summary = snapshot_from_hash("ef", hash, std::nullopt);
  ASSERT_TRUE(summary.output);
  EXPECT_TRUE(summary.output->bytes.empty());
  EXPECT_EQ(summary.output_bytes, std::int64_t(out.bytes.size()));
  ASSERT_TRUE(summary.reports);
  EXPECT_EQ(*summary.reports, service::reports_to_json(out.reports));
  EXPECT_EQ(summary.output->faces, out.faces);
  const JobSnapshot full = snapshot_from_hash("ef", hash, out.bytes);
  EXPECT_EQ(full.output->bytes, out.bytes);
}

}  // namespace
}  // namespace mdn::http::redis
