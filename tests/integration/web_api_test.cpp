// What the web page (server/web/) needs of the API, against the real server on loopback:
// results compressed where it pays and cheaply (a text mesh gzip-encoded at the fastest level,
// never cpp-httplib's per-request Brotli at quality 11, which took 11 s for a 4.4 MB OFF), and
// the queue position of a waiting job (progress.jobs_ahead).
#include <chrono>
#include <iostream>

#include "http_fixture.h"

namespace mdn::test {
namespace {

using nlohmann::json;

// Posts a job and waits for it; returns its id.
std::string finished_job(httplib::Client& c, const std::string& body, const std::string& params) {
  httplib::MultipartFormDataItems form = {{"mesh", body, "mesh.off", "application/octet-stream"},
                                          {"params", params, "", ""}};
  auto r = c.Post("/v1/jobs", form);
  EXPECT_TRUE(r && r->status == 202) << (r ? r->body : "no answer");
  if (!r || r->status != 202) return {};
  const std::string id = parse_json(r->body).at("id");
  EXPECT_EQ(wait_job(c, id).value("state", ""), "succeeded");
  return id;
}

TEST(WebApi, TextResultsAreGzipEncodedCheaplyAndBinaryOnesNot) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  // A 4 MB OFF (a 100 x 100 grid per cube face), converted only (mode none): the result is OFF.
  const std::string off = off_text(cube(100));
  ASSERT_GT(off.size(), 3'500'000u);
  const std::string id = finished_job(*c, off, R"({"mode":"none"})");
  const std::string url = "/v1/jobs/" + id + "/result";

  auto plain = c->Get(url, {{"Accept-Encoding", "identity"}});
  ASSERT_TRUE(plain && plain->status == 200);
  EXPECT_EQ(plain->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(plain->get_header_value("Vary"), "Accept-Encoding");
  ASSERT_GT(plain->body.size(), 3'500'000u);

  // What Chromium sends. gzip, not Brotli; the client decodes it to the same bytes.
  c->set_decompress(false);
  const auto start = Clock::now();
  auto wire = c->Get(url, {{"Accept-Encoding", "gzip, deflate, br, zstd"}});
  const double seconds = seconds_since(start);
  ASSERT_TRUE(wire && wire->status == 200);
  EXPECT_EQ(wire->get_header_value("Content-Encoding"), "gzip");
  EXPECT_LT(wire->body.size() * 2, plain->body.size()) << "gzip should at least halve an OFF";
  std::cout << "4 MB OFF result (" << plain->body.size() << " B, " << wire->body.size() << " B gzip-encoded): "
            << seconds << " s\n";
  // Loose (a busy 2-core CI machine): the fastest gzip level takes tens of milliseconds here;
  // Brotli at quality 11 took 11 s.
  EXPECT_LT(seconds, 3.0);
  c->set_decompress(true);
  auto decoded = c->Get(url, {{"Accept-Encoding", "gzip"}});
  ASSERT_TRUE(decoded && decoded->status == 200);
  EXPECT_TRUE(decoded->body == plain->body) << "the gzip-encoded result decodes to other bytes";

  // Brotli alone is not offered: the bytes go as they are.
  EXPECT_EQ(c->Get(url, {{"Accept-Encoding", "br"}})->get_header_value("Content-Encoding"), "");
  // A byte range is a range of the bytes themselves, never encoded.
  auto part = c->Get(url, {{"Accept-Encoding", "gzip"}, {"Range", "bytes=0-99"}});
  ASSERT_TRUE(part && part->status == 206);
  EXPECT_EQ(part->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(part->body, plain->body.substr(0, 100));

  // A binary result (glb) would not shrink: never encoded.
  const std::string glb = finished_job(*c, off_text(cube(8)), R"({"mode":"none","output":{"format":"glb"}})");
  auto binary = c->Get("/v1/jobs/" + glb + "/result", {{"Accept-Encoding", "gzip, br"}});
  ASSERT_TRUE(binary && binary->status == 200);
  EXPECT_EQ(binary->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(binary->body.substr(0, 4), "glTF");
}

TEST(WebApi, QueuedJobsSayHowManyStartFirst) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string mesh = noisy_sphere_off(5, 3);
  std::vector<std::string> ids;
  for (int i = 0; i < 3; ++i) {
    auto r = c->Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, mesh, "model/x-off");
    ASSERT_TRUE(r && r->status == 202) << (r ? r->body : "");
    ids.push_back(parse_json(r->body).at("id"));
  }
  // The first runs (no position); the two others wait behind it, in order.
  for (const auto deadline = Clock::now() + std::chrono::seconds(30); Clock::now() < deadline;) {
    if (parse_json(c->Get("/v1/jobs/" + ids[0])->body).at("state") == "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const json first = parse_json(c->Get("/v1/jobs/" + ids[0])->body);
  EXPECT_EQ(first.at("state"), "running");
  EXPECT_FALSE(first.at("progress").contains("jobs_ahead")) << first;
  for (int i = 1; i < 3; ++i) {
    const json job = parse_json(c->Get("/v1/jobs/" + ids[i])->body);
    EXPECT_EQ(job.at("state"), "queued") << job;
    EXPECT_EQ(job.at("progress").value("jobs_ahead", -1), i - 1) << job;
  }
  // The first one cancelled: the others move up.
  c->Delete("/v1/jobs/" + ids[0]);
  EXPECT_EQ(wait_job(*c, ids[0]).value("state", ""), "cancelled");
  for (const auto deadline = Clock::now() + std::chrono::seconds(30); Clock::now() < deadline;) {
    if (parse_json(c->Get("/v1/jobs/" + ids[1])->body).at("state") == "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(parse_json(c->Get("/v1/jobs/" + ids[2])->body).at("progress").value("jobs_ahead", -1), 0);
  for (const auto& id : ids) c->Delete("/v1/jobs/" + id);
}

}  // namespace
}  // namespace mdn::test
