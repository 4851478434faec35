#include "server/http/jobs/redis/store.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "server/http/jobs/redis/connection.h"
#include "server/http/jobs/redis/finish_waiters.h"
#include "server/http/jobs/redis/job_codec.h"
#include "server/http/jobs/redis/monitor.h"
#include "server/http/jobs/redis/recent_results.h"
#include "server/http/jobs/redis/script_args.h"
#include "server/http/jobs/redis/shared.h"
#include "server/http/jobs/redis/worker_slots.h"
#include "server/http/secure_random.h"
#include "service/params_json.h"

namespace mdn::http {
namespace {

using namespace redis;

using namespace std::chrono_literals;

// This replica's consumer name in the group: <host>-<pid>-<6 hex digits>.
std::string consumer_name() {
  char host[256] = "host";
  gethostname(host, sizeof host - 1);
  return std::string(host) + "-" + std::to_string(getpid()) + "-" + random_hex(3);
}

// ------------------------------------------------------------------ the store
// The JobStore calls come from request threads (stop() from main's, once); the store's own
// thread is the subscriber. Its parts keep their own locks: Monitor (whether Redis answers),
// WorkerSlots (the slots and the finisher), FinishWaiters (the long polls), RecentResults. The
// drain and stop flags are the store's, set by begin_drain() and stop(), read by every part;
// stop_mutex_ guards stopped_.
class RedisJobStore final : public JobStore {
 public:
  RedisJobStore(const ServerConfig& c, WorkerPool& worker_pool, std::shared_ptr<const EventLog> log)
      : config_(c),
        worker_pool_(worker_pool),
        log_(std::move(log)),
        pool_(c.queue.value(), 10s),
        keys_{c.queue_prefix, c.queue_prefix + "queue", consumer_name()},
        ttl_ms_(std::to_string(std::max<std::int64_t>(1, std::int64_t(std::llround(c.result_ttl_s * 1000))))),
        monitor_(pool_, keys_, log_, stopping_),
        slots_(config_, worker_pool_, log_, pool_, monitor_, keys_, ttl_ms_, draining_, stopping_, recent_) {
    if (c.max_body_bytes > (std::int64_t{512} << 20))
      throw ConfigError("--max-body: Redis stores values of at most 512 MiB; lower it with --queue redis://");
    const int slots = c.effective_workers();
    // One attempt now, so that a server whose Redis answers is ready as soon as it listens
    // (at most the 1 s connect timeout when it does not; the monitor keeps trying).
    try {
      Connection first(pool_.address(), pool_.timeout());
      ensure_group(first, keys_.stream);
      first.checked({"PING"});
      monitor_.mark_up();
    } catch (const std::exception&) {
    }
    monitor_.start();
    subscriber_ = std::thread([this] { subscriber_loop(); });
    slots_.start(slots);
    if (log_) {
      const RedisAddress& a = pool_.address();
      log_->info("job_store", {{"kind", "redis"}, {"host", a.host}, {"port", a.port}, {"db", a.db},
                               {"prefix", keys_.prefix}, {"consumer", keys_.consumer}, {"slots", slots},
                               {"reclaim_idle_s", c.queue_reclaim_idle_s}, {"max_attempts", c.queue_max_attempts}});
    }
  }

  ~RedisJobStore() override { stop(); }

  // ---------------------------------------------------------------- JobStore
  // The body's count in the queued bytes (owner.queued_bytes) ends with this call: Redis keeps
  // the body from then on. The client's share of stored jobs is counted in Redis, across
  // replicas (decision 78).
  Submitted submit(service::JobInput input, const std::optional<std::string>& key,
                   const std::string& fingerprint, Owner owner) override {
    if (worker_pool_.draining() || draining_) {
      Problem p = make_problem(ProblemType::Draining, "the server is shutting down and accepts no new jobs");
      p.retry_after_s = 5;
      throw HttpError(std::move(p));
    }
    const std::string id = new_job_id();
    const std::string created = std::to_string(now_ms());
    const std::string format(io::to_string(input.format));
    const std::string params = service::to_json(input.params).dump();
    const std::string idem = key ? keys_.prefix + "idem:" + *key : keys_.prefix + "idem:";
    const std::string capacity = std::to_string(config_.queue_capacity);
    const std::string job_prefix = keys_.prefix + "job:";
    // A worker slot of this replica waiting for work: accept and start in one step, and hand
    // the job to that slot. It starts running here and now, while Redis stores it (a megabyte
    // and its fsync take a few ms); until the script has accepted and started it for this
    // replica, its end is held back, and a run that was not accepted ends unreported. (Not
    // while Redis is known to be down: the request is refused at once.)
    WorkerSlots::Reservation slot(slots_);
    struct Early {
      RedisJobStore& store;
      std::shared_ptr<Job> job;
      ~Early() {
        if (!job) return;
        store.worker_pool_.settle(job, false);
        ++store.early_runs_discarded_;
      }
    } early{*this, slot && monitor_.up() ? worker_pool_.submit(id, input, {.admit = false, .held = true}) : nullptr};
    const std::int64_t input_bytes = std::int64_t(input.bytes.size());
    const std::string input_length = std::to_string(input_bytes), input_name = keys_.input(id);
    auto reply = run([&](Connection& c) {
      // The input by a plain SET, then the script (see lua/submit_job.lua), in one round trip.
      const std::vector<std::string_view> set = {"SET", input_name, input.bytes, "PX", kUnacceptedInputMs};
      const SubmitFields job{id,          input_length, format, params, created, capacity, fingerprint, key ? "1" : "0",
                             share_key(owner.client), client_quota_};
      const Argv args = slot ? SubmitStartArgs{keys_.stream, keys_.job(id), input_name, idem, slots_.start_fields(), job}.to_argv()
                             : SubmitArgs{keys_.job(id), input_name, keys_.stream, idem, job, Keys::kGroup, job_prefix}.to_argv();
      return std::move(c.checked_pipeline({set, views(args)}).back());
    });
    std::string_view outcome;
    try {
      outcome = str(element(reply.get(), 0));
      if (outcome == "run") {
        Taken t = parse_taken(reply);
        if (early.job) {
          worker_pool_.settle(early.job, true);
          t.early = std::move(early.job);
        } else {
          t.input = std::move(input.bytes);
        }
        slot.hand(std::move(t));
        ++started_on_submit_;
        outcome = "ok";
      }
    } catch (const std::exception& e) {
      throw HttpError(make_problem(ProblemType::QueueError, e.what()));
    }
    throw_if_refused(outcome, reply, capacity);
    if (outcome == "replay") {
      const std::string earlier(str(element(reply.get(), 1)));
      if (auto s = find(earlier, false)) return {std::move(*s), true};
      // It expired between the two calls: the key is free again.
      throw_unavailable("the job of this Idempotency-Key expired while being replayed; retry");
    }
    JobSnapshot s;
    s.id = id;
    s.asynchronous = true;
    s.input_bytes = input_bytes;
    s.created_wall = std::chrono::system_clock::time_point(std::chrono::milliseconds(std::stoll(created)));
    return {std::move(s), false};
  }

  std::optional<JobSnapshot> find(const std::string& id, bool with_result) override {
    if (!valid_id(id)) return std::nullopt;
    // Plain reads, no script: polls are the most frequent request. The hash and the result
    // expire together; a result missing next to a succeeded hash means it just expired.
    const std::string hash = keys_.job(id), result_name = keys_.result(id);
    // A result this replica stored is not read back (the hash says whether it still counts).
    std::optional<RecentResults::Entry> local = with_result ? recent_.find(id) : std::nullopt;
    std::vector<Reply> replies;
    run([&](Connection& c) {
      if (with_result && !local) replies = c.checked_pipeline({{"HGETALL", hash}, {"GET", result_name}});
      else replies = c.checked_pipeline({{"HGETALL", hash}});
      return Reply();
    });
    const redisReply* fields = replies.at(0).get();
    if (fields->type != REDIS_REPLY_ARRAY || fields->elements == 0) return std::nullopt;
    std::map<std::string, std::string> h;
    for (std::size_t i = 0; i + 1 < fields->elements; i += 2)
      h[std::string(str(fields->element[i]))] = std::string(str(fields->element[i + 1]));
    std::optional<std::string> result;
    if (with_result && h["state"] == "succeeded") {
      if (local && local->finished_ms == h["finished_ms"]) {
        result = *local->bytes;
        ++results_served_locally_;
      } else {
        if (local) {  // not the run this replica stored (cannot happen: a succeeded job is final)
          Reply r = run([&](Connection& c) { return c.checked({"GET", result_name}); });
          replies.push_back(std::move(r));
        }
        if (replies.back()->type != REDIS_REPLY_STRING) return std::nullopt;
        result = std::string(str(replies.back().get()));
      }
    }
    try {
      return snapshot_from_hash(id, std::move(h), result);
    } catch (const std::exception& e) {
      throw HttpError(make_problem(ProblemType::QueueError, std::string("the stored job could not be read: ") + e.what()));
    }
  }

  std::optional<JobSnapshot> wait_finished(const std::string& id, Clock::time_point deadline) override {
    if (!valid_id(id)) return std::nullopt;
    // Registered before the first read, so that a "done" message between the read and the wait
    // is not missed. Without messages (the subscriber reconnecting), the job is read again every
    // kWaitRecheck.
    FinishWaiters::Ticket ticket = waiters_.enter(id);
    for (;;) {
      std::optional<JobSnapshot> s = find(id, false);
      if (!s || is_terminal(s->state) || draining_ || Clock::now() >= deadline) return s;
      waiters_.wait(ticket, std::min(deadline, Clock::now() + kWaitRecheck), [&] { return draining_ || stopping_; });
    }
  }

  // Results live in Redis (nothing waits for this); the result gives its client's slot up.
  void result_fetched(const std::string& id) override {
    if (!valid_id(id)) return;
    run([&](Connection& c) { return c.checked(views(FetchedArgs{keys_.job(id)}.to_argv())); });
  }

  CancelResult cancel(const std::string& id) override {
    CancelResult r;
    if (!valid_id(id)) return r;
    auto reply = run([&](Connection& c) {
      return c.checked(views(CancelArgs{keys_.job(id), keys_.input(id), keys_.result(id), slots_.cancelled_problem(),
                                        std::to_string(now_ms()), ttl_ms_}.to_argv()));
    });
    const std::string_view outcome = str(reply.get());
    if (outcome == "none") return r;
    if (outcome == "removed") {
      recent_.erase(id);
      r.outcome = CancelOutcome::Removed;
      return r;
    }
    r.outcome = outcome == "cancelled" ? CancelOutcome::CancelledQueued : CancelOutcome::CancelRequested;
    if (auto s = find(id, false)) r.job = std::move(*s);
    else r.job.id = id;
    return r;
  }

  std::optional<Problem> unavailable() const override {
    if (monitor_.up()) return std::nullopt;
    Problem p = make_problem(ProblemType::QueueUnavailable, "the shared job store (Redis) cannot be reached; the server reconnects by itself");
    p.retry_after_s = kRetryAfterS;
    return p;
  }

  void begin_drain() override {
    draining_ = true;
    wake_waiters();
  }

  bool wait_drained(Clock::time_point deadline) override {
    // First the shared jobs this replica runs (their results go to Redis), then the local ones.
    while (slots_.busy() > 0) {
      if (Clock::now() >= deadline || stopping_) return false;
      std::this_thread::sleep_for(20ms);
    }
    return worker_pool_.wait_drained(deadline);
  }

  void stop() override {
    std::lock_guard lock(stop_mutex_);
    if (stopped_) return;
    draining_ = true;
    stopping_ = true;
    slots_.stop();
    monitor_.join();
    if (subscriber_.joinable()) subscriber_.join();
    wake_waiters();
    stopped_ = true;
  }

  void render_metrics(std::string& out) const override {
    auto line = [&](const char* name, const char* type, const char* help, std::int64_t v) {
      out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" + name + " " +
             std::to_string(v) + "\n";
    };
    line("mdn_queue_redis_up", "gauge", "1 while the shared job store (Redis) answers.", monitor_.up() ? 1 : 0);
    line("mdn_queue_shared_length", "gauge",
         "Jobs waiting in the shared Redis queue for a worker of any replica (sampled every second).", monitor_.length());
    line("mdn_queue_shared_pending", "gauge",
         "Jobs taken by a worker of any replica and not yet finished (XPENDING, sampled every second).", monitor_.pending());
    line("mdn_queue_reclaimed_total", "counter",
         "Jobs this replica took over from a worker that stopped answering (XAUTOCLAIM).", slots_.reclaimed());
    line("mdn_queue_started_on_submit_total", "counter",
         "Jobs this replica accepted and started at once on one of its idle workers (no queue round trip).",
         started_on_submit_);
    line("mdn_queue_retries_total", "counter", "Runs this replica started of jobs that had run before.", slots_.retries());
    line("mdn_queue_early_runs_discarded_total", "counter",
         "Runs this replica began while Redis was accepting their job, then dropped because Redis did not start "
         "the job here (refused, replayed, queued behind others, or Redis unreachable).",
         early_runs_discarded_);
    line("mdn_queue_results_served_locally_total", "counter",
         "Results this replica served from its own memory (it had stored them) instead of reading them from Redis.",
         results_served_locally_);
    line("mdn_queue_attempts_exhausted_total", "counter",
         "Jobs this replica failed because they reached --queue-max-attempts.", slots_.exhausted());
    line("mdn_queue_redis_reconnects_total", "counter", "Times Redis answered again after being unreachable.",
         monitor_.reconnects());
    line("mdn_queue_shared_running", "gauge", "Shared jobs this replica took and has not stored yet (running or storing).", slots_.busy());
  }

  std::string_view kind() const override { return "redis"; }

 private:
  // Expiry of an input SET before its job is accepted (lua/submit_job.lua removes it, or deletes the
  // input of a refused job): only an input whose script never ran expires.
  static constexpr const char* kUnacceptedInputMs = "600000";
  static constexpr int kRetryAfterS = 2;

  // The sorted set of a client's jobs (lua/finish_helpers.lua); "" for none.
  std::string share_key(const std::string& client) const {
    return client.empty() ? std::string() : keys_.prefix + "client:" + client;
  }

  static bool valid_id(const std::string& id) {
    return id.size() == 32 && std::all_of(id.begin(), id.end(), [](char c) {
             return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
           });
  }

  // The submit script's refusals as problems: the input not stored, an Idempotency-Key reused,
  // the shared queue full, the client over its share of stored jobs (decision 78).
  void throw_if_refused(std::string_view outcome, const Reply& reply, const std::string& capacity) const {
    if (outcome == "noinput")
      throw HttpError(make_problem(ProblemType::QueueError, "the job's input could not be stored"));
    if (outcome == "reused")
      throw HttpError(make_problem(ProblemType::IdempotencyKeyReused, "this Idempotency-Key was already used with a different body or parameters"));
    if (outcome == "full") {
      Problem p = make_problem(ProblemType::QueueFull, "all " + capacity + " slots of the shared queue are taken; retry later");
      p.retry_after_s = 5;
      throw HttpError(std::move(p));
    }
    if (outcome == "over") {
      Problem p = make_problem(ProblemType::OverClientShare,
                               "this client keeps " + std::string(str(element(reply.get(), 1))) +
                                   " jobs, its share of the job store (" + client_quota_ +
                                   ", --client-max-stored-jobs); download or delete finished ones, or retry later");
      p.extensions["limit_jobs"] = std::stoi(client_quota_);
      // Until its first slot frees: its oldest finished job's lifetime ends (or 5 s while all run).
      const double frees_ms = std::stod(std::string(str(element(reply.get(), 2))));
      p.retry_after_s = frees_ms >= 9e15 ? 5 : int(std::clamp(std::ceil((frees_ms - double(now_ms())) / 1000), 1.0, 60.0));
      throw HttpError(std::move(p));
    }
  }

  [[noreturn]] void throw_unavailable(const std::string& detail) const {
    Problem p = make_problem(ProblemType::QueueUnavailable, detail);
    p.retry_after_s = kRetryAfterS;
    throw HttpError(std::move(p));
  }

  // One request-thread operation on a pooled connection; Redis failures become problems.
  template <class F>
  Reply run(F&& f) {
    // The monitor found Redis unusable (down, or refusing us): answer at once, as /readyz does.
    if (auto p = unavailable()) throw HttpError(*p);
    std::unique_ptr<Connection> c;
    try {
      c = pool_.take();
      Reply r = f(*c);
      pool_.give(std::move(c));
      return r;
    } catch (const RedisDown& e) {
      monitor_.mark_down(e.what());
      throw_unavailable(std::string("the shared job store (Redis) cannot be reached: ") + e.what());
    } catch (const RedisReplyError& e) {
      pool_.give(std::move(c));
      if (transient_reply(e.what())) throw_unavailable(std::string("the shared job store (Redis) is busy: ") + e.what());
      throw HttpError(make_problem(ProblemType::QueueError, std::string("the shared job store (Redis) refused: ") + e.what()));
    }
  }

  // ---------------------------------------------------------------- long polls
  // Subscribed to "<prefix>done" (published by expire_job when a job finishes): wakes this
  // replica's long polls of that job. After a (re)connection every long poll reads its job
  // again, as messages may have been missed meanwhile.
  void subscriber_loop() {
    std::unique_ptr<Connection> c;
    const std::string channel = keys_.prefix + "done";
    while (!stopping_) {
      try {
        if (reconnect(c, pool_)) {
          c->checked({"SUBSCRIBE", channel});
          wake_waiters();
        }
        Reply m = c->next_message(250ms);
        // ["message", channel, job id]
        if (!m || m->type != REDIS_REPLY_ARRAY || m->elements != 3 || str(m->element[0]) != "message") continue;
        const std::string id(str(m->element[2]));
        waiters_.done(id);
      } catch (const std::exception&) {
        c.reset();
        sleep_unless(stopping_, 500ms);
      }
    }
  }

  void wake_waiters() { waiters_.wake_all(); }

  // ---------------------------------------------------------------- state
  const ServerConfig config_;
  WorkerPool& worker_pool_;
  const std::shared_ptr<const EventLog> log_;
  Pool pool_;


  const Keys keys_;
  const std::string ttl_ms_;
  const std::string client_quota_ = std::to_string(config_.effective_client_max_stored_jobs());

  std::atomic<bool> draining_{false}, stopping_{false};
  std::atomic<std::int64_t> started_on_submit_{0}, results_served_locally_{0}, early_runs_discarded_{0};

  RecentResults recent_;

  // Long polls waiting on this replica; each reads its job again at least every kWaitRecheck.
  static constexpr std::chrono::seconds kWaitRecheck{5};
  FinishWaiters waiters_;
  std::thread subscriber_;

  Monitor monitor_;
  WorkerSlots slots_;
  std::mutex stop_mutex_;
  bool stopped_ = false;
};

}  // namespace

std::unique_ptr<JobStore> make_redis_job_store(const ServerConfig& config, WorkerPool& worker_pool,
                                               std::shared_ptr<const EventLog> log) {
  return std::make_unique<RedisJobStore>(config, worker_pool, std::move(log));
}

}  // namespace mdn::http
