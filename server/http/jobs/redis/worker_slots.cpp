#include "server/http/jobs/redis/worker_slots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "server/http/problem.h"
#include "server/http/jobs/redis/job_codec.h"
#include "service/params_json.h"

namespace mdn::http::redis {

using nlohmann::json;
using namespace std::chrono_literals;

namespace {

Reply eval(Connection& c, const Argv& args) { return c.checked(views(args)); }

std::string exhausted_problem_text(int max_attempts) {
  Problem p = make_problem(ProblemType::AttemptsExhausted, "the job was started " + std::to_string(max_attempts) +
                               " times and its worker stopped answering each time (crash, kill or lost "
                               "node); it is not run again");
  p.extensions["attempts"] = max_attempts;
  return problem_text(p);
}

}  // namespace

Taken parse_taken(const Reply& r) {
  Taken t;
  t.outcome = std::string(str(element(r.get(), 0)));
  t.attempt = int(element(r.get(), 1)->integer);
  t.previous = std::string(str(element(r.get(), 2)));
  t.input = std::string(str(element(r.get(), 3)));
  t.format = std::string(str(element(r.get(), 4)));
  t.params = std::string(str(element(r.get(), 5)));
  t.entry_id = std::string(str(element(r.get(), 6)));
  t.job_id = std::string(str(element(r.get(), 7)));
  return t;
}

WorkerSlots::WorkerSlots(const ServerConfig& config, WorkerPool& worker_pool, std::shared_ptr<const EventLog> log,
                         const Pool& pool, Monitor& monitor, const Keys& keys, const std::string& ttl_ms,
                         const std::atomic<bool>& draining, const std::atomic<bool>& stopping, RecentResults& recent)
    : config_(config),
      worker_pool_(worker_pool),
      log_(std::move(log)),
      pool_(pool),
      monitor_(monitor),
      keys_(keys),
      ttl_ms_(ttl_ms),
      draining_(draining),
      stopping_(stopping),
      recent_(recent),
      reclaim_idle_ms_(std::max<std::int64_t>(100, std::int64_t(std::llround(config.queue_reclaim_idle_s * 1000)))),
      exhausted_problem_(exhausted_problem_text(config.queue_max_attempts)),
      cancelled_problem_(problem_text(cancelled_before_start())),
      lost_problem_(problem_text(make_problem(ProblemType::InputLost, "the job's input is no longer in the job store"))) {
  if (const char* v = std::getenv("MDN_TEST_HANDOFF_PICKUP_DELAY_MS"))
    handoff_pickup_delay_ = std::chrono::milliseconds(std::atoi(v));
}

void WorkerSlots::start(int slots) {
  finisher_ = std::thread([this] { finisher_loop(); });
  for (int i = 0; i < slots; ++i) slots_.emplace_back([this] { slot_loop(); });
}

void WorkerSlots::stop() {
  handoff_cv_.notify_all();
  for (auto& t : slots_) t.join();
  // Jobs handed to a slot that stopped first (rare): back to the queue while Redis answers.
  for (std::unique_ptr<Connection> c; !handoffs_.empty(); handoffs_.pop_front(), --busy_) {
    try {
      release(c, handoffs_.front());
    } catch (const std::exception& ex) {
      if (log_) log_->warn("job_unreleased", {{"job_id", handoffs_.front().job_id}, {"detail", ex.what()}});
    }
  }
  finishes_.close();  // the finisher stores what is queued, then ends
  if (finisher_.joinable()) finisher_.join();
}

StartFields WorkerSlots::start_fields() const {
  return {keys_.consumer,     std::to_string(now_ms()), std::to_string(config_.queue_max_attempts),
          Keys::kGroup,       exhausted_problem_,       cancelled_problem_,
          ttl_ms_,            lost_problem_,            keys_.prefix + "job:"};
}

// ---------------------------------------------------------------- submit()'s hand-over

WorkerSlots::Reservation::Reservation(WorkerSlots& s) : s_(s) {
  std::lock_guard lock(s_.handoff_mutex_);
  // A slot handed a job it has not picked up yet still counts in idle_slots_: not free.
  if (!s_.draining_ && s_.idle_slots_ > s_.reserved_ + static_cast<int>(s_.handoffs_.size())) {
    ++s_.reserved_;
    held_ = true;
  }
}

void WorkerSlots::Reservation::release(std::optional<Taken> t) {
  if (!held_) return;
  {
    std::lock_guard lock(s_.handoff_mutex_);
    --s_.reserved_;
    if (t) {
      ++s_.busy_;
      s_.handoffs_.push_back(std::move(*t));
    }
    held_ = false;
  }
  s_.handoff_cv_.notify_all();
}

// A job started for this replica by submit(), if one is (or is about to be) handed over; waits
// while a reservation is outstanding. Marks the slot busy when it returns one.
std::optional<Taken> WorkerSlots::take_handoff(bool& idle, bool wait) {
  std::unique_lock lock(handoff_mutex_);
  if (!idle) {
    ++idle_slots_;
    idle = true;
  }
  if (wait)
    handoff_cv_.wait_for(lock, 2s, [&] { return !handoffs_.empty() || reserved_ == 0 || stopping_; });
  if (handoff_pickup_delay_.count() > 0 && !handoffs_.empty()) {  // test hook, see its member
    lock.unlock();
    std::this_thread::sleep_for(handoff_pickup_delay_);
    lock.lock();
  }
  std::optional<Taken> t = pop_handoff_locked();
  if (t) {
    --idle_slots_;
    idle = false;
  }
  return t;
}

std::optional<Taken> WorkerSlots::pop_handoff_locked() {
  if (handoffs_.empty()) return std::nullopt;
  Taken t = std::move(handoffs_.front());
  handoffs_.pop_front();
  return t;
}

void WorkerSlots::leave_idle(bool& idle) {
  std::lock_guard lock(handoff_mutex_);
  if (idle) --idle_slots_;
  idle = false;
}

// ---------------------------------------------------------------- the slots

// The next job for this slot: one taken over from a silent worker (XAUTOCLAIM, at most every
// half idle threshold), else the next new one (lua/take.lua). `last_id`: where XREAD should wait.
Taken WorkerSlots::next_job(Connection& c, std::string& last_id) {
  const auto now = Clock::now();
  bool reclaim = false;
  {
    std::lock_guard lock(reclaim_mutex_);
    if (now >= next_reclaim_) {
      next_reclaim_ = now + std::chrono::milliseconds(std::clamp<std::int64_t>(reclaim_idle_ms_ / 2, 100, 1000));
      reclaim = true;
    }
  }
  if (reclaim) {
    Reply r = c.checked({"XAUTOCLAIM", keys_.stream, Keys::kGroup, keys_.consumer, std::to_string(reclaim_idle_ms_),
                         "0-0", "COUNT", "1"});
    // [next cursor, [[entry id, [field, value, ...]], ...], deleted ids]
    const redisReply* entries = element(r.get(), 1);
    for (std::size_t i = 0; i < entries->elements; ++i) {
      const redisReply* e = entries->element[i];
      if (!e || e->type != REDIS_REPLY_ARRAY || e->elements < 2) continue;  // deleted meanwhile
      std::string entry_id(str(e->element[0])), job_id;
      const redisReply* fields = e->element[1];
      if (fields && fields->type == REDIS_REPLY_ARRAY)
        for (std::size_t k = 0; k + 1 < fields->elements; k += 2)
          if (str(fields->element[k]) == "id") job_id = std::string(str(fields->element[k + 1]));
      Taken t = parse_taken(eval(c, StartArgs{keys_.stream, start_fields(), entry_id, job_id}.to_argv()));
      t.reclaimed = true;
      return t;
    }
  }
  Taken t = parse_taken(eval(c, TakeArgs{keys_.stream, start_fields()}.to_argv()));
  if (t.outcome == "none") last_id = t.entry_id;
  return t;
}

void WorkerSlots::slot_loop() {
  std::unique_ptr<Connection> c;
  auto backoff = 100ms;
  std::string last_id = "0-0";
  bool idle = false;  // counted in idle_slots_ (submit() may hand this slot a job)
  while (!stopping_) {
    try {
      if (draining_) {  // no new jobs; those already handed over still run
        leave_idle(idle);
        std::optional<Taken> handed;
        {
          std::lock_guard lock(handoff_mutex_);
          handed = pop_handoff_locked();
        }
        if (handed) run_taken(c, std::move(*handed));
        else std::this_thread::sleep_for(50ms);
        continue;
      }
      if (std::optional<Taken> handed = take_handoff(idle, true)) {
        run_taken(c, std::move(*handed));
        continue;
      }
      reconnect(c, pool_);
      Taken t = next_job(*c, last_id);
      backoff = 100ms;
      if (t.outcome == "none") {
        // A job submit() started for this slot after lua/take.lua looked (its entry is the last one,
        // so XREAD would not wake for it): run it now.
        if (std::optional<Taken> handed = take_handoff(idle, true)) {
          run_taken(c, std::move(*handed));
          continue;
        }
        // Wait for an entry newer than the last one (read-only: no write, no fsync).
        c->checked({"XREAD", "COUNT", "1", "BLOCK", "1000", "STREAMS", keys_.stream, last_id});
        continue;
      }
      leave_idle(idle);
      ++busy_;
      run_taken(c, std::move(t));
    } catch (const RedisDown& e) {
      c.reset();
      monitor_.mark_down(e.what());
      sleep_unless(stopping_, backoff);
      backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
    } catch (const RedisReplyError& e) {
      if (std::string_view(e.what()).find("NOGROUP") != std::string_view::npos) {
        try {
          ensure_group(*c, keys_.stream);
          continue;
        } catch (const std::exception&) {
        }
      }
      if (log_) log_->error("queue_worker_error", {{"detail", e.what()}});
      sleep_unless(stopping_, backoff);
      backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
    } catch (const std::exception& e) {
      if (log_) log_->error("queue_worker_error", {{"detail", e.what()}});
      sleep_unless(stopping_, backoff);
      backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
    }
  }
}

// Retries `f` on a fresh connection until it succeeds or the replica stops (results are
// kept in memory meanwhile: Redis being down must not lose a finished job).
template <class F>
bool WorkerSlots::retry(std::unique_ptr<Connection>& c, F&& f) {
  auto backoff = 100ms;
  while (true) {
    try {
      reconnect(c, pool_);
      f(*c);
      return true;
    } catch (const RedisDown& e) {
      c.reset();
      monitor_.mark_down(e.what());
    } catch (const RedisReplyError& e) {
      if (!transient_reply(e.what())) throw;
    }
    if (stopping_) return false;
    sleep_unless(stopping_, backoff);
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
  }
}

// Hands a started job back to the queue (this replica stops), not counted as an attempt.
void WorkerSlots::release(std::unique_ptr<Connection>& c, const Taken& e) {
  retry(c, [&](Connection& conn) {
    conn.checked(views(ReleaseArgs{keys_.job(e.job_id), keys_.stream, keys_.consumer, e.entry_id, Keys::kGroup, e.job_id}
                           .to_argv()));
  });
  if (log_) log_->info("job_released", {{"job_id", e.job_id}, {"detail", "this replica stopped; back in the queue"}});
}

// Runs a taken job already counted in busy_.
void WorkerSlots::run_taken(std::unique_ptr<Connection>& c, Taken t) {
  struct Done {
    std::atomic<int>& busy;
    ~Done() { --busy; }
  } done{busy_};
  process(c, std::move(t));
}

// Runs while the job does: see watch() in worker_slots.h.
WorkerSlots::RunEnd WorkerSlots::watch(std::unique_ptr<Connection>& conn, const Taken& e, const std::shared_ptr<Job>& job,
                                       bool& cancel_by_user) {
  RunEnd end = RunEnd::Finished;
  std::string last_stage;
  double last_fraction = -1;
  // Every 200 ms a read-only check (cancel flag, still ours); a heartbeat with the progress
  // (a write: it resets the entry's idle time) when the stage changes and at least every
  // quarter of the idle threshold (at most every second).
  const auto beat_every = std::chrono::milliseconds(std::clamp<std::int64_t>(reclaim_idle_ms_ / 4, 100, 1000));
  auto last_beat = Clock::now();
  while (!job->wait_for(200ms)) {
    if (stopping_ && end == RunEnd::Finished) {
      end = RunEnd::Released;
      worker_pool_.cancel(job);
    }
    if (end != RunEnd::Finished || cancel_by_user) continue;
    const JobSnapshot s = job->snapshot();
    const bool changed = s.stage != last_stage || std::abs(s.fraction - last_fraction) >= 0.01;
    const bool due = s.stage != last_stage || Clock::now() - last_beat >= beat_every;
    char fraction[32];
    std::snprintf(fraction, sizeof fraction, "%.4f", s.fraction);
    try {
      reconnect(conn, pool_);
      Reply b = conn->checked(views(due ? BeatArgs{keys_.job(e.job_id), keys_.stream, keys_.consumer, changed ? s.stage : "",
                                                   fraction, e.entry_id, Keys::kGroup}
                                              .to_argv()
                                        : CheckArgs{keys_.job(e.job_id), keys_.consumer}.to_argv()));
      if (due) {
        last_beat = Clock::now();
        last_stage = s.stage;
        last_fraction = s.fraction;
      }
      const std::string_view v = str(b.get());
      if (v == "cancel") {
        cancel_by_user = true;
        worker_pool_.cancel(job);
      } else if (v == "lost") {
        end = RunEnd::Lost;
        worker_pool_.cancel(job);
      }
    } catch (const RedisDown& ex) {
      conn.reset();
      monitor_.mark_down(ex.what());  // the job goes on; its result waits for Redis below
    } catch (const RedisReplyError& ex) {
      if (log_) log_->warn("heartbeat_failed", {{"job_id", e.job_id}, {"detail", ex.what()}});
    }
  }
  return end;
}

// Runs a started job on the slot's connection `conn` (re-made when it breaks).
void WorkerSlots::process(std::unique_ptr<Connection>& conn, Taken t) {
  const Taken& e = t;
  if (e.reclaimed && (e.outcome == "run" || e.outcome == "exhausted")) {
    ++reclaimed_;
    if (log_)
      log_->warn("job_reclaimed", {{"job_id", e.job_id}, {"from", e.previous},
                                   {"idle_threshold_s", config_.queue_reclaim_idle_s}});
  }
  if (e.outcome == "exhausted") {
    ++exhausted_;
    if (log_) log_->warn("job_attempts_exhausted", {{"job_id", e.job_id}, {"attempts", e.attempt}});
    return;
  }
  if (e.outcome != "run") return;
  if (e.attempt > 1) {
    ++retries_;
    if (log_) log_->info("job_retry", {{"job_id", e.job_id}, {"attempt", e.attempt}});
  }
  service::JobInput input;
  input.bytes = std::move(t.input);
  const std::string& format = e.format;
  const std::string& params = e.params;
  std::optional<Problem> error;
  try {
    input.format = io::format_from_string(format).value_or(io::Format::Off);
    input.params = service::job_params_from_json(json::parse(params));
  } catch (...) {
    error = problem_from_exception(std::current_exception());
  }
  JobState state = JobState::Failed;
  std::string result, summary;
  std::int64_t result_bytes = 0;
  RunEnd end = RunEnd::Finished;
  if (!error) {
    auto job = e.early ? e.early : worker_pool_.submit(e.job_id, std::move(input), {.admit = false});
    bool cancel_by_user = false;
    end = watch(conn, e, job, cancel_by_user);
    const JobSnapshot s = job->snapshot();
    state = s.state;
    error = s.error;
    if (state == JobState::Cancelled && cancel_by_user)
      error = make_problem(ProblemType::Cancelled, "cancelled by DELETE while running");
    else if (state == JobState::Cancelled && end == RunEnd::Finished)  // cancelled by this replica's stop
      end = RunEnd::Released;
    if (state == JobState::Succeeded) {
      result_bytes = std::int64_t(s.output->bytes.size());
      if (result_bytes > config_.queue_max_result_bytes) {
        state = JobState::Failed;
        error = make_problem(ProblemType::ResultTooLarge, "the result has " + std::to_string(result_bytes) + " bytes; the job store keeps at most " +
                                 std::to_string(config_.queue_max_result_bytes) + " (--queue-max-result)");
        error->extensions["maximum"] = config_.queue_max_result_bytes;
      } else {
        result = s.output->bytes;
        summary = output_text(*s.output);
      }
    }
  }
  if (end == RunEnd::Lost) {
    if (log_) log_->warn("job_lost", {{"job_id", e.job_id}, {"detail", "another replica took the job over"}});
    return;
  }
  std::unique_ptr<Connection>& fin = conn;
  if (end == RunEnd::Released) {
    release(fin, e);
    return;
  }
  // Stored by the finisher thread, so that this slot takes its next job meanwhile (the
  // worker does not wait for the result's transfer and fsync). Counted as busy until stored.
  Finish f{e.job_id, e.entry_id, std::string(to_string(state)), error ? problem_text(*error) : std::string(),
           std::move(summary), std::move(result), std::to_string(now_ms()), std::to_string(result_bytes)};
  ++busy_;
  finishes_.push(std::move(f));
}

// Stores finished jobs' results and states in order; on stop, stores what is left while
// Redis answers (a result not stored means the job runs again elsewhere).
void WorkerSlots::finisher_loop() {
  std::unique_ptr<Connection> c;
  for (;;) {
    std::optional<Finish> next = finishes_.pop();
    if (!next) return;
    Finish& f = *next;
    std::string stored;
    bool done = false;
    try {
      done = retry(c, [&](Connection& conn) {
        const std::string result = keys_.result(f.job_id), staged = result + ":" + keys_.consumer;
        const Argv args = FinishArgs{keys_.job(f.job_id), keys_.input(f.job_id), keys_.stream, result, staged, keys_.consumer,
                                     f.state, f.error, f.summary, ttl_ms_, f.finished_ms, f.entry_id, Keys::kGroup,
                                     f.result_bytes}
                              .to_argv();
        const std::vector<std::string_view> finish = views(args);
        // The result by a plain SET, then the script (see lua/finish.lua), in one round trip.
        std::vector<Reply> r = f.state == "succeeded"
                                   ? conn.checked_pipeline({{"SET", staged, f.result, "PX", ttl_ms_}, finish})
                                   : conn.checked_pipeline({finish});
        stored = std::string(str(r.back().get()));
      });
      if (done && stored == "ok" && f.state == "succeeded")
        recent_.add(f.job_id, f.finished_ms, std::move(f.result));
    } catch (const std::exception& ex) {
      if (log_) log_->error("job_unstored", {{"job_id", f.job_id}, {"detail", ex.what()}});
    }
    --busy_;
    if (!done && log_)
      log_->warn("job_unstored", {{"job_id", f.job_id}, {"detail", "stopped while Redis was unreachable; the job will run again"}});
    else if (stored == "stale" && log_)
      log_->warn("job_lost", {{"job_id", f.job_id}, {"detail", "another replica took the job over"}});
  }
}

}  // namespace mdn::http::redis
