// The Prometheus text of GET /metrics (server/http/metrics.h): counters, cumulative histograms,
// label escaping, gauges.
#include "server/http/metrics.h"

#include <gtest/gtest.h>

#include <string>

namespace mdn::http {
namespace {

bool has_line(const std::string& text, const std::string& line) {
  return text.find("\n" + line + "\n") != std::string::npos || text.rfind(line + "\n", 0) == 0;
}

TEST(Metrics, CountersAddUpPerLabelSet) {
  Metrics m;
  m.count_request("/v1/jobs", "POST", 202);
  m.count_request("/v1/jobs", "POST", 202);
  m.count_request("/v1/jobs", "POST", 503);
  m.add_bytes_in(10);
  m.add_bytes_in(5);
  m.add_bytes_out(7);
  const std::string text = m.render({0, 64, 0, 2, false, 0, 0, 1});
  EXPECT_TRUE(has_line(text, R"(mdn_http_requests_total{route="/v1/jobs",method="POST",status="202"} 2)")) << text;
  EXPECT_TRUE(has_line(text, R"(mdn_http_requests_total{route="/v1/jobs",method="POST",status="503"} 1)")) << text;
  EXPECT_TRUE(has_line(text, "mdn_http_request_bytes_total 15"));
  EXPECT_TRUE(has_line(text, "mdn_http_response_bytes_total 7"));
  EXPECT_TRUE(has_line(text, "# TYPE mdn_http_requests_total counter"));
}

TEST(Metrics, LabelValuesAreEscaped) {
  Metrics m;
  m.count_request("a\"b\\c\nd", "GET", 404);
  const std::string text = m.render({0, 1, 0, 1, false, 0, 0, 1});
  EXPECT_NE(text.find(R"(route="a\"b\\c\nd")"), std::string::npos) << text;
}

TEST(Metrics, HistogramBucketsAreCumulativeWithSumAndCount) {
  Histogram h({0.1, 1});
  h.observe(0.05);
  h.observe(0.5);
  h.observe(0.5);
  h.observe(7);
  std::string text;
  h.render(text, "x_seconds");
  EXPECT_TRUE(has_line(text, R"(x_seconds_bucket{le="0.1"} 1)")) << text;
  EXPECT_TRUE(has_line(text, R"(x_seconds_bucket{le="1"} 3)")) << text;
  EXPECT_TRUE(has_line(text, R"(x_seconds_bucket{le="+Inf"} 4)")) << text;
  EXPECT_TRUE(has_line(text, "x_seconds_count 4")) << text;
  EXPECT_TRUE(has_line(text, "x_seconds_sum 8.05")) << text;
}

TEST(Metrics, FinishedJobsAreCountedByStateAndGaugesReadAtScrapeTime) {
  Metrics m;
  m.job_finished("succeeded", 0.01, 0.2);
  m.job_finished("failed", 0.01, 0.2);
  m.job_finished("succeeded", 0.01, 0.2);
  const std::string text = m.render({3, 64, 1, 2, true, 5, 4096, 65536});
  EXPECT_TRUE(has_line(text, R"(mdn_jobs_total{state="succeeded"} 2)")) << text;
  EXPECT_TRUE(has_line(text, R"(mdn_jobs_total{state="failed"} 1)")) << text;
  EXPECT_TRUE(has_line(text, "mdn_job_duration_seconds_count 3")) << text;
  EXPECT_TRUE(has_line(text, "mdn_queue_depth 3"));
  EXPECT_TRUE(has_line(text, "mdn_queue_capacity 64"));
  EXPECT_TRUE(has_line(text, "mdn_jobs_running 1"));
  EXPECT_TRUE(has_line(text, "mdn_workers 2"));
  EXPECT_TRUE(has_line(text, "mdn_draining 1"));
  EXPECT_TRUE(has_line(text, "mdn_long_polls 5"));
  EXPECT_TRUE(has_line(text, "mdn_queued_request_bytes 4096"));
  EXPECT_TRUE(has_line(text, "mdn_max_queued_request_bytes 65536"));
}

}  // namespace
}  // namespace mdn::http
