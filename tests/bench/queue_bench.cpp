// Benchmark of the shared job store (issue 6's targets). Prints figures, asserts nothing;
// compare numbers only within one run on one machine.
//
//   queue_bench [--jobs N] [--runs N] [--level L] [--format glb|drc|off] [--fsync always|everysec]
//               [--rounds R] [--wait S] [--poll-ms P] [--clients C] [--redis-workers W]
//               [--params JSON] [--only latency|throughput|redis-throughput] [--memory3]
//               [--commandstats]
//
// A redis-server (Debian's, /usr/bin/redis-server) is started on a free loopback port with the
// compose file's settings (append-only file, fsync on every write: --fsync always; everysec for
// comparison) in a temporary directory.
// Servers run in-process (mdn::http::HttpService, one per "replica", each with its own queue
// and Redis consumer) and are reached over real HTTP on loopback.
// Input: a noisy icosphere (20 * 4^L faces, default L = 5: 20,480 faces), default parameters,
// posted as --format (default glb: Draco-compressed glTF, what scanners and asset pipelines
// send; off: 1 MB of text for the same mesh). The result comes back in the same format.
//
// 1. Latency: asynchronous jobs one at a time (POST /v1/jobs, poll GET every 1 ms, GET
//    /result), 1 replica with 1 worker, memory store vs Redis store, alternating one job each
//    so that both see the same background load; the median of the pairwise differences is what
//    the Redis round trips add to a job (target: <= 10 ms). --params (X-Denoise-Params) makes
//    the jobs cheap, so that the denoising's own spread does not hide the difference.
// 2. Throughput: C clients (8), N asynchronous jobs; 1 replica x 2 workers (memory) vs 3
//    replicas x W workers (Redis; W = 1 by default), each job posted to one replica and
//    followed (long polls, GET ?wait=S with S = 30 by default, as the client examples do; or
//    with --wait 0, GET every --poll-ms, 10) and fetched through another (target: 3 replicas
//    >= 1 replica x 2 workers). --rounds R alternates the two R times and reports the median of
//    each and the median of the per-round ratios. Each run also prints how busy the CPUs were
//    and the CPU time per job (this process and redis-server): whether a set-up was bound by
//    the CPUs or by waiting, and what the store costs per job. --memory3 adds 3 replicas x 1
//    worker with memory stores (each job polled where it was posted): what three replicas on
//    two cores cost without Redis.
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/io/document.h"
#include "core/noise.h"
#include "server/http/http_server.h"
#include "server/service_parts.h"
#include "bench_stats.h"
#include "support/ports.h"
#include "support/shapes.h"

// After Eigen: <httplib.h> pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>
#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using mdn::bench::Clock;

using mdn::bench::median;
using mdn::bench::ms_since;

int free_port() { return mdn::test::free_loopback_port(); }

class Redis {
 public:
  explicit Redis(const std::string& fsync)
      : dir_(fs::temp_directory_path() / ("mdn_queue_bench_" + std::to_string(getpid()))), port_(free_port()) {
    fs::create_directories(dir_);
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      const std::string port = std::to_string(port_), log = (dir_ / "redis.log").string();
      execl("/usr/bin/redis-server", "redis-server", "--port", port.c_str(), "--bind", "127.0.0.1", "--dir",
            dir_.c_str(), "--appendonly", "yes", "--appendfsync", fsync.c_str(), "--save", "", "--logfile", log.c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    // Ready once it accepts connections (the replicas then wait for /readyz).
    for (int i = 0; i < 500; ++i) {
      const int fd = socket(AF_INET, SOCK_STREAM, 0);
      sockaddr_in addr{};
      addr.sin_family = AF_INET;
      addr.sin_port = htons(std::uint16_t(port_));
      addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
      close(fd);
      if (ok) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  ~Redis() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    fs::remove_all(dir_);
  }
  pid_t pid() const { return pid_; }
  // Runs redis-cli against this server; its output.
  std::string cli(const std::string& args) const {
    std::string out;
    if (std::FILE* f = popen(("redis-cli -p " + std::to_string(port_) + " " + args).c_str(), "r")) {
      char buf[4096];
      for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) out.append(buf, n);
      pclose(f);
    }
    return out;
  }
  std::string url() const { return "redis://127.0.0.1:" + std::to_string(port_) + "/0"; }

 private:
  fs::path dir_;
  int port_;
  pid_t pid_ = -1;
};

struct Replica {
  Replica(int workers, const std::string& queue, const std::string& prefix) {
    mdn::http::ServerConfig config;
    config.port = 0;
    config.workers = workers;
    config.queue_capacity = 1000;
    config.log_level = "off";
    config.queue = mdn::http::parse_queue_setting(queue);
    config.queue_prefix = prefix;
    auto log = std::make_shared<const mdn::http::EventLog>(config);
    service = std::make_unique<mdn::http::HttpService>(config, log, mdn::http::make_service_parts(config, log));
    port = service->bind();
    thread = std::thread([this] { service->serve(); });
    // Wait until ready (the Redis store connects in the background).
    httplib::Client c("127.0.0.1", port);
    for (int i = 0; i < 500; ++i) {
      auto r = c.Get("/readyz");
      if (r && r->status == 200) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  ~Replica() {
    service->stop();
    thread.join();
  }
  std::unique_ptr<mdn::http::HttpService> service;
  int port = 0;
  std::thread thread;
};

// One asynchronous job: posted to `post`, polled (every `poll_ms`) and fetched through `poll`.
// Returns the milliseconds from POST to the last byte of the result, or -1 on failure.
// With wait_s > 0 the polls are long polls (GET ?wait=wait_s) instead of GET every poll_ms.
double run_job(httplib::Client& post, httplib::Client& poll, const std::string& body, int poll_ms,
               const std::string& params = "", int wait_s = 0) {
  httplib::Headers headers;
  if (!params.empty()) headers.emplace("X-Denoise-Params", params);
  const auto t = Clock::now();
  auto r = post.Post("/v1/jobs", headers, body, "application/octet-stream");  // recognised by content
  if (!r || r->status != 202) {
    std::fprintf(stderr, "  POST /v1/jobs: %d %s\n", r ? r->status : -1, r ? r->body.c_str() : "");
    return -1;
  }
  const std::string id = nlohmann::json::parse(r->body).value("id", "");
  const std::string job_url = "/v1/jobs/" + id + (wait_s > 0 ? "?wait=" + std::to_string(wait_s) : "");
  for (;;) {
    auto g = poll.Get(job_url.c_str());
    if (!g || g->status != 200) {
      std::fprintf(stderr, "  GET /v1/jobs/%s: %d %s\n", id.c_str(), g ? g->status : -1, g ? g->body.c_str() : "");
      return -1;
    }
    const std::string state = nlohmann::json::parse(g->body).value("state", "");
    if (state == "succeeded") break;
    if (state != "queued" && state != "running") {
      std::fprintf(stderr, "  job %s: %s\n", id.c_str(), g->body.c_str());
      return -1;
    }
    if (wait_s == 0) std::this_thread::sleep_for(std::chrono::milliseconds(poll_ms));
  }
  auto res = poll.Get(("/v1/jobs/" + id + "/result").c_str());
  if (!res || res->status != 200) {
    std::fprintf(stderr, "  GET /v1/jobs/%s/result: %d\n", id.c_str(), res ? res->status : -1);
    return -1;
  }
  const double ms = ms_since(t);
  poll.Delete(("/v1/jobs/" + id).c_str());
  return ms;
}

// Job latencies on two replicas, alternating one job each.
void latencies(Replica& a, Replica& b, const std::string& body, const std::string& params, int runs,
               std::vector<double>& out_a, std::vector<double>& out_b) {
  httplib::Client ca("127.0.0.1", a.port), cb("127.0.0.1", b.port);
  ca.set_read_timeout(600, 0);
  cb.set_read_timeout(600, 0);
  run_job(ca, ca, body, 1, params);  // warm-up
  run_job(cb, cb, body, 1, params);
  for (int i = 0; i < runs; ++i) {
    out_a.push_back(run_job(ca, ca, body, 1, params));
    out_b.push_back(run_job(cb, cb, body, 1, params));
  }
}

// The machine's busy share since the last call (all cores, from /proc/stat): whether a
// throughput run was bound by the CPUs or by waiting.
double cpu_busy_since(std::pair<long long, long long>& last) {
  std::FILE* f = std::fopen("/proc/stat", "r");
  long long v[8] = {};
  if (!f || std::fscanf(f, "cpu %lld %lld %lld %lld %lld %lld %lld %lld", v, v + 1, v + 2, v + 3, v + 4, v + 5, v + 6,
                        v + 7) != 8) {
    if (f) std::fclose(f);
    return -1;
  }
  std::fclose(f);
  long long total = 0;
  for (long long x : v) total += x;
  const long long idle = v[3] + v[4];
  const auto prev = last;
  last = {total, idle};
  const long long dt = total - prev.first;
  return dt > 0 ? 100.0 * double(dt - (idle - prev.second)) / double(dt) : -1;
}

// CPU seconds used so far by this process (pid 0) or by process `pid`, for CPU per job.
double cpu_seconds(pid_t pid) {
  double s = 0;
  if (pid == 0) {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    s = double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  } else {
    std::FILE* f = std::fopen(("/proc/" + std::to_string(pid) + "/stat").c_str(), "r");
    if (f) {
      char buf[1024] = {};
      const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
      std::fclose(f);
      buf[n] = 0;
      // Fields 14 and 15 (utime, stime, in clock ticks) follow the ")" that ends the command name.
      const char* p = std::strrchr(buf, ')');
      long long ut = 0, st = 0;
      if (p && std::sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lld %lld", &ut, &st) == 2)
        s += double(ut + st) / double(sysconf(_SC_CLK_TCK));
    }
  }
  return s;
}

// Jobs per second: 8 clients, `jobs` in all, job k posted to replica k % n, polled and
// fetched through replica (k + 1) % n.
double throughput(std::vector<std::unique_ptr<Replica>>& replicas, const std::string& body, int jobs, int poll_ms,
                  int clients_n, pid_t redis_pid, int wait_s) {
  std::atomic<int> next{0}, failed{0};
  std::pair<long long, long long> cpu{};
  cpu_busy_since(cpu);
  const double self0 = cpu_seconds(0), redis0 = redis_pid > 0 ? cpu_seconds(redis_pid) : 0;
  const auto start = Clock::now();
  std::vector<std::thread> clients;
  const std::size_t n = replicas.size();
  for (int k = 0; k < clients_n; ++k) {
    clients.emplace_back([&] {
      std::vector<std::unique_ptr<httplib::Client>> cs;
      for (auto& r : replicas) {
        cs.push_back(std::make_unique<httplib::Client>("127.0.0.1", r->port));
        cs.back()->set_read_timeout(600, 0);
      }
      for (int j; (j = next.fetch_add(1)) < jobs;)
        if (run_job(*cs[std::size_t(j) % n], *cs[std::size_t(j + (redis_pid > 0 ? 1 : 0)) % n], body, poll_ms, "",
                    wait_s) < 0)
          ++failed;
    });
  }
  for (auto& t : clients) t.join();
  const double busy = cpu_busy_since(cpu);
  const double self_ms = 1000 * (cpu_seconds(0) - self0) / jobs;
  const double redis_ms = redis_pid > 0 ? 1000 * (cpu_seconds(redis_pid) - redis0) / jobs : 0;
  std::printf("  %zu replica(s): %.2f jobs/s, CPU busy %.0f%%, CPU ms per job %.2f (this process %.2f, redis-server %.2f)\n",
              n, jobs / (ms_since(start) / 1000), busy, self_ms + redis_ms, self_ms, redis_ms);
  if (failed) std::printf("  (%d jobs failed)\n", failed.load());
  return jobs / (ms_since(start) / 1000);
}

}  // namespace

int main(int argc, char** argv) {
  int jobs = 24, runs = 15, level = 5, rounds = 1, poll_ms = 10, clients = 8;
  bool commandstats = false;  // print Redis's INFO commandstats after each Redis throughput run
  bool memory3 = false;       // also 3 replicas x 1 worker with memory stores in each throughput round
  int redis_workers = 1;  // workers per Redis replica in the throughput runs
  int wait_s = 30;  // > 0: throughput clients long-poll (GET ?wait=); 0: they poll every poll_ms
  std::string only;    // "latency", "throughput" or "redis-throughput": run one part
  std::string params;  // X-Denoise-Params of the latency jobs (default: none)
  std::string fsync = "always";
  std::string format = "glb";  // what clients post (and get back): glb (Draco-compressed), drc or off
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--jobs" && i + 1 < argc) jobs = std::atoi(argv[++i]);
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--level" && i + 1 < argc) level = std::atoi(argv[++i]);
    else if (a == "--fsync" && i + 1 < argc) fsync = argv[++i];
    else if (a == "--rounds" && i + 1 < argc) rounds = std::atoi(argv[++i]);
    else if (a == "--poll-ms" && i + 1 < argc) poll_ms = std::atoi(argv[++i]);
    else if (a == "--clients" && i + 1 < argc) clients = std::atoi(argv[++i]);
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else if (a == "--params" && i + 1 < argc) params = argv[++i];
    else if (a == "--wait" && i + 1 < argc) wait_s = std::atoi(argv[++i]);
    else if (a == "--format" && i + 1 < argc) format = argv[++i];
    else if (a == "--redis-workers" && i + 1 < argc) redis_workers = std::atoi(argv[++i]);
    else if (a == "--commandstats") commandstats = true;
    else if (a == "--memory3") memory3 = true;
    else {
      std::fprintf(stderr,
                   "usage: %s [--jobs N] [--runs N] [--level L] [--format glb|drc|off] [--fsync always|everysec] "
                   "[--rounds R] [--wait S] [--poll-ms P] [--clients C] [--redis-workers W] [--params JSON] "
                   "[--only latency|throughput|redis-throughput] [--memory3] [--commandstats]\n",
                   argv[0]);
      return 2;
    }
  }
  if (!fs::exists("/usr/bin/redis-server")) {
    std::fprintf(stderr, "redis-server is not installed (scripts/deps/apt-test.txt)\n");
    return 1;
  }
  mdn::TriMesh mesh = mdn::test::sphere(level);
  mdn::NoiseSpec noise;
  noise.seed = 1;
  mesh.V = mdn::add_noise(mesh, noise);
  const std::optional<mdn::io::Format> input_format = mdn::io::format_from_string(format);
  if (!input_format) {
    std::fprintf(stderr, "--format: glb, drc, off, ...\n");
    return 2;
  }
  mdn::io::EncodeOptions encode;
  encode.format = *input_format;
  const std::string body = mdn::io::decode(mdn::test::off_text(mesh), mdn::io::Format::Off)->encode(encode).bytes;
  std::printf("input: noisy icosphere, %lld faces, %s %zu bytes; %u hardware threads\n",
              static_cast<long long>(mesh.F.rows()), format.c_str(), body.size(), std::thread::hardware_concurrency());
  Redis redis(fsync);
  std::printf("redis-server: appendonly yes, appendfsync %s\n", fsync.c_str());

  // 1. Latency, one job at a time, one worker.
  std::vector<double> memory, shared;
  if (only.empty() || only == "latency") {
    Replica m(1, "memory", "mdn:");
    Replica r(1, redis.url(), "lat:");
    latencies(m, r, body, params, runs, memory, shared);
  }
  std::vector<double> added;  // per pair: a Redis job minus the memory job just before it
  for (std::size_t i = 0; i < memory.size() && i < shared.size(); ++i) added.push_back(shared[i] - memory[i]);
  if (!memory.empty())
    std::printf("latency (1 worker, POST -> poll every 1 ms -> result, %d jobs each, alternating%s%s): memory median "
                "%.1f ms, redis median %.1f ms, added %.1f ms (median of pairwise differences %.1f ms; target <= 10 ms)\n",
                runs, params.empty() ? "" : ", params ", params.c_str(), median(memory), median(shared),
                median(shared) - median(memory), median(added));

  // 2. Throughput, alternating the two set-ups `rounds` times.
  std::vector<double> one, three, ratios;
  for (int round = 0; round < rounds && only != "latency"; ++round) {
    if (only != "redis-throughput") {
      std::vector<std::unique_ptr<Replica>> replicas;
      replicas.push_back(std::make_unique<Replica>(2, "memory", "mdn:"));
      one.push_back(throughput(replicas, body, jobs, poll_ms, clients, 0, wait_s));
    }
    {
      std::vector<std::unique_ptr<Replica>> replicas;
      for (int i = 0; i < 3; ++i) replicas.push_back(std::make_unique<Replica>(redis_workers, redis.url(), "tp:"));
      if (commandstats) redis.cli("CONFIG RESETSTAT");
      three.push_back(throughput(replicas, body, jobs, poll_ms, clients, redis.pid(), wait_s));
    }
    if (memory3) {  // what 3 replicas cost without Redis: memory stores, each job polled where it was posted
      std::vector<std::unique_ptr<Replica>> replicas;
      for (int i = 0; i < 3; ++i) replicas.push_back(std::make_unique<Replica>(1, "memory", "mdn:"));
      throughput(replicas, body, jobs, poll_ms, clients, 0, wait_s);
    }
    if (commandstats) {  // where redis-server's time went, per command (microseconds per call)
      std::string stats = redis.cli("INFO commandstats");
      std::printf("%s", stats.c_str());
    }
    if (!one.empty()) ratios.push_back(three.back() / one.back());
    if (rounds > 1 && !one.empty())
      std::printf("  round %d: %.2f vs %.2f jobs/s, ratio %.2f\n", round + 1, one.back(), three.back(), ratios.back());
  }
  if (!one.empty())
    std::printf("throughput (%d jobs, %d clients %s %d %s, median of %d): 1 replica x 2 workers (memory) %.2f jobs/s, 3 replicas x %d "
                "worker(s) (redis) %.2f jobs/s, ratio of medians %.2f, median of per-round ratios %.2f (target >= 1)\n",
                jobs, clients, wait_s > 0 ? "long-polling, wait" : "polling every", wait_s > 0 ? wait_s : poll_ms,
                wait_s > 0 ? "s" : "ms", rounds, median(one), redis_workers, median(three), median(three) / median(one),
                median(ratios));
  return 0;
}
