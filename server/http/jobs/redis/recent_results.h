// The results this replica stored lately, so that GET /result through it need not read them
// back from Redis (a megabyte through Redis costs a few milliseconds each way). The store
// serves one only while Redis holds its job as succeeded with the same finish time (the entry's
// finished_ms): deleted and expired jobs are never served from here. Oldest out first, within
// a byte budget and a number of places; a result larger than a quarter of the budget is not kept.
//
// Thread-safety contract: every method may be called from any thread; one mutex guards the
// table, held only for the table's own work (never while copying a result out: entries share
// their bytes).
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace mdn::http::redis {

class RecentResults {
 public:
  struct Entry {
    std::string finished_ms;  // the job's finished_ms when it was stored
    std::shared_ptr<const std::string> bytes;
  };
  struct Limits {
    std::size_t bytes = std::size_t{64} << 20;  // all results together
    std::size_t places = 4096;                  // entries, counting those erased since (bounds the order)
  };
  RecentResults() : RecentResults(Limits{}) {}  // clang: a defaulted one is deleted (const limits_ with no initializer)
  explicit RecentResults(Limits limits) : limits_(limits) {}

  // Keeps `bytes` for job `id` (replacing an earlier entry), dropping the oldest beyond the limits.
  void add(const std::string& id, const std::string& finished_ms, std::string bytes);
  std::optional<Entry> find(const std::string& id) const;
  void erase(const std::string& id);  // DELETE of the job; its place goes when it comes first
  std::size_t total_bytes() const;

 private:
  void erase_locked(const std::string& id);

  const Limits limits_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, Entry> entries_;
  std::deque<std::string> order_;
  std::size_t total_ = 0;
};

}  // namespace mdn::http::redis
