// A small fixed-size thread pool with a blocking, statically partitioned parallel_for.
// Work is split into contiguous chunks by index, so per-element results never depend on
// the number of threads (no reductions happen inside parallel_for).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace mdn {

class Executor {
 public:
  // threads <= 1 runs everything on the calling thread. Not copyable.
  explicit Executor(int threads = 1);
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  int threads() const { return threads_; }

  // Calls fn(begin, end) on disjoint chunks covering [0, n) and waits for all of them.
  // Not re-entrant: one parallel_for at a time per Executor (the pipeline owns its own).
  void parallel_for(std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& fn);

 private:
  void worker_loop(int index);

  int threads_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  const std::function<void(std::int64_t, std::int64_t)>* task_ = nullptr;
  std::int64_t task_n_ = 0;
  std::uint64_t generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
};

}  // namespace mdn
