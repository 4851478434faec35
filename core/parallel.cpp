#include "core/parallel.h"

#include <algorithm>
#include <chrono>

namespace mdn {

namespace {
// Decision 47: how long a worker waits for the next task, and the caller for a running chunk,
// before it sleeps on a condition variable.
constexpr std::chrono::microseconds kSpin{200};

void relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

// Spins until done() or kSpin has passed (checking the clock every 64 rounds, and yielding the
// core then, so that a spinning thread gives way to any other that is ready to run); returns
// done().
template <typename Done>
bool spin_until(const Done& done) {
  const auto deadline = std::chrono::steady_clock::now() + kSpin;
  for (unsigned k = 1;; ++k) {
    if (done()) return true;
    if ((k & 63) == 0) {
      if (std::chrono::steady_clock::now() > deadline) return done();
      std::this_thread::yield();
    }
    relax();
  }
}
}  // namespace

Executor::Executor(int threads) : threads_(std::max(1, threads)) {
  for (int i = 1; i < threads_; ++i) workers_.emplace_back([this] { worker_loop(); });
}

Executor::~Executor() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  stopping_.store(true, std::memory_order_release);
  start_cv_.notify_all();
  for (auto& t : workers_) t.join();
}

namespace {
// Chunk `index` of `parts` contiguous chunks of [0, n).
std::pair<std::int64_t, std::int64_t> chunk(std::int64_t n, std::int64_t parts, std::int64_t index) {
  const std::int64_t base = n / parts, extra = n % parts;
  const std::int64_t begin = index * base + std::min<std::int64_t>(index, extra);
  return {begin, begin + base + (index < extra ? 1 : 0)};
}
}  // namespace

void Executor::parallel_for(std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& fn) {
  if (n <= 0) return;
  if (threads_ == 1 || n < 2 * threads_) {
    fn(0, n);
    return;
  }
  run(n, threads_, fn);
}

void Executor::parallel_for(std::int64_t n, std::int64_t grain, const std::function<void(std::int64_t, std::int64_t)>& fn) {
  if (n <= 0) return;
  const std::int64_t parts = std::min<std::int64_t>((n + std::max<std::int64_t>(grain, 1) - 1) / std::max<std::int64_t>(grain, 1),
                                                    64 * static_cast<std::int64_t>(threads_));
  if (threads_ == 1 || parts <= 1) {
    fn(0, n);
    return;
  }
  run(n, parts, fn);
}

// Claims and runs chunks of `generation` until none is left. The CAS fails once a newer
// generation has started, so a late worker never runs an old task's chunk.
void Executor::run_chunks(std::uint64_t generation, const Task& fn, std::int64_t n, std::int64_t parts) {
  std::uint64_t current = next_.load(std::memory_order_relaxed);
  for (;;) {
    if ((current >> 32) != (generation & 0xffffffffULL)) return;
    const auto index = static_cast<std::int64_t>(current & 0xffffffffULL);
    if (index >= parts) return;
    if (!next_.compare_exchange_weak(current, current + 1, std::memory_order_acq_rel, std::memory_order_relaxed)) continue;
    const auto [b, e] = chunk(n, parts, index);
    fn(b, e);
    if (done_.fetch_add(1, std::memory_order_acq_rel) + 1 == parts) {
      std::lock_guard lock(mutex_);
      done_cv_.notify_one();
    }
    current = next_.load(std::memory_order_relaxed);
  }
}

void Executor::run(std::int64_t n, std::int64_t parts, const Task& fn) {
  std::uint64_t generation;
  {
    std::lock_guard lock(mutex_);
    task_ = &fn;
    task_n_ = n;
    task_parts_ = parts;
    generation = ++generation_;
    done_.store(0, std::memory_order_relaxed);
    next_.store((generation & 0xffffffffULL) << 32, std::memory_order_release);
    published_.store(generation, std::memory_order_release);
  }
  start_cv_.notify_all();
  run_chunks(generation, fn, n, parts);
  // Every chunk is claimed; wait for those still running on workers.
  if (!spin_until([&] { return done_.load(std::memory_order_acquire) == parts; })) {
    std::unique_lock lock(mutex_);
    done_cv_.wait(lock, [&] { return done_.load(std::memory_order_acquire) == parts; });
  }
  std::lock_guard lock(mutex_);
  task_ = nullptr;
}

void Executor::worker_loop() {
  std::uint64_t seen = 0;
  for (;;) {
    std::uint64_t generation;
    const Task* task;
    std::int64_t n, parts;
    spin_until([&] { return stopping_.load(std::memory_order_acquire) || published_.load(std::memory_order_acquire) != seen; });
    {
      std::unique_lock lock(mutex_);
      start_cv_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation = generation_;
      task = task_;
      n = task_n_;
      parts = task_parts_;
      if (task == nullptr) continue;  // that task is over
    }
    // Copied under the lock with its generation: used only if a claim of that generation succeeds.
    run_chunks(generation, *task, n, parts);
  }
}

}  // namespace mdn
