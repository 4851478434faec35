// The long polls (GET /v1/jobs/{id}?wait=) waiting on this replica, per job. Every script that
// ends a job publishes its id on <prefix>done; the store's subscriber calls done(id), which wakes
// that job's waiters, who then read the job once. wake_all() (the subscriber reconnected, a drain
// or a stop) makes every waiter read its job again.
//
// Thread-safety contract: every method may be called from any thread; one mutex guards the
// table and one condition variable wakes the waiters. A Ticket belongs to the thread that
// entered it.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <unordered_map>

namespace mdn::http::redis {

class FinishWaiters {
 public:
  using Clock = std::chrono::steady_clock;

  // One waiter on one job, registered before the caller's first read of the job (so a "done"
  // between that read and the wait is not missed); leaves the table when destroyed.
  class Ticket {
   public:
    Ticket(const Ticket&) = delete;
    Ticket& operator=(const Ticket&) = delete;
    ~Ticket() { owner_.leave(id_); }

   private:
    friend class FinishWaiters;
    Ticket(FinishWaiters& owner, std::string id, std::uint64_t seen) : owner_(owner), id_(std::move(id)), seen_(seen) {}
    FinishWaiters& owner_;
    const std::string id_;
    std::uint64_t seen_;
  };

  Ticket enter(const std::string& id);
  // Blocks until the ticket's job is done (or wake_all), `until` passes, or give_up() holds
  // (checked on each wake-up).
  void wait(Ticket& ticket, Clock::time_point until, const std::function<bool()>& give_up);
  void done(const std::string& id);
  void wake_all();

 private:
  void leave(const std::string& id);

  struct Entry {
    int count = 0;           // tickets on the job
    std::uint64_t done = 0;  // bumped by each done(id) or wake_all()
  };
  std::mutex mutex_;
  std::condition_variable cv_;
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace mdn::http::redis
