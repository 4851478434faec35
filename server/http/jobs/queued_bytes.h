// The bytes of request bodies this process holds for jobs that have not started decoding yet
// (queued asynchronous and synchronous jobs alike): a bound for the server (--max-queued-bytes)
// and one per client (--client-max-queued-bytes), decision 79. A job's Hold is taken when its
// body has been read and released when the pool frees the body (its run has decoded it, or it
// ended without running); the Redis store releases it as soon as Redis keeps the body.
//
// Thread-safety contract: every method may be called from any thread at any time; one mutex
// guards the counts and is a leaf (nothing is called while it is held). A Hold may outlive its
// ledger (it shares the counts).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace mdn::http {

class QueuedBytes {
  struct Counts;

 public:
  // `total_limit` and `client_limit` in bytes, both >= 1.
  QueuedBytes(std::int64_t total_limit, std::int64_t client_limit);

  // Bytes counted for one client until release() or destruction. Move-only; empty by default.
  class Hold {
   public:
    Hold() = default;
    Hold(Hold&& other) noexcept;
    Hold& operator=(Hold&& other) noexcept;
    Hold(const Hold&) = delete;
    Hold& operator=(const Hold&) = delete;
    ~Hold() { release(); }
    void release();
    std::int64_t bytes() const { return bytes_; }

   private:
    friend class QueuedBytes;
    std::shared_ptr<Counts> counts_;
    std::string client_;
    std::int64_t bytes_ = 0;
  };

  // Throws HttpError when `bytes` more for `client` would pass a bound: 429 over-client-share
  // (the client's own share; others are still served) before 503 queue-full (the server's),
  // each with Retry-After `retry_after_s`. `bytes` larger than a bound alone is still admitted
  // when nothing is counted against that bound (a lone --max-body body always fits).
  void check(const std::string& client, std::int64_t bytes, int retry_after_s) const;
  // check(), then counts `bytes` for `client` (atomically with the check).
  Hold reserve(const std::string& client, std::int64_t bytes, int retry_after_s);

  std::int64_t total() const;
  std::int64_t total_limit() const { return total_limit_; }
  std::int64_t client_limit() const { return client_limit_; }

 private:
  void check_locked(const std::string& client, std::int64_t bytes, int retry_after_s) const;

  const std::int64_t total_limit_, client_limit_;
  std::shared_ptr<Counts> counts_;
};

}  // namespace mdn::http
