// The worker pool: threads that run jobs, the run queue they take them from (bounded for the
// jobs it admits), cancellation, the time limit, progress and the finished hook. It keeps no
// job beyond its run: where asynchronous jobs live is a JobStore's business (job_store.h:
// MemoryJobStore in this process, RedisJobStore in Redis); both, and the synchronous
// POST /v1/denoise, hand it jobs through submit(). HTTP threads never run the pipeline.
//
// Thread-safety contract: every public method of WorkerPool and Job may be called from any
// thread at any time. WorkerPool::mutex_ guards the run queue and the counters; each Job's own
// mutex guards its state, progress and result. Lock order: a store's mutex, then the pool's,
// then a job's, never the reverse; the pool never calls into a store. Workers never hold the
// pool's mutex while running a job. A Job's output, once published, is immutable and shared
// (std::shared_ptr<const>).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/io/document.h"
#include "server/http/jobs/job.h"
#include "server/http/jobs/queued_bytes.h"
#include "server/http/problem.h"
#include "service/job_runner.h"

namespace mdn::http {

class Job {
 public:
  Job(std::string id, service::JobInput input, bool asynchronous);
  const std::string& id() const { return id_; }
  bool asynchronous() const { return asynchronous_; }
  JobSnapshot snapshot() const;
  JobState state() const;
  // When its end was published; nullopt while queued or running.
  std::optional<Clock::time_point> finished_at() const;
  // Blocks until the job is finished or the timeout passes; true when finished.
  bool wait_for(std::chrono::milliseconds timeout) const;
  // Marks the result as fetched by a client (the drain counts the results nobody fetched).
  void mark_result_fetched();
  bool result_fetched() const;

 private:
  friend class WorkerPool;
  class Observer;

  const std::string id_;
  const bool asynchronous_;
  const Clock::time_point created_ = Clock::now();
  const std::chrono::system_clock::time_point created_wall_ = std::chrono::system_clock::now();
  std::atomic<bool> cancel_{false};

  mutable std::mutex mutex_;
  mutable std::condition_variable done_cv_;
  service::JobInput input_;  // released when the job starts running
  std::int64_t input_bytes_ = 0;
  QueuedBytes::Hold queued_bytes_;  // released with input_ (decision 79)
  JobState state_ = JobState::Queued;
  std::string stage_ = "queued";
  double fraction_ = 0;
  std::optional<Clock::time_point> started_, finished_;
  std::optional<Problem> error_;
  std::shared_ptr<const service::JobOutput> output_;
  bool result_fetched_ = false;
  // Submission::held: until settle(), the end of the run waits here, unreported.
  struct End {
    JobState state;
    std::optional<Problem> error;
    std::shared_ptr<const service::JobOutput> output;
  };
  bool held_ = false, discarded_ = false;
  std::optional<End> held_end_;
};

struct WorkerPoolOptions {
  int workers = 1;                 // worker threads, >= 1
  int threads_per_job = 1;         // passed to the core pipeline
  int capacity = 64;               // admitted jobs waiting for a worker
  std::chrono::milliseconds time_limit{300'000};  // running time per job
  io::Limits limits;               // decoder limits
};

// Called when a job has run, just before its final state is published (so a client that sees
// the job finished also sees it in the metrics): on the worker thread, or for a held run that
// ended before it was settled, on the thread calling settle(). Must not call back into the
// pool.
using JobFinishedHook = std::function<void(const JobSnapshot&)>;

class WorkerPool {
 public:
  WorkerPool(WorkerPoolOptions options, JobFinishedHook on_finished = {});
  ~WorkerPool();  // joins the workers (each ends its run); jobs still queued end cancelled
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  struct Submission {
    bool asynchronous = true;  // POST /v1/jobs (either store); false: POST /v1/denoise
    // Admitted here: refused (HttpError 503 draining or queue-full, with Retry-After) while
    // draining or when `capacity` admitted jobs wait. False: a job its store accepted against
    // its own capacity (Redis: a worker slot took it), which runs even while draining.
    bool admit = true;
    // Started before its store has accepted it (the Redis store overlaps the accepting with
    // the run): it runs at once, but its end is not published (finished hook, final state)
    // until settle(job, true). The caller must settle it either way.
    bool held = false;
    // The body's count in the queued bytes (queued_bytes.h): kept until the run takes the body
    // or the job ends without running.
    QueuedBytes::Hold queued_bytes{};
  };
  // Queues a job for the next free worker; `id` is the store's (or a request's) id, which
  // names it in logs and metrics. The caller keeps the job: the pool forgets it once it ended.
  std::shared_ptr<Job> submit(std::string id, service::JobInput input, Submission how);
  // Throws what submit() would for an admitted job now (draining, queue full); the memory
  // store checks it before its own limits so that the answers keep their order.
  void check_admission() const;

  // Kept: the held job's end is published as usual (now, if the run already ended). Not kept:
  // it is cancelled and its end is never reported (for metrics and logs it never ran).
  void settle(const std::shared_ptr<Job>& job, bool keep);

  enum class Cancelled { Queued, Requested, AlreadyFinished };
  // Queued: withdrawn and ended Cancelled with `why`. Running: cancellation requested (the
  // pipeline stops at its next iteration). Finished: nothing.
  Cancelled cancel(const std::shared_ptr<Job>& job, Problem why);
  // The same, for a synchronous request whose client went away (or a job the server gives up).
  void cancel(const std::shared_ptr<Job>& job);

  // Refuses admitted jobs from now on (503); what was submitted still runs.
  void begin_drain();
  bool draining() const;
  // Waits until no job is queued or running, the deadline passes or abandon() was called.
  // True if everything finished.
  bool wait_drained(Clock::time_point deadline);
  // A forced stop: drain waits end now (the stores cancelled their jobs first).
  void abandon();

  // The jobs waiting for a worker, oldest first.
  std::vector<std::shared_ptr<Job>> queued_jobs() const;
  // Jobs queued before this one (0: it starts next); nullopt when it is not in the queue.
  std::optional<int> jobs_ahead(const Job& job) const;

  int queued() const;
  int running() const;
  int capacity() const { return options_.capacity; }
  int workers() const { return options_.workers; }
  bool saturated() const;       // the queue is full
  int retry_after_s() const;    // a hint for clients told to come back: the measured queue wait

 private:
  void worker_loop();
  void run(const std::shared_ptr<Job>& job);
  // The end of a run: the finished hook (unless discarded), then the final state, with the
  // worker given back (running_) in the same critical section when `from_worker`.
  void end_run(Job& job, Job::End end, bool report, bool from_worker);
  void finish_locked(Job& job, JobState state, std::optional<Problem> error,
                     std::shared_ptr<const service::JobOutput> output);  // job.mutex_ held
  void check_admission_locked() const;  // mutex_ held
  // After a body of at least 1 MiB was freed: hands the allocator's free pages back to the
  // system (malloc_trim), so that memory a burst of large bodies took returns (decision 79).
  static void return_freed_memory(std::int64_t freed_bytes);

  const WorkerPoolOptions options_;
  const JobFinishedHook on_finished_;

  mutable std::mutex mutex_;
  std::condition_variable work_cv_;
  mutable std::condition_variable idle_cv_;
  std::deque<std::shared_ptr<Job>> queue_;
  int running_ = 0;
  bool draining_ = false;
  bool stop_ = false;
  bool abandoned_ = false;  // abandon() was called: drain waits no longer
  std::atomic<double> queue_wait_s_{-1};  // moving average of measured queue waits; -1: none yet
  std::vector<std::thread> workers_;
};

}  // namespace mdn::http
