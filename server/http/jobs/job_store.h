// Where asynchronous jobs (POST /v1/jobs) live: the interface the HTTP layer talks to, with two
// implementations chosen by --queue:
//   memory   MemoryJobStore (memory_job_store.h): the job table in this process; a single
//            node needs nothing else. Jobs die with the process.
//   redis:// RedisJobStore (redis/store.h): input, parameters, state, progress and result in
//            Redis, the queue a Redis Stream with a consumer group; any replica accepts, any
//            replica's workers run, any replica answers.
// Both run their jobs on this process's WorkerPool (worker_pool.h) through WorkerPool::submit.
// Synchronous POST /v1/denoise never goes through a JobStore: it goes to the WorkerPool
// directly in both modes (see docker/README.md, "Job store").
//
// Thread-safety contract: every method may be called from any thread at any time.
// Errors: methods throw HttpError (503 queue-unavailable with Retry-After when the store cannot
// be reached, 503 queue-full / store-full / draining, 429 over-client-share with Retry-After
// when the submitting client holds its share of stored jobs, 422 idempotency-key-reused) and
// nothing else escapes
// but std::bad_alloc.
#pragma once

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "server/http/jobs/job.h"
#include "server/http/jobs/queued_bytes.h"
#include "server/http/problem.h"
#include "service/job_runner.h"

namespace mdn::http {

class JobStore {
 public:
  virtual ~JobStore() = default;

  struct Submitted {
    JobSnapshot job;
    bool replayed = false;  // an earlier job with the same Idempotency-Key and body
  };
  // Whose job it is (fair shares, decision 78): `client` names the API key's client, or the
  // source address without keys ("" counts against no share); `queued_bytes` counts its body
  // until the body is in a worker's hands (memory) or in Redis.
  struct Owner {
    std::string client;
    QueuedBytes::Hold queued_bytes;
  };
  // Accepts an asynchronous job. Once this returns, the job is stored: it runs even if this
  // process dies (Redis) or until this process stops (memory). `fingerprint` identifies the
  // body and parameters for idempotency and is ignored without a key. A client that already
  // keeps its share of stored jobs (--client-max-stored-jobs: jobs queued, running, or finished
  // within their result lifetime and neither downloaded nor cancelled) is refused 429.
  virtual Submitted submit(service::JobInput input, const std::optional<std::string>& idempotency_key,
                           const std::string& fingerprint, Owner owner) = 0;

  // The job's state; nullopt when unknown, deleted or expired. With `with_result`, a succeeded
  // job's output carries its bytes (GET /result); without, only their count (output_bytes).
  virtual std::optional<JobSnapshot> find(const std::string& id, bool with_result) = 0;
  // Long poll (GET /v1/jobs/{id}?wait=): blocks until the job is finished, `deadline` passes or
  // the server drains, then answers as find(id, false) does.
  virtual std::optional<JobSnapshot> wait_finished(const std::string& id, Clock::time_point deadline) = 0;
  // GET /result delivered the bytes once (the memory store counts, at a drain, the results nobody fetched).
  virtual void result_fetched(const std::string& id) = 0;

  enum class CancelOutcome { NotFound, CancelledQueued, CancelRequested, Removed };
  struct CancelResult {
    CancelOutcome outcome = CancelOutcome::NotFound;
    JobSnapshot job;  // after the cancellation (CancelledQueued, CancelRequested)
  };
  // Queued: cancelled at once. Running: cancellation requested; the worker running it, on
  // whichever replica, stops at its next checkpoint. Finished: the job and its result removed.
  virtual CancelResult cancel(const std::string& id) = 0;

  // Why the store cannot take jobs now (Redis unreachable), for /readyz; nullopt when it can.
  virtual std::optional<Problem> unavailable() const = 0;

  // Drain (SIGTERM): stop taking new jobs; wait for what this process runs; stop.
  virtual void begin_drain() = 0;
  virtual bool wait_drained(Clock::time_point deadline) = 0;
  virtual void stop() = 0;

  // Extra Prometheus lines (HELP/TYPE included) for GET /metrics.
  virtual void render_metrics(std::string& out) const = 0;
  virtual std::string_view kind() const = 0;  // "memory" or "redis"

  // For the drain's log: jobs this process keeps that are queued or running (the memory
  // store; a shared store keeps none here), and succeeded ones whose result nobody fetched
  // (lost when a memory store stops).
  virtual std::vector<JobSnapshot> unfinished() { return {}; }
  virtual int unfetched_results() { return 0; }
  // After the drain's jobs ended: whether a succeeded job's result, not fetched yet, has a client
  // that asked about it (status, long poll or result) within the last few seconds: the drain
  // keeps serving until it is fetched, its client goes quiet, or the grace ends (decision 67).
  // A shared store keeps results beyond this process: false.
  virtual bool results_awaited() { return false; }
};

}  // namespace mdn::http
