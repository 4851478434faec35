#include "server/http/jobs/memory_job_store.h"

#include <algorithm>
#include <cmath>

#include "server/http/secure_random.h"

namespace mdn::http {
namespace {

// A downloaded result or a cancelled job gives its slot up (decision 62): it no longer counts
// against its client's share either.
bool holds_slot(const Job& job) {
  const JobState state = job.state();
  return !((state == JobState::Succeeded && job.result_fetched()) || state == JobState::Cancelled);
}

}  // namespace

MemoryJobStore::MemoryJobStore(WorkerPool& pool, MemoryJobStoreOptions options)
    : pool_(pool), options_(options) {}

MemoryJobStore::~MemoryJobStore() {
  for (const auto& job : all())
    pool_.cancel(job, make_problem(ProblemType::ShuttingDown, "the server stopped before this job ran"));
}

std::vector<std::shared_ptr<Job>> MemoryJobStore::all() {
  std::vector<std::shared_ptr<Job>> out;
  std::lock_guard lock(mutex_);
  sweep_locked();
  for (const auto& [id, job] : jobs_) out.push_back(job);
  return out;
}

JobStore::Submitted MemoryJobStore::submit(service::JobInput input, const std::optional<std::string>& idempotency_key,
                                           const std::string& fingerprint, Owner owner) {
  std::lock_guard lock(mutex_);
  sweep_locked();
  if (idempotency_key) {
    if (auto it = idempotency_.find(*idempotency_key); it != idempotency_.end()) {
      if (it->second.fingerprint != fingerprint) {
        Problem p = make_problem(ProblemType::IdempotencyKeyReused, "this Idempotency-Key was already used with a different body or parameters");
        throw HttpError(std::move(p));
      }
      if (auto job = jobs_.find(it->second.job_id); job != jobs_.end()) return {snapshot(*job->second), true};
      idempotency_.erase(it);  // its job expired: the key is free again
    }
  }
  pool_.check_admission();  // draining, queue full: before the store's own limit, as always
  // The client's share before the store's: a client over its share is told so (429) even when
  // the store is full because of it (decision 78).
  if (!owner.client.empty()) check_client_share_locked(owner.client);
  // An accepted job stays retrievable for its whole result lifetime: when every stored-job
  // slot is taken, new jobs are refused rather than old ones evicted early; except that a
  // result already downloaded, or a job cancelled, gives its slot up first (decision 62).
  if (int(jobs_.size()) >= options_.max_stored) evict_done_locked();
  if (int(jobs_.size()) >= options_.max_stored) {
    Problem p = make_problem(ProblemType::StoreFull, "all " + std::to_string(options_.max_stored) +
                                 " stored-job slots hold jobs within their result lifetime; retry later");
    p.retry_after_s = store_retry_after_s_locked();
    throw HttpError(std::move(p));
  }
  // 128 bits from the kernel's CSPRNG: ids are unguessable, even from many of one's own.
  std::string id;
  do id = new_job_id();
  while (jobs_.count(id) != 0);
  auto job = pool_.submit(id, std::move(input),
                          {.asynchronous = true, .admit = true, .queued_bytes = std::move(owner.queued_bytes)});
  jobs_.emplace(id, job);
  if (!owner.client.empty()) {
    client_jobs_[owner.client].insert(id);
    clients_.emplace(id, std::move(owner.client));
  }
  if (idempotency_key) idempotency_[*idempotency_key] = {fingerprint, id};
  return {snapshot(*job), false};
}

std::shared_ptr<Job> MemoryJobStore::find_job(const std::string& id) {
  std::lock_guard lock(mutex_);
  sweep_locked();
  auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

std::shared_ptr<Job> MemoryJobStore::job(const std::string& id) { return find_job(id); }

// A client that asks within this long of its last request still follows the job: about six
// of the web page's polls during a drain (300 ms apart), two of a client polling every 1.5 s.
constexpr std::chrono::seconds kStillFollowing{3};

void MemoryJobStore::asked(const std::string& id) {
  std::lock_guard lock(mutex_);
  asked_[id] = Clock::now();
}

std::optional<JobSnapshot> MemoryJobStore::find(const std::string& id, bool) {
  auto job = find_job(id);
  if (!job) return std::nullopt;
  asked(id);
  return snapshot(*job);
}

std::optional<JobSnapshot> MemoryJobStore::wait_finished(const std::string& id, Clock::time_point deadline) {
  auto job = find_job(id);
  if (!job) return std::nullopt;
  asked(id);
  // In slices, so that a drain ends the wait.
  for (auto now = Clock::now(); now < deadline && !pool_.draining(); now = Clock::now())
    if (job->wait_for(std::min<std::chrono::milliseconds>(
            std::chrono::ceil<std::chrono::milliseconds>(deadline - now), std::chrono::milliseconds(250))))
      break;
  return snapshot(*job);
}

void MemoryJobStore::result_fetched(const std::string& id) {
  auto job = find_job(id);
  if (!job) return;
  job->mark_result_fetched();
  std::lock_guard lock(mutex_);
  leave_share_locked(id);
}

void MemoryJobStore::leave_share_locked(const std::string& id) {
  const auto it = clients_.find(id);
  if (it == clients_.end()) return;
  if (auto jobs = client_jobs_.find(it->second); jobs != client_jobs_.end()) {
    jobs->second.erase(id);
    if (jobs->second.empty()) client_jobs_.erase(jobs);
  }
  clients_.erase(it);
}

JobStore::CancelResult MemoryJobStore::cancel(const std::string& id) {
  CancelResult r;
  std::lock_guard lock(mutex_);
  sweep_locked();
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return r;
  std::shared_ptr<Job> job = it->second;
  switch (pool_.cancel(job, cancelled_before_start())) {
    case WorkerPool::Cancelled::Queued:
      r.outcome = CancelOutcome::CancelledQueued;
      leave_share_locked(id);
      break;
    case WorkerPool::Cancelled::Requested: r.outcome = CancelOutcome::CancelRequested; break;
    case WorkerPool::Cancelled::AlreadyFinished:
      drop_locked(id);
      r.outcome = CancelOutcome::Removed;
      break;
  }
  r.job = job->snapshot();
  return r;
}

void MemoryJobStore::stop() {
  for (const auto& job : all()) pool_.cancel(job);
}

std::vector<JobSnapshot> MemoryJobStore::unfinished() {
  std::vector<JobSnapshot> out;
  for (const auto& job : all()) {
    JobSnapshot s = job->snapshot();
    if (!is_terminal(s.state)) out.push_back(std::move(s));
  }
  return out;
}

bool MemoryJobStore::results_awaited() {
  const auto since = Clock::now() - kStillFollowing;
  std::vector<std::shared_ptr<Job>> followed;  // asked about lately; checked outside the lock
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, when] : asked_)
      if (auto it = jobs_.find(id); when > since && it != jobs_.end()) followed.push_back(it->second);
  }
  return std::any_of(followed.begin(), followed.end(),
                     [](const auto& job) { return job->state() == JobState::Succeeded && !job->result_fetched(); });
}

int MemoryJobStore::unfetched_results() {
  int n = 0;
  for (const auto& job : all())
    if (job->state() == JobState::Succeeded && !job->result_fetched()) ++n;
  return n;
}

JobSnapshot MemoryJobStore::snapshot(const Job& job) const {
  JobSnapshot s = job.snapshot();
  if (s.state == JobState::Queued) s.jobs_ahead = pool_.jobs_ahead(job);
  return s;
}

void MemoryJobStore::drop_locked(const std::string& id) {
  leave_share_locked(id);
  jobs_.erase(id);
  asked_.erase(id);
  for (auto k = idempotency_.begin(); k != idempotency_.end();)
    k = k->second.job_id == id ? idempotency_.erase(k) : std::next(k);
}

void MemoryJobStore::evict_done_locked() {
  const std::string* oldest = nullptr;
  std::optional<Clock::time_point> oldest_at;
  for (const auto& [id, job] : jobs_) {
    if (holds_slot(*job)) continue;
    const auto finished = job->finished_at();
    if (finished && (!oldest_at || *finished < *oldest_at)) {
      oldest = &id;
      oldest_at = finished;
    }
  }
  if (oldest) drop_locked(std::string(*oldest));
}

void MemoryJobStore::sweep_locked() {
  const auto now = Clock::now();
  std::vector<std::string> expired;
  for (const auto& [id, job] : jobs_)
    if (auto finished = job->finished_at(); finished && *finished + options_.result_ttl <= now) expired.push_back(id);
  for (const auto& id : expired) drop_locked(id);
}

void MemoryJobStore::check_client_share_locked(const std::string& client) const {
  const auto own = client_jobs_.find(client);
  if (own == client_jobs_.end() || int(own->second.size()) < options_.max_stored_per_client) return;
  int held = 0;
  std::optional<Clock::time_point> oldest_finished;
  for (const std::string& id : own->second) {
    const Job& job = *jobs_.at(id);
    if (!holds_slot(job)) continue;  // cancelled while running
    ++held;
    if (auto finished = job.finished_at(); finished && (!oldest_finished || *finished < *oldest_finished))
      oldest_finished = finished;
  }
  if (held < options_.max_stored_per_client) return;
  Problem p = make_problem(ProblemType::OverClientShare,
                           "this client keeps " + std::to_string(held) + " jobs, its share of the job store (" +
                               std::to_string(options_.max_stored_per_client) +
                               ", --client-max-stored-jobs); download or delete finished ones, or retry later");
  p.extensions["limit_jobs"] = options_.max_stored_per_client;
  // A slot of this client frees when it downloads a result (now) or its oldest finished job's
  // lifetime ends; with none finished, when its queued jobs run.
  const double left = oldest_finished
                           ? std::chrono::duration<double>(*oldest_finished + options_.result_ttl - Clock::now()).count()
                           : double(pool_.retry_after_s());
  p.retry_after_s = int(std::clamp(std::ceil(left), 1.0, 60.0));
  throw HttpError(std::move(p));
}

int MemoryJobStore::store_retry_after_s_locked() const {
  // When the oldest finished job's lifetime ends, a slot frees (at least 1 s, at most 60).
  std::optional<Clock::time_point> oldest;
  for (const auto& [id, job] : jobs_)
    if (auto finished = job->finished_at(); finished && (!oldest || *finished < *oldest)) oldest = finished;
  if (!oldest) return pool_.retry_after_s();
  const double left = std::chrono::duration<double>(*oldest + options_.result_ttl - Clock::now()).count();
  return int(std::clamp(std::ceil(left), 1.0, 60.0));
}

}  // namespace mdn::http
