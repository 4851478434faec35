// Fair shares (issue 49, items 4 and 5; decisions 78 and 79), against the real server over
// loopback: one client over its share of the job store or of the queued request bytes is told
// 429 with Retry-After while another client is still served; downloaded and cancelled jobs give
// their slots up; the bytes of queued bodies are bounded, and the memory they took returns once
// the jobs end. Behind a --trusted-proxies proxy each forwarded client has its own share
// (decision 86). (The Redis store's shares: redis_queue_test, ClientSharesHoldAcrossReplicas.)
#include "http_fixture.h"

#include <optional>
#include <sstream>

namespace mdn::test {
namespace {

using nlohmann::json;

// Two (or more) clients of --api-keys; client(i) talks as the i-th.
class Clients {
 public:
  explicit Clients(int n) : dir_(temp_dir("shares")) {
    std::string text;
    for (int i = 0; i < n; ++i) {
      keys_.push_back("key-" + std::to_string(i) + "-aaaaaaaaaaaaaaaa");
      text += "client-" + std::to_string(i) + ":" + keys_.back() + "\n";
    }
    write_file(dir_ + "/keys", text);
  }
  ~Clients() { fs::remove_all(dir_); }
  std::string file() const { return dir_ + "/keys"; }
  std::unique_ptr<httplib::Client> as(const ServerProcess& s, int i) const {
    auto c = s.client();
    c->set_bearer_token_auth(keys_.at(std::size_t(i)).c_str());
    return c;
  }

 private:
  std::string dir_;
  std::vector<std::string> keys_;
};

// A body the server accepts as OFF (only a worker's decoding refuses it) of about `bytes`.
std::string off_of_size(std::size_t bytes) { return "OFF\n#" + std::string(bytes, 'x') + "\n"; }

// Keeps the only worker busy for about half a minute on an idle machine (level 6 took 6.5 s;
// the server's exit ends it), so that what is submitted next stays queued.
std::string start_long_job(httplib::Client& c) {
  auto r = c.Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, noisy_sphere_off(7, 3), "model/x-off");
  EXPECT_TRUE(r);
  if (!r) return {};
  EXPECT_EQ(r->status, 202) << r->body;
  return parse_json(r->body).value("id", "");
}

void expect_over_share(const httplib::Result& r) {
  const json p = expect_problem(r, 429);
  EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:over-client-share");
  ASSERT_TRUE(r);
  const int retry = std::atoi(r->get_header_value("Retry-After").c_str());
  EXPECT_GE(retry, 1) << "Retry-After: '" << r->get_header_value("Retry-After") << "'";
  EXPECT_LE(retry, 60);
}

// Finding 4: one key's never-fetched jobs filled the store (1,024 in under a second) and every
// other client got 503 store-full for the whole result lifetime.
TEST(HttpClientShares, OneClientSubmittingUntilRefusedGets429WhileAnotherIsServed) {
  Clients keys(2);
  ServerProcess s({"--api-keys", keys.file(), "--max-stored-jobs", "64", "--workers", "1"});
  ASSERT_TRUE(s.started()) << s.log();
  auto greedy = keys.as(s, 0);
  const std::string tiny = noisy_sphere_off(1);
  int accepted = 0;
  std::optional<httplib::Result> refused;
  for (int i = 0; i < 65 && !refused; ++i) {
    auto r = greedy->Post("/v1/jobs", tiny, "model/x-off");
    ASSERT_TRUE(r);
    if (r->status == 202) ++accepted;
    else refused.emplace(std::move(r));
  }
  ASSERT_TRUE(refused) << "65 jobs of one client were all accepted";
  EXPECT_EQ(accepted, 16) << "a quarter of --max-stored-jobs by default";
  expect_over_share(*refused);
  EXPECT_EQ(parse_json((*refused)->body).value("limit_jobs", 0), 16);
  // The other client is served, and gets its result.
  auto other = keys.as(s, 1);
  auto created = other->Post("/v1/jobs", tiny, "model/x-off");
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 202) << created->body;
  const std::string id = parse_json(created->body).value("id", "");
  EXPECT_EQ(wait_job(*other, id).value("state", ""), "succeeded");
  auto result = other->Get("/v1/jobs/" + id + "/result");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  // Still refused: nothing of the greedy client's was downloaded or cancelled.
  expect_over_share(greedy->Post("/v1/jobs", tiny, "model/x-off"));
}

// Finding 4's second half: a fetched result kept its slot until its lifetime ended, which capped
// throughput at --max-stored-jobs per --result-ttl. Downloaded and cancelled jobs give it up.
TEST(HttpClientShares, DownloadedAndCancelledJobsFreeTheirSlots) {
  ServerProcess s({"--max-stored-jobs", "4", "--client-max-stored-jobs", "4", "--workers", "1"});
  ASSERT_TRUE(s.started()) << s.log();
  auto c = s.client();
  const std::string tiny = noisy_sphere_off(1);
  auto submit_all = [&](const char* round) {
    std::vector<std::string> ids;
    for (int i = 0; i < 4; ++i) {
      auto r = c->Post("/v1/jobs", tiny, "model/x-off");
      EXPECT_TRUE(r) << round;
      if (!r) continue;
      EXPECT_EQ(r->status, 202) << round << ", job " << i << ": " << r->body;
      if (r->status == 202) ids.push_back(parse_json(r->body).value("id", ""));
    }
    return ids;
  };
  for (const std::string& id : submit_all("first round")) {
    EXPECT_EQ(wait_job(*c, id).value("state", ""), "succeeded");
    auto r = c->Get("/v1/jobs/" + id + "/result");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
  }
  const std::vector<std::string> second = submit_all("after downloading every result");
  ASSERT_EQ(second.size(), 4u);
  // Full again: a fifth is refused (the client's share and the store are both taken).
  expect_over_share(c->Post("/v1/jobs", tiny, "model/x-off"));
  for (const std::string& id : second) {
    auto r = c->Delete("/v1/jobs/" + id);
    ASSERT_TRUE(r);
    EXPECT_TRUE(r->status == 200 || r->status == 202 || r->status == 204) << r->status << " " << r->body;
  }
  for (const std::string& id : second) wait_job(*c, id);  // a running one ends cancelled
  EXPECT_EQ(submit_all("after cancelling every job").size(), 4u);
}

// Finding 5: 25 queued bodies of 40 MB took the server to 1.46 GB. Each client may queue its
// share of bytes (429 beyond), all clients together --max-queued-bytes (503 queue-full beyond);
// a body declared over a share is refused before it is read.
TEST(HttpClientShares, QueuedBytesOverAShareAreRefusedAndMemoryStaysBounded) {
  Clients keys(4);
  ServerProcess s({"--api-keys", keys.file(), "--workers", "1", "--max-queued-bytes", "25M",
                   "--client-max-queued-bytes", "12M"});
  ASSERT_TRUE(s.started()) << s.log();
  auto first = keys.as(s, 0);
  ASSERT_FALSE(start_long_job(*first).empty());
  const std::string body = off_of_size(8 << 20);
  auto a = first->Post("/v1/jobs", body, "model/x-off");
  ASSERT_TRUE(a);
  ASSERT_EQ(a->status, 202) << a->body;
  auto metrics = s.client()->Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_EQ(metric_value(metrics->body, "mdn_queued_request_bytes"), double(body.size()));
  EXPECT_EQ(metric_value(metrics->body, "mdn_max_queued_request_bytes"), double(25 << 20));
  const double rss_one = status_mib(s.pid(), "VmRSS");
  // The same client again: 16 MB would pass its 12 MB share. Twenty times: none is kept.
  for (int i = 0; i < 20; ++i) {
    auto r = first->Post("/v1/jobs", body, "model/x-off");
    expect_over_share(r);
    if (r && i == 0) {
      EXPECT_EQ(parse_json(r->body).value("limit_bytes", 0), 12 << 20);
    }
  }
  EXPECT_LT(status_mib(s.pid(), "VmRSS"), rss_one + 40) << "refused bodies were kept";
  // Other clients are served until all of them together reach --max-queued-bytes.
  auto second = keys.as(s, 1)->Post("/v1/jobs", body, "model/x-off");
  ASSERT_TRUE(second);
  EXPECT_EQ(second->status, 202) << second->body;
  auto third = keys.as(s, 2)->Post("/v1/jobs", body, "model/x-off");
  ASSERT_TRUE(third);
  EXPECT_EQ(third->status, 202) << third->body;
  auto fourth = keys.as(s, 3)->Post("/v1/jobs", body, "model/x-off");
  const json p = expect_problem(fourth, 503);
  EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:queue-full");
  ASSERT_TRUE(fourth);
  EXPECT_FALSE(fourth->get_header_value("Retry-After").empty());
  // Once the first client's queued job is cancelled, its share is free again.
  ASSERT_TRUE(first->Delete("/v1/jobs/" + parse_json(a->body).value("id", "")));
  auto again = first->Post("/v1/jobs", body, "model/x-off");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 202) << again->body;
}

// Finding 5's second half: 735 MB stayed resident after every queued body was cancelled.
TEST(HttpClientShares, MemoryOfCancelledBodiesReturns) {
  ServerProcess s({"--workers", "1"});
  ASSERT_TRUE(s.started()) << s.log();
  auto c = s.client();
  const std::string long_job = start_long_job(*c);
  ASSERT_FALSE(long_job.empty());
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));  // decoded: its memory settles
  const double before = status_mib(s.pid(), "VmRSS");
  const std::string body = off_of_size(24 << 20);
  std::vector<std::string> ids;
  for (int i = 0; i < 6; ++i) {
    auto r = c->Post("/v1/jobs", body, "model/x-off");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 202) << r->body;
    ids.push_back(parse_json(r->body).value("id", ""));
  }
  const double queued = status_mib(s.pid(), "VmRSS");
  EXPECT_GT(queued, before + 120) << "the queued bodies were not resident (the test measures nothing)";
  for (const std::string& id : ids) {
    auto r = c->Delete("/v1/jobs/" + id);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;  // cancelled while queued
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_LT(status_mib(s.pid(), "VmRSS"), before + 50)
      << "VmRSS " << before << " MiB before, " << queued << " MiB with 144 MB queued";
  auto still = c->Get("/v1/jobs/" + long_job);
  ASSERT_TRUE(still);
  EXPECT_EQ(parse_json(still->body).value("state", ""), "running") << "the worker was free: " << still->body;
}


// Decision 86: behind the shipped nginx every client arrived from nginx's address and shared one
// share, so one anonymous client over it locked every other out (issue 49's finding 4 again).
// From a --trusted-proxies peer the client is the rightmost untrusted X-Forwarded-For entry.
// Here the loopback peer plays nginx; `xff` is what nginx would send (the client's own header,
// if any, then the address it saw). Returns the statuses of `n` tiny jobs.
std::vector<int> submit_as(httplib::Client& c, const std::string& xff, int n) {
  std::vector<int> statuses;
  for (int i = 0; i < n; ++i) {
    auto r = c.Post("/v1/jobs", {{"X-Forwarded-For", xff}}, noisy_sphere_off(1), "model/x-off");
    EXPECT_TRUE(r) << xff;
    if (!r) break;
    if (r->status != 202) expect_over_share(r);
    statuses.push_back(r->status);
  }
  return statuses;
}

TEST(HttpClientShares, BehindATrustedProxyEachForwardedClientHasItsOwnShare) {
  ServerProcess s({"--trusted-proxies", "10.0.0.0/8,127.0.0.1/32,::1/128", "--client-max-stored-jobs", "2",
                   "--workers", "1", "--log-format", "json"});
  ASSERT_TRUE(s.started()) << s.log();
  auto c = s.client();
  EXPECT_EQ(submit_as(*c, "198.51.100.1", 3), (std::vector<int>{202, 202, 429}));
  // A second client through the same proxy is served; its own share ends at 2 as well.
  EXPECT_EQ(submit_as(*c, "198.51.100.2", 3), (std::vector<int>{202, 202, 429}));
  // Spoofing: entries a client writes itself stay left of the one the proxy appends, and the
  // walk stops at that one (here as the first client, whatever it claims to be).
  EXPECT_EQ(submit_as(*c, "198.51.100.3, 198.51.100.1", 1), (std::vector<int>{429}));
  // Through a chain of trusted proxies (a load balancer's 10.x before nginx), a third client.
  EXPECT_EQ(submit_as(*c, "198.51.100.1, 203.0.113.9, 10.1.2.3", 1), (std::vector<int>{202}));
  // The access log names the client, and the proxy it came through.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  int logged = 0;
  std::istringstream lines(s.log());
  for (std::string line; std::getline(lines, line);) {
    const json j = parse_json(line);
    if (!j.is_object() || j.value("event", "") != "request" || j.value("route", "") != "/v1/jobs") continue;
    EXPECT_EQ(j.value("proxy", ""), "127.0.0.1") << line;
    const std::string remote = j.value("remote", "");
    EXPECT_TRUE(remote == "198.51.100.1" || remote == "198.51.100.2" || remote == "203.0.113.9") << line;
    ++logged;
  }
  EXPECT_EQ(logged, 8) << s.log();
}

// Without the flag, or from a peer outside it, X-Forwarded-For is anybody's to write: ignored,
// and the same traffic is one client (the peer's address).
TEST(HttpClientShares, FromAnUntrustedPeerForwardedForIsIgnored) {
  const std::vector<std::vector<std::string>> trusts = {{}, {"--trusted-proxies", "10.0.0.0/8,::1/128"}};
  for (const std::vector<std::string>& trust : trusts) {
    std::vector<std::string> args = {"--client-max-stored-jobs", "2", "--workers", "1"};
    args.insert(args.end(), trust.begin(), trust.end());
    ServerProcess s(args);
    ASSERT_TRUE(s.started()) << s.log();
    auto c = s.client();
    EXPECT_EQ(submit_as(*c, "198.51.100.1", 2), (std::vector<int>{202, 202})) << trust.size();
    EXPECT_EQ(submit_as(*c, "198.51.100.2", 1), (std::vector<int>{429})) << trust.size();
  }
}

TEST(HttpClientShares, ABadTrustedProxyListStopsTheServer) {
  ServerProcess s({"--trusted-proxies", "10.0.0.0/8,192.168.0.0/33"});
  EXPECT_EQ(s.wait_exit(), 2);
  EXPECT_NE(s.log().find("--trusted-proxies: '192.168.0.0/33' is not an IPv4 or IPv6"), std::string::npos) << s.log();
}

}  // namespace
}  // namespace mdn::test
