// ExitWatchdog (server/exit_watchdog.h): after the drain, main() arms it so that a worker
// stuck in a step that polls no cancellation cannot keep the process alive past the bound.
#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "server/exit_watchdog.h"

namespace mdn::http {
namespace {

using namespace std::chrono_literals;

TEST(ExitWatchdog, FiresOnceTheBoundPassesWithoutADisarm) {
  std::atomic<int> fired{0};
  const auto start = std::chrono::steady_clock::now();
  std::atomic<std::int64_t> after_ms{0};
  {
    ExitWatchdog w([&] {
      after_ms = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start).count();
      ++fired;
    });
    w.arm(100ms);
    w.arm(10s);  // a second arm keeps the first deadline
    // A shutdown stuck past the bound (the destructor would join a stuck worker).
    const auto deadline = start + 5s;
    while (fired == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(fired, 1);
  EXPECT_GE(after_ms, 100);
  EXPECT_LT(after_ms, 2000);
}

TEST(ExitWatchdog, AShutdownDoneInTimeDisarmsIt) {
  std::atomic<int> fired{0};
  {
    ExitWatchdog w([&] { ++fired; });
    w.arm(200ms);
    w.disarm();
    std::this_thread::sleep_for(300ms);
  }
  EXPECT_EQ(fired, 0);
  ExitWatchdog never_armed([&] { ++fired; });  // destroyed without a thread
  EXPECT_EQ(fired, 0);
}

}  // namespace
}  // namespace mdn::http
