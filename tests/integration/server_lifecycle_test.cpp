// The server's start and stop as an operator meets them (issue 34): a second server on a busy
// port is refused (exit 3, the port named) instead of sharing it through SO_REUSEPORT, a stop
// is not held by finished results nobody downloaded, and a result finished during the drain is
// served to the client polling for it (issue 50). The real binary, over loopback.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "integration/http_fixture.h"

namespace mdn::test {
namespace {

using nlohmann::json;

// Two servers on one port split the connections between them (3 of 6 polls of an async job
// answered 404 "no job"): the second must not start.
TEST(ServerLifecycle, ASecondServerOnABusyPortExitsThreeNamingThePort) {
  ServerProcess first({});
  ASSERT_TRUE(first.started()) << first.log();
  const std::string port = std::to_string(first.port());
  ServerProcess second({"--port", port});
  EXPECT_FALSE(second.started()) << second.log();
  EXPECT_EQ(second.wait_exit(std::chrono::seconds(10)), 3) << second.log();
  const std::string log = second.log();
  EXPECT_NE(log.find("cannot_listen"), std::string::npos) << log;
  EXPECT_NE(log.find("127.0.0.1:" + port + ": the port is in use"), std::string::npos) << log;
  // The first one still answers every request.
  auto c = first.client();
  for (int i = 0; i < 4; ++i) {
    auto r = c->Get("/healthz");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
  }
}

// A finished asynchronous result that was never downloaded held SIGTERM for the whole grace
// (30 s) and the exit status was 1. Now the stop ends with the running jobs: here at once.
TEST(ServerLifecycle, AnUndownloadedResultDoesNotHoldTheStop) {
  ServerProcess server({"--workers", "1", "--drain-grace", "30"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  auto posted = c->Post("/v1/jobs", {{"X-Denoise-Params", R"({"n_normal":3,"n_vertex":3})"}}, noisy_sphere_off(1),
                        "model/x-off");
  ASSERT_TRUE(posted);
  ASSERT_EQ(posted->status, 202) << posted->body;
  const std::string id = parse_json(posted->body)["id"];
  ASSERT_EQ(wait_job(*c, id).value("state", ""), "succeeded");
  const auto signalled = std::chrono::steady_clock::now();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(std::chrono::seconds(40)), 0) << server.log();
  const double exit_s = seconds_since(signalled);
  std::printf("SIGTERM with one undownloaded result, grace 30 s: exited after %.2f s\n", exit_s);
  EXPECT_LT(exit_s, 10.0) << "the stop waited for the undownloaded result";
  // The log says what the drain does not wait for.
  EXPECT_NE(server.log().find("results_not_downloaded=1"), std::string::npos) << server.log();
}

// Posts a job of a few hundred milliseconds (a noisy sphere, 5k faces) and waits until a worker
// runs it; returns its id, or "" (with a test failure) if it was not accepted.
std::string start_job(httplib::Client& c, const std::string& params) {
  auto posted = c.Post("/v1/jobs", {{"X-Denoise-Params", params}}, noisy_sphere_off(4, 7), "model/x-off");
  EXPECT_TRUE(posted && posted->status == 202) << (posted ? posted->body : "no answer");
  if (!posted || posted->status != 202) return "";
  const std::string id = parse_json(posted->body)["id"];
  for (int i = 0; i < 200; ++i) {  // until it runs
    if (parse_json(c.Get("/v1/jobs/" + id)->body).value("state", "") != "queued") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return id;
}

// A running job holds the stop until it ends; the log names it when the drain starts.
TEST(ServerLifecycle, TheStopWaitsForARunningJobAndNamesIt) {
  ServerProcess server({"--workers", "1", "--drain-grace", "60"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string id = start_job(*c, R"({"n_normal":200,"n_vertex":200})");
  ASSERT_FALSE(id.empty());
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(std::chrono::seconds(90)), 0) << server.log();
  const std::string log = server.log();
  const auto draining = log.find("draining");
  ASSERT_NE(draining, std::string::npos) << log;
  EXPECT_NE(log.find(id, draining), std::string::npos) << "the drain does not name the job it waits for:\n" << log;
  EXPECT_NE(log.find("job_finished"), std::string::npos) << log;
}

// Issue 50: a job that finishes during the drain stays downloadable by the client polling for
// it (the server used to exit 77 ms after the job, before the poll could fetch it); the exit
// follows the download, not the grace period.
TEST(ServerLifecycle, AJobFinishedDuringTheDrainIsDownloadableByItsPollingClient) {
  ServerProcess server({"--workers", "1", "--drain-grace", "60"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string id = start_job(*c, R"({"n_normal":200,"n_vertex":100})");
  ASSERT_FALSE(id.empty());
  // The client polls as the web page does (a status request every 300 ms), then fetches.
  int result_status = 0;
  std::string result_body;
  std::chrono::steady_clock::time_point fetched;
  std::thread poller([&] {
    auto pc = server.client();
    for (int i = 0; i < 400; ++i) {
      auto r = pc->Get("/v1/jobs/" + id);
      if (!r) return;
      if (parse_json(r->body).value("state", "") == "succeeded") break;
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    auto r = pc->Get("/v1/jobs/" + id + "/result");
    result_status = r ? r->status : -1;
    if (r) result_body = r->body;
    fetched = std::chrono::steady_clock::now();
  });
  const auto signalled = std::chrono::steady_clock::now();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(std::chrono::seconds(90)), 0) << server.log();
  const auto exited = std::chrono::steady_clock::now();
  poller.join();
  EXPECT_EQ(result_status, 200) << server.log();
  EXPECT_EQ(result_body.rfind("OFF", 0), 0u) << result_body.substr(0, 100);
  EXPECT_LE(fetched, exited) << "the server exited before the polling client fetched the result";
  const double exit_s = std::chrono::duration<double>(exited - signalled).count();
  if (result_status == 200)
    std::printf("SIGTERM while a polled job ran: exited %.2f s after the signal, %.2f s after the download\n", exit_s,
                std::chrono::duration<double>(exited - fetched).count());
  EXPECT_LT(exit_s, 45.0) << "the drain waited for its grace period";
}

}  // namespace
}  // namespace mdn::test
