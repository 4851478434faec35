// Whether Redis answers, as this replica sees it, and the monitor thread: every second (every
// 250 ms while Redis is down) a PING, the shared queue's length and pending count (for /metrics
// and /readyz), the consumer group made again if Redis lost it; every minute, the consumers gone
// for an hour with nothing pending are forgotten. Any thread whose command fails marks Redis
// down (mark_down), which wakes the monitor at once; only a successful round marks it up again
// (mark_up), but for the store's first attempt at startup.
//
// Thread-safety contract: up(), length(), pending(), reconnects(), mark_up() and mark_down() may
// be called from any thread: the state is atomics (up_ and ever_up_ change by exchange, so each
// change is logged once). length_ and pending_ are written by the monitor thread only. The mutex
// guards nothing but the monitor's sleep (its condition variable); the thread ends at its next
// wake-up once the store's stop flag is set, and join() wakes it and waits for it.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "server/http/log.h"
#include "server/http/jobs/redis/shared.h"

namespace mdn::http::redis {

class Monitor {
 public:
  // `pool`: cleared on mark_down (its connections are likely broken); the monitor's own
  // connection goes to the same address. `stopping`: the store's stop flag.
  Monitor(Pool& pool, const Keys& keys, std::shared_ptr<const EventLog> log, const std::atomic<bool>& stopping)
      : pool_(pool), keys_(keys), log_(std::move(log)), stopping_(stopping) {}
  Monitor(const Monitor&) = delete;
  Monitor& operator=(const Monitor&) = delete;

  void start();
  void join();  // after the stop flag is set

  bool up() const { return up_; }
  void mark_up();
  void mark_down(const std::string& why);

  std::int64_t length() const { return length_; }    // waiting for a worker of any replica
  std::int64_t pending() const { return pending_; }  // taken by a worker of any replica
  std::int64_t reconnects() const { return reconnects_; }

 private:
  void loop();

  Pool& pool_;
  const Keys& keys_;
  const std::shared_ptr<const EventLog> log_;
  const std::atomic<bool>& stopping_;

  std::atomic<bool> up_{false}, ever_up_{false};
  std::atomic<std::int64_t> length_{0}, pending_{0}, reconnects_{0};

  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread thread_;
};

}  // namespace mdn::http::redis
