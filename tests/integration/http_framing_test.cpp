// Issue 49 over real HTTP on loopback, against the built server: lines that never end (items 2
// and 8), drips that held the lanes (item 3), a body below the minimum rate (items 3 and 7),
// refusals that arrive without a reset (item 7), metrics labels from closed sets (item 6),
// chunk sizes written "0x1c" or "+1c" and Transfer-Encoding: gzip, chunked (item 8). Each
// prints the server's peak memory under its attack ("[ figures  ]").
#include <arpa/inet.h>
#include <fcntl.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <thread>
#include <vector>

#include "http_fixture.h"

namespace mdn::test {
namespace {




struct Streamed {
  std::string response;
  std::size_t sent = 0;
  double answered_after_s = -1;  // when the first byte of an answer came
};

// Sends `prefix`, then `block` again and again as fast as the server takes it, until it answers
// (then reads the answer until it closes), at most `budget` bytes or `max_s` seconds.
Streamed stream_until_answered(int port, const std::string& prefix, const std::string& block, std::size_t budget,
                               double max_s) {
  Streamed out;
  const int fd = connect_loopback(port);
  if (fd < 0) return out;
  const auto start = Clock::now();
  send(fd, prefix.data(), prefix.size(), MSG_NOSIGNAL);
  char buf[4096];
  while (seconds_since(start) < max_s) {
    pollfd p{fd, short(POLLIN | (out.sent < budget ? POLLOUT : 0)), 0};
    if (poll(&p, 1, 50) <= 0) continue;
    if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
      const ssize_t n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
      if (n > 0) {
        if (out.response.empty()) out.answered_after_s = seconds_since(start);
        out.response.append(buf, std::size_t(n));
        continue;
      }
      if (n == 0 || (errno != EAGAIN && errno != EINTR)) break;
    }
    if (out.response.empty() && (p.revents & POLLOUT)) {
      const ssize_t n = send(fd, block.data(), block.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0)
        out.sent += std::size_t(n);
      else if (errno != EAGAIN && errno != EINTR)
        break;
    }
  }
  out.response += read_until_close(fd, 2);
  close(fd);
  return out;
}

int status_of(const std::string& response) {
  return response.rfind("HTTP/1.1 ", 0) == 0 ? std::atoi(response.c_str() + 9) : 0;
}

// Item 2: a request line, a header line, a head of many lines, and a chunk extension, each
// streamed without end (64 MiB at most, as fast as loopback goes): cpp-httplib's line reader
// grew with them (1.5 GB in 30 s) and nothing was answered until a timeout. The gate now
// refuses each once it passes its limit (8 KiB a line, 64 KiB a head, 4 KiB a chunk line),
// while the bytes still flow, with a problem+json body and a lingering close.
TEST(HttpFraming, LinesThatNeverEndAreRefusedWhileTheyStream) {
  ServerProcess server({});
  ASSERT_TRUE(server.started()) << server.log();
  std::string header_lines;
  while (header_lines.size() < 16384) header_lines += "X-Filler: " + std::string(90, 'f') + "\r\n";
  const struct {
    const char* what;
    std::string prefix, block;
    int status;
  } cases[] = {
      {"request line", "GET /", std::string(16384, 'a'), 414},
      {"header line", "GET /healthz HTTP/1.1\r\nHost: x\r\nX-Long: ", std::string(16384, 'a'), 431},
      {"head of many lines", "GET /healthz HTTP/1.1\r\nHost: x\r\n", header_lines, 431},
      {"chunk extension",
       "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nTransfer-Encoding: chunked\r\n\r\n1;ext=",
       std::string(16384, 'e'), 400},
  };
  for (const auto& c : cases) {
    const Streamed s = stream_until_answered(server.port(), c.prefix, c.block, std::size_t{64} << 20, 6);
    std::printf("[ figures  ] %s without end: answered %d after %.3f s and %zu bytes sent; server peak %.1f MiB\n",
                c.what, status_of(s.response), s.answered_after_s, s.sent, status_mib(server.pid(), "VmHWM"));
    EXPECT_EQ(status_of(s.response), c.status) << c.what << ": " << s.response.substr(0, 300);
    EXPECT_NE(s.response.find("application/problem+json"), std::string::npos) << c.what;
    EXPECT_GE(s.answered_after_s, 0) << c.what;
    EXPECT_LT(s.answered_after_s, 3) << c.what << ": not answered while the line streamed";
  }
  EXPECT_LT(status_mib(server.pid(), "VmHWM"), 300);
  EXPECT_EQ(server.client()->Get("/healthz")->status, 200);
}

// Item 8: strtoul read "0x1c" and "+1c" as chunk sizes; RFC 9112 7.1 allows hexadecimal digits
// only. The same body with its sizes in plain hexadecimal is accepted.
TEST(HttpFraming, ChunkSizesWithAPrefixOrASignAreRefused) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string off = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  char size[16];
  std::snprintf(size, sizeof size, "%zx", off.size());
  for (const std::string& written : {std::string(size), "0x" + std::string(size), "+" + std::string(size)}) {
    const std::string request =
        "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\n"
        "X-Denoise-Params: {\"mode\":\"none\"}\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n" +
        written + "\r\n" + off + "\r\n0\r\n\r\n";
    std::string response;
    const int status = raw_status(server.port(), request, &response, true, 10);
    if (written == size) {
      EXPECT_EQ(status, 200) << response.substr(0, 400);
    } else {
      EXPECT_EQ(status, 400) << written << ": " << response.substr(0, 400);
      EXPECT_NE(response.find("chunked coding is invalid"), std::string::npos) << response.substr(0, 400);
    }
  }
}

// Item 8: "Transfer-Encoding: gzip, chunked" waited for the 408 of the head timeout (10 s); a
// coding other than chunked alone cannot be framed: 400 at once, and the connection closed.
TEST(HttpFraming, ATransferCodingOtherThanChunkedIsRefusedAtOnce) {
  ServerProcess server({});
  ASSERT_TRUE(server.started()) << server.log();
  for (const char* coding : {"gzip, chunked", "gzip", "chunked, gzip", "identity"}) {
    const int fd = connect_loopback(server.port());
    ASSERT_GE(fd, 0);
    const std::string head =
        std::string("POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nTransfer-Encoding: ") +
        coding + "\r\n\r\n5\r\nOFF\n\n";
    const auto start = Clock::now();
    send(fd, head.data(), head.size(), MSG_NOSIGNAL);
    const std::string response = read_until_close(fd, 5);
    const double took = seconds_since(start);
    close(fd);
    EXPECT_EQ(status_of(response), 400) << coding << ": " << response.substr(0, 300);
    EXPECT_NE(response.find("is not supported"), std::string::npos) << response.substr(0, 300);
    EXPECT_LT(took, 2) << coding;
  }
}

// Item 3: two connections dripping a request line past 8 KiB to /healthz held both threads of
// the probe lane (/healthz took 8-10 s), and eight from other addresses the main lane. A line
// over the limit is now refused by the gate itself: no lane waits for the rest of it.
TEST(HttpFraming, DrippedHeadsHoldNoLane) {
  ServerProcess server({"--io-threads", "8"});
  ASSERT_TRUE(server.started()) << server.log();
  std::vector<int> drips;
  for (int i = 0; i < 2; ++i) drips.push_back(connect_loopback(server.port()));
  for (int i = 0; i < 8; ++i) {
    const std::string source = "127.0.0." + std::to_string(2 + i);
    const int fd = connect_from(source.c_str(), server.port());
    ASSERT_GE(fd, 0) << "cannot bind " << source;
    drips.push_back(fd);
  }
  for (std::size_t i = 0; i < drips.size(); ++i) {
    const std::string line = std::string(i < 2 ? "GET /healthz?" : "GET /v1/params?") + std::string(8200, 'a');
    send(drips[i], line.data(), line.size(), MSG_NOSIGNAL);
  }
  double worst_probe = 0, worst_main = 0;
  const auto start = Clock::now();
  while (seconds_since(start) < 4) {
    for (int fd : drips) send(fd, "a", 1, MSG_NOSIGNAL);  // a byte each, never the line's end
    const auto t0 = Clock::now();
    worst_probe =
        std::max(worst_probe, raw_status(server.port(), "GET /healthz HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n",
                                         nullptr, false, 5) == 200
                                  ? seconds_since(t0)
                                  : 99.0);
    const int other = connect_from("127.0.0.20", server.port());
    ASSERT_GE(other, 0);
    const std::string get = "GET /v1/params HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
    const auto t1 = Clock::now();
    send(other, get.data(), get.size(), MSG_NOSIGNAL);
    const std::string response = read_until_close(other, 5);
    close(other);
    worst_main = std::max(worst_main, status_of(response) == 200 ? seconds_since(t1) : 99.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
  }
  int refused = 0;
  for (int fd : drips) {
    refused += status_of(read_until_close(fd, 2)) == 414;
    close(fd);
  }
  std::printf(
      "[ figures  ] 10 dripped request lines: worst /healthz %.4f s, worst /v1/params %.4f s, %d answered 414; "
      "server peak %.1f MiB\n",
      worst_probe, worst_main, refused, status_mib(server.pid(), "VmHWM"));
  EXPECT_LT(worst_probe, 1.0);
  EXPECT_LT(worst_main, 1.0);
  EXPECT_EQ(refused, int(drips.size()));
}

// Sends a request head whose body then trickles at 2 bytes/s (never a stall of the 10 s allowed)
// until the server answers or `limit_s` passes; the answer ("" if none) and the seconds taken.
std::pair<std::string, double> trickle_a_body(int port, double limit_s) {
  const int fd = connect_loopback(port);
  EXPECT_GE(fd, 0);
  if (fd < 0) return {};
  const std::string head =
      "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nContent-Length: 100000\r\n\r\n";
  send(fd, head.data(), head.size(), MSG_NOSIGNAL);
  const auto start = Clock::now();
  std::string response;
  char buf[4096];
  while (seconds_since(start) < limit_s && response.empty()) {
    send(fd, "O", 1, MSG_NOSIGNAL);
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 500) == 1) {
      const ssize_t n = recv(fd, buf, sizeof buf, 0);
      if (n <= 0) break;
      response.assign(buf, std::size_t(n));
    }
  }
  const double took = seconds_since(start);
  if (!response.empty()) response += read_until_close(fd, 2);  // the rest of the answer
  close(fd);
  return {response, took};
}

// Items 3 and 7: a body trickled at 2 bytes/s was held for the whole --body-timeout (300 s).
// Past a grace of 10 s a body must keep up with 500 bytes/s (decision 63): 408 and close.
TEST(HttpFraming, ABodyBelowTheMinimumRateIsRefusedAfterItsGrace) {
  ServerProcess server({});
  ASSERT_TRUE(server.started()) << server.log();
  const auto [response, took] = trickle_a_body(server.port(), 20);
  std::printf("[ figures  ] a body at 2 bytes/s: answered %d after %.2f s\n", status_of(response), took);
  EXPECT_EQ(status_of(response), 408) << response;
  EXPECT_NE(response.find("slower than the server's minimum rate"), std::string::npos) << response;
  EXPECT_GT(took, 9);
  EXPECT_LT(took, 15);
}

// Issue 49, item 5: the floor and its grace are flags (--body-min-rate, --body-rate-grace).
TEST(HttpFraming, TheMinimumRateAndItsGraceAreSettings) {
  ServerProcess strict({"--body-rate-grace", "1", "--body-min-rate", "100"});
  ASSERT_TRUE(strict.started()) << strict.log();
  const auto [refused, took] = trickle_a_body(strict.port(), 10);
  EXPECT_EQ(status_of(refused), 408) << refused;
  EXPECT_LT(took, 4);
  ServerProcess without({"--body-rate-grace", "1", "--body-min-rate", "0"});
  ASSERT_TRUE(without.started()) << without.log();
  EXPECT_EQ(trickle_a_body(without.port(), 3).first, "") << "a floor of 0 refused a slow body";
}

// Item 7: at the per-client cap the 503 was written and the socket closed with the client's
// request unread, so the client saw a reset instead of the answer. Now the refusal is a
// lingering close (decision 64): every refused client writes its whole request and reads its
// 503.
TEST(HttpFraming, RefusalsAtTheConnectionCapArriveWithoutAReset) {
  ServerProcess server({"--max-connections-per-client", "4", "--io-threads", "8"});
  ASSERT_TRUE(server.started()) << server.log();
  std::vector<int> held;  // four requests whose bodies never come: served, so never evicted
  const std::string head =
      "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nContent-Length: 100000\r\n\r\nOFF\n";
  for (int i = 0; i < 4; ++i) {
    held.push_back(connect_loopback(server.port()));
    send(held.back(), head.data(), head.size(), MSG_NOSIGNAL);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const std::string request =
      "POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nContent-Length: 4000000\r\n\r\n" +
      std::string(4000000, 'x');
  int answered = 0;
  const int attempts = 20;
  for (int i = 0; i < attempts; ++i) {
    const int fd = connect_loopback(server.port());
    ASSERT_GE(fd, 0);
    ::fcntl(fd, F_SETFL, O_NONBLOCK);
    std::size_t sent = 0;
    std::string response;
    const auto start = Clock::now();
    char buf[4096];
    bool eof = false;  // the answer is whole (the server shut its side); the request goes on
    while (seconds_since(start) < 5 && !(eof && sent == request.size())) {
      pollfd p{fd, short((eof ? 0 : POLLIN) | (sent < request.size() ? POLLOUT : 0)), 0};
      if (poll(&p, 1, 50) <= 0) continue;
      if (p.revents & POLLOUT) {
        const ssize_t n = send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
        if (n > 0)
          sent += std::size_t(n);
        else if (errno != EAGAIN && errno != EINTR)
          break;  // reset: a client such as cpp-httplib's stops here
      }
      if (!eof && (p.revents & (POLLIN | POLLHUP | POLLERR))) {
        const ssize_t n = recv(fd, buf, sizeof buf, 0);
        if (n > 0)
          response.append(buf, std::size_t(n));
        else if (n == 0)
          eof = true;
        else if (errno != EAGAIN)
          break;
      }
    }
    close(fd);
    const bool ok = status_of(response) == 503 && sent == request.size();
    if (!ok)
      std::printf("attempt %d: sent %zu of %zu (%s) after %.3f s, answer: %s\n", i, sent, request.size(),
                  std::strerror(errno), seconds_since(start), response.substr(0, 40).c_str());
    answered += ok;
  }
  for (int fd : held) close(fd);
  std::printf("[ figures  ] %d of %d connections refused at the cap read their 503\n", answered, attempts);
  EXPECT_EQ(answered, attempts);
}

// Item 6: every distinct request method became a series of mdn_http_requests_total forever
// (20,000 made a scrape of 81 MB). Methods outside the standard ones count as "other".
TEST(HttpFraming, OddMethodsDoNotGrowTheMetrics) {
  ServerProcess server({});
  ASSERT_TRUE(server.started()) << server.log();
  auto odd = [&](int from, int to) {
    for (int i = from; i < to; ++i) {
      std::string request = "M";  // an odd method: M0, M1, ...
      request += std::to_string(i);
      request += " /healthz HTTP/1.1\r\nHost: x\r\n\r\n";
      raw_status(server.port(), request, nullptr, false, 3);
    }
  };
  odd(0, 10);
  const std::string before = server.client()->Get("/metrics")->body;
  odd(10, 1010);
  const std::string after = server.client()->Get("/metrics")->body;
  std::printf("[ figures  ] /metrics after 10 odd methods: %zu bytes, after 1,010: %zu bytes; server peak %.1f MiB\n",
              before.size(), after.size(), status_mib(server.pid(), "VmHWM"));
  EXPECT_EQ(after.find("method=\"M500\""), std::string::npos);
  EXPECT_NE(after.find("method=\"other\""), std::string::npos) << after.substr(0, 2000);
  // The same series; only counts change (a digit or two).
  EXPECT_LT(after.size(), before.size() + 200);
}

}  // namespace
}  // namespace mdn::test

namespace mdn::test {
namespace {

// Item 4: a downloaded result kept its stored-job slot for its whole lifetime (600 s), so with
// 1,024 slots asynchronous throughput was capped at 1.7 jobs a second. A downloaded or
// cancelled result now gives its slot up first (decision 62); results not downloaded are kept.
TEST(HttpFairShares, DownloadedOrCancelledResultsFreeTheirSlots) {
  ServerProcess server({"--workers", "2", "--max-stored-jobs", "3", "--client-max-stored-jobs", "4"});  // one client may fill it
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string mesh = noisy_sphere_off(1);
  const httplib::Headers params = {{"X-Denoise-Params", R"({"mode":"none"})"}};
  for (int i = 0; i < 9; ++i) {  // three times the slots, each result downloaded
    auto posted = c->Post("/v1/jobs", params, mesh, "model/x-off");
    ASSERT_TRUE(posted);
    ASSERT_EQ(posted->status, 202) << "job " << i << ": " << posted->body;
    const std::string id = parse_json(posted->body).value("id", "");
    EXPECT_EQ(wait_job(*c, id).value("state", ""), "succeeded") << id;
    auto result = c->Get("/v1/jobs/" + id + "/result");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200) << id;
  }
  // Results not downloaded are kept for their lifetime: with three of them the store is full.
  std::vector<std::string> kept;
  for (int i = 0; i < 3; ++i) {
    auto posted = c->Post("/v1/jobs", params, mesh, "model/x-off");
    ASSERT_TRUE(posted);
    ASSERT_EQ(posted->status, 202) << posted->body;
    kept.push_back(parse_json(posted->body).value("id", ""));
    wait_job(*c, kept.back());
  }
  const nlohmann::json refused = expect_problem(c->Post("/v1/jobs", params, mesh, "model/x-off"), 503);
  EXPECT_EQ(refused.value("type", ""), "urn:meshdenoise:problem:store-full") << refused.dump();
  for (const auto& id : kept)
    EXPECT_EQ(c->Get("/v1/jobs/" + id)->status, 200) << id << " was evicted before its lifetime";
}

}  // namespace
}  // namespace mdn::test
