#include "server/exit_watchdog.h"

#include <utility>

namespace mdn::http {

ExitWatchdog::ExitWatchdog(std::function<void()> on_expired) : on_expired_(std::move(on_expired)) {}

ExitWatchdog::~ExitWatchdog() {
  disarm();
  if (thread_.joinable()) thread_.join();
}

void ExitWatchdog::arm(std::chrono::milliseconds bound) {
  std::lock_guard lock(mutex_);
  if (armed_ || disarmed_) return;
  armed_ = true;
  const auto deadline = std::chrono::steady_clock::now() + bound;
  thread_ = std::thread([this, deadline] {
    {
      std::unique_lock lock(mutex_);
      if (cv_.wait_until(lock, deadline, [&] { return disarmed_; })) return;
    }
    on_expired_();
  });
}

void ExitWatchdog::disarm() {
  {
    std::lock_guard lock(mutex_);
    disarmed_ = true;
  }
  cv_.notify_all();
}

}  // namespace mdn::http
