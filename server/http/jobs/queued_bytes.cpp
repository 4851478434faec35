#include "server/http/jobs/queued_bytes.h"

#include <algorithm>
#include <utility>

#include "server/http/problem.h"

namespace mdn::http {

struct QueuedBytes::Counts {
  std::mutex mutex;
  std::int64_t total = 0;
  std::map<std::string, std::int64_t> per_client;  // only clients with bytes counted
};

QueuedBytes::QueuedBytes(std::int64_t total_limit, std::int64_t client_limit)
    : total_limit_(std::max<std::int64_t>(1, total_limit)),
      client_limit_(std::max<std::int64_t>(1, client_limit)),
      counts_(std::make_shared<Counts>()) {}

QueuedBytes::Hold::Hold(Hold&& other) noexcept
    : counts_(std::move(other.counts_)), client_(std::move(other.client_)), bytes_(std::exchange(other.bytes_, 0)) {}

QueuedBytes::Hold& QueuedBytes::Hold::operator=(Hold&& other) noexcept {
  if (this != &other) {
    release();
    counts_ = std::move(other.counts_);
    client_ = std::move(other.client_);
    bytes_ = std::exchange(other.bytes_, 0);
  }
  return *this;
}

void QueuedBytes::Hold::release() {
  if (!counts_) return;
  {
    std::lock_guard lock(counts_->mutex);
    counts_->total -= bytes_;
    if (auto it = counts_->per_client.find(client_); it != counts_->per_client.end() && (it->second -= bytes_) <= 0)
      counts_->per_client.erase(it);
  }
  counts_.reset();
  bytes_ = 0;
}

void QueuedBytes::check_locked(const std::string& client, std::int64_t bytes, int retry_after_s) const {
  const auto it = counts_->per_client.find(client);
  const std::int64_t own = it == counts_->per_client.end() ? 0 : it->second;
  auto refuse = [&](ProblemType type, const std::string& detail, std::int64_t limit, std::int64_t held) {
    Problem p = make_problem(type, detail);
    p.retry_after_s = retry_after_s;
    p.extensions["limit_bytes"] = limit;
    p.extensions["queued_bytes"] = held;
    throw HttpError(std::move(p));
  };
  if (own > 0 && own + bytes > client_limit_)
    refuse(ProblemType::OverClientShare,
           "this client's queued request bodies would exceed its share of " + std::to_string(client_limit_) +
               " bytes (--client-max-queued-bytes); retry when its queued jobs have started",
           client_limit_, own);
  if (counts_->total > 0 && counts_->total + bytes > total_limit_)
    refuse(ProblemType::QueueFull,
           "the queued request bodies of all clients would exceed " + std::to_string(total_limit_) +
               " bytes (--max-queued-bytes); retry later",
           total_limit_, counts_->total);
}

void QueuedBytes::check(const std::string& client, std::int64_t bytes, int retry_after_s) const {
  std::lock_guard lock(counts_->mutex);
  check_locked(client, bytes, retry_after_s);
}

QueuedBytes::Hold QueuedBytes::reserve(const std::string& client, std::int64_t bytes, int retry_after_s) {
  Hold hold;
  std::lock_guard lock(counts_->mutex);
  check_locked(client, bytes, retry_after_s);
  counts_->total += bytes;
  counts_->per_client[client] += bytes;
  hold.counts_ = counts_;
  hold.client_ = client;
  hold.bytes_ = bytes;
  return hold;
}

std::int64_t QueuedBytes::total() const {
  std::lock_guard lock(counts_->mutex);
  return counts_->total;
}

}  // namespace mdn::http
