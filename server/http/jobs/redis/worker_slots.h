// This replica's worker slots (one thread per --workers) and their finisher thread. A slot waits
// for a job (handed over by submit(), taken over from a silent worker with XAUTOCLAIM, or the
// next new one by lua/take.lua), runs it on the local WorkerPool with a check every 200 ms and
// heartbeats, and pushes the finished job to the finisher, which stores result and state
// (lua/finish.lua) while the slot takes its next job. A job this replica stops running goes
// back to the queue (lua/release.lua), not counted as an attempt.
//
// Thread-safety contract. From request threads: Reservation (submit's hand-over),
// start_fields(), cancelled_problem(), busy() and the counters; from the store's constructor:
// start(); from its stop(), once, after it set the stop flag: stop(). The rest runs on the slot
// threads and the finisher; the configuration, names and problem texts are constant.
// handoff_mutex_ guards handoffs_, idle_slots_ and reserved_ (handoff_cv_ wakes a slot waiting
// for a hand-over); stop() empties handoffs_ once the slots have ended. reclaim_mutex_ guards
// next_reclaim_; finishes_ has its own lock (work_queue.h). busy_ and the counters are
// atomics. The store's drain and stop flags are read, never written: draining, no slot is
// reserved and a slot takes no new job but runs those already handed over; stopping, a slot
// cancels its running job and releases it, then ends, and the finisher stores what is queued
// while Redis answers.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "server/http/config.h"
#include "server/http/jobs/worker_pool.h"
#include "server/http/log.h"
#include "server/http/jobs/redis/monitor.h"
#include "server/http/jobs/redis/recent_results.h"
#include "server/http/jobs/redis/script_args.h"
#include "server/http/jobs/redis/shared.h"
#include "server/http/jobs/redis/work_queue.h"

namespace mdn::http::redis {

// What lua/take.lua, lua/start.lua or lua/submit_start.lua answered.
struct Taken {
  std::string outcome;  // run, none, gone, done, cancelled, exhausted, lost
  int attempt = 0;
  std::string previous, input, format, params, entry_id, job_id;
  bool reclaimed = false;
  std::shared_ptr<Job> early;  // started by submit() while Redis accepted it (then no input)
};
Taken parse_taken(const Reply& r);

class WorkerSlots {
 public:
  // `ttl_ms`: --result-ttl in ms, as the scripts take it; `recent`: where the finisher keeps
  // the results it stored.
  WorkerSlots(const ServerConfig& config, WorkerPool& worker_pool, std::shared_ptr<const EventLog> log, const Pool& pool,
              Monitor& monitor, const Keys& keys, const std::string& ttl_ms, const std::atomic<bool>& draining,
              const std::atomic<bool>& stopping, RecentResults& recent);
  WorkerSlots(const WorkerSlots&) = delete;
  WorkerSlots& operator=(const WorkerSlots&) = delete;

  void start(int slots);  // the finisher and `slots` slot threads
  // Joins the slots, releases the jobs handed over to none (while Redis answers), lets the
  // finisher store what is queued, joins it.
  void stop();

  // What every start of a job by this replica passes to lua/start_job.lua.
  StartFields start_fields() const;
  // The error stored for a job cancelled before it started (lua/start_job.lua, lua/cancel.lua).
  const std::string& cancelled_problem() const { return cancelled_problem_; }

  // A worker slot of this replica reserved by submit() for a job it accepts and starts in one
  // step (lua/submit_start.lua); released unused when the job could not start at once (others
  // waited). Rarely, the reserved slot takes another job meanwhile (lua/take.lua in flight): the
  // handed job then waits for the first free slot of this replica.
  class Reservation {
   public:
    explicit Reservation(WorkerSlots& s);
    Reservation(const Reservation&) = delete;
    Reservation& operator=(const Reservation&) = delete;
    ~Reservation() { release(std::nullopt); }
    explicit operator bool() const { return held_; }
    // The started job, for the waiting slot (counted as busy from now on, like a taken one).
    void hand(Taken t) { release(std::move(t)); }

   private:
    void release(std::optional<Taken> t);
    WorkerSlots& s_;
    bool held_ = false;
  };

  int busy() const { return busy_; }  // jobs taken and not yet stored (running, or waiting for the finisher)
  std::int64_t reclaimed() const { return reclaimed_; }
  std::int64_t retries() const { return retries_; }
  std::int64_t exhausted() const { return exhausted_; }

 private:
  struct Finish {
    std::string job_id, entry_id, state, error, summary, result, finished_ms, result_bytes;
  };

  void slot_loop();
  std::optional<Taken> take_handoff(bool& idle, bool wait);
  std::optional<Taken> pop_handoff_locked();
  void leave_idle(bool& idle);
  Taken next_job(Connection& c, std::string& last_id);
  void run_taken(std::unique_ptr<Connection>& c, Taken t);
  void process(std::unique_ptr<Connection>& conn, Taken t);
  // How a run ended for this replica: finished here, lost to another replica, or released
  // (this replica stops: the job goes back to the stream).
  enum class RunEnd { Finished, Lost, Released };
  // Waits for `job`, with a read-only check every 200 ms and heartbeats carrying its progress;
  // cancels it when the user DELETEs it (`cancel_by_user`), another replica took it over or
  // this replica stops.
  RunEnd watch(std::unique_ptr<Connection>& conn, const Taken& e, const std::shared_ptr<Job>& job, bool& cancel_by_user);
  void release(std::unique_ptr<Connection>& c, const Taken& e);
  void finisher_loop();
  template <class F>
  bool retry(std::unique_ptr<Connection>& c, F&& f);

  const ServerConfig& config_;
  WorkerPool& worker_pool_;
  const std::shared_ptr<const EventLog> log_;
  const Pool& pool_;
  Monitor& monitor_;
  const Keys& keys_;
  const std::string& ttl_ms_;
  const std::atomic<bool>& draining_;
  const std::atomic<bool>& stopping_;
  RecentResults& recent_;
  const std::int64_t reclaim_idle_ms_;
  const std::string exhausted_problem_, cancelled_problem_, lost_problem_;  // stored as a job's error

  std::atomic<int> busy_{0};
  std::atomic<std::int64_t> reclaimed_{0}, retries_{0}, exhausted_{0};

  // Jobs submit() started for this replica's idle slots (lua/submit_start.lua).
  std::mutex handoff_mutex_;
  std::condition_variable handoff_cv_;
  std::deque<Taken> handoffs_;
  int idle_slots_ = 0;  // slots waiting for work
  int reserved_ = 0;    // of those, promised to a submit() in flight
  // Test hook (MDN_TEST_HANDOFF_PICKUP_DELAY_MS; tests/integration/redis_queue_test.cpp): a slot
  // handed a job waits this long before picking it up, which widens the window in which the
  // slot still counts as idle; never set in production.
  std::chrono::milliseconds handoff_pickup_delay_{0};

  std::mutex reclaim_mutex_;
  Clock::time_point next_reclaim_ = Clock::now();

  WorkQueue<Finish> finishes_;  // slots -> the finisher
  std::thread finisher_;
  std::vector<std::thread> slots_;
};

}  // namespace mdn::http::redis
