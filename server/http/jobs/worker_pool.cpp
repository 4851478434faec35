#include "server/http/jobs/worker_pool.h"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/errors.h"
#include "core/progress.h"

namespace mdn::http {

namespace {
double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
}  // namespace

// Progress and cancellation for one running job: reports the stage into the Job and asks the
// pipeline to stop when the job was cancelled or its time limit passed (polled by the core
// between iterations, so a stop takes at most one iteration).
class Job::Observer final : public ProgressObserver {
 public:
  Observer(Job& job, Clock::time_point deadline) : job_(job), deadline_(deadline) {}
  void on_progress(Stage stage, double fraction) override {
    std::lock_guard lock(job_.mutex_);
    job_.stage_ = std::string(to_string(stage));
    job_.fraction_ = std::clamp(fraction, 0.0, 1.0);
  }
  bool cancel_requested() override {
    if (job_.cancel_.load()) return true;
    if (Clock::now() > deadline_) {
      timed_out_ = true;
      return true;
    }
    return false;
  }
  bool timed_out() const { return timed_out_; }

 private:
  Job& job_;
  Clock::time_point deadline_;
  bool timed_out_ = false;
};

Job::Job(std::string id, service::JobInput input, bool asynchronous)
    : id_(std::move(id)), asynchronous_(asynchronous), input_(std::move(input)) {
  input_bytes_ = std::int64_t(input_.bytes.size());
}

JobSnapshot Job::snapshot() const {
  JobSnapshot s;
  s.id = id_;
  s.asynchronous = asynchronous_;
  s.created_wall = created_wall_;
  s.cancel_requested = cancel_.load();
  const auto now = Clock::now();
  std::lock_guard lock(mutex_);
  s.state = state_;
  s.stage = stage_;
  s.fraction = fraction_;
  s.input_bytes = input_bytes_;
  s.queue_wait_s = seconds_between(created_, started_.value_or(finished_.value_or(now)));
  s.run_s = started_ ? seconds_between(*started_, finished_.value_or(now)) : 0.0;
  s.error = error_;
  s.output = output_;
  s.output_bytes = output_ ? std::int64_t(output_->bytes.size()) : 0;
  s.attempts = started_ ? 1 : 0;
  return s;
}

JobState Job::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

bool Job::wait_for(std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  return done_cv_.wait_for(lock, timeout, [&] { return is_terminal(state_); });
}

void Job::mark_result_fetched() {
  std::lock_guard lock(mutex_);
  result_fetched_ = true;
}

bool Job::result_fetched() const {
  std::lock_guard lock(mutex_);
  return result_fetched_;
}

std::optional<Clock::time_point> Job::finished_at() const {
  std::lock_guard lock(mutex_);
  return finished_;
}

WorkerPool::WorkerPool(WorkerPoolOptions options, JobFinishedHook on_finished)
    : options_(std::move(options)), on_finished_(std::move(on_finished)) {
  const int n = std::max(1, options_.workers);
  workers_.reserve(std::size_t(n));
  for (int i = 0; i < n; ++i) workers_.emplace_back([this] { worker_loop(); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    draining_ = true;
  }
  work_cv_.notify_all();
  for (auto& t : workers_) t.join();
  // Jobs still queued never ran: mark them cancelled so waiters wake up.
  std::lock_guard lock(mutex_);
  for (auto& job : queue_) {
    std::lock_guard job_lock(job->mutex_);
    finish_locked(*job, JobState::Cancelled,
                  make_problem(ProblemType::ShuttingDown, "the server stopped before this job ran"),
                  nullptr);
  }
  queue_.clear();
}

void WorkerPool::check_admission_locked() const {
  if (draining_ || stop_) {
    Problem p = make_problem(ProblemType::Draining, "the server is shutting down and accepts no new jobs");
    p.retry_after_s = retry_after_s();
    throw HttpError(std::move(p));
  }
  if (int(queue_.size()) >= options_.capacity) {
    Problem p = make_problem(ProblemType::QueueFull, "all " + std::to_string(options_.capacity) + " queue slots are taken; retry later");
    p.retry_after_s = retry_after_s();
    throw HttpError(std::move(p));
  }
}

void WorkerPool::check_admission() const {
  std::lock_guard lock(mutex_);
  check_admission_locked();
}

std::shared_ptr<Job> WorkerPool::submit(std::string id, service::JobInput input, Submission how) {
  input.threads = options_.threads_per_job;
  auto job = std::make_shared<Job>(std::move(id), std::move(input), how.asynchronous);
  job->held_ = how.held;
  job->queued_bytes_ = std::move(how.queued_bytes);
  {
    std::lock_guard lock(mutex_);
    if (how.admit) check_admission_locked();
    queue_.push_back(job);
  }
  work_cv_.notify_one();
  return job;
}

void WorkerPool::settle(const std::shared_ptr<Job>& job, bool keep) {
  std::optional<Job::End> end;
  {
    std::lock_guard lock(job->mutex_);
    if (!job->held_) return;
    job->held_ = false;
    job->discarded_ = !keep;
    end = std::move(job->held_end_);
    job->held_end_.reset();
  }
  if (end) end_run(*job, std::move(*end), keep, false);  // the worker was given back at its end
  else if (!keep) cancel(job);  // queued: ends now; running: its end goes unreported
}

WorkerPool::Cancelled WorkerPool::cancel(const std::shared_ptr<Job>& job, Problem why) {
  std::unique_lock lock(mutex_);
  std::unique_lock job_lock(job->mutex_);
  if (is_terminal(job->state_)) return Cancelled::AlreadyFinished;
  job->cancel_ = true;
  if (job->state_ != JobState::Queued) return Cancelled::Requested;
  queue_.erase(std::remove(queue_.begin(), queue_.end(), job), queue_.end());
  finish_locked(*job, JobState::Cancelled, std::move(why), nullptr);
  const std::int64_t freed = job->input_bytes_;
  job_lock.unlock();
  lock.unlock();
  idle_cv_.notify_all();
  return_freed_memory(freed);
  return Cancelled::Queued;
}

void WorkerPool::cancel(const std::shared_ptr<Job>& job) {
  job->cancel_ = true;  // a finished job too: its snapshot says so
  cancel(job, make_problem(ProblemType::Cancelled, "the client went away before the job started"));
}

void WorkerPool::abandon() {
  {
    std::lock_guard lock(mutex_);
    abandoned_ = true;
  }
  idle_cv_.notify_all();
}

void WorkerPool::begin_drain() {
  std::lock_guard lock(mutex_);
  draining_ = true;
}

bool WorkerPool::draining() const {
  std::lock_guard lock(mutex_);
  return draining_;
}

bool WorkerPool::wait_drained(Clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  // Results waiting for their download do not hold the drain: nobody may ever fetch them, and
  // waiting for them kept every stop for the whole grace (issue 34). main() logs how many go.
  auto drained = [&] { return queue_.empty() && running_ == 0; };
  while (!drained()) {
    if (Clock::now() >= deadline || abandoned_) return false;
    idle_cv_.wait_until(lock, std::min(deadline, Clock::now() + std::chrono::milliseconds(100)));
  }
  return true;
}

int WorkerPool::queued() const {
  std::lock_guard lock(mutex_);
  return int(queue_.size());
}

int WorkerPool::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

bool WorkerPool::saturated() const {
  std::lock_guard lock(mutex_);
  return int(queue_.size()) >= options_.capacity;
}

std::vector<std::shared_ptr<Job>> WorkerPool::queued_jobs() const {
  std::lock_guard lock(mutex_);
  return {queue_.begin(), queue_.end()};
}

std::optional<int> WorkerPool::jobs_ahead(const Job& job) const {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < queue_.size(); ++i)
    if (queue_[i].get() == &job) return int(i);
  return std::nullopt;
}

int WorkerPool::retry_after_s() const {
  // How long jobs now wait in the queue before a worker takes them (measured), at least 1 s,
  // at most 60: a client told to come back then finds a slot about as soon as one frees.
  const double wait = queue_wait_s_.load();
  return wait < 0 ? 1 : int(std::clamp(std::ceil(wait), 1.0, 60.0));
}

void WorkerPool::worker_loop() {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      work_cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      job = std::move(queue_.front());
      queue_.pop_front();
      ++running_;
      std::lock_guard job_lock(job->mutex_);
      job->state_ = JobState::Running;
      job->started_ = Clock::now();
      job->stage_ = "decode";
      // Moving average of the measured queue waits (the last few jobs weigh most).
      const double wait = seconds_between(job->created_, *job->started_), old = queue_wait_s_.load();
      queue_wait_s_.store(old < 0 ? wait : 0.7 * old + 0.3 * wait);
    }
    run(job);  // gives the worker back (running_) as it publishes the end, or holds it
    idle_cv_.notify_all();
  }
}

void WorkerPool::run(const std::shared_ptr<Job>& job) {
  service::JobInput input;
  {
    std::lock_guard lock(job->mutex_);
    input = std::move(job->input_);
    job->input_ = {};
    job->queued_bytes_.release();  // the run holds the body now; the workers bound how many
  }
  Job::Observer observer(*job, *job->started_ + options_.time_limit);
  std::shared_ptr<const service::JobOutput> output;
  std::optional<Problem> error;
  JobState state = JobState::Succeeded;
  try {
    if (job->cancel_) throw CancelledError();
    // Handed over: the request bytes are freed once decoded, not held through the denoising.
    output = std::make_shared<const service::JobOutput>(service::run_job(std::move(input), options_.limits, &observer));
  } catch (const CancelledError&) {
    if (observer.timed_out()) {
      state = JobState::Failed;
      const double limit_s = std::chrono::duration<double>(options_.time_limit).count();
      error = make_problem(ProblemType::TimeLimitExceeded, "the job ran longer than the server's limit of " + std::to_string(limit_s) + " s");
      error->extensions["time_limit_s"] = limit_s;
    } else {
      state = JobState::Cancelled;
      error = make_problem(ProblemType::Cancelled, "cancelled while running");
    }
  } catch (...) {
    state = JobState::Failed;
    error = problem_from_exception(std::current_exception());
  }
  input = {};  // free the rest of the request (the bytes, if decoding failed) before publishing
  return_freed_memory(job->input_bytes_);
  bool report = true;
  {
    std::lock_guard lock(mutex_);  // the pool's mutex first (lock order)
    std::lock_guard job_lock(job->mutex_);
    if (job->held_) {  // not accepted yet: settle() ends it; the worker is free already
      job->held_end_ = Job::End{state, std::move(error), std::move(output)};
      --running_;
      return;
    }
    report = !job->discarded_;
  }
  end_run(*job, Job::End{state, std::move(error), std::move(output)}, report, true);
}

void WorkerPool::end_run(Job& job, Job::End end, bool report, bool from_worker) {
  if (on_finished_ && report) {
    // Before the final state is published: a client that sees the job finished (the waiting
    // request, a poll) also sees it counted in the metrics.
    JobSnapshot s = job.snapshot();
    s.state = end.state;
    s.error = end.error;
    s.output = end.output;
    s.output_bytes = end.output ? std::int64_t(end.output->bytes.size()) : 0;
    if (end.state == JobState::Succeeded) s.stage = "done", s.fraction = 1;
    on_finished_(s);
  }
  // The worker is given back (running_) and the job's end published (its state, waking the
  // waiting request) in one critical section of the pool's mutex: whoever sees the job
  // finished (a synchronous response, a poll) and then reads running() (GET /metrics) no
  // longer finds it counted, and wait_drained() never sees running_ at 0 with the job still
  // running. Lowering running_ after finish_locked() let a client read mdn_jobs_running 1
  // after its result.
  std::lock_guard lock(mutex_);
  if (from_worker) --running_;
  std::lock_guard job_lock(job.mutex_);
  finish_locked(job, end.state, std::move(end.error), std::move(end.output));
}

void WorkerPool::finish_locked(Job& job, JobState state, std::optional<Problem> error,
                             std::shared_ptr<const service::JobOutput> output) {
  job.state_ = state;
  job.finished_ = Clock::now();
  job.error_ = std::move(error);
  job.output_ = std::move(output);
  // Moved out to be destroyed: assigning {} to a std::string keeps its buffer (libstdc++ copies
  // an empty short string into it), so a cancelled job held its whole body until it expired.
  { service::JobInput freed = std::move(job.input_); }
  job.queued_bytes_.release();
  if (state == JobState::Succeeded) {
    job.stage_ = "done";
    job.fraction_ = 1;
  }
  job.done_cv_.notify_all();
}

void WorkerPool::return_freed_memory(std::int64_t freed_bytes) {
  // glibc keeps freed memory in its arenas (one per thread that allocated); 25 cancelled 40 MB
  // bodies left 735 MB resident. malloc_trim(0) returns every arena's free pages.
  if (freed_bytes >= (std::int64_t{1} << 20)) malloc_trim(0);
}

}  // namespace mdn::http
