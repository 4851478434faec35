#include "server/http/jobs/redis/monitor.h"

#include <algorithm>
#include <chrono>

#include "server/http/jobs/worker_pool.h"
#include "server/http/jobs/redis/script_args.h"

namespace mdn::http::redis {

using namespace std::chrono_literals;

void Monitor::start() { thread_ = std::thread([this] { loop(); }); }

void Monitor::join() {
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void Monitor::mark_down(const std::string& why) {
  if (up_.exchange(false) && log_) log_->warn("redis_unavailable", {{"detail", why}});
  pool_.clear();
  wake_.notify_all();
}

void Monitor::mark_up() {
  if (up_.exchange(true)) return;
  if (ever_up_.exchange(true)) {
    ++reconnects_;
    if (log_) log_->info("redis_reconnected", {{"consumer", keys_.consumer}});
  } else if (log_) {
    log_->info("redis_connected", {{"consumer", keys_.consumer}});
  }
}

void Monitor::loop() {
  std::unique_ptr<Connection> c;
  bool warned = false;  // "unreachable at startup" is logged once
  auto next_forget = Clock::now() + 60s;
  while (!stopping_) {
    try {
      if (reconnect(c, pool_)) ensure_group(*c, keys_.stream);
      c->checked({"PING"});
      const std::int64_t len = c->checked({"XLEN", keys_.stream})->integer;
      Reply p = c->command({"XPENDING", keys_.stream, Keys::kGroup});
      if (p->type == REDIS_REPLY_ERROR) {  // NOGROUP: the stream was lost (Redis without persistence)
        ensure_group(*c, keys_.stream);
      } else if (p->type == REDIS_REPLY_ARRAY && p->elements > 0) {
        pending_ = p->element[0]->integer;
        length_ = std::max<std::int64_t>(0, len - pending_);
      }
      mark_up();
      if (Clock::now() >= next_forget) {
        next_forget = Clock::now() + 60s;
        Reply f = c->command(views(ForgetConsumersArgs{keys_.stream, Keys::kGroup, "3600000"}.to_argv()));
        if (f->type == REDIS_REPLY_INTEGER && f->integer > 0 && log_)
          log_->info("redis_consumers_forgotten", {{"count", f->integer}});
      }
    } catch (const std::exception& e) {
      c.reset();
      if (!ever_up_ && !warned && log_) log_->warn("redis_unavailable", {{"detail", e.what()}});
      warned = true;
      mark_down(e.what());
    }
    std::unique_lock lock(mutex_);
    wake_.wait_for(lock, up_ ? 1000ms : 250ms, [&] { return stopping_.load(); });
  }
}

}  // namespace mdn::http::redis
