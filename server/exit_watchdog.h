// Bounds the end of a shutdown. After the drain (or a forced stop) the server still stops the
// store, the HTTP listener and joins its workers; a worker stuck in a step that cannot be
// interrupted (Draco's decoder or encoder, which poll no cancellation) would hold the process
// forever. main() arms this watchdog when the drain ends; if the shutdown is not done within
// the bound, `on_expired` runs (main: log the stuck jobs, flush, std::_Exit(1) without joining).
//
// Thread-safety contract: arm() and disarm() may be called from any thread; on_expired runs on
// the watchdog's own thread, at most once, and must not call back into the watchdog. The
// destructor disarms and joins.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace mdn::http {

class ExitWatchdog {
 public:
  explicit ExitWatchdog(std::function<void()> on_expired);
  ~ExitWatchdog();
  ExitWatchdog(const ExitWatchdog&) = delete;
  ExitWatchdog& operator=(const ExitWatchdog&) = delete;

  // Starts the countdown (a second call keeps the first deadline).
  void arm(std::chrono::milliseconds bound);
  // The shutdown finished in time: on_expired will not run.
  void disarm();

 private:
  std::function<void()> on_expired_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool armed_ = false, disarmed_ = false;
  std::thread thread_;
};

}  // namespace mdn::http
