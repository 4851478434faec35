// The bounded job queue and its worker pool. HTTP threads never run the pipeline: they submit
// a Job here and either wait for it (POST /v1/denoise) or return its id (POST /v1/jobs).
//
// Thread-safety contract: every public method of JobQueue and Job may be called from any
// thread at any time. JobQueue::mutex_ guards the queue, the job table and the idempotency
// keys; each Job's own mutex guards its state, progress and result. Lock order: the queue's
// mutex before a job's, never the reverse. Workers never hold the queue's mutex while running
// a job. A Job's output, once published, is immutable and shared (std::shared_ptr<const>).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/io/document.h"
#include "server/http/problem.h"
#include "service/job_runner.h"

namespace mdn::http {

using Clock = std::chrono::steady_clock;

enum class JobState { Queued, Running, Succeeded, Failed, Cancelled };
std::string_view to_string(JobState state);  // "queued", "running", ...
inline bool is_terminal(JobState s) { return s == JobState::Succeeded || s == JobState::Failed || s == JobState::Cancelled; }

// A consistent copy of a job's public state.
struct JobSnapshot {
  std::string id;
  JobState state = JobState::Queued;
  std::string stage = "queued";  // "queued", "decode", a core Stage name, "done"
  double fraction = 0;           // of the stage, [0, 1]
  bool cancel_requested = false;
  bool asynchronous = false;
  std::int64_t input_bytes = 0;
  std::chrono::system_clock::time_point created_wall;
  double queue_wait_s = 0;  // so far, or until it started
  double run_s = 0;         // so far, or until it finished
  std::optional<Problem> error;                          // Failed (and Cancelled: why)
  // Succeeded. The shared job store (Redis) fills `output` without its bytes unless the result
  // itself was asked for; output_bytes is the result's size either way.
  std::shared_ptr<const service::JobOutput> output;
  std::int64_t output_bytes = 0;
  // The shared store: each surface's report as the worker rendered it (service::report_to_json);
  // `output` then has no reports of its own. Unset: render output->reports.
  std::optional<nlohmann::json> reports;
  int attempts = 0;  // runs started (Redis: more than 1 after a takeover); 0 while queued
  std::optional<int> jobs_ahead;  // Queued, where the store knows it (memory): jobs to start first
};

class Job {
 public:
  Job(std::string id, service::JobInput input, bool asynchronous);
  const std::string& id() const { return id_; }
  JobSnapshot snapshot() const;
  JobState state() const;
  // Blocks until the job is finished or the timeout passes; true when finished.
  bool wait_for(std::chrono::milliseconds timeout) const;
  // Marks the result as fetched by a client (the drain counts the results nobody fetched).
  void mark_result_fetched();
  bool result_fetched() const;

 private:
  friend class JobQueue;
  class Observer;

  const std::string id_;
  const bool asynchronous_;
  bool external_ = false;  // run_external(): not in the job table
  const Clock::time_point created_ = Clock::now();
  const std::chrono::system_clock::time_point created_wall_ = std::chrono::system_clock::now();
  std::atomic<bool> cancel_{false};

  mutable std::mutex mutex_;
  mutable std::condition_variable done_cv_;
  service::JobInput input_;  // released when the job starts running
  std::int64_t input_bytes_ = 0;
  JobState state_ = JobState::Queued;
  std::string stage_ = "queued";
  double fraction_ = 0;
  std::optional<Clock::time_point> started_, finished_;
  std::optional<Problem> error_;
  std::shared_ptr<const service::JobOutput> output_;
  bool result_fetched_ = false;
  // run_external(held): until settle(), the end of the run waits here, unreported.
  struct End {
    JobState state;
    std::optional<Problem> error;
    std::shared_ptr<const service::JobOutput> output;
  };
  bool held_ = false, discarded_ = false;
  std::optional<End> held_end_;
};

struct JobQueueOptions {
  int workers = 1;                 // worker threads, >= 1
  int threads_per_job = 1;         // passed to the core pipeline
  int capacity = 64;               // jobs waiting for a worker
  std::chrono::milliseconds time_limit{300'000};  // running time per job
  std::chrono::milliseconds result_ttl{600'000};  // how long finished jobs stay
  int max_stored = 1024;           // asynchronous jobs kept at most (queued, running, finished);
                                   // when all are taken, new ones get 503 (none is evicted early)
  io::Limits limits;               // decoder limits
};

// Called when a job has run, just before its final state is published (so a client that sees
// the job finished also sees it in the metrics): on the worker thread, or for a held run that
// ended before it was settled, on the thread calling settle(). Must not call back into the
// queue.
using JobFinishedHook = std::function<void(const JobSnapshot&)>;

class JobQueue {
 public:
  JobQueue(JobQueueOptions options, JobFinishedHook on_finished = {});
  ~JobQueue();  // cancels what is left and joins the workers
  JobQueue(const JobQueue&) = delete;
  JobQueue& operator=(const JobQueue&) = delete;

  struct Submitted {
    std::shared_ptr<Job> job;
    bool replayed = false;  // an earlier job with the same Idempotency-Key and body
  };
  // Enqueues a job. Throws HttpError: 503 (queue full or draining, with Retry-After) or
  // 422 idempotency-key-reused (same key, different body). `fingerprint` identifies the body
  // and parameters for idempotency and is ignored without a key.
  Submitted submit(service::JobInput input, bool asynchronous,
                   const std::optional<std::string>& idempotency_key = std::nullopt,
                   const std::string& fingerprint = {});

  std::shared_ptr<Job> find(const std::string& id);

  // Runs a job accepted elsewhere (the shared Redis queue): no capacity or drain check, not
  // listed by find() nor kept after it finishes; `id` only names it in logs and metrics.
  // The caller waits on the returned job and may cancel it with cancel(job).
  // `held`: a run started before the shared queue has accepted the job (so that it overlaps
  // the accepting); it runs at once, but its end is not published (finished hook, final
  // state) until settle(job, true). The caller must settle it either way.
  std::shared_ptr<Job> run_external(std::string id, service::JobInput input, bool held = false);
  // Kept: the held job's end is published as usual (now, if the run already ended). Not kept:
  // it is cancelled and its end is never reported (for metrics and logs it never ran).
  void settle(const std::shared_ptr<Job>& job, bool keep);

  enum class CancelOutcome { NotFound, CancelledQueued, CancelRequested, Removed };
  // Queued: cancelled at once. Running: cancellation requested (the pipeline stops at its next
  // iteration). Finished: the job and its result are removed.
  CancelOutcome cancel(const std::string& id);
  // Requests cancellation of one job object (a synchronous request whose client went away).
  void cancel(const std::shared_ptr<Job>& job);

  // Cancels every queued job and requests cancellation of every running one (forced stop).
  void cancel_all();

  // Refuses new jobs from now on (503); what was accepted still runs.
  void begin_drain();
  bool draining() const;
  // Waits until no job is queued or running, or the deadline passes. True if everything
  // finished. Finished results not downloaded yet do not hold it (see unfetched_results()).
  bool wait_drained(Clock::time_point deadline);

  // Jobs a drain that ends now would abandon: queued or running (running synchronous jobs are
  // not listed; their requests are answered 503).
  std::vector<JobSnapshot> unfinished() const;
  // Succeeded asynchronous jobs whose result was never fetched (lost when a memory store stops).
  int unfetched_results() const;

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
  void sweep_locked();  // mutex_ held: drops finished jobs past their result lifetime
  int store_retry_after_s_locked() const;  // mutex_ held: until a stored-job slot frees
  std::string new_id_locked();

  const JobQueueOptions options_;
  const JobFinishedHook on_finished_;

  mutable std::mutex mutex_;
  std::condition_variable work_cv_;
  mutable std::condition_variable idle_cv_;
  std::deque<std::shared_ptr<Job>> queue_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;  // every known job by id
  std::deque<std::string> finished_order_;            // ids of finished jobs, oldest first
  struct IdempotencyEntry { std::string fingerprint, job_id; };
  std::map<std::string, IdempotencyEntry> idempotency_;
  int running_ = 0;
  bool draining_ = false;
  bool stop_ = false;
  bool abandoned_ = false;  // cancel_all() was called: drain waits no longer
  std::atomic<double> queue_wait_s_{-1};  // moving average of measured queue waits; -1: none yet
  std::vector<std::thread> workers_;
};

}  // namespace mdn::http
