// Benchmark of meshdenoise-server's overhead and worker scaling (issue 4's targets). Prints
// figures, asserts nothing; compare numbers only within one run on one machine.
//
//   http_bench [--data DIR] [--runs N] [--jobs N]
//
// 1. Overhead: median latency of POST /v1/denoise with a Draco-compressed noisy Fandisk .glb
//    against the median in-process run_job time for the same bytes and parameters
//    (target: ratio <= 1.3).
// 2. Throughput: jobs per second with 1 worker and with 2 workers, 8 concurrent clients
//    (target on a 2-core machine: 2 workers >= 1.8x 1 worker).
// The server runs in-process (mdn::http::HttpService) on a loopback port and is reached over
// real HTTP with cpp-httplib's client, so the figures include parsing, queueing and transfer.
// DIR holds CGAL's demo data (DIR/data/meshes/fandisk.off); default $MDN_CGAL_DATA, else
// <source>/third_party_data/cgal (scripts/fetch-cgal-data.sh fetches it).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/io/document.h"
#include "core/noise.h"
#include "server/http/http_server.h"
#include "server/service_parts.h"
#include "bench_stats.h"
#include "service/job_runner.h"

// After Eigen: <httplib.h> pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace {

namespace fs = std::filesystem;
using mdn::bench::Clock;

using mdn::bench::median;
using mdn::bench::ms_since;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The noisy Fandisk as a Draco-compressed GLB (noise: along the normal, 0.2 x mean edge, seed 1).
std::string noisy_fandisk_glb(const fs::path& data) {
  fs::path off;
  for (const fs::path& p : {data / "data" / "meshes" / "fandisk.off", data / "meshes" / "fandisk.off", data / "fandisk.off"})
    if (fs::exists(p)) off = p;
  if (off.empty()) {
    const std::string cmd = "bash '" + (fs::path(MDN_SOURCE_DIR) / "scripts" / "fetch-cgal-data.sh").string() + "' '" +
                            data.string() + "'";
    std::printf("fandisk.off not found under %s; running %s\n", data.c_str(), cmd.c_str());
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("fetch-cgal-data.sh failed");
    off = data / "data" / "meshes" / "fandisk.off";
  }
  auto doc = mdn::io::decode(read_file(off), mdn::io::Format::Off);
  mdn::TriMesh& mesh = doc->surfaces().at(0);
  mdn::NoiseSpec noise;
  mesh.V = mdn::add_noise(mesh, noise);
  mdn::io::EncodeOptions options;
  options.format = mdn::io::Format::Glb;
  options.compression = mdn::io::Compression::Draco;
  return doc->encode(options).bytes;
}

struct Server {
  explicit Server(int workers) {
    mdn::http::ServerConfig config;
    config.port = 0;
    config.workers = workers;
    config.queue_capacity = 1000;
    config.log_level = "off";
    auto log = std::make_shared<const mdn::http::EventLog>(config);
    service = std::make_unique<mdn::http::HttpService>(config, log, mdn::http::make_service_parts(config, log));
    port = service->bind();
    thread = std::thread([this] { service->serve(); });
  }
  ~Server() {
    service->stop();
    thread.join();
  }
  std::unique_ptr<mdn::http::HttpService> service;
  int port = 0;
  std::thread thread;
};

// Jobs per second with `workers` workers: 8 clients, `jobs` synchronous requests in all.
double throughput(int workers, const std::string& glb, int jobs) {
  Server server(workers);
  std::atomic<int> next{0}, failed{0};
  const auto start = Clock::now();
  std::vector<std::thread> clients;
  for (int k = 0; k < 8; ++k) {
    clients.emplace_back([&] {
      httplib::Client c("127.0.0.1", server.port);
      c.set_read_timeout(600, 0);
      while (next.fetch_add(1) < jobs) {
        auto r = c.Post("/v1/denoise", glb, "model/gltf-binary");
        if (!r || r->status != 200) ++failed;
      }
    });
  }
  for (auto& t : clients) t.join();
  const double seconds = ms_since(start) / 1000;
  if (failed) std::printf("  (%d requests failed)\n", failed.load());
  return jobs / seconds;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path data = std::getenv("MDN_CGAL_DATA") ? fs::path(std::getenv("MDN_CGAL_DATA"))
                                                : fs::path(MDN_SOURCE_DIR) / "third_party_data" / "cgal";
  int runs = 15, jobs = 24;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--jobs" && i + 1 < argc) jobs = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--data DIR] [--runs N] [--jobs N]\n", argv[0]);
      return 2;
    }
  }
  const std::string glb = noisy_fandisk_glb(data);
  std::printf("input: noisy Fandisk, Draco GLB, %zu bytes; %u hardware threads\n", glb.size(),
              std::thread::hardware_concurrency());

  // 1. In-process pipeline (decode + denoise + encode) vs one synchronous HTTP request.
  mdn::service::JobInput input{glb, mdn::io::Format::Glb, {}, 1, std::nullopt};
  std::vector<double> direct, http;
  mdn::service::run_job(input, {});  // warm-up
  for (int i = 0; i < runs; ++i) {
    const auto t = Clock::now();
    mdn::service::run_job(input, {});
    direct.push_back(ms_since(t));
  }
  {
    Server server(1);
    httplib::Client c("127.0.0.1", server.port);
    c.set_read_timeout(600, 0);
    c.Post("/v1/denoise", glb, "model/gltf-binary");  // warm-up
    for (int i = 0; i < runs; ++i) {
      const auto t = Clock::now();
      auto r = c.Post("/v1/denoise", glb, "model/gltf-binary");
      http.push_back(ms_since(t));
      if (!r || r->status != 200) std::printf("  request failed: %d\n", r ? r->status : -1);
    }
  }
  const double d = median(direct), h = median(http);
  std::printf("overhead: in-process run_job median %.1f ms, POST /v1/denoise median %.1f ms, ratio %.3f (target <= 1.3)\n",
              d, h, h / d);

  // 2. Worker scaling.
  const double one = throughput(1, glb, jobs), two = throughput(2, glb, jobs);
  std::printf("throughput: 1 worker %.2f jobs/s, 2 workers %.2f jobs/s, speed-up %.2fx (target >= 1.8x)\n", one, two,
              two / one);
  return 0;
}
