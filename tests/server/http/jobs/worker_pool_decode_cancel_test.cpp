// The job's time limit and DELETE reach the decoder (issue 17, "every loop bounded"): a job
// whose input takes long to decode ends within its time limit (failed, time-limit-exceeded)
// or soon after its cancellation (cancelled), not when the decoder is done. The input is a
// large ASCII OFF generated here; its decode time is measured first, so the assertions hold
// on slow and fast machines alike.
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "server/http/jobs/memory_job_store.h"
#include "server/http/jobs/worker_pool.h"

namespace mdn::http {
namespace {

using namespace std::chrono_literals;
using Seconds = std::chrono::duration<double>;

// n x n vertices on a grid, two triangles per cell: about 20 bytes a vertex and a face.
std::string big_off(int n) {
  std::string out = "OFF\n" + std::to_string(n * n) + " " + std::to_string(2 * (n - 1) * (n - 1)) + " 0\n";
  out.reserve(std::size_t(n) * n * 40);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) out += std::to_string(i) + " " + std::to_string(j) + " 0\n";
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      out += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + "\n";
      out += "3 " + std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(c) + "\n";
    }
  return out;
}

struct Fixture {
  std::string bytes = big_off(800);  // 640 k vertices, 1.3 M faces, about 36 MB
  double decode_s = 0;
  Fixture() {
    const auto start = Clock::now();
    io::Limits limits;
    io::decode(bytes, io::Format::Off, limits);
    decode_s = Seconds(Clock::now() - start).count();
    std::printf("decoding the %zu-byte OFF alone takes %.3f s\n", bytes.size(), decode_s);
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

service::JobInput input() {
  service::JobInput in;
  in.bytes = fixture().bytes;
  in.format = io::Format::Off;
  return in;
}

TEST(WorkerPoolDecodeCancel, TheTimeLimitStopsADecode) {
  const double decode_s = fixture().decode_s;
  WorkerPoolOptions o;
  o.workers = 1;
  o.time_limit = std::chrono::milliseconds(std::int64_t(decode_s * 1000 / 10));  // a tenth of the decode
  WorkerPool pool(o);
  MemoryJobStore q(pool);
  auto job = q.job(q.submit(input(), std::nullopt, "", {}).job.id);
  ASSERT_TRUE(job->wait_for(60s));
  const JobSnapshot s = job->snapshot();
  EXPECT_EQ(s.state, JobState::Failed);
  ASSERT_TRUE(s.error);
  EXPECT_EQ(s.error->type, "time-limit-exceeded");
  EXPECT_EQ(s.stage, "decode");
  const double limit_s = Seconds(o.time_limit).count();
  std::printf("time limit %.3f s: the job ran %.3f s (the decode alone takes %.3f s)\n", limit_s, s.run_s, decode_s);
  EXPECT_LT(s.run_s, limit_s + std::max(0.05, decode_s / 4)) << "stopped within the limit plus a few polls";
}

TEST(WorkerPoolDecodeCancel, DeleteStopsADecode) {
  const double decode_s = fixture().decode_s;
  WorkerPoolOptions o;
  o.workers = 1;
  WorkerPool pool(o);
  MemoryJobStore q(pool);
  auto job = q.job(q.submit(input(), std::nullopt, "", {}).job.id);
  const auto deadline = Clock::now() + 30s;
  while (job->state() == JobState::Queued && Clock::now() < deadline) std::this_thread::sleep_for(1ms);
  std::this_thread::sleep_for(std::chrono::milliseconds(std::int64_t(decode_s * 1000 / 10)));  // inside the decode
  const auto cancelled = Clock::now();
  ASSERT_EQ(q.cancel(job->id()).outcome, JobStore::CancelOutcome::CancelRequested);
  ASSERT_TRUE(job->wait_for(60s));
  const double stop_s = Seconds(Clock::now() - cancelled).count();
  const JobSnapshot s = job->snapshot();
  EXPECT_EQ(s.state, JobState::Cancelled);
  EXPECT_EQ(s.stage, "decode");
  std::printf("DELETE during the decode: stopped %.1f ms later (the decode alone takes %.3f s)\n", stop_s * 1000, decode_s);
  EXPECT_LT(stop_s, std::max(0.05, decode_s / 4));
}

}  // namespace
}  // namespace mdn::http
