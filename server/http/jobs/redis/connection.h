// hiredis, thinly wrapped: owned replies, one synchronous connection (used by one thread at a
// time), a pool of idle connections (thread-safe: its own mutex), and the two failures the store
// tells apart (RedisDown: unreachable; RedisReplyError: Redis said no). Only the files of this
// folder include hiredis.
#pragma once

#include <hiredis.h>
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "server/http/config.h"

namespace mdn::http::redis {

struct ReplyDeleter {
  void operator()(redisReply* r) const {
    if (r) freeReplyObject(r);
  }
};
using Reply = std::unique_ptr<redisReply, ReplyDeleter>;

// RedisDown: the connection failed (refused, reset, timed out), the store is unreachable.
// RedisReplyError: Redis answered with an error reply ("-ERR ...", "-LOADING ...").
struct RedisDown : std::runtime_error { using std::runtime_error::runtime_error; };
struct RedisReplyError : std::runtime_error { using std::runtime_error::runtime_error; };

// Element i of an array reply; anything else is a reply this code does not understand.
inline const redisReply* element(const redisReply* r, std::size_t i) {
  if (!r || r->type != REDIS_REPLY_ARRAY || i >= r->elements || !r->element[i])
    throw std::runtime_error("unexpected reply from Redis (expected an array of at least " + std::to_string(i + 1) + ")");
  return r->element[i];
}

inline std::string_view str(const redisReply* r) {
  if (!r || (r->type != REDIS_REPLY_STRING && r->type != REDIS_REPLY_STATUS && r->type != REDIS_REPLY_ERROR))
    return {};
  return {r->str, r->len};
}

// One synchronous connection; used by one thread at a time.
class Connection {
 public:
  Connection(const RedisAddress& a, std::chrono::milliseconds timeout) {
    const timeval connect_tv{1, 0};
    ctx_ = redisConnectWithTimeout(a.host.c_str(), a.port, connect_tv);
    if (!ctx_) throw RedisDown("cannot allocate a Redis context");
    if (ctx_->err) {
      const std::string why = ctx_->errstr;
      redisFree(ctx_);
      ctx_ = nullptr;
      throw RedisDown("cannot connect to Redis at " + a.host + ":" + std::to_string(a.port) + ": " + why);
    }
    const timeval tv{long(timeout.count() / 1000), long((timeout.count() % 1000) * 1000)};
    redisSetTimeout(ctx_, tv);
    if (!a.password.empty()) expect_ok(command({"AUTH", a.password}), "AUTH");
    if (a.db != 0) expect_ok(command({"SELECT", std::to_string(a.db)}), "SELECT");
  }
  ~Connection() {
    if (ctx_) redisFree(ctx_);
  }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Sends one command; an error reply is returned (callers decide), a broken connection throws
  // RedisDown and leaves this connection unusable.
  Reply command(const std::vector<std::string_view>& args) {
    if (broken_) throw RedisDown("connection already failed");
    std::vector<const char*> argv;
    std::vector<std::size_t> lens;
    argv.reserve(args.size());
    lens.reserve(args.size());
    for (auto a : args) {
      argv.push_back(a.data());
      lens.push_back(a.size());
    }
    Reply r(static_cast<redisReply*>(redisCommandArgv(ctx_, int(args.size()), argv.data(), lens.data())));
    if (!r) {
      broken_ = true;
      throw RedisDown(std::string("Redis connection failed: ") + (ctx_->err ? ctx_->errstr : "no reply"));
    }
    return r;
  }
  // Several commands in one round trip; replies in order (error replies included).
  std::vector<Reply> pipeline(const std::vector<std::vector<std::string_view>>& commands) {
    if (broken_) throw RedisDown("connection already failed");
    for (const auto& args : commands) {
      std::vector<const char*> argv;
      std::vector<std::size_t> lens;
      for (auto a : args) {
        argv.push_back(a.data());
        lens.push_back(a.size());
      }
      if (redisAppendCommandArgv(ctx_, int(args.size()), argv.data(), lens.data()) != REDIS_OK) {
        broken_ = true;
        throw RedisDown(std::string("Redis connection failed: ") + ctx_->errstr);
      }
    }
    std::vector<Reply> out;
    for (std::size_t i = 0; i < commands.size(); ++i) {
      void* r = nullptr;
      if (redisGetReply(ctx_, &r) != REDIS_OK || !r) {
        broken_ = true;
        throw RedisDown(std::string("Redis connection failed: ") + (ctx_->err ? ctx_->errstr : "no reply"));
      }
      out.emplace_back(static_cast<redisReply*>(r));
    }
    return out;
  }
  // Like command(), but an error reply throws RedisReplyError.
  Reply checked(const std::vector<std::string_view>& args) {
    Reply r = command(args);
    if (r->type == REDIS_REPLY_ERROR) throw RedisReplyError(std::string(str(r.get())));
    return r;
  }
  // Like pipeline(), but an error reply to any of the commands throws RedisReplyError.
  std::vector<Reply> checked_pipeline(const std::vector<std::vector<std::string_view>>& commands) {
    std::vector<Reply> replies = pipeline(commands);
    for (const Reply& r : replies)
      if (r->type == REDIS_REPLY_ERROR) throw RedisReplyError(std::string(str(r.get())));
    return replies;
  }
  // On a subscribed connection: the next message pushed by Redis, or nullptr when none came
  // within `wait`.
  Reply next_message(std::chrono::milliseconds wait) {
    if (broken_) throw RedisDown("connection already failed");
    void* r = nullptr;
    if (redisGetReplyFromReader(ctx_, &r) == REDIS_OK && !r) {
      pollfd p{ctx_->fd, POLLIN, 0};
      if (::poll(&p, 1, int(wait.count())) == 0) return Reply();
      if (redisGetReply(ctx_, &r) != REDIS_OK) r = nullptr;
    }
    if (!r) {
      broken_ = true;
      throw RedisDown(std::string("Redis connection failed: ") + (ctx_->err ? ctx_->errstr : "no reply"));
    }
    return Reply(static_cast<redisReply*>(r));
  }
  bool broken() const { return broken_; }

 private:
  static void expect_ok(const Reply& r, const char* what) {
    if (r->type == REDIS_REPLY_ERROR) throw RedisDown(std::string(what) + " refused: " + std::string(str(r.get())));
  }
  redisContext* ctx_ = nullptr;
  bool broken_ = false;
};

// Connections for request threads: taken, used, given back (a broken one is dropped).
class Pool {
 public:
  Pool(RedisAddress a, std::chrono::milliseconds timeout) : address_(std::move(a)), timeout_(timeout) {}
  std::unique_ptr<Connection> take() {
    {
      std::lock_guard lock(mutex_);
      if (!idle_.empty()) {
        auto c = std::move(idle_.back());
        idle_.pop_back();
        return c;
      }
    }
    return std::make_unique<Connection>(address_, timeout_);
  }
  void give(std::unique_ptr<Connection> c) {
    if (!c || c->broken()) return;
    std::lock_guard lock(mutex_);
    if (idle_.size() < 16) idle_.push_back(std::move(c));
  }
  void clear() {
    std::lock_guard lock(mutex_);
    idle_.clear();
  }
  const RedisAddress& address() const { return address_; }
  std::chrono::milliseconds timeout() const { return timeout_; }

 private:
  const RedisAddress address_;
  const std::chrono::milliseconds timeout_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Connection>> idle_;
};

// Redis error replies that mean "not now" rather than "never": loading, out of memory, a
// replica, a failed snapshot, or a password missing or wrong (the operator's to fix; 503 with
// Retry-After, as /readyz says).
inline bool transient_reply(std::string_view e) {
  for (std::string_view p : {"LOADING", "BUSY", "OOM", "READONLY", "MASTERDOWN", "TRYAGAIN", "CLUSTERDOWN",
                             "NOREPLICAS", "MISCONF", "NOAUTH", "WRONGPASS", "NOPERM"})
    if (e.rfind(p, 0) == 0) return true;
  return false;
}

}  // namespace mdn::http::redis
