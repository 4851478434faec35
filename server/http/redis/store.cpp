#include "server/http/redis/store.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <map>
#include <mutex>
#include <random>
#include <thread>
#include <unordered_map>
#include <vector>

#include "server/http/redis/connection.h"
#include "server/http/redis/finish_waiters.h"
#include "server/http/redis/job_codec.h"
#include "server/http/redis/recent_results.h"
#include "server/http/redis/script_args.h"
#include "server/http/redis/work_queue.h"
#include "server/params_json.h"

namespace mdn::http {
namespace {

using namespace redis;

using nlohmann::json;
using namespace std::chrono_literals;



std::string random_hex(std::mt19937_64& rng, int words) {
  std::string out;
  char buf[17];
  for (int i = 0; i < words; ++i) {
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(rng()));
    out += buf;
  }
  return out;
}

// ------------------------------------------------------------------ the store

class RedisJobStore final : public JobStore {
 public:
  RedisJobStore(const ServerConfig& c, JobQueue& queue, std::shared_ptr<const EventLog> log)
      : config_(c),
        queue_(queue),
        log_(std::move(log)),
        pool_(c.queue.value(), 10s),
        prefix_(c.queue_prefix),
        stream_(prefix_ + "queue"),
        ttl_ms_(std::to_string(std::max<std::int64_t>(1, std::int64_t(std::llround(c.result_ttl_s * 1000))))),
        reclaim_idle_ms_(std::max<std::int64_t>(100, std::int64_t(std::llround(c.queue_reclaim_idle_s * 1000)))) {
    if (c.max_body_bytes > (std::int64_t{512} << 20))
      throw ConfigError("--max-body: Redis stores values of at most 512 MiB; lower it with --queue redis://");
    std::random_device rd;
    rng_.seed((std::uint64_t(rd()) << 32) ^ rd());
    char host[256] = "host";
    gethostname(host, sizeof host - 1);
    consumer_ = std::string(host) + "-" + std::to_string(getpid()) + "-" + random_hex(rng_, 1).substr(0, 6);
    exhausted_problem_ = problem_text([&] {
      Problem p = make_problem(ProblemType::AttemptsExhausted, "the job was started " + std::to_string(c.queue_max_attempts) +
                                   " times and its worker stopped answering each time (crash, kill or lost "
                                   "node); it is not run again");
      p.extensions["attempts"] = c.queue_max_attempts;
      return p;
    }());
    cancelled_problem_ = problem_text(cancelled_before_start());
    lost_problem_ = problem_text(
        make_problem(ProblemType::InputLost, "the job's input is no longer in the job store"));
    if (const char* v = std::getenv("MDN_TEST_HANDOFF_PICKUP_DELAY_MS"))
      handoff_pickup_delay_ = std::chrono::milliseconds(std::atoi(v));
    const int slots = c.effective_workers();
    // One attempt now, so that a server whose Redis answers is ready as soon as it listens
    // (at most the 1 s connect timeout when it does not; the monitor keeps trying).
    try {
      Connection first(pool_.address(), pool_.timeout());
      ensure_group(first);
      first.checked({"PING"});
      mark_up();
    } catch (const std::exception&) {
    }
    monitor_ = std::thread([this] { monitor_loop(); });
    finisher_ = std::thread([this] { finisher_loop(); });
    subscriber_ = std::thread([this] { subscriber_loop(); });
    for (int i = 0; i < slots; ++i) slots_.emplace_back([this] { slot_loop(); });
    if (log_) {
      const RedisAddress& a = pool_.address();
      log_->info("job_store", {{"kind", "redis"}, {"host", a.host}, {"port", a.port}, {"db", a.db},
                               {"prefix", prefix_}, {"consumer", consumer_}, {"slots", slots},
                               {"reclaim_idle_s", c.queue_reclaim_idle_s}, {"max_attempts", c.queue_max_attempts}});
    }
  }

  ~RedisJobStore() override { stop(); }

  // ---------------------------------------------------------------- JobStore
  Submitted submit(service::JobInput input, const std::optional<std::string>& key,
                   const std::string& fingerprint) override {
    if (queue_.draining() || draining_) {
      Problem p = make_problem(ProblemType::Draining, "the server is shutting down and accepts no new jobs");
      p.retry_after_s = 5;
      throw HttpError(std::move(p));
    }
    std::string id;
    {
      std::lock_guard lock(rng_mutex_);
      id = random_hex(rng_, 2);
    }
    const std::string created = std::to_string(now_ms());
    const std::string format(io::to_string(input.format));
    const std::string params = service::to_json(input.params).dump();
    const std::string idem = key ? prefix_ + "idem:" + *key : prefix_ + "idem:";
    const std::string capacity = std::to_string(config_.queue_capacity);
    const std::string job_prefix = prefix_ + "job:";
    // A worker slot of this replica waiting for work: accept and start in one step, and hand
    // the job to that slot. It starts running here and now, while Redis stores it (a megabyte
    // and its fsync take a few ms); until the script has accepted and started it for this
    // replica, its end is held back, and a run that was not accepted ends unreported. (Not
    // while Redis is known to be down: the request is refused at once.)
    SlotReservation slot(*this);
    struct Early {
      RedisJobStore& store;
      std::shared_ptr<Job> job;
      ~Early() {
        if (!job) return;
        store.queue_.settle(job, false);
        ++store.early_runs_discarded_;
      }
    } early{*this, slot && up_ ? queue_.run_external(id, input, true) : nullptr};
    const std::int64_t input_bytes = std::int64_t(input.bytes.size());
    const std::string input_length = std::to_string(input_bytes), input_name = input_key(id);
    auto reply = run([&](Connection& c) {
      // The input by a plain SET, then the script (see lua/submit_job.lua), in one round trip.
      const std::vector<std::string_view> set = {"SET", input_name, input.bytes, "PX", kUnacceptedInputMs};
      const SubmitFields job{id, input_length, format, params, created, capacity, fingerprint, key ? "1" : "0"};
      const Argv args = slot ? SubmitStartArgs{stream_, job_key(id), input_name, idem, start_fields(), job}.to_argv()
                             : SubmitArgs{job_key(id), input_name, stream_, idem, job, kGroup, job_prefix}.to_argv();
      return std::move(c.checked_pipeline({set, views(args)}).back());
    });
    std::string_view outcome;
    try {
      outcome = str(element(reply.get(), 0));
      if (outcome == "run") {
        Taken t = parse_taken(reply);
        if (early.job) {
          queue_.settle(early.job, true);
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
    if (outcome == "noinput")
      throw HttpError(make_problem(ProblemType::QueueError, "the job's input could not be stored"));
    if (outcome == "reused")
      throw HttpError(make_problem(ProblemType::IdempotencyKeyReused, "this Idempotency-Key was already used with a different body or parameters"));
    if (outcome == "full") {
      Problem p = make_problem(ProblemType::QueueFull, "all " + capacity + " slots of the shared queue are taken; retry later");
      p.retry_after_s = 5;
      throw HttpError(std::move(p));
    }
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
    const std::string hash = job_key(id), result_name = result_key(id);
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

  void result_fetched(const std::string&) override {}  // results live in Redis: nothing waits for this

  CancelResult cancel(const std::string& id) override {
    CancelResult r;
    if (!valid_id(id)) return r;
    auto reply = run([&](Connection& c) {
      return c.checked(views(CancelArgs{job_key(id), input_key(id), result_key(id), cancelled_problem_,
                                        std::to_string(now_ms()), ttl_ms_}.to_argv()));
    });
    const std::string_view outcome = str(reply.get());
    if (outcome == "none") return r;
    if (outcome == "removed") {
      recent_.erase(id);
      r.outcome = JobQueue::CancelOutcome::Removed;
      return r;
    }
    r.outcome = outcome == "cancelled" ? JobQueue::CancelOutcome::CancelledQueued : JobQueue::CancelOutcome::CancelRequested;
    if (auto s = find(id, false)) r.job = std::move(*s);
    else r.job.id = id;
    return r;
  }

  std::optional<Problem> unavailable() const override {
    if (up_) return std::nullopt;
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
    while (busy_ > 0) {
      if (Clock::now() >= deadline || stopping_) return false;
      std::this_thread::sleep_for(20ms);
    }
    return queue_.wait_drained(deadline);
  }

  void stop() override {
    std::lock_guard lock(stop_mutex_);
    if (stopped_) return;
    draining_ = true;
    stopping_ = true;
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
    monitor_wake_.notify_all();
    if (monitor_.joinable()) monitor_.join();
    if (subscriber_.joinable()) subscriber_.join();
    wake_waiters();
    stopped_ = true;
  }

  void render_metrics(std::string& out) const override {
    auto line = [&](const char* name, const char* type, const char* help, std::int64_t v) {
      out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" + name + " " +
             std::to_string(v) + "\n";
    };
    line("mdn_queue_redis_up", "gauge", "1 while the shared job store (Redis) answers.", up_ ? 1 : 0);
    line("mdn_queue_shared_length", "gauge",
         "Jobs waiting in the shared Redis queue for a worker of any replica (sampled every second).", length_);
    line("mdn_queue_shared_pending", "gauge",
         "Jobs taken by a worker of any replica and not yet finished (XPENDING, sampled every second).", pending_);
    line("mdn_queue_reclaimed_total", "counter",
         "Jobs this replica took over from a worker that stopped answering (XAUTOCLAIM).", reclaimed_);
    line("mdn_queue_started_on_submit_total", "counter",
         "Jobs this replica accepted and started at once on one of its idle workers (no queue round trip).",
         started_on_submit_);
    line("mdn_queue_retries_total", "counter", "Runs this replica started of jobs that had run before.", retries_);
    line("mdn_queue_early_runs_discarded_total", "counter",
         "Runs this replica began while Redis was accepting their job, then dropped because Redis did not start "
         "the job here (refused, replayed, queued behind others, or Redis unreachable).",
         early_runs_discarded_);
    line("mdn_queue_results_served_locally_total", "counter",
         "Results this replica served from its own memory (it had stored them) instead of reading them from Redis.",
         results_served_locally_);
    line("mdn_queue_attempts_exhausted_total", "counter",
         "Jobs this replica failed because they reached --queue-max-attempts.", exhausted_);
    line("mdn_queue_redis_reconnects_total", "counter", "Times Redis answered again after being unreachable.",
         reconnects_);
    line("mdn_queue_shared_running", "gauge", "Shared jobs this replica took and has not stored yet (running or storing).", busy_);
  }

  std::string_view kind() const override { return "redis"; }

 private:
  static constexpr const char* kGroup = "workers";
  // Expiry of an input SET before its job is accepted (lua/submit_job.lua removes it, or deletes the
  // input of a refused job): only an input whose script never ran expires.
  static constexpr const char* kUnacceptedInputMs = "600000";
  static constexpr int kRetryAfterS = 2;

  std::string job_key(const std::string& id) const { return prefix_ + "job:" + id; }
  std::string input_key(const std::string& id) const { return prefix_ + "job:" + id + ":input"; }
  std::string result_key(const std::string& id) const { return prefix_ + "job:" + id + ":result"; }
  static bool valid_id(const std::string& id) {
    return id.size() == 32 && std::all_of(id.begin(), id.end(), [](char c) {
             return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
           });
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
      mark_down(e.what());
      throw_unavailable(std::string("the shared job store (Redis) cannot be reached: ") + e.what());
    } catch (const RedisReplyError& e) {
      pool_.give(std::move(c));
      if (transient_reply(e.what())) throw_unavailable(std::string("the shared job store (Redis) is busy: ") + e.what());
      throw HttpError(make_problem(ProblemType::QueueError, std::string("the shared job store (Redis) refused: ") + e.what()));
    }
  }

  void mark_down(const std::string& why) {
    if (up_.exchange(false) && log_) log_->warn("redis_unavailable", {{"detail", why}});
    pool_.clear();
    monitor_wake_.notify_all();
  }

  void mark_up() {
    if (up_.exchange(true)) return;
    if (ever_up_.exchange(true)) {
      ++reconnects_;
      if (log_) log_->info("redis_reconnected", {{"consumer", consumer_}});
    } else if (log_) {
      log_->info("redis_connected", {{"consumer", consumer_}});
    }
  }

  void ensure_group(Connection& c) {
    Reply r = c.command({"XGROUP", "CREATE", stream_, kGroup, "0", "MKSTREAM"});
    if (r->type == REDIS_REPLY_ERROR && str(r.get()).rfind("BUSYGROUP", 0) != 0)
      throw RedisReplyError(std::string(str(r.get())));
  }

  // ---------------------------------------------------------------- monitor
  // Every second: PING, the queue's length and pending count (for /metrics and /readyz); every
  // minute, forget consumers gone for an hour with nothing pending.
  void monitor_loop() {
    std::unique_ptr<Connection> c;
    bool warned = false;  // "unreachable at startup" is logged once
    auto next_forget = Clock::now() + 60s;
    while (!stopping_) {
      try {
        if (!c || c->broken()) {
          c.reset();
          c = std::make_unique<Connection>(pool_.address(), pool_.timeout());
          ensure_group(*c);
        }
        c->checked({"PING"});
        const std::int64_t len = c->checked({"XLEN", stream_})->integer;
        Reply p = c->command({"XPENDING", stream_, kGroup});
        if (p->type == REDIS_REPLY_ERROR) {  // NOGROUP: the stream was lost (Redis without persistence)
          ensure_group(*c);
        } else if (p->type == REDIS_REPLY_ARRAY && p->elements > 0) {
          pending_ = p->element[0]->integer;
          length_ = std::max<std::int64_t>(0, len - pending_);
        }
        mark_up();
        if (Clock::now() >= next_forget) {
          next_forget = Clock::now() + 60s;
          Reply f = c->command(views(ForgetConsumersArgs{stream_, kGroup, "3600000"}.to_argv()));
          if (f->type == REDIS_REPLY_INTEGER && f->integer > 0 && log_)
            log_->info("redis_consumers_forgotten", {{"count", f->integer}});
        }
      } catch (const std::exception& e) {
        c.reset();
        if (!ever_up_ && !warned && log_) log_->warn("redis_unavailable", {{"detail", e.what()}});
        warned = true;
        mark_down(e.what());
      }
      std::unique_lock lock(monitor_mutex_);
      monitor_wake_.wait_for(lock, up_ ? 1000ms : 250ms, [&] { return stopping_.load(); });
    }
  }

  // ---------------------------------------------------------------- long polls
  // Subscribed to "<prefix>done" (published by expire_job when a job finishes): wakes this
  // replica's long polls of that job. After a (re)connection every long poll reads its job
  // again, as messages may have been missed meanwhile.
  void subscriber_loop() {
    std::unique_ptr<Connection> c;
    const std::string channel = prefix_ + "done";
    while (!stopping_) {
      try {
        if (!c || c->broken()) {
          c.reset();
          c = std::make_unique<Connection>(pool_.address(), pool_.timeout());
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
        sleep_unless_stopping(500ms);
      }
    }
  }

  void wake_waiters() { waiters_.wake_all(); }

  // ---------------------------------------------------------------- worker slots
  struct Finish {
    std::string job_id, entry_id, state, error, summary, result, finished_ms, result_bytes;
  };

  // What lua/take.lua or lua/start.lua answered.
  struct Taken {
    std::string outcome;  // run, none, gone, done, cancelled, exhausted, lost
    int attempt = 0;
    std::string previous, input, format, params, entry_id, job_id;
    bool reclaimed = false;
    std::shared_ptr<Job> early;  // started by submit() while Redis accepted it (then no input)
  };

  // A worker slot of this replica reserved by submit() for a job it accepts and starts in one
  // step (lua/submit_start.lua); released unused when the job could not start at once (others waited).
  // Rarely, the reserved slot takes another job meanwhile (lua/take.lua in flight): the handed job then
  // waits for the first free slot of this replica.
  class SlotReservation {
   public:
    explicit SlotReservation(RedisJobStore& s) : s_(s) {
      std::lock_guard lock(s_.handoff_mutex_);
      // A slot handed a job it has not picked up yet still counts in idle_slots_: not free.
      if (!s_.draining_ && s_.idle_slots_ > s_.reserved_ + static_cast<int>(s_.handoffs_.size())) {
        ++s_.reserved_;
        held_ = true;
      }
    }
    SlotReservation(const SlotReservation&) = delete;
    SlotReservation& operator=(const SlotReservation&) = delete;
    ~SlotReservation() { release(std::nullopt); }
    explicit operator bool() const { return held_; }
    // The started job, for the waiting slot (counted as busy from now on, like a taken one).
    void hand(Taken t) { release(std::move(t)); }

   private:
    void release(std::optional<Taken> t) {
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
    RedisJobStore& s_;
    bool held_ = false;
  };

  // A job started for this replica by submit(), if one is (or is about to be) handed over; waits
  // while a reservation is outstanding. Marks the slot busy when it returns one.
  std::optional<Taken> take_handoff(bool& idle, bool wait) {
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

  std::optional<Taken> pop_handoff_locked() {
    if (handoffs_.empty()) return std::nullopt;
    Taken t = std::move(handoffs_.front());
    handoffs_.pop_front();
    return t;
  }

  void leave_idle(bool& idle) {
    std::lock_guard lock(handoff_mutex_);
    if (idle) --idle_slots_;
    idle = false;
  }

  static Taken parse_taken(const Reply& r) {
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

  StartFields start_fields() const {
    return {consumer_, std::to_string(now_ms()), std::to_string(config_.queue_max_attempts), kGroup, exhausted_problem_,
            cancelled_problem_, ttl_ms_, lost_problem_, prefix_ + "job:"};
  }

  static Reply eval(Connection& c, const Argv& args) { return c.checked(views(args)); }

  // The next job for this slot: one taken over from a silent worker (XAUTOCLAIM, at most every
  // half idle threshold), else the next new one (lua/take.lua). `last_id`: where XREAD should wait.
  Taken next_job(Connection& c, std::string& last_id) {
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
      Reply r = c.checked({"XAUTOCLAIM", stream_, kGroup, consumer_, std::to_string(reclaim_idle_ms_), "0-0", "COUNT", "1"});
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
        Taken t = parse_taken(eval(c, StartArgs{stream_, start_fields(), entry_id, job_id}.to_argv()));
        t.reclaimed = true;
        return t;
      }
    }
    Taken t = parse_taken(eval(c, TakeArgs{stream_, start_fields()}.to_argv()));
    if (t.outcome == "none") last_id = t.entry_id;
    return t;
  }

  void slot_loop() {
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
        if (!c || c->broken()) {
          c.reset();
          c = std::make_unique<Connection>(pool_.address(), pool_.timeout());
        }
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
          c->checked({"XREAD", "COUNT", "1", "BLOCK", "1000", "STREAMS", stream_, last_id});
          continue;
        }
        leave_idle(idle);
        ++busy_;
        run_taken(c, std::move(t));
      } catch (const RedisDown& e) {
        c.reset();
        mark_down(e.what());
        sleep_unless_stopping(backoff);
        backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
      } catch (const RedisReplyError& e) {
        if (std::string_view(e.what()).find("NOGROUP") != std::string_view::npos) {
          try {
            ensure_group(*c);
            continue;
          } catch (const std::exception&) {
          }
        }
        if (log_) log_->error("queue_worker_error", {{"detail", e.what()}});
        sleep_unless_stopping(backoff);
        backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
      } catch (const std::exception& e) {
        if (log_) log_->error("queue_worker_error", {{"detail", e.what()}});
        sleep_unless_stopping(backoff);
        backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
      }
    }
  }

  // Hands a started job back to the queue (this replica stops), not counted as an attempt.
  void release(std::unique_ptr<Connection>& c, const Taken& e) {
    retry(c, [&](Connection& conn) {
      conn.checked(views(ReleaseArgs{job_key(e.job_id), stream_, consumer_, e.entry_id, kGroup, e.job_id}.to_argv()));
    });
    if (log_) log_->info("job_released", {{"job_id", e.job_id}, {"detail", "this replica stopped; back in the queue"}});
  }

  // Runs a taken job already counted in busy_.
  void run_taken(std::unique_ptr<Connection>& c, Taken t) {
    struct Done {
      std::atomic<int>& busy;
      ~Done() { --busy; }
    } done{busy_};
    process(c, std::move(t));
  }

  void sleep_unless_stopping(std::chrono::milliseconds d) {
    const auto end = Clock::now() + d;
    while (!stopping_ && Clock::now() < end) std::this_thread::sleep_for(20ms);
  }

  // Retries `f` on a fresh connection until it succeeds or the replica stops (results are
  // kept in memory meanwhile: Redis being down must not lose a finished job).
  template <class F>
  bool retry(std::unique_ptr<Connection>& c, F&& f) {
    auto backoff = 100ms;
    while (true) {
      try {
        if (!c || c->broken()) {
          c.reset();
          c = std::make_unique<Connection>(pool_.address(), pool_.timeout());
        }
        f(*c);
        return true;
      } catch (const RedisDown& e) {
        c.reset();
        mark_down(e.what());
      } catch (const RedisReplyError& e) {
        if (!transient_reply(e.what())) throw;
      }
      if (stopping_) return false;
      sleep_unless_stopping(backoff);
      backoff = std::min<std::chrono::milliseconds>(backoff * 2, 2000ms);
    }
  }

  // Runs a started job on the slot's connection `conn` (re-made when it breaks).
  void process(std::unique_ptr<Connection>& conn, Taken t) {
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
    std::unique_ptr<Connection>& beat = conn;
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
    enum class End { Finished, Lost, Released } end = End::Finished;
    if (!error) {
      auto job = e.early ? e.early : queue_.run_external(e.job_id, std::move(input));
      bool cancel_by_user = false;
      std::string last_stage;
      double last_fraction = -1;
      // Every 200 ms a read-only check (cancel flag, still ours); a heartbeat with the progress
      // (a write: it resets the entry's idle time) when the stage changes and at least every
      // quarter of the idle threshold (at most every second).
      const auto beat_every = std::chrono::milliseconds(std::clamp<std::int64_t>(reclaim_idle_ms_ / 4, 100, 1000));
      auto last_beat = Clock::now();
      while (!job->wait_for(200ms)) {
        if (stopping_ && end == End::Finished) {
          end = End::Released;
          queue_.cancel(job);
        }
        if (end != End::Finished || cancel_by_user) continue;
        const JobSnapshot s = job->snapshot();
        const bool changed = s.stage != last_stage || std::abs(s.fraction - last_fraction) >= 0.01;
        const bool due = s.stage != last_stage || Clock::now() - last_beat >= beat_every;
        char fraction[32];
        std::snprintf(fraction, sizeof fraction, "%.4f", s.fraction);
        try {
          if (!beat || beat->broken()) {
            beat.reset();
            beat = std::make_unique<Connection>(pool_.address(), pool_.timeout());
          }
          Reply b = beat->checked(views(due ? BeatArgs{job_key(e.job_id), stream_, consumer_, changed ? s.stage : "",
                                                       fraction, e.entry_id, kGroup}
                                                  .to_argv()
                                            : CheckArgs{job_key(e.job_id), consumer_}.to_argv()));
          if (due) {
            last_beat = Clock::now();
            last_stage = s.stage;
            last_fraction = s.fraction;
          }
          const std::string_view v = str(b.get());
          if (v == "cancel") {
            cancel_by_user = true;
            queue_.cancel(job);
          } else if (v == "lost") {
            end = End::Lost;
            queue_.cancel(job);
          }
        } catch (const RedisDown& ex) {
          beat.reset();
          mark_down(ex.what());  // the job goes on; its result waits for Redis below
        } catch (const RedisReplyError& ex) {
          if (log_) log_->warn("heartbeat_failed", {{"job_id", e.job_id}, {"detail", ex.what()}});
        }
      }
      const JobSnapshot s = job->snapshot();
      state = s.state;
      error = s.error;
      if (state == JobState::Cancelled && cancel_by_user)
        error = make_problem(ProblemType::Cancelled, "cancelled by DELETE while running");
      else if (state == JobState::Cancelled && end == End::Finished)  // cancelled by this replica's stop
        end = End::Released;
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
    if (end == End::Lost) {
      if (log_) log_->warn("job_lost", {{"job_id", e.job_id}, {"detail", "another replica took the job over"}});
      return;
    }
    std::unique_ptr<Connection>& fin = conn;
    if (end == End::Released) {
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
  void finisher_loop() {
    std::unique_ptr<Connection> c;
    for (;;) {
      std::optional<Finish> next = finishes_.pop();
      if (!next) return;
      Finish& f = *next;
      std::string stored;
      bool done = false;
      try {
        done = retry(c, [&](Connection& conn) {
          const std::string result = result_key(f.job_id), staged = result + ":" + consumer_;
          const Argv args = FinishArgs{job_key(f.job_id), input_key(f.job_id), stream_, result, staged, consumer_,
                                       f.state, f.error, f.summary, ttl_ms_, f.finished_ms, f.entry_id, kGroup,
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

  // ---------------------------------------------------------------- state
  const ServerConfig config_;
  JobQueue& queue_;
  const std::shared_ptr<const EventLog> log_;
  Pool pool_;
  const std::string prefix_, stream_, ttl_ms_;
  std::string exhausted_problem_, cancelled_problem_, lost_problem_;  // stored as a job's error
  const std::int64_t reclaim_idle_ms_;
  std::string consumer_;

  std::mutex rng_mutex_;
  std::mt19937_64 rng_;

  std::atomic<bool> up_{false}, ever_up_{false}, draining_{false}, stopping_{false};
  std::atomic<std::int64_t> length_{0}, pending_{0}, reclaimed_{0}, started_on_submit_{0}, retries_{0}, exhausted_{0}, reconnects_{0},
      results_served_locally_{0}, early_runs_discarded_{0};
  std::atomic<int> busy_{0};  // jobs taken and not yet stored (running, or waiting for the finisher)

  RecentResults recent_;

  WorkQueue<Finish> finishes_;  // slots -> the finisher
  std::thread finisher_;

  // Long polls waiting on this replica; each reads its job again at least every kWaitRecheck.
  static constexpr std::chrono::seconds kWaitRecheck{5};
  FinishWaiters waiters_;
  std::thread subscriber_;

  // Jobs submit() started for this replica's idle slots (lua/submit_start.lua).
  std::mutex handoff_mutex_;
  std::condition_variable handoff_cv_;
  std::deque<Taken> handoffs_;
  // Test hook (MDN_TEST_HANDOFF_PICKUP_DELAY_MS; tests/integration/redis_queue_test.cpp): a slot
  // handed a job waits this long before picking it up, which widens the window in which the
  // slot still counts as idle; never set in production.
  std::chrono::milliseconds handoff_pickup_delay_{0};
  int idle_slots_ = 0;  // slots waiting for work
  int reserved_ = 0;    // of those, promised to a submit() in flight

  std::mutex reclaim_mutex_;
  Clock::time_point next_reclaim_ = Clock::now();

  std::mutex monitor_mutex_;
  std::condition_variable monitor_wake_;
  std::thread monitor_;
  std::vector<std::thread> slots_;
  std::mutex stop_mutex_;
  bool stopped_ = false;
};

}  // namespace

std::unique_ptr<JobStore> make_redis_job_store(const ServerConfig& config, JobQueue& queue,
                                               std::shared_ptr<const EventLog> log) {
  return std::make_unique<RedisJobStore>(config, queue, std::move(log));
}

}  // namespace mdn::http
