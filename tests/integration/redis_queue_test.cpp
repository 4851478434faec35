// The shared job store (--queue redis://...) end to end: a real redis-server from Debian's
// packages on a free loopback port (append-only file, fsync on every write as in the compose
// file, in a temporary directory) and real meshdenoise-server replicas speaking real HTTP.
//
//   - 3 replicas, jobs posted round-robin and each polled and fetched through other replicas:
//     all succeed, byte-identical to the CLI.
//   - A replica killed (SIGKILL) while it runs a job: another replica takes it over and
//     finishes it; the jobs queued behind it run too; nothing is lost or stored twice.
//   - Redis killed and restarted: clear 503s (with Retry-After) while it is down, full service
//     after, every accepted job finished.
//   - Cancellation across replicas; idempotency across replicas; --queue-max-attempts; result
//     expiry and --queue-max-result; Redis unreachable at startup; a malformed --queue.
//
// No timing is asserted: every wait polls with a generous deadline.
#include "http_fixture.h"

#include <map>

#include "server/http/config.h"

namespace mdn::test {
namespace {

using nlohmann::json;
using Seconds = std::chrono::seconds;

// A job of a few seconds (20k faces, many iterations): long enough to be seen running.
const char* kMediumParams = R"({"n_normal":600,"n_vertex":600,"n_aniso":20})";
const char* kSmallParams = R"({"n_normal":12,"n_vertex":8})";

int free_port() { return mdn::test::free_loopback_port(); }

// Sends one inline command and returns the first reply line ("+PONG", "-LOADING ...", "").
std::string redis_inline(int port, const std::string& command) {
  const int fd = connect_loopback(port);
  if (fd < 0) return {};
  const std::string line = command + "\r\n";
  send(fd, line.data(), line.size(), MSG_NOSIGNAL);
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string out;
  char buf[512];
  while (out.find("\r\n") == std::string::npos) {
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    out.append(buf, std::size_t(n));
  }
  close(fd);
  return out.substr(0, out.find("\r\n"));
}

// How many keys match `pattern` (KEYS, through a script: its reply is one line, ":N").
int count_keys(int port, const std::string& pattern) {
  const std::string reply = redis_inline(port, "EVAL \"return #redis.call('KEYS', ARGV[1])\" 0 " + pattern);
  return reply.size() > 1 && reply[0] == ':' ? std::stoi(reply.substr(1)) : -1;
}

// redis-server as a child process; restartable on the same port and data directory.
class RedisServer {
 public:
  explicit RedisServer(int port = free_port()) : dir_(temp_dir("redis")), port_(port) { start(); }
  ~RedisServer() {
    kill_now();
    fs::remove_all(dir_);
  }
  RedisServer(const RedisServer&) = delete;
  RedisServer& operator=(const RedisServer&) = delete;

  static std::string binary() { return "/usr/bin/redis-server"; }
  std::string url() const { return "redis://127.0.0.1:" + std::to_string(port_) + "/0"; }
  int port() const { return port_; }
  bool running() const { return pid_ > 0; }

  // Starts and waits until it answers PING (after loading its append-only file).
  void start() {
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      const std::string port = std::to_string(port_), log = dir_ + "/redis.log";
      execl(binary().c_str(), binary().c_str(), "--port", port.c_str(), "--bind", "127.0.0.1", "--dir", dir_.c_str(),
            "--appendonly", "yes", "--appendfsync", "always", "--save", "", "--daemonize", "no", "--logfile",
            log.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + Seconds(30);
    while (std::chrono::steady_clock::now() < deadline) {
      if (redis_inline(port_, "PING") == "+PONG") return;
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ADD_FAILURE() << "redis-server did not start on port " << port_ << ": " << read_file(dir_ + "/redis.log");
  }
  // SIGKILL: nothing flushed at exit; what was acknowledged is already in the append-only file.
  void kill_now() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  std::string command(const std::string& c) const { return redis_inline(port_, c); }

 private:
  std::string dir_;
  int port_;
  pid_t pid_ = -1;
};

class RedisQueue : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(server_binary())) << server_binary() << " was not built";
    ASSERT_TRUE(fs::exists(RedisServer::binary())) << "redis-server is not installed (scripts/deps/apt-test.txt)";
    dir_ = temp_dir("redisq");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A replica on the shared queue; `extra` flags after the common ones.
  static std::unique_ptr<ServerProcess> replica(const RedisServer& redis, std::vector<std::string> extra = {},
                                                std::vector<std::string> env = {}) {
    std::vector<std::string> args = {"--queue", redis.url(), "--workers", "1", "--queue-reclaim-idle", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto s = std::make_unique<ServerProcess>(args, env);
    EXPECT_TRUE(s->started()) << s->log();
    return s;
  }

  std::string cli_output(const std::string& input, const std::string& params) {
    const std::string in = dir_ + "/in.off", out = dir_ + "/out.off";
    write_file(in, input);
    fs::remove(out);
    const auto [code, text] =
        run_command(cli_binary() + " --params " + shell_quote(params) + " " + shell_quote(in) + " " + shell_quote(out) + " 2>&1");
    EXPECT_EQ(code, 0) << text;
    return read_file(out);
  }

  static std::string post_job(ServerProcess& s, const std::string& body, const std::string& params,
                              httplib::Headers headers = {}) {
    headers.emplace("X-Denoise-Params", params);
    auto r = s.client()->Post("/v1/jobs", headers, body, "model/x-off");
    EXPECT_TRUE(r);
    if (!r) return {};
    EXPECT_EQ(r->status, 202) << r->body;
    return parse_json(r->body).value("id", "");
  }

  // Polls until the job's state is one of `states` (or the deadline); returns its last JSON.
  static json wait_state(ServerProcess& s, const std::string& id, std::initializer_list<std::string_view> states,
                         Seconds timeout = Seconds(90)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    auto c = s.client();
    json job;
    while (std::chrono::steady_clock::now() < deadline) {
      auto r = c->Get("/v1/jobs/" + id);
      if (r && r->status == 200) {
        job = parse_json(r->body);
        for (auto st : states)
          if (job.value("state", "") == st) return job;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return job;
  }

  // Polls a replica's GET `path` until it answers `status`.
  static bool wait_status(ServerProcess& s, const std::string& path, int status, Seconds timeout = Seconds(30)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    auto c = s.client(5);
    while (std::chrono::steady_clock::now() < deadline) {
      auto r = c->Get(path.c_str());
      if (r && r->status == status) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }

  static double metric(ServerProcess& s, const std::string& name) {
    auto r = s.client()->Get("/metrics");
    return r ? metric_value(r->body, name) : -1;
  }

  std::string dir_;
};

TEST_F(RedisQueue, ThreeReplicasRoundRobinResultsEqualTheCli) {
  RedisServer redis;
  std::vector<std::unique_ptr<ServerProcess>> replicas;
  for (int i = 0; i < 3; ++i) replicas.push_back(replica(redis));
  for (auto& r : replicas) ASSERT_TRUE(wait_status(*r, "/readyz", 200)) << r->log();

  const int n = 6;
  std::vector<std::string> inputs, ids;
  for (int i = 0; i < n; ++i) {
    inputs.push_back(noisy_sphere_off(3, 100 + std::uint64_t(i)));
    ids.push_back(post_job(*replicas[std::size_t(i % 3)], inputs.back(), kSmallParams));
    ASSERT_FALSE(ids.back().empty());
  }
  for (int i = 0; i < n; ++i) {
    ServerProcess& poller = *replicas[std::size_t((i + 1) % 3)];
    ServerProcess& fetcher = *replicas[std::size_t((i + 2) % 3)];
    const json job = wait_state(poller, ids[std::size_t(i)], {"succeeded", "failed", "cancelled"});
    ASSERT_EQ(job.value("state", ""), "succeeded") << job.dump();
    EXPECT_EQ(job["result"].value("faces", 0), 1280);
    auto r = fetcher.client()->Get("/v1/jobs/" + ids[std::size_t(i)] + "/result");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(r->body, cli_output(inputs[std::size_t(i)], kSmallParams)) << "job " << i;
    EXPECT_EQ(r->get_header_value("X-Denoise-Output-Bytes"), std::to_string(r->body.size()));
  }
  // What the job says about its result (parameters, reports, counts) is what the memory store
  // says for the same job: only timings differ.
  {
    ServerProcess memory({"--workers", "1"});
    ASSERT_TRUE(memory.started()) << memory.log();
    const std::string local = post_job(memory, inputs[0], kSmallParams);
    json expected = wait_state(memory, local, {"succeeded", "failed"});
    json shared = wait_state(*replicas[2], ids[0], {"succeeded", "failed"});
    ASSERT_TRUE(expected.contains("result") && shared.contains("result")) << expected.dump() << shared.dump();
    expected["result"].erase("timings_ms");
    shared["result"].erase("timings_ms");
    EXPECT_EQ(shared["result"], expected["result"]);
    auto a = memory.client()->Get("/v1/jobs/" + local + "/result");
    auto b = replicas[0]->client()->Get("/v1/jobs/" + ids[0] + "/result");
    ASSERT_TRUE(a && b);
    for (const char* h : {"X-Denoise-Params", "X-Denoise-Summary", "X-Denoise-Vertices", "X-Denoise-Faces",
                          "X-Denoise-Output-Bytes", "Content-Type", "Content-Disposition"})
      EXPECT_EQ(b->get_header_value(h), a->get_header_value(h)) << h;
  }
  // The work was shared: every replica's workers ran some of it, or at least the queue drained.
  for (auto& r : replicas) {
    auto ready = r->client()->Get("/readyz");
    ASSERT_TRUE(ready);
    EXPECT_EQ(parse_json(ready->body).value("job_store", ""), "redis");
  }
}

TEST_F(RedisQueue, KilledReplicasJobIsTakenOverAndNothingIsLost) {
  RedisServer redis;
  auto a = replica(redis);
  ASSERT_TRUE(wait_status(*a, "/readyz", 200));
  const std::string medium = noisy_sphere_off(5, 7);
  const std::string id = post_job(*a, medium, kMediumParams);
  ASSERT_FALSE(id.empty());
  // Jobs queued behind it (A's only worker is busy: they wait in the shared queue).
  std::vector<std::string> small_inputs, small_ids;
  for (int i = 0; i < 3; ++i) {
    small_inputs.push_back(noisy_sphere_off(2, 200 + std::uint64_t(i)));
    small_ids.push_back(post_job(*a, small_inputs.back(), kSmallParams));
  }
  const json running = wait_state(*a, id, {"running", "succeeded", "failed"});
  ASSERT_EQ(running.value("state", ""), "running") << running.dump();
  a->signal(SIGKILL);
  a->wait_exit();

  auto b = replica(redis);
  const json done = wait_state(*b, id, {"succeeded", "failed", "cancelled"}, Seconds(120));
  ASSERT_EQ(done.value("state", ""), "succeeded") << done.dump() << "\n" << b->log();
  EXPECT_EQ(done.value("attempts", 0), 2) << done.dump();
  auto r = b->client()->Get("/v1/jobs/" + id + "/result");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->body, cli_output(medium, kMediumParams));
  for (std::size_t i = 0; i < small_ids.size(); ++i) {
    const json s = wait_state(*b, small_ids[i], {"succeeded", "failed", "cancelled"});
    ASSERT_EQ(s.value("state", ""), "succeeded") << s.dump();
    EXPECT_FALSE(s.contains("attempts")) << "never ran before: " << s.dump();
    auto sr = b->client()->Get("/v1/jobs/" + small_ids[i] + "/result");
    ASSERT_TRUE(sr);
    EXPECT_EQ(sr->body, cli_output(small_inputs[i], kSmallParams));
  }
  EXPECT_EQ(metric(*b, "mdn_queue_reclaimed_total"), 1);
  EXPECT_EQ(metric(*b, "mdn_queue_retries_total"), 1);
  // Every entry acknowledged: nothing pending, nothing waiting (sampled each second).
  const auto deadline = std::chrono::steady_clock::now() + Seconds(20);
  while (std::chrono::steady_clock::now() < deadline &&
         (metric(*b, "mdn_queue_shared_pending") != 0 || metric(*b, "mdn_queue_shared_length") != 0))
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(metric(*b, "mdn_queue_shared_pending"), 0);
  EXPECT_EQ(metric(*b, "mdn_queue_shared_length"), 0);
  EXPECT_NE(b->log().find("job_reclaimed"), std::string::npos);
}

TEST_F(RedisQueue, RedisRestartGivesClear503sThenFullService) {
  RedisServer redis;
  auto a = replica(redis);
  auto b = replica(redis);
  ASSERT_TRUE(wait_status(*a, "/readyz", 200));
  ASSERT_TRUE(wait_status(*b, "/readyz", 200));
  // Accepted before the outage: two that run through it and four queued behind them.
  std::vector<std::pair<std::string, std::string>> jobs;  // id, params
  std::vector<std::string> inputs;
  for (int i = 0; i < 6; ++i) {
    const bool medium = i < 2;
    inputs.push_back(medium ? noisy_sphere_off(5, 300 + std::uint64_t(i)) : noisy_sphere_off(3, 300 + std::uint64_t(i)));
    const char* params = medium ? R"({"n_normal":200,"n_vertex":200,"n_aniso":10})" : kSmallParams;
    jobs.emplace_back(post_job(i % 2 ? *b : *a, inputs.back(), params), params);
    ASSERT_FALSE(jobs.back().first.empty());
  }
  redis.kill_now();

  for (ServerProcess* s : {a.get(), b.get()}) {
    ASSERT_TRUE(wait_status(*s, "/readyz", 503)) << s->log();
    auto c = s->client();
    const json p = expect_problem(c->Get("/readyz"), 503);
    EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:queue-unavailable");
    auto ready = c->Get("/readyz");
    ASSERT_TRUE(ready);
    EXPECT_FALSE(ready->get_header_value("Retry-After").empty());
    auto post = c->Post("/v1/jobs", noisy_sphere_off(1), "model/x-off");
    const json pp = expect_problem(post, 503);
    EXPECT_EQ(pp.value("type", ""), "urn:meshdenoise:problem:queue-unavailable");
    ASSERT_TRUE(post);
    EXPECT_FALSE(post->get_header_value("Retry-After").empty());
    expect_problem(c->Get("/v1/jobs/" + jobs[0].first), 503);
    expect_problem(c->Get("/v1/jobs/" + jobs[0].first + "/result"), 503);
    expect_problem(c->Delete("/v1/jobs/" + jobs[0].first), 503);
    // Synchronous denoising needs no shared state: it keeps working.
    auto sync = c->Post("/v1/denoise", noisy_sphere_off(1), "model/x-off");
    ASSERT_TRUE(sync);
    EXPECT_EQ(sync->status, 200);
    EXPECT_EQ(metric(*s, "mdn_queue_redis_up"), 0);
  }

  redis.start();
  for (ServerProcess* s : {a.get(), b.get()}) ASSERT_TRUE(wait_status(*s, "/readyz", 200)) << s->log();
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const json job = wait_state(i % 2 ? *a : *b, jobs[i].first, {"succeeded", "failed", "cancelled"});
    ASSERT_EQ(job.value("state", ""), "succeeded") << i << ": " << job.dump();
    auto r = (i % 2 ? *b : *a).client()->Get("/v1/jobs/" + jobs[i].first + "/result");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->body, cli_output(inputs[i], jobs[i].second)) << "job " << i;
  }
  const std::string after = post_job(*a, noisy_sphere_off(2, 9), kSmallParams);
  EXPECT_EQ(wait_state(*b, after, {"succeeded", "failed"}).value("state", ""), "succeeded");
  EXPECT_GE(metric(*a, "mdn_queue_redis_reconnects_total"), 1);
  EXPECT_NE(a->log().find("redis_reconnected"), std::string::npos);
}

TEST_F(RedisQueue, CancelAcrossReplicas) {
  RedisServer redis;
  auto a = replica(redis);
  auto b = replica(redis);
  auto c = replica(redis);
  const std::string heavy = noisy_sphere_off(5, 3);
  // Three heavy jobs, two workers (a and b; c's worker is kept busy too): the third waits.
  std::vector<std::string> ids;
  for (int i = 0; i < 4; ++i) ids.push_back(post_job(*a, heavy, kHeavyParams));
  std::string running, queued;
  const auto deadline = std::chrono::steady_clock::now() + Seconds(60);
  while ((running.empty() || queued.empty()) && std::chrono::steady_clock::now() < deadline) {
    for (const auto& id : ids) {
      const std::string st = parse_json(b->client()->Get("/v1/jobs/" + id)->body).value("state", "");
      if (st == "running" && running.empty()) running = id;
      if (st == "queued") queued = id;
    }
    if (running.empty() || queued.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_FALSE(running.empty());
  ASSERT_FALSE(queued.empty());

  auto dq = c->client()->Delete("/v1/jobs/" + queued);
  ASSERT_TRUE(dq);
  EXPECT_EQ(dq->status, 200) << dq->body;
  EXPECT_EQ(parse_json(dq->body).value("state", ""), "cancelled");

  auto dr = c->client()->Delete("/v1/jobs/" + running);
  ASSERT_TRUE(dr);
  EXPECT_EQ(dr->status, 202) << dr->body;
  EXPECT_TRUE(parse_json(dr->body).value("cancel_requested", false));
  const json stopped = wait_state(*b, running, {"cancelled", "succeeded", "failed"}, Seconds(30));
  EXPECT_EQ(stopped.value("state", ""), "cancelled") << stopped.dump();
  EXPECT_EQ(stopped["error"].value("type", ""), "urn:meshdenoise:problem:cancelled");
  const json p = expect_problem(a->client()->Get("/v1/jobs/" + running + "/result"), 409);
  EXPECT_EQ(p.value("job_state", ""), "cancelled");

  // A finished job: DELETE removes it everywhere.
  auto gone = b->client()->Delete("/v1/jobs/" + running);
  ASSERT_TRUE(gone);
  EXPECT_EQ(gone->status, 204);
  for (ServerProcess* s : {a.get(), b.get(), c.get()}) expect_problem(s->client()->Get("/v1/jobs/" + running), 404);
  // Leave nothing heavy running.
  for (const auto& id : ids) b->client()->Delete("/v1/jobs/" + id);
}

// A replica whose worker waits for work starts a job it accepts at once (one Redis step, the
// input not read back); a busy one leaves it in the shared queue, where it waits its turn.
// The replica's slot picks up a job handed to it 300 ms late (a test hook): a second job
// posted meanwhile must still find the only worker taken. Once, under CI load, it was started
// at once as well: reported running and tied to this replica while it waited for the worker,
// where another replica's idle worker could have taken it from the shared queue.
TEST_F(RedisQueue, AnIdleReplicaStartsAJobAtOnceABusyOneQueuesIt) {
  RedisServer redis;
  auto a = replica(redis, {}, {"MDN_TEST_HANDOFF_PICKUP_DELAY_MS=300"});
  ASSERT_TRUE(wait_status(*a, "/readyz", 200)) << a->log();
  const std::string small = noisy_sphere_off(3, 7);
  const std::string first = post_job(*a, small, kSmallParams);
  EXPECT_EQ(wait_state(*a, first, {"succeeded", "failed"}).value("state", ""), "succeeded");
  EXPECT_EQ(metric(*a, "mdn_queue_started_on_submit_total"), 1);
  auto r = a->client()->Get("/v1/jobs/" + first + "/result");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body, cli_output(small, kSmallParams));

  // The second right after the heavy one, while the slot has not picked the heavy one up yet.
  const std::string heavy_input = noisy_sphere_off(5, 3);
  const std::string heavy = post_job(*a, heavy_input, kHeavyParams);
  const std::string second = post_job(*a, small, kSmallParams);
  EXPECT_EQ(wait_state(*a, heavy, {"running", "succeeded", "failed"}).value("state", ""), "running");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(parse_json(a->client()->Get("/v1/jobs/" + second)->body).value("state", ""), "queued")
      << "the heavy job: " << a->client()->Get("/v1/jobs/" + heavy)->body;
  EXPECT_EQ(metric(*a, "mdn_queue_started_on_submit_total"), 2);
  auto d = a->client()->Delete("/v1/jobs/" + heavy);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->status, 202) << d->body;
  EXPECT_EQ(wait_state(*a, second, {"succeeded", "failed"}).value("state", ""), "succeeded");
  EXPECT_EQ(metric(*a, "mdn_queue_started_on_submit_total"), 2);
  EXPECT_EQ(a->client()->Get("/v1/jobs/" + second + "/result")->body, r->body);
}

// A long poll through another replica than the one running the job answers when the job ends:
// the runner's "done" message wakes it, well before its 5 s fallback re-read.
TEST_F(RedisQueue, LongPollThroughAnotherReplicaAnswersWhenTheJobEnds) {
  using Ms = std::chrono::milliseconds;
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration_cast<Ms>(std::chrono::steady_clock::now() - t).count();
  };
  RedisServer redis;
  auto a = replica(redis);
  auto b = replica(redis);
  for (ServerProcess* s : {a.get(), b.get()}) ASSERT_TRUE(wait_status(*s, "/readyz", 200)) << s->log();

  // Posted to a, whose worker waits for work: a runs it (started on submit). b's long poll
  // answers within its client's 4 s read timeout only if a's "done" message woke it (b would
  // read the job again only after 5 s).
  const std::string id = post_job(*a, noisy_sphere_off(3, 9), kSmallParams);
  auto r = b->client(4)->Get("/v1/jobs/" + id + "?wait=30");
  ASSERT_TRUE(r) << "the long poll on b was not woken by the job's end on a";
  EXPECT_EQ(parse_json(r->body).value("state", ""), "succeeded") << r->body;
  EXPECT_EQ(metric(*a, "mdn_queue_started_on_submit_total"), 1);

  const std::string heavy = post_job(*a, noisy_sphere_off(6, 3), kHeavyParams);
  auto t = std::chrono::steady_clock::now();
  r = b->client()->Get("/v1/jobs/" + heavy + "?wait=0.5");
  ASSERT_TRUE(r);
  EXPECT_GE(since(t), 490);
  const std::string state = parse_json(r->body).value("state", "");
  EXPECT_TRUE(state == "queued" || state == "running") << state;

  // Cancelled through a once b's long poll waits: b answers with the end, well within 4 s.
  std::thread canceller([&] {
    for (int i = 0; i < 500 && metric(*b, "mdn_long_polls") != 1; ++i) std::this_thread::sleep_for(Ms(20));
    a->client()->Delete("/v1/jobs/" + heavy);
  });
  r = b->client(4)->Get("/v1/jobs/" + heavy + "?wait=60");
  canceller.join();
  ASSERT_TRUE(r) << "the long poll on b was not woken by the job's cancellation";
  EXPECT_EQ(parse_json(r->body).value("state", ""), "cancelled") << r->body;
  EXPECT_EQ(metric(*b, "mdn_long_polls"), 0);
  expect_problem(b->client()->Get("/v1/jobs/" + heavy + "?wait=61"), 400);
}

TEST_F(RedisQueue, IdempotencyKeyHoldsAcrossReplicas) {
  RedisServer redis;
  auto a = replica(redis);
  auto b = replica(redis);
  const std::string body = noisy_sphere_off(2, 5);
  httplib::Headers key = {{"Idempotency-Key", "order-42"}, {"X-Denoise-Params", kSmallParams}};
  auto first = a->client()->Post("/v1/jobs", key, body, "model/x-off");
  auto again = b->client()->Post("/v1/jobs", key, body, "model/x-off");
  ASSERT_TRUE(first && again);
  ASSERT_EQ(first->status, 202) << first->body;
  ASSERT_EQ(again->status, 202) << again->body;
  EXPECT_EQ(parse_json(again->body).value("id", "x"), parse_json(first->body).value("id", "y"));
  EXPECT_EQ(again->get_header_value("Idempotent-Replayed"), "true");
  EXPECT_EQ(first->get_header_value("Idempotent-Replayed"), "");
  const json p = expect_problem(b->client()->Post("/v1/jobs", key, noisy_sphere_off(2, 6), "model/x-off"), 422);
  EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:idempotency-key-reused");
  const std::string id = parse_json(first->body).value("id", "");
  EXPECT_EQ(wait_state(*a, id, {"succeeded", "failed"}).value("state", ""), "succeeded");
  // Each POST stored its input before the script decided; the replayed and the refused ones
  // were deleted at once (not left to expire), the job's own when it finished. Its result was
  // staged under the replica's key and renamed: no staged copy is left.
  EXPECT_EQ(count_keys(redis.port(), "mdn:job:*:input"), 0);
  EXPECT_EQ(count_keys(redis.port(), "mdn:job:*:result"), 1);
  EXPECT_EQ(count_keys(redis.port(), "mdn:job:*:result:*"), 0);
  // B's idle worker started each of its two POSTs while Redis decided (a replay, a refusal):
  // neither was accepted, so neither run is reported, however it ended.
  const auto deadline = std::chrono::steady_clock::now() + Seconds(30);
  while (std::chrono::steady_clock::now() < deadline && metric(*b, "mdn_jobs_running") != 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(metric(*b, "mdn_jobs_running"), 0);
  EXPECT_EQ(metric(*b, "mdn_jobs_total{state=\"succeeded\"}"), -1) << "not a series: no job ended on B";
  EXPECT_EQ(metric(*b, "mdn_jobs_total{state=\"cancelled\"}"), -1);
  EXPECT_EQ(metric(*b, "mdn_queue_early_runs_discarded_total"), 2);
  EXPECT_EQ(metric(*a, "mdn_queue_early_runs_discarded_total"), 0);
  EXPECT_EQ(metric(*a, "mdn_jobs_total{state=\"succeeded\"}"), 1);
  // A serves the result it stored from memory, B reads it from Redis: the same bytes.
  auto from_a = a->client()->Get("/v1/jobs/" + id + "/result");
  auto from_b = b->client()->Get("/v1/jobs/" + id + "/result");
  ASSERT_TRUE(from_a && from_b);
  ASSERT_EQ(from_a->status, 200);
  EXPECT_EQ(from_a->body, from_b->body);
  EXPECT_EQ(from_a->body, cli_output(body, kSmallParams));
  EXPECT_EQ(metric(*a, "mdn_queue_results_served_locally_total"), 1);
  EXPECT_EQ(metric(*b, "mdn_queue_results_served_locally_total"), 0);
  // Deleting the job frees the key, and A no longer serves the result it keeps.
  auto del = b->client()->Delete("/v1/jobs/" + id);
  ASSERT_TRUE(del);
  EXPECT_EQ(del->status, 204);
  expect_problem(a->client()->Get("/v1/jobs/" + id + "/result"), 404);
  auto fresh = a->client()->Post("/v1/jobs", key, noisy_sphere_off(2, 6), "model/x-off");
  ASSERT_TRUE(fresh);
  EXPECT_EQ(fresh->status, 202) << fresh->body;
  EXPECT_NE(parse_json(fresh->body).value("id", ""), id);
}

TEST_F(RedisQueue, AJobWhoseWorkersKeepDyingFailsAfterMaxAttempts) {
  RedisServer redis;
  auto a = replica(redis, {"--queue-max-attempts", "1"});
  const std::string id = post_job(*a, noisy_sphere_off(5, 8), kMediumParams);
  ASSERT_EQ(wait_state(*a, id, {"running", "succeeded"}).value("state", ""), "running");
  a->signal(SIGKILL);
  a->wait_exit();
  auto b = replica(redis, {"--queue-max-attempts", "1"});
  const json job = wait_state(*b, id, {"failed", "succeeded", "cancelled"});
  ASSERT_EQ(job.value("state", ""), "failed") << job.dump();
  EXPECT_EQ(job["error"].value("type", ""), "urn:meshdenoise:problem:attempts-exhausted");
  EXPECT_EQ(job["error"].value("attempts", 0), 1) << job.dump();
  EXPECT_EQ(metric(*b, "mdn_queue_attempts_exhausted_total"), 1);
}

TEST_F(RedisQueue, ResultsExpireAndSizesAreBounded) {
  RedisServer redis;
  // Two services on one Redis, kept apart by their key prefix.
  auto expiring = replica(redis, {"--queue-prefix", "t1:", "--result-ttl", "1"});
  auto bounded = replica(redis, {"--queue-prefix", "t2:", "--queue-max-result", "1K", "--max-body", "64K"});
  const std::string id = post_job(*expiring, noisy_sphere_off(1), kSmallParams);
  EXPECT_EQ(wait_state(*expiring, id, {"succeeded", "failed"}).value("state", ""), "succeeded");
  EXPECT_TRUE(wait_status(*expiring, "/v1/jobs/" + id, 404, Seconds(30)));
  expect_problem(expiring->client()->Get("/v1/jobs/" + id + "/result"), 404);
  expect_problem(bounded->client()->Get("/v1/jobs/" + id), 404);  // other prefix: another service

  const std::string big = post_job(*bounded, noisy_sphere_off(2, 1), kSmallParams);
  const json job = wait_state(*bounded, big, {"succeeded", "failed"});
  ASSERT_EQ(job.value("state", ""), "failed") << job.dump();
  EXPECT_EQ(job["error"].value("type", ""), "urn:meshdenoise:problem:result-too-large");
  expect_problem(bounded->client()->Post("/v1/jobs", noisy_sphere_off(4, 1), "model/x-off"), 413);
}

TEST_F(RedisQueue, UnreachableAtStartupThenConnects) {
  const int port = free_port();
  ServerProcess s({"--queue", "redis://127.0.0.1:" + std::to_string(port), "--workers", "1"});
  ASSERT_TRUE(s.started()) << s.log();
  auto c = s.client();
  auto health = c->Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  expect_problem(c->Get("/readyz"), 503);
  expect_problem(c->Post("/v1/jobs", noisy_sphere_off(1), "model/x-off"), 503);
  expect_problem(c->Get("/v1/jobs/0123456789abcdef0123456789abcdef"), 503);
  // Redis appears on that port: the server connects by itself.
  RedisServer redis(port);
  EXPECT_TRUE(wait_status(s, "/readyz", 200)) << s.log();
  const std::string id = post_job(s, noisy_sphere_off(1), kSmallParams);
  EXPECT_EQ(wait_state(s, id, {"succeeded", "failed"}).value("state", ""), "succeeded");
}

TEST_F(RedisQueue, AStoppingReplicaHandsItsJobBack) {
  RedisServer redis;
  auto a = replica(redis, {"--drain-grace", "0.2"});
  const std::string medium = noisy_sphere_off(5, 12);
  const std::string id = post_job(*a, medium, kMediumParams);
  ASSERT_EQ(wait_state(*a, id, {"running", "succeeded"}).value("state", ""), "running");
  a->signal(SIGTERM);  // the grace ends before the job does: it goes back to the queue
  EXPECT_EQ(a->wait_exit(Seconds(60)), 1) << a->log();  // an incomplete drain exits non-zero
  EXPECT_NE(a->log().find("job_released"), std::string::npos) << a->log();
  // Another replica takes it at once (no idle threshold to wait for) and it is no retry.
  auto b = replica(redis, {"--queue-reclaim-idle", "3600"});
  const json job = wait_state(*b, id, {"succeeded", "failed", "cancelled"}, Seconds(120));
  ASSERT_EQ(job.value("state", ""), "succeeded") << job.dump();
  EXPECT_FALSE(job.contains("attempts")) << job.dump();
  auto r = b->client()->Get("/v1/jobs/" + id + "/result");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->body, cli_output(medium, kMediumParams));
  EXPECT_EQ(metric(*b, "mdn_queue_reclaimed_total"), 0);
}

// Issue 17: a drain out of grace keeps every job it did not finish in Redis for another
// replica: the running one is handed back, those still queued in the stream stay there.
TEST_F(RedisQueue, JobsADrainAbandonsStayInRedisForAnotherReplica) {
  RedisServer redis;
  auto a = replica(redis, {"--workers", "1", "--drain-grace", "0.2"});
  // One job long enough to be running when the signal comes, two small ones queued behind it.
  std::vector<std::string> ids{post_job(*a, noisy_sphere_off(5, 14), kMediumParams)};
  for (int i = 0; i < 2; ++i) ids.push_back(post_job(*a, noisy_sphere_off(1, 15 + std::uint64_t(i)), kSmallParams));
  ASSERT_EQ(wait_state(*a, ids[0], {"running", "succeeded"}).value("state", ""), "running");
  a->signal(SIGTERM);
  EXPECT_EQ(a->wait_exit(Seconds(60)), 1) << a->log();
  // The queued ones never left the stream (A ran only the first, cancelled and handed back).
  std::istringstream lines(a->log());
  for (std::string line; std::getline(lines, line);) {
    if (line.find("job_finished") == std::string::npos) continue;
    for (std::size_t i = 1; i < ids.size(); ++i) EXPECT_EQ(line.find(ids[i]), std::string::npos) << line;
  }
  auto b = replica(redis, {"--queue-reclaim-idle", "3600"});
  for (const auto& id : ids) {
    const json job = wait_state(*b, id, {"succeeded", "failed", "cancelled"}, Seconds(120));
    EXPECT_EQ(job.value("state", ""), "succeeded") << id << ": " << job.dump() << "\n" << a->log();
  }
}

TEST_F(RedisQueue, ADrainingReplicaFinishesItsJobAndExits) {
  RedisServer redis;
  auto a = replica(redis);
  const std::string body = noisy_sphere_off(5, 13);
  const char* params = R"({"n_normal":200,"n_vertex":200,"n_aniso":10})";
  const std::string id = post_job(*a, body, params);
  ASSERT_EQ(wait_state(*a, id, {"running", "succeeded"}).value("state", ""), "running");
  a->signal(SIGTERM);
  EXPECT_EQ(a->wait_exit(Seconds(60)), 0) << a->log();
  // Stored before the replica exited: readable through any other replica.
  auto b = replica(redis);
  const json job = wait_state(*b, id, {"succeeded", "failed", "cancelled"}, Seconds(10));
  EXPECT_EQ(job.value("state", ""), "succeeded") << job.dump();
  EXPECT_FALSE(job.contains("attempts")) << job.dump();
}

TEST(RedisUrl, ParsesWhatOperatorsWrite) {
  using http::parse_redis_url;
  const auto a = parse_redis_url("redis://cache.internal");
  EXPECT_EQ(a.host, "cache.internal");
  EXPECT_EQ(a.port, 6379);
  EXPECT_EQ(a.db, 0);
  EXPECT_EQ(a.password, "");
  const auto b = parse_redis_url("redis://:s3cret@10.0.0.5:6380/3");
  EXPECT_EQ(b.host, "10.0.0.5");
  EXPECT_EQ(b.port, 6380);
  EXPECT_EQ(b.db, 3);
  EXPECT_EQ(b.password, "s3cret");
  const auto c = parse_redis_url("redis://default:p@ss@[::1]:7000");
  EXPECT_EQ(c.host, "::1");
  EXPECT_EQ(c.port, 7000);
  EXPECT_EQ(c.password, "p@ss");
  for (const char* bad : {"redis://", "redis://:pw@", "redis://h:", "redis://h:0", "redis://h/16", "redis://h/x",
                          "rediss://h", "memory2", "redis://h h"})
    EXPECT_THROW(parse_redis_url(bad), http::ConfigError) << bad;
  // Neither --help nor the log shows a password.
  const auto [code, text] = run_command("MDN_QUEUE=redis://:hunter2@h:1/0 " + shell_quote(server_binary()) + " --help");
  EXPECT_EQ(code, 0);
  EXPECT_EQ(text.find("hunter2"), std::string::npos) << text;
  ServerProcess s({"--queue", "redis://:hunter2@127.0.0.1:" + std::to_string(free_port()) + "/2"});
  ASSERT_TRUE(s.started()) << s.log();
  const auto deadline = std::chrono::steady_clock::now() + Seconds(10);
  while (s.log().find("redis_unavailable") == std::string::npos && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_NE(s.log().find("job_store"), std::string::npos) << s.log();
  EXPECT_NE(s.log().find("db=2"), std::string::npos) << s.log();
  EXPECT_EQ(s.log().find("hunter2"), std::string::npos) << s.log();
}

TEST_F(RedisQueue, MalformedQueueUrlStopsAtStartup) {
  for (const std::string url : {"redis://", "http://127.0.0.1:6379", "redis://host:99999", "redis://host/99"}) {
    const auto [code, text] = run_command(shell_quote(server_binary()) + " --queue " + shell_quote(url) + " 2>&1");
    EXPECT_EQ(code, 2) << url << ": " << text;
    EXPECT_NE(text.find("--queue"), std::string::npos) << text;
  }
  const auto [code, text] = run_command("MDN_QUEUE=redis:/x " + shell_quote(server_binary()) + " --help 2>&1");
  EXPECT_EQ(code, 2) << text;
  EXPECT_NE(text.find("MDN_QUEUE"), std::string::npos) << text;
}

// --api-keys with the shared store: a job's id carries its owner's tag, so any replica with
// the same key file serves it to its owner and answers 404 to every other client (issue 32).
TEST_F(RedisQueue, ApiKeysScopeJobsAcrossReplicas) {
  RedisServer redis;
  const std::string dir = temp_dir("keys");
  write_file(dir + "/keys", "station-a:key-aaaaaaaaaaaaaaaa\nstation-b:key-bbbbbbbbbbbbbbbb\n");
  auto a = replica(redis, {"--api-keys", dir + "/keys"});
  auto b = replica(redis, {"--api-keys", dir + "/keys"});
  auto as = [](ServerProcess& s, const char* key) {
    auto c = s.client();
    c->set_bearer_token_auth(key);
    return c;
  };
  auto created = as(*a, "key-aaaaaaaaaaaaaaaa")->Post("/v1/jobs", {{"X-Denoise-Params", kSmallParams}}, noisy_sphere_off(2, 5),
                                                     "model/x-off");
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 202) << created->body;
  const std::string id = parse_json(created->body).value("id", "");
  ASSERT_EQ(id.size(), 64u);
  auto owner_on_b = as(*b, "key-aaaaaaaaaaaaaaaa");
  auto done = owner_on_b->Get("/v1/jobs/" + id + "?wait=30");
  ASSERT_TRUE(done);
  EXPECT_EQ(done->status, 200) << done->body;
  EXPECT_EQ(parse_json(done->body).value("id", ""), id);
  for (ServerProcess* s : {a.get(), b.get()}) {
    auto other = as(*s, "key-bbbbbbbbbbbbbbbb");
    expect_problem(other->Get("/v1/jobs/" + id), 404);
    expect_problem(other->Get("/v1/jobs/" + id + "/result"), 404);
    expect_problem(other->Delete("/v1/jobs/" + id), 404);
  }
  auto result = owner_on_b->Get("/v1/jobs/" + id + "/result");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
}

// Issue 49, item 4 with the shared store: one client's share of stored jobs is counted in Redis,
// so it holds across replicas; over it, 429 with Retry-After while another client is served; a
// downloaded result and a cancelled job give their slots up (decision 78).
TEST_F(RedisQueue, ClientSharesHoldAcrossReplicas) {
  RedisServer redis;
  const std::string dir = temp_dir("shares");
  write_file(dir + "/keys", "greedy:key-aaaaaaaaaaaaaaaa\nother:key-bbbbbbbbbbbbbbbb\n");
  const std::vector<std::string> flags = {"--api-keys", dir + "/keys", "--client-max-stored-jobs", "2"};
  auto a = replica(redis, flags);
  auto b = replica(redis, flags);
  auto as = [](ServerProcess& s, const char* key) {
    auto c = s.client();
    c->set_bearer_token_auth(key);
    return c;
  };
  const std::string small = noisy_sphere_off(1, 3);
  auto submit = [&](ServerProcess& s, const char* key) {
    return as(s, key)->Post("/v1/jobs", {{"X-Denoise-Params", kSmallParams}}, small, "model/x-off");
  };
  std::vector<std::string> ids;
  for (ServerProcess* s : {a.get(), b.get()}) {  // one job on each replica: the share is full
    auto r = submit(*s, "key-aaaaaaaaaaaaaaaa");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 202) << r->body;
    ids.push_back(parse_json(r->body).value("id", ""));
  }
  for (ServerProcess* s : {a.get(), b.get()}) {
    auto r = submit(*s, "key-aaaaaaaaaaaaaaaa");
    const json p = expect_problem(r, 429);
    EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:over-client-share");
    ASSERT_TRUE(r);
    EXPECT_FALSE(r->get_header_value("Retry-After").empty());
  }
  auto other = submit(*b, "key-bbbbbbbbbbbbbbbb");
  ASSERT_TRUE(other);
  ASSERT_EQ(other->status, 202) << other->body;
  const std::string other_id = parse_json(other->body).value("id", "");
  auto other_a = as(*a, "key-bbbbbbbbbbbbbbbb");
  ASSERT_TRUE(other_a->Get("/v1/jobs/" + other_id + "?wait=30"));
  auto other_result = other_a->Get("/v1/jobs/" + other_id + "/result");
  ASSERT_TRUE(other_result);
  EXPECT_EQ(other_result->status, 200) << other_result->body;
  // Downloading one result frees its slot (on the other replica).
  auto greedy_a = as(*a, "key-aaaaaaaaaaaaaaaa");
  auto done = greedy_a->Get("/v1/jobs/" + ids[0] + "?wait=30");
  ASSERT_TRUE(done);
  EXPECT_EQ(parse_json(done->body).value("state", ""), "succeeded") << done->body;
  auto result = greedy_a->Get("/v1/jobs/" + ids[0] + "/result");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  auto third = submit(*b, "key-aaaaaaaaaaaaaaaa");
  ASSERT_TRUE(third);
  ASSERT_EQ(third->status, 202) << third->body;
  expect_problem(submit(*a, "key-aaaaaaaaaaaaaaaa"), 429);
  // Deleting one (finished or not) frees its slot too.
  auto deleted = as(*b, "key-aaaaaaaaaaaaaaaa")->Delete("/v1/jobs/" + ids[1]);
  ASSERT_TRUE(deleted);
  EXPECT_TRUE(deleted->status == 200 || deleted->status == 202 || deleted->status == 204) << deleted->body;
  if (deleted->status == 202) wait_state(*a, ids[1], {"cancelled", "succeeded"});  // a running job ends first
  auto fourth = submit(*a, "key-aaaaaaaaaaaaaaaa");
  ASSERT_TRUE(fourth);
  EXPECT_EQ(fourth->status, 202) << fourth->body;
}

}  // namespace
}  // namespace mdn::test
