#include "core/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

using namespace mdn;

namespace {

// Every index of [0, n) visited exactly once, by chunks that are contiguous and disjoint.
void expect_cover(Executor& ex, std::int64_t n, std::int64_t grain) {
  std::vector<std::atomic<int>> hits(static_cast<std::size_t>(n));
  auto body = [&](std::int64_t b, std::int64_t e) {
    ASSERT_LE(0, b);
    ASSERT_LE(b, e);
    ASSERT_LE(e, n);
    for (std::int64_t i = b; i < e; ++i) hits[static_cast<std::size_t>(i)].fetch_add(1);
  };
  if (grain > 0)
    ex.parallel_for(n, grain, body);
  else
    ex.parallel_for(n, body);
  for (std::int64_t i = 0; i < n; ++i) ASSERT_EQ(hits[static_cast<std::size_t>(i)].load(), 1) << "n " << n << " grain " << grain << " i " << i;
}

}  // namespace

TEST(Executor, CoversEveryIndexOnceForAnySizeGrainAndThreadCount) {
  for (int threads : {1, 2, 3, 8}) {
    Executor ex(threads);
    for (std::int64_t n : {0, 1, 2, 7, 100, 4097, 100000})
      for (std::int64_t grain : {0, 1, 16, 4096, 1 << 20}) expect_cover(ex, n, grain);
  }
}

TEST(Executor, ManyShortTasksInARowNeverMixTheirChunks) {
  // Workers that wake late must not run a finished task's chunks (generation-tagged claims).
  Executor ex(4);
  std::vector<std::int64_t> out(64);
  for (int task = 0; task < 20000; ++task) {
    ex.parallel_for(static_cast<std::int64_t>(out.size()), 4, [&](std::int64_t b, std::int64_t e) {
      for (std::int64_t i = b; i < e; ++i) out[static_cast<std::size_t>(i)] = task;
    });
    for (std::int64_t v : out) ASSERT_EQ(v, task);
  }
}

TEST(Executor, TheCallerTakesTheChunksOfABusyWorker) {
  // One chunk sleeps; the others are all done by the time it ends, on whichever thread was free.
  Executor ex(2);
  std::atomic<int> chunks{0};
  const auto t0 = std::chrono::steady_clock::now();
  ex.parallel_for(64, 1, [&](std::int64_t b, std::int64_t) {
    if (b == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    chunks.fetch_add(1);
  });
  EXPECT_EQ(chunks.load(), 64);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(50));
}

TEST(Executor, AWorkerJoinsWhetherItSpinsOrSleeps) {
  // Decision 47: right after a task the worker spins; after a long pause it sleeps. Either way
  // it must take a chunk of the next task: each of the two chunks waits (up to 5 s) until both
  // have started, which only two threads can achieve.
  Executor ex(2);
  const auto both_start = [&] {
    std::atomic<int> started{0};
    std::atomic<bool> together{true};
    ex.parallel_for(4, [&](std::int64_t, std::int64_t) {  // two chunks of two
      started.fetch_add(1);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
      while (started.load() < 2)
        if (std::chrono::steady_clock::now() > deadline) {
          together = false;
          return;
        }
    });
    return together.load();
  };
  EXPECT_TRUE(both_start());  // the workers were just created
  EXPECT_TRUE(both_start());  // right after a task: spinning
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(both_start());  // after a pause far longer than the spin: asleep
}
