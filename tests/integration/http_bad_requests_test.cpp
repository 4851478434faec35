// A table of bad requests, each answered with the right 4xx application/problem+json, and the
// server healthy afterwards; connections closed after requests that leave bytes unread; and
// mutated raw requests. Runs against the real binary with small limits.
#include <poll.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <thread>

#include "http_fixture.h"
#include "io/meshopt_fixture.h"
#include "support/mutate.h"

namespace mdn::test {
namespace {

using nlohmann::json;

std::string off_with(const std::string& vertices, const std::string& faces, int nv, int nf) {
  return "OFF\n" + std::to_string(nv) + " " + std::to_string(nf) + " 0\n" + vertices + faces;
}

struct BadRequest {
  std::string name;
  std::function<httplib::Result(httplib::Client&)> send;  // or raw:
  std::string raw;
  int status;
  std::string type;   // problem slug ("" = do not check)
  std::string field;  // invalid-params: the named field
};

class HttpBadRequests : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    server_ = new ServerProcess({"--workers", "1", "--max-body", "65536", "--max-faces", "1000"});
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  static ServerProcess* server_;
};
ServerProcess* HttpBadRequests::server_ = nullptr;

httplib::Result post(httplib::Client& c, const std::string& path, const std::string& body, const std::string& type,
                     httplib::Headers headers = {}) {
  return c.Post(path, headers, body, type);
}

TEST_F(HttpBadRequests, EachIsAnsweredWithTheRightProblemAndTheServerStaysHealthy) {
  ASSERT_TRUE(server_->started()) << server_->log();
  const std::string good = noisy_sphere_off(1);  // 80 faces
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
  const std::string big(100000, 'x');
  const std::string glb_header = std::string("glTF\x02\x00\x00\x00", 8);
  std::string huge_glb = glb_header + std::string("\xff\xff\xff\x7f", 4) + std::string(40, '\0');
  const std::string gltf_external =
      R"({"asset":{"version":"2.0"},"buffers":[{"uri":"http://example.org/x.bin","byteLength":36}],)"
      R"("bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
  // Relative URIs too: only the command-line tool reads files beside a .gltf (issue 18).
  std::string gltf_relative_buffer = gltf_external;
  gltf_relative_buffer.replace(gltf_relative_buffer.find("http://example.org/x.bin"), 24, "x.bin");
  const std::string gltf_external_image =
      R"({"asset":{"version":"2.0"},"images":[{"uri":"texture.png"}],"buffers":[{"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA","byteLength":36}],)"
      R"("bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
  // STL: a binary file cut short, and an ASCII one that stops inside a facet.
  std::string truncated_stl(80, ' ');
  truncated_stl += std::string("\x02\x00\x00\x00", 4) + std::string(50, '\0');  // two facets declared, one given
  const std::string cut_ascii_stl = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n";
  // EXT_meshopt_compression that lies: the first ATTRIBUTES stream claims one element more
  // than its buffer view holds (same number of digits, so the GLB's lengths still agree).
  std::string lying_meshopt = test_io::meshopt_sphere_glb(test_io::make_sphere(), true);
  {
    const std::size_t mode = lying_meshopt.find(R"("mode":"ATTRIBUTES")");
    const std::size_t last_digit = lying_meshopt.rfind(',', mode) - 1;
    char& digit = lying_meshopt[last_digit];
    digit = digit == '9' ? '8' : static_cast<char>(digit + 1);
  }
  const std::string p = "/v1/denoise?params=";

  std::vector<BadRequest> table = {
      {"malformed glb", [&](auto& c) { return post(c, "/v1/denoise", glb_header + "garbage", "model/gltf-binary"); }, "", 400, "malformed-mesh", ""},
      {"glb with an impossible length", [&](auto& c) { return post(c, "/v1/denoise", huge_glb, "model/gltf-binary"); }, "", 400, "malformed-mesh", ""},
      {"malformed gltf json", [&](auto& c) { return post(c, "/v1/denoise", "{\"asset\": [", "model/gltf+json"); }, "", 400, "malformed-mesh", ""},
      {"gltf with an external buffer", [&](auto& c) { return post(c, "/v1/denoise", gltf_external, "model/gltf+json"); }, "", 422, "unsupported-content", ""},
      {"gltf with a relative buffer uri", [&](auto& c) { return post(c, "/v1/denoise", gltf_relative_buffer, "model/gltf+json"); }, "", 422, "unsupported-content", ""},
      {"gltf with an external image", [&](auto& c) { return post(c, "/v1/denoise", gltf_external_image, "model/gltf+json"); }, "", 422, "unsupported-content", ""},
      {"meshopt stream that lies about its count", [&](auto& c) { return post(c, "/v1/denoise", lying_meshopt, "model/gltf-binary"); }, "", 400, "malformed-mesh", ""},
      {"truncated binary stl", [&](auto& c) { return post(c, "/v1/denoise", truncated_stl, "model/stl"); }, "", 400, "malformed-mesh", ""},
      {"ascii stl cut inside a facet", [&](auto& c) { return post(c, "/v1/denoise", cut_ascii_stl, "model/stl"); }, "", 400, "malformed-mesh", ""},
      {"malformed drc", [&](auto& c) { return post(c, "/v1/denoise", "DRACO\x02\x02\x01\x01garbage", "model/x-draco"); }, "", 400, "malformed-mesh", ""},
      {"unrecognisable octet-stream", [&](auto& c) { return post(c, "/v1/denoise", std::string(64, '\x07'), "application/octet-stream"); }, "", 415, "unsupported-media-type", ""},
      {"wrong content type", [&](auto& c) { return post(c, "/v1/denoise", good, "image/png"); }, "", 415, "unsupported-media-type", ""},
      {"json content type", [&](auto& c) { return post(c, "/v1/jobs", good, "application/json"); }, "", 415, "unsupported-media-type", ""},
      {"form-urlencoded (curl -d)", [&](auto& c) { return post(c, "/v1/denoise", good, "application/x-www-form-urlencoded"); }, "", 415, "unsupported-media-type", ""},
      {"empty body", [&](auto& c) { return post(c, "/v1/denoise", "", "model/x-off"); }, "", 400, "empty-body", ""},
      {"body over the limit", [&](auto& c) { return post(c, "/v1/denoise", big, "model/x-off"); }, "", 413, "too-large", ""},
      {"chunked body over the limit",
       [&](auto& c) {
         return c.Post("/v1/denoise", [&](std::size_t offset, httplib::DataSink& sink) {
           if (offset < big.size()) sink.write(big.data(), 8192); else sink.done();
           return true;
         }, "model/x-off");
       }, "", 413, "too-large", ""},
      {"huge declared size", nullptr,
       "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nContent-Length: 99999999999999\r\n\r\nOFF\n", 413, "too-large", ""},
      {"no length", nullptr, "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\n\r\n", 411, "length-required", ""},
      {"too many faces", [&](auto& c) { return post(c, "/v1/denoise", noisy_sphere_off(3), "model/x-off"); }, "", 413, "too-large", ""},
      {"NaN coordinate", [&](auto& c) { return post(c, "/v1/denoise", off_with("0 0 0\n1 nan 0\n0 1 0\n", "3 0 1 2\n", 3, 1), "model/x-off"); }, "", 400, "", ""},
      {"index out of range", [&](auto& c) { return post(c, "/v1/denoise", off_with(tri, "3 0 1 7\n", 3, 1), "model/x-off"); }, "", 400, "", ""},
      {"truncated off", [&](auto& c) { return post(c, "/v1/denoise", off_with(tri, "", 3, 5), "model/x-off"); }, "", 400, "malformed-mesh", ""},
      {"bad params json (query)", [&](auto& c) { return post(c, p + url_encode("{\"alpha\":"), good, "model/x-off"); }, "", 400, "invalid-params", "params"},
      {"bad params json (header)", [&](auto& c) { return post(c, "/v1/denoise", good, "model/x-off", {{"X-Denoise-Params", "{oops}"}}); }, "", 400, "invalid-params", "params"},
      {"params not an object", [&](auto& c) { return post(c, p + url_encode("[1,2]"), good, "model/x-off"); }, "", 400, "invalid-params", "params"},
      {"parameter out of range", [&](auto& c) { return post(c, p + url_encode("{\"alpha\":11}"), good, "model/x-off"); }, "", 400, "invalid-params", "alpha"},
      {"negative iterations", [&](auto& c) { return post(c, p + url_encode("{\"n_vertex\":-1}"), good, "model/x-off"); }, "", 400, "invalid-params", "n_vertex"},
      {"parameter of the wrong type", [&](auto& c) { return post(c, p + url_encode("{\"n_normal\":\"ten\"}"), good, "model/x-off"); }, "", 400, "invalid-params", "n_normal"},
      {"non-integer iterations", [&](auto& c) { return post(c, p + url_encode("{\"n_normal\":2.5}"), good, "model/x-off"); }, "", 400, "invalid-params", "n_normal"},
      {"unknown parameter", [&](auto& c) { return post(c, p + url_encode("{\"sigma\":1}"), good, "model/x-off"); }, "", 400, "invalid-params", "sigma"},
      {"unknown enumeration value", [&](auto& c) { return post(c, p + url_encode("{\"region_mode\":\"maybe\"}"), good, "model/x-off"); }, "", 400, "invalid-params", "region_mode"},
      {"unknown output format", [&](auto& c) { return post(c, p + url_encode("{\"output\":{\"format\":\"xyz\"}}"), good, "model/x-off"); }, "", 400, "invalid-params", "output.format"},
      {"draco bits out of range", [&](auto& c) { return post(c, p + url_encode("{\"output\":{\"position_bits\":4}}"), good, "model/x-off"); }, "", 400, "invalid-params", "output.position_bits"},
      {"parameters given twice", [&](auto& c) { return post(c, p + url_encode("{}"), good, "model/x-off", {{"X-Denoise-Params", "{}"}}); }, "", 400, "invalid-params", ""},
      {"form without mesh", [&](auto& c) { return c.Post("/v1/denoise", httplib::MultipartFormDataItems{{"params", "{}", "", ""}}); }, "", 400, "bad-form", ""},
      {"form with an unknown field", [&](auto& c) { return c.Post("/v1/jobs", httplib::MultipartFormDataItems{{"file", good, "a.off", ""}}); }, "", 400, "bad-form", ""},
      {"bad Idempotency-Key", [&](auto& c) { return post(c, "/v1/jobs", good, "model/x-off", {{"Idempotency-Key", std::string(300, 'k')}}); }, "", 400, "bad-idempotency-key", ""},
      {"multi-range request", [&](auto& c) { return c.Get("/v1/params", {{"Range", "bytes=0-1,5-6,9-10"}}); }, "", 416, "multiple-ranges", ""},
      {"unknown job id", [&](auto& c) { return c.Get("/v1/jobs/0123456789abcdef0123456789abcdef"); }, "", 404, "job-not-found", ""},
      {"unknown job result", [&](auto& c) { return c.Get("/v1/jobs/nope/result"); }, "", 404, "job-not-found", ""},
      {"cancel an unknown job", [&](auto& c) { return c.Delete("/v1/jobs/nope"); }, "", 404, "job-not-found", ""},
      {"unknown route", [&](auto& c) { return c.Get("/v2/denoise"); }, "", 404, "not-found", ""},
      {"wrong method", [&](auto& c) { return c.Get("/v1/denoise"); }, "", 405, "method-not-allowed", ""},
      {"garbage request line", nullptr, "NOT-HTTP\r\n\r\n", 400, "", ""},
  };
  ASSERT_GE(table.size(), 30u);

  auto c = server_->client();
  for (const BadRequest& row : table) {
    SCOPED_TRACE(row.name);
    if (row.send) {
      auto r = row.send(*c);
      json problem = expect_problem(r, row.status);
      if (!problem.is_object()) problem = json::object();  // reported; the health check still runs
      if (!row.type.empty()) {
        EXPECT_EQ(problem.value("type", ""), "urn:meshdenoise:problem:" + row.type) << (r ? r->body : "");
      }
      if (!row.field.empty()) {
        EXPECT_EQ(problem.value("field", ""), row.field) << (r ? r->body : "");
      }
      if (row.field == "alpha") {
        EXPECT_EQ(problem.value("minimum", -1.0), 0.0);
        EXPECT_EQ(problem.value("maximum", -1.0), 10.0);
      }
    } else {
      std::string response;
      EXPECT_EQ(raw_status(server_->port(), row.raw, &response), row.status) << response;
      EXPECT_NE(response.find("application/problem+json"), std::string::npos) << response;
      if (!row.type.empty()) {
        EXPECT_NE(response.find("urn:meshdenoise:problem:" + row.type), std::string::npos) << response;
      }
    }
    // Healthy after every bad request, on the same keep-alive client.
    auto health = c->Get("/healthz");
    ASSERT_TRUE(health) << "server unreachable after: " << row.name;
    ASSERT_EQ(health->status, 200);
  }
  // Still does real work.
  auto ok = c->Post("/v1/denoise", good, "model/x-off");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200) << ok->body;
}

TEST_F(HttpBadRequests, AnUnreadBodyDoesNotBecomeTheNextRequest) {
  ASSERT_TRUE(server_->started()) << server_->log();
  // Refused before its body is read (two ranges): the connection must close rather than parse
  // the body as a second request.
  std::string response;
  const int status = raw_status(server_->port(),
                                "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\n"
                                "Range: bytes=0-1,2-3\r\nContent-Length: 44\r\n\r\n"
                                "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n12345678",
                                &response, /*read_until_close=*/true);
  EXPECT_EQ(status, 416);
  EXPECT_EQ(response.find("HTTP/1.1", 10), std::string::npos) << response;
}

// After a request it cannot parse (a garbage request line, a request target over the limit),
// the server cannot tell where the next request would start: it answers once, says
// "Connection: close", and closes. cpp-httplib 0.11.4 alone answers without closing and parses
// each following line as a request of its own, so a request sent after the answer was served.
TEST_F(HttpBadRequests, AnUnparseableRequestIsAnsweredOnceAndTheConnectionCloses) {
  ASSERT_TRUE(server_->started()) << server_->log();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"NOT-HTTP\r\n", "HTTP/1.1 400 "},
      {"GET /" + std::string(9000, 'a') + " HTTP/1.1\r\nHost: x\r\n\r\n", "HTTP/1.1 414 "},
  };
  for (const auto& [request, status_line] : cases) {
    SCOPED_TRACE(status_line);
    const int fd = connect_loopback(server_->port());
    ASSERT_GE(fd, 0);
    ASSERT_EQ(send(fd, request.data(), request.size(), MSG_NOSIGNAL), ssize_t(request.size()));
    pollfd p{fd, POLLIN, 0};
    ASSERT_EQ(poll(&p, 1, 5000), 1) << "no answer";
    // A well-formed request after the answer, on the same connection: it must not be served.
    const std::string next = "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n";
    send(fd, next.data(), next.size(), MSG_NOSIGNAL);  // may fail once the server has closed
    const auto start = std::chrono::steady_clock::now();
    const std::string response = read_until_close(fd, 5);
    const double waited_s = seconds_since(start);
    close(fd);
    EXPECT_EQ(response.rfind(status_line, 0), 0u) << response;
    EXPECT_NE(response.find("Connection: close\r\n"), std::string::npos) << response;
    EXPECT_NE(response.find("application/problem+json"), std::string::npos) << response;
    EXPECT_EQ(response.find("HTTP/1.1", 10), std::string::npos) << "a second answer: " << response;
    EXPECT_LT(waited_s, 1.5) << "the server kept the connection open";
  }
  auto c = server_->client();
  auto health = c->Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
}

// Each connection closes only itself: garbage requests (each closed after its 400) arrive
// while keep-alive clients go on using their connections. A close aimed at the wrong socket
// would cut a keep-alive client off or cost a garbage request its answer.
TEST_F(HttpBadRequests, ClosingAnUnparseableRequestsConnectionLeavesTheOthersAlone) {
  ASSERT_TRUE(server_->started()) << server_->log();
  std::atomic<bool> done{false};
  std::atomic<int> served{0}, failed{0}, answered{0};
  std::vector<std::thread> keep_alive;
  for (int k = 0; k < 2; ++k)
    keep_alive.emplace_back([&] {
      auto c = server_->client(10);
      c->set_keep_alive(true);
      while (!done) {
        auto r = c->Get("/healthz");
        (r && r->status == 200 ? served : failed)++;
      }
    });
  std::vector<std::thread> garbage;
  for (int g = 0; g < 3; ++g)
    garbage.emplace_back([&] {
      for (int i = 0; i < 40; ++i) {
        std::string response;
        if (raw_status(server_->port(), "NOT-HTTP\r\n\r\n", &response, /*read_until_close=*/true) == 400 &&
            response.find("Connection: close\r\n") != std::string::npos)
          ++answered;
      }
    });
  for (auto& t : garbage) t.join();
  done = true;
  for (auto& t : keep_alive) t.join();
  EXPECT_EQ(answered, 120);
  EXPECT_EQ(failed, 0) << served << " keep-alive requests served";
  EXPECT_GT(served, 0);
}

// Raw requests mutated in their request line, one header, or their body (Content-Length kept
// right), each on its own connection: every one must get an answer, and none a 5xx other than
// a full queue. Seeds: a synchronous job with ?params=, an asynchronous one with an
// Idempotency-Key and X-Denoise-Params, a multipart form, and a ranged long poll.
TEST_F(HttpBadRequests, MutatedRequestsAreEachAnsweredWithoutAServerError) {
  ASSERT_TRUE(server_->started()) << server_->log();
  struct SeedRequest {
    std::string line;
    std::vector<std::string> headers;
    std::string body;
  };
  const std::string off = noisy_sphere_off(1);
  const std::string boundary = "XyZb0undary";
  const std::string form = "--" + boundary + "\r\nContent-Disposition: form-data; name=\"params\"\r\n\r\n{\"n_normal\":3}\r\n--" +
                           boundary + "\r\nContent-Disposition: form-data; name=\"mesh\"; filename=\"a.off\"\r\n" +
                           "Content-Type: model/x-off\r\n\r\n" + off + "\r\n--" + boundary + "--\r\n";
  const std::vector<SeedRequest> seeds = {
      {"POST /v1/denoise?params=%7B%22n_normal%22%3A3%7D", {"Content-Type: model/x-off"}, off},
      {"POST /v1/jobs", {"Content-Type: model/x-off", "Idempotency-Key: abc", "X-Denoise-Params: {\"n_vertex\":2}"}, off},
      {"POST /v1/denoise", {"Content-Type: multipart/form-data; boundary=" + boundary}, form},
      {"GET /v1/jobs/0123456789abcdef0123456789abcdef?wait=0", {"Range: bytes=0-3"}, ""},
  };
  const auto one_line = [](std::string s) {  // a CR or LF would start another line
    std::erase_if(s, [](char c) { return c == '\r' || c == '\n'; });
    return s;
  };
  std::mt19937_64 rng(20261123);
  std::map<int, int> statuses;
  const int mutants = 4 * test::mutants_per_seed(75);
  for (int i = 0; i < mutants; ++i) {
    SeedRequest r = seeds[std::size_t(i) % seeds.size()];
    switch (rng() % 3) {
      case 0: r.line = test::mutate(r.line, /*text=*/true, rng); break;
      case 1: {
        std::string& h = r.headers[rng() % r.headers.size()];
        h = test::mutate(h, /*text=*/true, rng);
        break;
      }
      default: r.body = test::mutate(r.body, /*text=*/true, rng);
    }
    std::string request = one_line(r.line) + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n";
    for (const std::string& h : r.headers) request += one_line(h) + "\r\n";
    if (!r.body.empty() || r.line.rfind("POST", 0) == 0) request += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
    request += "\r\n" + r.body;
    std::string response;
    const int status = raw_status(server_->port(), request, &response, /*read_until_close=*/false, /*timeout_s=*/30);
    ++statuses[status];
    const bool queue_full = status == 503 && response.find("problem:queue-full") != std::string::npos;
    EXPECT_TRUE(status >= 200 && (status < 500 || queue_full))
        << "mutant " << i << ": " << request.substr(0, request.find("\r\n\r\n")) << "\n-> " << response.substr(0, 400);
  }
  std::string seen;
  for (const auto& [status, n] : statuses) seen += " " + std::to_string(status) + "x" + std::to_string(n);
  // Not vacuous: some mutants still succeed, and most are refused.
  EXPECT_GT(statuses[200] + statuses[202], 0) << seen;
  EXPECT_GT(statuses[400] + statuses[404] + statuses[415] + statuses[422], mutants / 4) << seen;
  auto c = server_->client();
  auto health = c->Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  std::printf("[ statuses ]%s\n", seen.c_str());
}

// The server answers 413 part-way through a chunked upload from a client that sent
// "Connection: close" (cpp-httplib's clients do, unless keep-alive is on). The client is still
// sending: the server must keep reading and discarding (a lingering close) until the client is
// done, not close at once. A plain close resets the connection: the client's next write fails, and
// cpp-httplib's client then gives up without reading the 413 (the fault behind a rare
// "no response" in the table above).
TEST_F(HttpBadRequests, AClientStillSendingWhenRefusedCanFinishAndReadTheAnswer) {
  ASSERT_TRUE(server_->started()) << server_->log();
  const int fd = connect_loopback(server_->port());
  ASSERT_GE(fd, 0);
  std::string chunk = "2000\r\n" + std::string(8192, 'x') + "\r\n";
  std::string request =
      "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nConnection: close\r\nContent-Type: model/x-off\r\n"
      "Transfer-Encoding: chunked\r\n\r\n";
  for (int i = 0; i < 12; ++i) request += chunk;  // 96 KiB: over the 64 KiB limit, not all read
  ASSERT_EQ(send(fd, request.data(), request.size(), MSG_NOSIGNAL), ssize_t(request.size()));
  pollfd p{fd, POLLIN, 0};
  ASSERT_EQ(poll(&p, 1, 5000), 1) << "no answer";
  // The answer is here; the server has had time to close. The client goes on sending its body.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(send(fd, chunk.data(), chunk.size(), MSG_NOSIGNAL), ssize_t(chunk.size()))
        << "write " << i << " after the answer failed: " << std::strerror(errno);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(send(fd, "0\r\n\r\n", 5, MSG_NOSIGNAL), 5) << std::strerror(errno);
  const std::string response = read_until_close(fd, 3);
  close(fd);
  EXPECT_EQ(response.rfind("HTTP/1.1 413 ", 0), 0u) << response;
  EXPECT_NE(response.find("urn:meshdenoise:problem:too-large"), std::string::npos) << response;
}

// Issue 17, protocol: 2,000 header fields were accepted; a request with both Transfer-Encoding
// and Content-Length left the connection open (RFC 9112, 6.3); POST /v1/jobs answered 202 to a
// body that is no mesh (the job failed later) and to parameters that do not validate.
TEST_F(HttpBadRequests, HeaderCountFramingAndJobBodiesAreCheckedAtOnce) {
  ASSERT_TRUE(server_->started()) << server_->log();
  std::string many = "GET /healthz HTTP/1.1\r\nHost: x\r\n";
  for (int i = 0; i < 2000; ++i) many += "X-H" + std::to_string(i) + ": v\r\n";
  std::string response;
  EXPECT_EQ(raw_status(server_->port(), many + "\r\n", &response), 431) << response.substr(0, 300);
  EXPECT_NE(response.find("too-many-headers"), std::string::npos) << response.substr(0, 300);
  std::string some = "GET /healthz HTTP/1.1\r\nHost: x\r\n";
  for (int i = 0; i < 50; ++i) some += "X-H" + std::to_string(i) + ": v\r\n";
  EXPECT_EQ(raw_status(server_->port(), some + "\r\n"), 200);

  // Both framings: answered 400 once, then the connection closes (the next request unserved).
  const std::string both = "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\n"
                           "Transfer-Encoding: chunked\r\nContent-Length: 5\r\n\r\n0\r\n\r\n"
                           "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n";
  EXPECT_EQ(raw_status(server_->port(), both, &response, /*read_until_close=*/true), 400) << response;
  EXPECT_NE(response.find("Connection: close\r\n"), std::string::npos) << response;
  EXPECT_EQ(response.find("HTTP/1.1", 10), std::string::npos) << "a second answer: " << response;

  auto c = server_->client();
  json p = expect_problem(c->Post("/v1/jobs", std::string("this is not a mesh at all\n"), "model/x-off"), 415);
  EXPECT_NE(p.value("detail", "").find("not a off file"), std::string::npos) << p.dump();
  p = expect_problem(c->Post("/v1/jobs", std::string("ply\nformat ascii 1.0\n"), "model/x-off"), 415);
  EXPECT_NE(p.value("detail", "").find("looks like ply"), std::string::npos) << p.dump();
  p = expect_problem(c->Post("/v1/jobs?params=%7B%22n_normal%22%3A-5%7D", noisy_sphere_off(1), "model/x-off"), 400);
  EXPECT_EQ(p.value("field", ""), "n_normal") << p.dump();
  auto ok = c->Post("/v1/jobs", noisy_sphere_off(1), "model/x-off");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 202) << ok->body;
}

// Issue 17: an OFF whose coordinates span more than the float range killed the server (SIGSEGV
// in Draco's encoder) when written as glb or drc; only degenerate triangles, or 1e300, were a 500.
TEST_F(HttpBadRequests, MeshesDracoCannotEncodeAre422NotACrash) {
  ASSERT_TRUE(server_->started()) << server_->log();
  auto c = server_->client();
  const std::string span = "OFF\n3 1 0\n3e38 0 0\n-3e38 0 0\n0 1 0\n3 0 1 2\n";
  const std::string huge = "OFF\n3 1 0\n1e300 0 0\n0 0 0\n0 1 0\n3 0 1 2\n";
  for (const std::string& body : {span, huge})
    for (const char* format : {"glb", "drc"}) {
      // Draco asked for: glTF output follows the input's compression (none for OFF) by default.
      const std::string params =
          std::string(R"({"mode":"manual","output":{"compression":"draco","format":")") + format + "\"}}";
      const json p = expect_problem(c->Post("/v1/denoise", {{"X-Denoise-Params", params}}, body, "model/x-off"), 422);
      EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:unsupported-content") << format << " " << p.dump();
    }
  auto health = c->Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
}

// Issue 17, protocol: a stalled upload held an I/O thread for the whole read timeout and got no
// 408. Now a body that sends nothing for --body-stall-timeout seconds is answered 408 (problem
// JSON) and its connection closed, for Content-Length and chunked bodies alike.
TEST(HttpBodyStall, AStalledBodyGets408AndTheConnectionClosesWithinTheTimeout) {
  ServerProcess server({"--body-stall-timeout", "1", "--io-threads", "4"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string heads[] = {
      "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nContent-Length: 1000\r\n\r\nOFF\n3 1 0\n",
      "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nTransfer-Encoding: chunked\r\n\r\n4\r\nOFF\n\r\n",
  };
  for (const std::string& head : heads) {
    const int fd = connect_loopback(server.port());
    ASSERT_GE(fd, 0);
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(send(fd, head.data(), head.size(), MSG_NOSIGNAL), ssize_t(head.size()));
    const std::string response = read_until_close(fd, 10);  // the server closes: recv returns 0
    const double after_s = seconds_since(start);
    close(fd);
    std::printf("stalled body: answered and closed after %.2f s (stall timeout 1 s)\n", after_s);
    EXPECT_EQ(response.rfind("HTTP/1.1 408 ", 0), 0u) << response;
    EXPECT_NE(response.find("urn:meshdenoise:problem:request-timeout"), std::string::npos) << response;
    EXPECT_NE(response.find("Connection: close"), std::string::npos) << response;
    EXPECT_GE(after_s, 0.8);
    EXPECT_LT(after_s, 3.0);
  }
  // The I/O threads are free again: four stalled uploads at once, then a request answered.
  std::vector<int> stalled;
  for (int i = 0; i < 4; ++i) {
    const int fd = connect_loopback(server.port());
    send(fd, heads[0].data(), heads[0].size(), MSG_NOSIGNAL);
    stalled.push_back(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  auto c = server.client(5);
  auto r = c->Get("/healthz");
  ASSERT_TRUE(r) << httplib::to_string(r.error());
  EXPECT_EQ(r->status, 200);
  for (int fd : stalled) close(fd);
}

}  // namespace
}  // namespace mdn::test
