// Prometheus metrics of the service (text exposition format 0.0.4), served at GET /metrics.
// Thread-safe: every method may be called from any thread (one mutex; updates are tiny).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

namespace mdn::http {

// A cumulative histogram with fixed upper bounds (seconds).
class Histogram {
 public:
  explicit Histogram(std::vector<double> bounds);
  void observe(double value);
  // Appends the _bucket, _sum and _count lines of `name`.
  void render(std::string& out, const std::string& name) const;

 private:
  std::vector<double> bounds_;
  std::vector<std::uint64_t> counts_;  // per bucket, not cumulative; last = +Inf
  double sum_ = 0;
  std::uint64_t count_ = 0;
};

class Metrics {
 public:
  Metrics();
  void count_request(const std::string& route, const std::string& method, int status);
  void add_bytes_in(std::int64_t n);
  void add_bytes_out(std::int64_t n);
  void job_finished(const std::string& state, double queue_wait_s, double run_s);

  struct Gauges {
    int queue_depth, queue_capacity, running, workers;
    bool draining;
    int long_polls;  // GET /v1/jobs/{id}?wait= requests waiting now
    std::int64_t queued_bytes = 0, max_queued_bytes = 0;  // request bodies no worker has taken yet, and their bound
  };
  // The whole exposition; gauges are read at scrape time.
  std::string render(const Gauges& gauges) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::tuple<std::string, std::string, int>, std::uint64_t> requests_;
  std::map<std::string, std::uint64_t> jobs_;
  std::uint64_t bytes_in_ = 0, bytes_out_ = 0;
  Histogram job_duration_, queue_wait_;
};

}  // namespace mdn::http
