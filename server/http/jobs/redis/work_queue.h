// A first-in first-out hand-over between threads: the worker slots push finished jobs, the
// store's finisher thread pops and stores them (so a slot takes its next job meanwhile).
// close() lets pop() drain what is left, then return nullopt.
//
// Thread-safety contract: every method may be called from any thread; one mutex guards the
// items and the closed flag, one condition variable wakes pop(). Items are moved in and out,
// never touched under the lock otherwise.
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

namespace mdn::http::redis {

template <class T>
class WorkQueue {
 public:
  void push(T item) {
    {
      std::lock_guard lock(mutex_);
      items_.push_back(std::move(item));
    }
    cv_.notify_one();
  }
  // Blocks until an item is there (the oldest comes out) or the queue is closed and empty.
  std::optional<T> pop() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return !items_.empty() || closed_; });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<T> items_;
  bool closed_ = false;
};

}  // namespace mdn::http::redis
