// The default job store (--queue memory): asynchronous jobs kept in this process, a single
// node needs nothing else; they die with the process. It keeps the job table, the ids, the
// result lifetime, the stored-job limit and the Idempotency-Keys, and runs each job on the
// WorkerPool through submit(), as the Redis store does.
//
// Thread-safety contract: every method may be called from any thread at any time. mutex_
// guards the table and the keys; it is taken before the pool's (never the reverse).
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "server/http/jobs/job_store.h"
#include "server/http/jobs/worker_pool.h"

namespace mdn::http {

struct MemoryJobStoreOptions {
  std::chrono::milliseconds result_ttl{600'000};  // how long finished jobs stay
  int max_stored = 1024;  // jobs kept at most (queued, running, finished); when all are taken,
                          // new ones get 503 (none is evicted early)
  // Jobs one client may keep that still hold their slot (not downloaded, not cancelled); beyond,
  // its new ones get 429 while other clients are served (decision 78).
  int max_stored_per_client = 256;
};

class MemoryJobStore final : public JobStore {
 public:
  MemoryJobStore(WorkerPool& pool, MemoryJobStoreOptions options = {});
  ~MemoryJobStore() override;  // requests cancellation of what still runs

  Submitted submit(service::JobInput input, const std::optional<std::string>& idempotency_key,
                   const std::string& fingerprint, Owner owner) override;
  std::optional<JobSnapshot> find(const std::string& id, bool with_result) override;
  std::optional<JobSnapshot> wait_finished(const std::string& id, Clock::time_point deadline) override;
  void result_fetched(const std::string& id) override;
  CancelResult cancel(const std::string& id) override;
  std::optional<Problem> unavailable() const override { return std::nullopt; }
  void begin_drain() override { pool_.begin_drain(); }
  bool wait_drained(Clock::time_point deadline) override { return pool_.wait_drained(deadline); }
  void stop() override;  // cancels every job it keeps (queued ones end, running ones stop)
  void render_metrics(std::string&) const override {}
  std::string_view kind() const override { return "memory"; }
  std::vector<JobSnapshot> unfinished() override;
  int unfetched_results() override;
  bool results_awaited() override;

  // The job object itself (tests); null when unknown or expired.
  std::shared_ptr<Job> job(const std::string& id);

 private:
  std::shared_ptr<Job> find_job(const std::string& id);
  JobSnapshot snapshot(const Job& job) const;
  void sweep_locked();  // mutex_ held: drops finished jobs past their result lifetime
  // mutex_ held: drops the job finished longest ago among those whose result was downloaded or
  // that were cancelled (decision 62), if any.
  void evict_done_locked();
  void drop_locked(const std::string& id);  // mutex_ held: the job and its keys
  int store_retry_after_s_locked() const;  // mutex_ held: until a stored-job slot frees
  // mutex_ held: 429 when `client` keeps max_stored_per_client jobs that hold their slot.
  void check_client_share_locked(const std::string& client) const;
  std::vector<std::shared_ptr<Job>> all();  // after a sweep

  WorkerPool& pool_;
  const MemoryJobStoreOptions options_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;  // every kept job by id
  // Each client's jobs that may still hold a slot (decision 78): a job leaves its client's set
  // once it can no longer hold one (downloaded, cancelled before it ran, removed), so checking
  // a share reads that client's few jobs, not the whole table.
  std::map<std::string, std::string> clients_;               // job id -> its Owner::client
  std::map<std::string, std::set<std::string>> client_jobs_;  // Owner::client -> job ids
  void leave_share_locked(const std::string& id);            // mutex_ held
  struct IdempotencyEntry { std::string fingerprint, job_id; };
  std::map<std::string, IdempotencyEntry> idempotency_;
  // When a client last asked about each job (find, wait_finished): who still follows a result.
  std::map<std::string, Clock::time_point> asked_;
  void asked(const std::string& id);
};

}  // namespace mdn::http
