#include "server/http/metrics.h"

#include <algorithm>
#include <charconv>
#include <iterator>
#include <string_view>

namespace mdn::http {
namespace {

// Shortest text that reads back as the same double ("0.005", not "0.0050000000000000001").
std::string format_double(double v) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : std::string("NaN");
}

// Label values: escape backslash, quote and newline (exposition format).
std::string escape_label(const std::string& v) {
  std::string out;
  for (char c : v) {
    if (c == '\\' || c == '"') out += '\\', out += c;
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

// Buckets from 5 ms to 10 min: the pipeline takes ~1 s on a 10k-face mesh (Table 2).
std::vector<double> duration_buckets() {
  return {0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120, 300, 600};
}

}  // namespace

Histogram::Histogram(std::vector<double> bounds) : bounds_(std::move(bounds)), counts_(bounds_.size() + 1, 0) {}

void Histogram::observe(double value) {
  std::size_t i = 0;
  while (i < bounds_.size() && value > bounds_[i]) ++i;
  ++counts_[i];
  sum_ += value;
  ++count_;
}

void Histogram::render(std::string& out, const std::string& name) const {
  std::uint64_t cumulative = 0;
  for (std::size_t i = 0; i < bounds_.size(); ++i) {
    cumulative += counts_[i];
    out += name + "_bucket{le=\"" + format_double(bounds_[i]) + "\"} " + std::to_string(cumulative) + "\n";
  }
  out += name + "_bucket{le=\"+Inf\"} " + std::to_string(count_) + "\n";
  out += name + "_sum " + format_double(sum_) + "\n";
  out += name + "_count " + std::to_string(count_) + "\n";
}

Metrics::Metrics() : job_duration_(duration_buckets()), queue_wait_(duration_buckets()) {}

void Metrics::count_request(const std::string& route, const std::string& method, int status) {
  // Issue 49, item 6: labels come from closed sets, so an attacker's methods (every distinct
  // one used to be a series forever: 20,000 made a scrape of 81 MB) all count as "other". The
  // route is already the route table's name ("unmatched" otherwise); a status outside
  // 100-599 (none is written) would be 0.
  static constexpr std::string_view kMethods[] = {"GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH", "CONNECT", "TRACE"};
  const bool known = std::find(std::begin(kMethods), std::end(kMethods), method) != std::end(kMethods);
  std::lock_guard lock(mutex_);
  ++requests_[{route, known ? method : std::string("other"), status >= 100 && status <= 599 ? status : 0}];
}

void Metrics::add_bytes_in(std::int64_t n) {
  std::lock_guard lock(mutex_);
  bytes_in_ += std::uint64_t(n);
}

void Metrics::add_bytes_out(std::int64_t n) {
  std::lock_guard lock(mutex_);
  bytes_out_ += std::uint64_t(n);
}

void Metrics::job_finished(const std::string& state, double queue_wait_s, double run_s) {
  std::lock_guard lock(mutex_);
  ++jobs_[state];
  queue_wait_.observe(queue_wait_s);
  job_duration_.observe(run_s);
}

std::string Metrics::render(const Gauges& g) const {
  std::lock_guard lock(mutex_);
  std::string out;
  out += "# HELP mdn_http_requests_total HTTP requests answered, by route pattern, method and status.\n";
  out += "# TYPE mdn_http_requests_total counter\n";
  for (const auto& [key, n] : requests_) {
    const auto& [route, method, status] = key;
    out += "mdn_http_requests_total{route=\"" + escape_label(route) + "\",method=\"" + escape_label(method) +
           "\",status=\"" + std::to_string(status) + "\"} " + std::to_string(n) + "\n";
  }
  out += "# HELP mdn_http_request_bytes_total Request body bytes received.\n";
  out += "# TYPE mdn_http_request_bytes_total counter\n";
  out += "mdn_http_request_bytes_total " + std::to_string(bytes_in_) + "\n";
  out += "# HELP mdn_http_response_bytes_total Response body bytes sent.\n";
  out += "# TYPE mdn_http_response_bytes_total counter\n";
  out += "mdn_http_response_bytes_total " + std::to_string(bytes_out_) + "\n";
  out += "# HELP mdn_jobs_total Jobs finished by a worker, by final state.\n";
  out += "# TYPE mdn_jobs_total counter\n";
  for (const auto& [state, n] : jobs_)
    out += "mdn_jobs_total{state=\"" + escape_label(state) + "\"} " + std::to_string(n) + "\n";
  out += "# HELP mdn_job_duration_seconds Running time of jobs (decode, denoise, encode).\n";
  out += "# TYPE mdn_job_duration_seconds histogram\n";
  job_duration_.render(out, "mdn_job_duration_seconds");
  out += "# HELP mdn_job_queue_wait_seconds Time jobs waited in the queue before a worker took them.\n";
  out += "# TYPE mdn_job_queue_wait_seconds histogram\n";
  queue_wait_.render(out, "mdn_job_queue_wait_seconds");
  out += "# HELP mdn_queue_depth Jobs waiting for a worker.\n# TYPE mdn_queue_depth gauge\n";
  out += "mdn_queue_depth " + std::to_string(g.queue_depth) + "\n";
  out += "# HELP mdn_queue_capacity Jobs the queue holds at most.\n# TYPE mdn_queue_capacity gauge\n";
  out += "mdn_queue_capacity " + std::to_string(g.queue_capacity) + "\n";
  out += "# HELP mdn_jobs_running Jobs being run by a worker.\n# TYPE mdn_jobs_running gauge\n";
  out += "mdn_jobs_running " + std::to_string(g.running) + "\n";
  out += "# HELP mdn_workers Worker threads.\n# TYPE mdn_workers gauge\n";
  out += "mdn_workers " + std::to_string(g.workers) + "\n";
  out += "# HELP mdn_draining 1 while the server drains after SIGTERM/SIGINT.\n# TYPE mdn_draining gauge\n";
  out += "mdn_draining " + std::string(g.draining ? "1" : "0") + "\n";
  out += "# HELP mdn_long_polls Long polls (GET /v1/jobs/{id}?wait=) waiting now; at most half the HTTP threads.\n"
         "# TYPE mdn_long_polls gauge\n";
  out += "mdn_long_polls " + std::to_string(g.long_polls) + "\n";
  out += "# HELP mdn_queued_request_bytes Bytes of request bodies this process holds for jobs no worker has taken yet "
         "(decision 79).\n# TYPE mdn_queued_request_bytes gauge\n";
  out += "mdn_queued_request_bytes " + std::to_string(g.queued_bytes) + "\n";
  out += "# HELP mdn_max_queued_request_bytes Their bound, --max-queued-bytes.\n# TYPE mdn_max_queued_request_bytes gauge\n";
  out += "mdn_max_queued_request_bytes " + std::to_string(g.max_queued_bytes) + "\n";
  return out;
}

}  // namespace mdn::http
