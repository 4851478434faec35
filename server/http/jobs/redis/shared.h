// What the store's parts (store, monitor, worker_slots) share: the names this replica uses in
// Redis, the consumer group's creation, and the two waits of their own threads (a connection
// re-made when broken, a sleep cut short by the stop flag).
//
// Thread-safety contract: Keys is a plain value, set once by the store's constructor and read
// from any thread; the functions touch only their arguments (a Connection is used by one thread
// at a time).
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "server/http/jobs/redis/connection.h"

namespace mdn::http::redis {

struct Keys {
  static constexpr const char* kGroup = "workers";  // the stream's one consumer group
  std::string prefix;    // --queue-prefix
  std::string stream;    // <prefix>queue
  std::string consumer;  // this replica's consumer name in the group
  std::string job(const std::string& id) const { return prefix + "job:" + id; }
  std::string input(const std::string& id) const { return prefix + "job:" + id + ":input"; }
  std::string result(const std::string& id) const { return prefix + "job:" + id + ":result"; }
};

// XGROUP CREATE ... MKSTREAM; a group already there is fine.
inline void ensure_group(Connection& c, const std::string& stream) {
  Reply r = c.command({"XGROUP", "CREATE", stream, Keys::kGroup, "0", "MKSTREAM"});
  if (r->type == REDIS_REPLY_ERROR && str(r.get()).rfind("BUSYGROUP", 0) != 0)
    throw RedisReplyError(std::string(str(r.get())));
}

// A thread's own connection: made anew (to the pool's address) when there is none or it broke.
// True when it was made now.
inline bool reconnect(std::unique_ptr<Connection>& c, const Pool& pool) {
  if (c && !c->broken()) return false;
  c.reset();
  c = std::make_unique<Connection>(pool.address(), pool.timeout());
  return true;
}

// Sleeps `d`, in steps of 20 ms, unless `stopping` is (or becomes) set.
inline void sleep_unless(const std::atomic<bool>& stopping, std::chrono::milliseconds d) {
  const auto end = std::chrono::steady_clock::now() + d;
  while (!stopping && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

}  // namespace mdn::http::redis
