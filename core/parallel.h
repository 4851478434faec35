// A small fixed-size thread pool with a blocking parallel_for over contiguous chunks.
// Work is split into contiguous chunks by index, so per-element results never depend on
// the number of threads (no reductions happen inside parallel_for). Chunks are claimed, not
// assigned (decision 28): the calling thread takes any chunk no worker has started, so a worker
// that is slow to wake (a busy machine) or to run costs the caller nothing but its share.
// Between tasks, workers and the waiting caller spin for a short while before they sleep
// (decision 47): on a virtual machine a sleeping worker woke too late to take any chunk of a
// small mesh's pass, so those passes ran on one thread.
#pragma once

#include <atomic>
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

  // Calls fn(begin, end) on `threads()` disjoint contiguous chunks covering [0, n) and waits
  // for all of them (the same chunk boundaries as a static split; callers may keep per-chunk
  // scratch the size of the input). Not re-entrant: one parallel_for at a time per Executor.
  void parallel_for(std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& fn);
  // The same over chunks of about `grain` elements (at most 64 per thread), claimed in index
  // order by whichever thread is free: the filters' passes, whose chunks then fit the caches and
  // balance over cores that other processes share. fn must not keep per-chunk state whose cost
  // grows with n.
  void parallel_for(std::int64_t n, std::int64_t grain, const std::function<void(std::int64_t, std::int64_t)>& fn);

 private:
  using Task = std::function<void(std::int64_t, std::int64_t)>;
  void run(std::int64_t n, std::int64_t parts, const Task& fn);
  void run_chunks(std::uint64_t generation, const Task& fn, std::int64_t n, std::int64_t parts);
  void worker_loop();

  int threads_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  // The current task; written under mutex_ before generation_ moves, read by workers after.
  const Task* task_ = nullptr;
  std::int64_t task_n_ = 0, task_parts_ = 0;
  std::uint64_t generation_ = 0;
  // generation_ as last published, read without the lock by workers that spin (decision 47).
  std::atomic<std::uint64_t> published_{0};
  // (generation << 32) | next chunk: a claim from an earlier generation fails its CAS.
  std::atomic<std::uint64_t> next_{0};
  std::atomic<std::int64_t> done_{0};
  bool stop_ = false;
  std::atomic<bool> stopping_{false};
};

}  // namespace mdn
