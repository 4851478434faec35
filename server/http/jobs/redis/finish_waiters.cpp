#include "server/http/jobs/redis/finish_waiters.h"

namespace mdn::http::redis {

FinishWaiters::Ticket FinishWaiters::enter(const std::string& id) {
  std::lock_guard lock(mutex_);
  Entry& e = entries_[id];
  ++e.count;
  return Ticket(*this, id, e.done);
}

void FinishWaiters::wait(Ticket& ticket, Clock::time_point until, const std::function<bool()>& give_up) {
  std::unique_lock lock(mutex_);
  cv_.wait_until(lock, until, [&] { return entries_[ticket.id_].done != ticket.seen_ || give_up(); });
  ticket.seen_ = entries_[ticket.id_].done;
}

void FinishWaiters::done(const std::string& id) {
  std::lock_guard lock(mutex_);
  if (auto it = entries_.find(id); it != entries_.end()) {
    ++it->second.done;
    cv_.notify_all();
  }
}

void FinishWaiters::wake_all() {
  std::lock_guard lock(mutex_);
  for (auto& [id, e] : entries_) ++e.done;
  cv_.notify_all();
}

void FinishWaiters::leave(const std::string& id) {
  std::lock_guard lock(mutex_);
  if (auto it = entries_.find(id); it != entries_.end() && --it->second.count == 0) entries_.erase(it);
}

}  // namespace mdn::http::redis
