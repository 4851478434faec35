// WorkerPool::submit with Submission::held, and settle(), used by the Redis store to start a job
// while Redis is still accepting it: a held run publishes its end (the finished hook, its final state) only
// once kept, and a run that was not accepted is never reported, whether it had ended or not.
// And a run's end is published with its worker given back (running() no longer counts it).
#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "server/http/jobs/worker_pool.h"
#include "support/shapes.h"

namespace mdn::http {
namespace {

using namespace std::chrono_literals;

service::JobInput off_input(int sphere_levels) {
  service::JobInput in;
  in.bytes = test::off_text(test::sphere(sphere_levels));
  in.format = io::Format::Off;
  return in;
}

struct Reported {
  std::atomic<int> count{0};
  JobFinishedHook hook() {
    return [this](const JobSnapshot&) { ++count; };
  }
};

WorkerPoolOptions one_worker() {
  WorkerPoolOptions o;
  o.workers = 1;
  return o;
}

// Waits until the pool's worker is done with everything it took (running() counts a run until
// its end has been handed over, published or held).
bool wait_idle(WorkerPool& q) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (q.running() == 0 && q.queued() == 0) return true;
    std::this_thread::sleep_for(5ms);
  }
  return false;
}

TEST(WorkerPoolHeld, AnEndedRunWaitsUnpublishedUntilKept) {
  Reported reported;
  WorkerPool q(one_worker(), reported.hook());
  auto job = q.submit("held", off_input(1), {.admit = false, .held = true});
  ASSERT_TRUE(wait_idle(q));
  EXPECT_EQ(job->state(), JobState::Running) << "held: the run's end is not published";
  EXPECT_FALSE(job->wait_for(0ms));
  EXPECT_EQ(reported.count, 0);
  q.settle(job, true);
  ASSERT_TRUE(job->wait_for(0ms));
  EXPECT_EQ(job->state(), JobState::Succeeded);
  EXPECT_EQ(reported.count, 1);
  q.settle(job, false);  // settling again changes nothing
  EXPECT_EQ(job->state(), JobState::Succeeded);
  EXPECT_EQ(reported.count, 1);
}

TEST(WorkerPoolHeld, AKeptRunStillRunningEndsAsUsual) {
  Reported reported;
  WorkerPool q(one_worker(), reported.hook());
  auto job = q.submit("kept", off_input(4), {.admit = false, .held = true});
  q.settle(job, true);
  ASSERT_TRUE(job->wait_for(60s));
  EXPECT_EQ(job->state(), JobState::Succeeded);
  EXPECT_EQ(reported.count, 1);
}

TEST(WorkerPoolHeld, ARunNotAcceptedIsNeverReported) {
  Reported reported;
  WorkerPool q(one_worker(), reported.hook());
  // Ended before the answer came.
  auto ended = q.submit("ended", off_input(1), {.admit = false, .held = true});
  ASSERT_TRUE(wait_idle(q));
  q.settle(ended, false);
  EXPECT_TRUE(ended->wait_for(0ms));
  // Still running (a 20k-face mesh): cancelled, and its end unreported too.
  auto running = q.submit("running", off_input(5), {.admit = false, .held = true});
  auto queued = q.submit("queued", off_input(1), {.admit = false, .held = true});  // behind it: the only worker is busy
  q.settle(running, false);
  q.settle(queued, false);
  ASSERT_TRUE(running->wait_for(60s));
  EXPECT_EQ(running->state(), JobState::Cancelled);
  ASSERT_TRUE(queued->wait_for(60s));
  EXPECT_EQ(queued->state(), JobState::Cancelled);
  ASSERT_TRUE(wait_idle(q));
  EXPECT_EQ(reported.count, 0);
  // An ordinary run on the same pool is reported as before.
  auto plain = q.submit("plain", off_input(1), {.admit = false});
  ASSERT_TRUE(plain->wait_for(60s));
  EXPECT_EQ(reported.count, 1);
}

// Whoever sees a job finished (the waiting request, a poll) and then reads running() (what
// GET /metrics shows as mdn_jobs_running) no longer finds it counted: the worker is given back
// as the end is published, not after. Repeated, since the old order failed only sometimes.
TEST(WorkerPool, AJobSeenFinishedIsNoLongerCountedRunning) {
  WorkerPool q(one_worker());
  int counted_after_end = 0;
  for (int i = 0; i < 200; ++i) {
    auto job = q.submit("job" + std::to_string(i), off_input(1), {.asynchronous = i % 2 == 1});
    ASSERT_TRUE(job->wait_for(60s));
    if (q.running() != 0) ++counted_after_end;
  }
  EXPECT_EQ(counted_after_end, 0) << "runs of 200 still counted as running after their end was seen";
}

}  // namespace
}  // namespace mdn::http
