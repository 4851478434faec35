// Long polls of the Redis store: a waiter wakes on its job's "done", on wake_all, at its deadline.
#include "server/http/jobs/redis/finish_waiters.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace mdn::http::redis {
namespace {

using namespace std::chrono_literals;
using Clock = FinishWaiters::Clock;

TEST(FinishWaiters, ADoneMessageWakesThatJobsWaitersOnly) {
  FinishWaiters w;
  std::atomic<bool> a_woke{false}, b_woke{false};
  std::thread a([&] {
    auto t = w.enter("a");
    w.wait(t, Clock::now() + 10s, [] { return false; });
    a_woke = true;
  });
  std::thread b([&] {
    auto t = w.enter("b");
    w.wait(t, Clock::now() + 600ms, [] { return false; });
    b_woke = true;
  });
  std::this_thread::sleep_for(100ms);
  w.done("a");
  a.join();
  EXPECT_TRUE(a_woke);
  EXPECT_FALSE(b_woke);  // still waiting for its own job (or its deadline)
  b.join();
}

TEST(FinishWaiters, ADoneBetweenEnterAndWaitIsNotMissed) {
  FinishWaiters w;
  auto t = w.enter("a");
  w.done("a");  // before the wait: the ticket has seen the old count
  const auto start = Clock::now();
  w.wait(t, start + 5s, [] { return false; });
  EXPECT_LT(Clock::now() - start, 1s);
}

TEST(FinishWaiters, WakeAllAndGiveUpEndTheWaitAndTheDeadlineHolds) {
  FinishWaiters w;
  {
    auto t = w.enter("a");
    std::thread waker([&] {
      std::this_thread::sleep_for(50ms);
      w.wake_all();
    });
    const auto start = Clock::now();
    w.wait(t, start + 5s, [] { return false; });
    EXPECT_LT(Clock::now() - start, 1s);
    waker.join();
  }
  auto t = w.enter("a");
  const auto start = Clock::now();
  w.wait(t, start + 100ms, [] { return false; });
  EXPECT_GE(Clock::now() - start, 100ms);
  w.wait(t, Clock::now() + 5s, [] { return true; });  // gives up at once
  w.done("nobody");  // a job nobody waits for: nothing to wake
}

}  // namespace
}  // namespace mdn::http::redis
