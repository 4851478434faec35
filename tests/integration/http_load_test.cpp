// Concurrency and operations against the real binary: 32 concurrent clients answered
// correctly, overload answered with 503 + Retry-After, a vanished client cancels its job,
// and SIGTERM drains without losing an accepted job.
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "http_fixture.h"

namespace mdn::test {
namespace {

using nlohmann::json;


std::string cli_denoise(const std::string& dir, const std::string& input, const std::string& name) {
  write_file(dir + "/" + name + ".off", input);
  const auto [code, out] = run_command(cli_binary() + " " + shell_quote(dir + "/" + name + ".off") + " " +
                                       shell_quote(dir + "/" + name + "_out.off") + " 2>&1");
  EXPECT_EQ(code, 0) << out;
  return read_file(dir + "/" + name + "_out.off");
}

// Posts n asynchronous OFF jobs; the ids of those answered 202 (fewer on any other answer).
std::vector<std::string> post_jobs(httplib::Client& c, int n, const std::string& body, const std::string& params) {
  std::vector<std::string> ids;
  for (int i = 0; i < n; ++i) {
    auto r = c.Post("/v1/jobs", {{"X-Denoise-Params", params}}, body, "model/x-off");
    if (!r || r->status != 202) break;
    ids.push_back(parse_json(r->body)["id"]);
  }
  return ids;
}

TEST(HttpLoad, ThirtyTwoConcurrentClientsAllAnsweredCorrectly) {
  ServerProcess server({"--workers", "2", "--queue-capacity", "64"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string dir = temp_dir("load");
  // Four distinct inputs, each sent by eight clients at once; every answer must equal the CLI's.
  std::vector<std::string> inputs, expected;
  for (int i = 0; i < 4; ++i) {
    inputs.push_back(noisy_sphere_off(2, 100 + std::uint64_t(i)));
    expected.push_back(cli_denoise(dir, inputs.back(), "in" + std::to_string(i)));
  }
  std::atomic<int> correct{0};
  std::mutex failures_mutex;
  std::vector<std::string> failures;
  std::vector<std::thread> clients;
  for (int k = 0; k < 32; ++k) {
    clients.emplace_back([&, k] {
      auto c = server.client();
      const int i = k % 4;
      const bool async = k % 2 == 1;
      std::string body;
      int status = 0;
      if (!async) {
        auto r = c->Post("/v1/denoise", inputs[std::size_t(i)], "model/x-off");
        status = r ? r->status : -1;
        body = r ? r->body : httplib::to_string(r.error());
      } else {
        auto r = c->Post("/v1/jobs", inputs[std::size_t(i)], "model/x-off");
        status = r ? r->status : -1;
        if (!r) body = httplib::to_string(r.error());
        if (r && r->status == 202) {
          const json job = wait_job(*c, parse_json(r->body).value("id", ""));
          auto res = c->Get("/v1/jobs/" + job.value("id", "") + "/result");
          status = res ? res->status : -1;
          if (res) body = res->body;
        }
      }
      if (status == 200 && body == expected[std::size_t(i)]) {
        ++correct;
      } else {
        std::lock_guard lock(failures_mutex);
        failures.push_back("client " + std::to_string(k) + (async ? " (async)" : " (sync)") + ": status " +
                           std::to_string(status) + (status == 200 ? " with other bytes" : "") + "; " +
                           body.substr(0, 300));
      }
    });
  }
  for (auto& t : clients) t.join();
  std::string all;
  for (const auto& f : failures) all += f + "\n";
  EXPECT_EQ(correct.load(), 32) << all << server.log();
  EXPECT_EQ(server.client()->Get("/healthz")->status, 200);
  fs::remove_all(dir);
}

TEST(HttpLoad, IdleConnectionsDoNotStarveOtherClients) {
  // cpp-httplib holds one I/O thread per open connection: with 4 threads, 12 idle connections
  // would block everyone else if idle connections were kept long. The short keep-alive frees
  // their threads, so a new client is still answered.
  ServerProcess server({"--io-threads", "4", "--keep-alive-timeout", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  std::vector<int> idle;
  for (int i = 0; i < 12; ++i) {
    const int fd = connect_loopback(server.port());
    ASSERT_GE(fd, 0);
    idle.push_back(fd);
  }
  auto c = server.client(/*read_timeout_s=*/20);
  auto r = c->Get("/healthz");
  ASSERT_TRUE(r) << httplib::to_string(r.error());
  EXPECT_EQ(r->status, 200);
  for (int fd : idle) close(fd);
}

TEST(HttpLoad, OverloadGives503WithRetryAfterAndNothingWorse) {
  ServerProcess server({"--workers", "1", "--queue-capacity", "2"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string heavy = noisy_sphere_off(4, 5);
  std::vector<std::string> accepted;
  int refused = 0;
  for (int i = 0; i < 8; ++i) {
    auto r = c->Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, heavy, "model/x-off");
    ASSERT_TRUE(r);
    if (r->status == 202) {
      accepted.push_back(r->get_header_value("Location"));
    } else {
      const json p = expect_problem(r, 503);
      EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:queue-full");
      EXPECT_GE(std::atoi(r->get_header_value("Retry-After").c_str()), 1);
      ++refused;
    }
  }
  // One running and two queued at most, whatever the timing.
  EXPECT_LE(accepted.size(), 3u);
  EXPECT_GE(refused, 5);
  // A full queue also refuses synchronous work, and /readyz reports it.
  expect_problem(c->Post("/v1/denoise", heavy, "model/x-off"), 503);
  auto ready = c->Get("/readyz");
  expect_problem(ready, 503);
  EXPECT_FALSE(ready->get_header_value("Retry-After").empty());
  EXPECT_EQ(c->Get("/healthz")->status, 200);
  for (const auto& url : accepted) c->Delete(url);
  // Once the queue drains, the server takes work again.
  for (int i = 0; i < 500 && c->Get("/readyz")->status != 200; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(c->Get("/readyz")->status, 200);
  auto ok = c->Post("/v1/denoise", noisy_sphere_off(1), "model/x-off");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
}

TEST(HttpLoad, VanishedClientCancelsItsJob) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string heavy = noisy_sphere_off(5, 6);
  {
    // A raw client: send the whole request, then go away without reading the answer.
    const int fd = connect_loopback(server.port());
    ASSERT_GE(fd, 0);
    const std::string head = std::string("POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\n") +
                             "X-Denoise-Params: " + kHeavyParams + "\r\nContent-Length: " +
                             std::to_string(heavy.size()) + "\r\n\r\n";
    const std::string request = head + heavy;
    std::size_t sent = 0;
    while (sent < request.size()) {
      const ssize_t n = send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
      ASSERT_GT(n, 0);
      sent += std::size_t(n);
    }
    auto c = server.client();
    for (int i = 0; i < 200 && c->Get("/readyz")->body.find("\"running\":1") == std::string::npos; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    close(fd);
  }
  auto c = server.client();
  double cancelled = 0;
  for (int i = 0; i < 250 && cancelled < 1; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    cancelled = metric_value(c->Get("/metrics")->body, "mdn_jobs_total{state=\"cancelled\"}");
  }
  EXPECT_EQ(cancelled, 1) << server.log();
  EXPECT_NE(server.log().find("client_gone"), std::string::npos);
  // The worker is free again at once.
  auto ok = c->Post("/v1/denoise", noisy_sphere_off(1), "model/x-off");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
}

TEST(HttpLoad, SigtermDrainsWithoutLosingAcceptedJobs) {
  ServerProcess server({"--workers", "1", "--drain-grace", "60"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  // Jobs of about half a second each, so the drain is still on when the test looks at it.
  const std::string medium = noisy_sphere_off(5, 7);
  const std::string params = R"({"n_normal":300,"n_vertex":100})";
  const std::vector<std::string> ids = post_jobs(*c, 3, medium, params);
  ASSERT_EQ(ids.size(), 3u);
  // A synchronous request in flight when the signal comes is answered too.
  std::string sync_body;
  int sync_status = 0;
  std::thread sync_client([&] {
    auto sc = server.client();
    auto r = sc->Post("/v1/denoise", {{"X-Denoise-Params", params}}, medium, "model/x-off");
    sync_status = r ? r->status : -1;
    if (r) sync_body = r->body;
  });
  // The signal only once the synchronous job is in (queued, running or done: four jobs in all);
  // a fixed pause lost that race on a loaded machine.
  const auto in_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  for (;;) {
    auto m = c->Get("/metrics");
    ASSERT_TRUE(m && m->status == 200);
    const double jobs = metric_value(m->body, "mdn_queue_depth") + metric_value(m->body, "mdn_jobs_running") +
                        std::max(0.0, metric_value(m->body, "mdn_jobs_total{state=\"succeeded\"}"));
    if (jobs >= 4) break;
    ASSERT_LT(std::chrono::steady_clock::now(), in_deadline) << "the synchronous job never arrived";
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  server.signal(SIGTERM);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  // Draining: not ready, no new jobs, but accepted jobs run.
  expect_problem(c->Get("/readyz"), 503);
  const json refused = expect_problem(c->Post("/v1/jobs", medium, "model/x-off"), 503);
  EXPECT_EQ(refused.value("type", ""), "urn:meshdenoise:problem:draining");
  sync_client.join();
  EXPECT_EQ(sync_status, 200);
  EXPECT_EQ(sync_body.rfind("OFF", 0), 0u);
  // Every accepted job done: the process exits 0 on its own, as soon as the last one ends
  // (results not downloaded do not hold it: server_lifecycle_test).
  EXPECT_EQ(server.wait_exit(std::chrono::seconds(60)), 0) << server.log();
  const std::string log = server.log();
  for (const auto& id : ids) {
    std::istringstream lines(log);
    bool succeeded = false;
    for (std::string line; std::getline(lines, line);)
      succeeded |= line.find("job_finished") != std::string::npos && line.find(id) != std::string::npos &&
                   line.find("state=succeeded") != std::string::npos;
    EXPECT_TRUE(succeeded) << id << " did not finish:\n" << log;
  }
}

// Issue 17: synchronous requests took stored-job slots, so accepted asynchronous jobs were
// evicted before their lifetime (1,063 of 1,572 answered 202 then 404). Now the store refuses
// new jobs when full, and every accepted job stays retrievable.
TEST(HttpLoad, AFullJobStoreRefusesNewJobsAndEvictsNone) {
  ServerProcess server({"--workers", "2", "--max-stored-jobs", "3", "--client-max-stored-jobs", "4"});  // one client may fill it
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string small = noisy_sphere_off(1);
  const std::string params = R"({"n_normal":3,"n_vertex":3})";
  std::vector<std::string> ids = post_jobs(*c, 3, small, params);
  ASSERT_EQ(ids.size(), 3u);
  // Synchronous requests take no slot: many of them, all answered, none evicts a job.
  for (int i = 0; i < 8; ++i) {
    auto r = c->Post("/v1/denoise", {{"X-Denoise-Params", params}}, small, "model/x-off");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;
  }
  const json refused = expect_problem(c->Post("/v1/jobs", {{"X-Denoise-Params", params}}, small, "model/x-off"), 503);
  EXPECT_EQ(refused.value("type", ""), "urn:meshdenoise:problem:store-full") << refused.dump();
  for (const auto& id : ids) {
    EXPECT_EQ(wait_job(*c, id).value("state", ""), "succeeded") << id;
    auto result = c->Get("/v1/jobs/" + id + "/result");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200) << id;
  }
  // DELETE frees a slot.
  auto deleted = c->Delete("/v1/jobs/" + ids[0]);
  ASSERT_TRUE(deleted);
  auto again = c->Post("/v1/jobs", {{"X-Denoise-Params", params}}, small, "model/x-off");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 202) << again->body;
}


// Issue 17: after an overload, accepted jobs returned 404 before their lifetime. Eight seconds
// of four clients posting as fast as they can (far beyond one worker's capacity): every job
// answered 202 is still there, finished, with its result. The memory figures are printed, not
// asserted (the 1.5x target is a benchmark figure).
TEST(HttpLoad, AnOverloadLosesNoAcceptedJob) {
  // The four clients are one address, one share: larger than the store, so that it fills (decision 78).
  ServerProcess server({"--workers", "1", "--queue-capacity", "8", "--max-stored-jobs", "256", "--client-max-stored-jobs", "257",
                        "--result-ttl", "120"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string small = noisy_sphere_off(1);
  const std::string params = R"({"n_normal":5,"n_vertex":5})";
  const double rss_before = status_mib(server.pid(), "VmRSS");
  std::mutex mutex;
  std::vector<std::string> accepted;
  std::map<int, int> statuses;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(8);
  std::vector<std::thread> clients;
  for (int k = 0; k < 4; ++k)
    clients.emplace_back([&] {
      auto c = server.client();
      while (std::chrono::steady_clock::now() < end) {
        auto r = c->Post("/v1/jobs", {{"X-Denoise-Params", params}}, small, "model/x-off");
        std::lock_guard lock(mutex);
        ++statuses[r ? r->status : -1];
        if (r && r->status == 202) accepted.push_back(parse_json(r->body)["id"]);
        if (r && r->status == 503) {
          EXPECT_FALSE(r->get_header_value("Retry-After").empty());
        }
      }
    });
  for (auto& t : clients) t.join();
  const double rss_peak = status_mib(server.pid(), "VmHWM");
  auto c = server.client();
  int lost = 0, succeeded = 0;
  for (const auto& id : accepted) {
    const json job = wait_job(*c, id);
    if (job.value("state", "") != "succeeded") {
      ++lost;
      ADD_FAILURE() << id << ": " << job.dump();
      continue;
    }
    auto result = c->Get("/v1/jobs/" + id + "/result");
    if (result && result->status == 200) ++succeeded;
    else ++lost;
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const double rss_after = status_mib(server.pid(), "VmRSS");
  std::ostringstream counts;
  for (const auto& [status, n] : statuses) counts << ' ' << status << ':' << n;
  std::printf("overload 8 s, 4 clients, 1 worker: answers%s; accepted %zu, lost %d; RSS before %.1f MiB, peak %.1f, after %.1f\n",
              counts.str().c_str(), accepted.size(), lost, rss_before, rss_peak, rss_after);
  EXPECT_EQ(lost, 0);
  EXPECT_EQ(succeeded, int(accepted.size()));
  EXPECT_GT(accepted.size(), 0u);
  for (const auto& [status, n] : statuses) EXPECT_TRUE(status == 202 || status == 503) << status << " x " << n;
  EXPECT_EQ(c->Get("/healthz")->status, 200);
}

// Issue 17: a drain out of grace dropped queued jobs without a log line and exited 0.
TEST(HttpLoad, ADrainOutOfGraceNamesEveryAbandonedJobAndExitsNonZero) {
  ServerProcess server({"--workers", "1", "--drain-grace", "0.5"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string medium = noisy_sphere_off(5, 9);
  const std::string params = R"({"n_normal":1000,"n_vertex":1000})";  // seconds each: still running at the grace
  const std::vector<std::string> ids = post_jobs(*c, 3, medium, params);
  ASSERT_EQ(ids.size(), 3u);
  const auto signalled = std::chrono::steady_clock::now();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(std::chrono::seconds(60)), 1) << server.log();
  // SIGTERM always ends the process within the grace plus the stop bound (5 s, main.cpp).
  const double exit_s = seconds_since(signalled);
  std::printf("SIGTERM with a running job, grace 0.5 s: exited after %.2f s\n", exit_s);
  EXPECT_LT(exit_s, 0.5 + 5 + 2);
  const std::string log = server.log();
  EXPECT_NE(log.find("drain_incomplete"), std::string::npos) << log;
  std::string abandoned;  // the job_abandoned lines
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);)
    if (line.find("job_abandoned") != std::string::npos) abandoned += line + "\n";
  for (const auto& id : ids) EXPECT_NE(abandoned.find(id), std::string::npos) << id << " not named:\n" << log;
}

}  // namespace
}  // namespace mdn::test
