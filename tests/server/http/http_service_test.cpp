// The HTTP service's handlers over parts a test builds itself (ServiceParts, http_server.h): a fake job
// store stands in for Redis, so "the store is unreachable" needs no Redis server to stop.
#include "server/http/http_server.h"
#include "server/service_parts.h"

#include <httplib.h>
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

namespace mdn::http {
namespace {

using nlohmann::json;

// A store that is unavailable while `down` is set, and otherwise knows no job.
class FakeStore final : public JobStore {
 public:
  std::atomic<bool> down{false};
  std::atomic<int> submits{0};

  Problem outage() const {
    Problem p = make_problem(ProblemType::QueueUnavailable, "the fake store is down");
    p.retry_after_s = 2;
    return p;
  }
  Submitted submit(service::JobInput, const std::optional<std::string>&, const std::string&, Owner) override {
    ++submits;
    if (down) throw HttpError(outage());
    throw HttpError(make_problem(ProblemType::QueueFull, "the fake store takes nothing"));
  }
  std::optional<JobSnapshot> find(const std::string&, bool) override {
    if (down) throw HttpError(outage());
    return std::nullopt;
  }
  std::optional<JobSnapshot> wait_finished(const std::string& id, Clock::time_point) override { return find(id, false); }
  void result_fetched(const std::string&) override {}
  CancelResult cancel(const std::string&) override { return {}; }
  std::optional<Problem> unavailable() const override {
    if (down) return outage();
    return std::nullopt;
  }
  void begin_drain() override {}
  bool wait_drained(Clock::time_point) override { return true; }
  void stop() override {}
  void render_metrics(std::string& out) const override { out += "fake_store_up " + std::string(down ? "0" : "1") + "\n"; }
  std::string_view kind() const override { return "fake"; }
};

void expect_problem(const httplib::Result& r, int status, const std::string& slug, const std::string& what) {
  ASSERT_TRUE(r) << what;
  EXPECT_EQ(r->status, status) << what;
  EXPECT_EQ(r->get_header_value("Content-Type"), kProblemMediaType) << what;
  EXPECT_EQ(json::parse(r->body)["type"], "urn:meshdenoise:problem:" + slug) << what;
}

class HttpServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    config_.port = 0;
    config_.workers = 1;
    config_.io_threads = 4;
    config_.log_level = "off";
    ServiceParts parts;
    parts.metrics = std::make_unique<Metrics>();
    parts.pool = std::make_unique<WorkerPool>(make_pool_options(config_));
    auto store = std::make_unique<FakeStore>();
    store_ = store.get();
    parts.store = std::move(store);
    service_ = std::make_unique<HttpService>(config_, nullptr, std::move(parts));
    port_ = service_->bind();
    thread_ = std::thread([this] { service_->serve(); });
  }
  void TearDown() override {
    service_->stop();
    thread_.join();
  }
  httplib::Client client() { return httplib::Client("127.0.0.1", port_); }

  ServerConfig config_;
  FakeStore* store_ = nullptr;
  std::unique_ptr<HttpService> service_;
  int port_ = 0;
  std::thread thread_;
};

TEST_F(HttpServiceTest, ReadyWhileTheStoreIsUpAndNamesIt) {
  auto c = client();
  auto r = c.Get("/readyz");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(json::parse(r->body)["job_store"], "fake");
}

TEST_F(HttpServiceTest, StoreUnavailableAnswers503WithRetryAfterUntilItIsBack) {
  auto c = client();
  store_->down = true;
  for (const char* path : {"/readyz", "/v1/jobs/abc"}) {
    auto r = c.Get(path);
    expect_problem(r, 503, "queue-unavailable", path);
    if (r) {
      EXPECT_EQ(r->get_header_value("Retry-After"), "2") << path;
    }
  }
  auto posted = c.Post("/v1/jobs", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "model/x-off");
  ASSERT_TRUE(posted);
  EXPECT_EQ(posted->status, 503);
  EXPECT_EQ(store_->submits, 1);

  store_->down = false;
  EXPECT_EQ(c.Get("/readyz")->status, 200);
  expect_problem(c.Get("/v1/jobs/abc"), 404, "job-not-found", "once the store is back");
}

TEST_F(HttpServiceTest, MetricsCarryTheStoresLines) {
  auto c = client();
  auto r = c.Get("/metrics");
  ASSERT_TRUE(r);
  EXPECT_NE(r->body.find("fake_store_up 1"), std::string::npos) << r->body;
}

TEST_F(HttpServiceTest, SynchronousDenoiseNeverTouchesTheStore) {
  store_->down = true;
  auto c = client();
  auto r = c.Post("/v1/denoise", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "model/x-off");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(store_->submits, 0);
}

}  // namespace
}  // namespace mdn::http
