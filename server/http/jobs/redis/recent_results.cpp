#include "server/http/jobs/redis/recent_results.h"

#include <utility>

namespace mdn::http::redis {

void RecentResults::add(const std::string& id, const std::string& finished_ms, std::string bytes) {
  if (bytes.size() > limits_.bytes / 4) return;
  std::lock_guard lock(mutex_);
  erase_locked(id);
  total_ += bytes.size();
  entries_[id] = {finished_ms, std::make_shared<const std::string>(std::move(bytes))};
  order_.push_back(id);
  // Places of erased entries count too, so that order_ stays bounded however many results
  // DELETE removed meanwhile.
  while (!order_.empty() && (total_ > limits_.bytes || order_.size() > limits_.places)) {
    erase_locked(order_.front());
    order_.pop_front();
  }
}

std::optional<RecentResults::Entry> RecentResults::find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(id);
  if (it == entries_.end()) return std::nullopt;
  return it->second;
}

void RecentResults::erase(const std::string& id) {
  std::lock_guard lock(mutex_);
  erase_locked(id);
}

std::size_t RecentResults::total_bytes() const {
  std::lock_guard lock(mutex_);
  return total_;
}

void RecentResults::erase_locked(const std::string& id) {
  auto it = entries_.find(id);
  if (it == entries_.end()) return;
  total_ -= it->second.bytes->size();
  entries_.erase(it);
}

}  // namespace mdn::http::redis
