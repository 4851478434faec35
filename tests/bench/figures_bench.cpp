// The data behind the pictures in docs/figures/ (scripts/make-figures.sh runs it and plots its
// rows): tab-separated rows on stdout, one per measurement, with a header line. Real runs of the
// core pipeline, as the CLI and the server run it; asserts nothing (never part of ctest).
//
//   figures_bench msae [--data DIR] [--meshes fandisk,bunny00] [--sigmas 0.1,0.2,...] [--seeds N] [--threads N]
//     columns: mesh faces sigma seed method msae ev seconds
//     methods: noisy (the input); auto (ParamMode::Auto, the default of the CLI and the service);
//     paper (ParamMode::Manual: Table 1's Fandisk row); laplacian (the one classic filter the
//     benches have: uniform Laplacian smoothing, lambda 0.5, with the iteration count of
//     {1, 2, 3, 5, 8, 12, 20, 30, 50} that gives the lowest MSAE against the ground truth, so an
//     oracle's pick: the best this filter can do).
//   figures_bench time [--data DIR] [--meshes fandisk] [--levels 0,1,2] [--threads N] [--runs N]
//     columns: mesh level faces method threads seconds (median of --runs; auto and paper as above)
//
// Noise: along the vertex normal, sigma in multiples of the mean edge length (core/noise.h), the
// paper's Figure 10 convention. DIR as table1_bench (CGAL's demo data, fetched if absent).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "cgal_data.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/params.h"
#include "core/auto/denoise.h"
#include "core/smoothing.h"
#include "core/topology.h"
#include "subdivide.h"

using namespace mdn;

namespace {

struct Options {
  std::string what;
  std::filesystem::path data;
  std::vector<std::string> meshes;
  std::vector<double> sigmas = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  std::vector<int> levels = {0, 1, 2};
  int seeds = 2;
  int threads = 1;
  int runs = 3;
};

[[noreturn]] void usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: figures_bench msae [--data DIR] [--meshes a,b] [--sigmas s,...] [--seeds N] [--threads N]\n"
               "       figures_bench time [--data DIR] [--meshes a] [--levels 0,1,2] [--threads N] [--runs N]\n");
  std::exit(code);
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  if (argc < 2) usage(2);
  o.what = argv[1];
  if (o.what == "--help" || o.what == "-h") usage(0);
  if (o.what != "msae" && o.what != "time") usage(2);
  o.meshes = o.what == "msae" ? std::vector<std::string>{"fandisk", "bunny00"} : std::vector<std::string>{"fandisk"};
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(2);
      return argv[++i];
    };
    auto count = [&](int lo, int hi) {
      const std::string v = value();
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || n < lo || n > hi) usage(2);
      return static_cast<int>(n);
    };
    if (a == "--data") o.data = value();
    else if (a == "--meshes") o.meshes = split(value());
    else if (a == "--sigmas") {
      o.sigmas.clear();
      for (const auto& s : split(value())) o.sigmas.push_back(std::atof(s.c_str()));
    } else if (a == "--levels") {
      o.levels.clear();
      for (const auto& s : split(value())) o.levels.push_back(std::atoi(s.c_str()));
    } else if (a == "--seeds") o.seeds = count(1, 100);
    else if (a == "--threads") o.threads = count(1, 256);
    else if (a == "--runs") o.runs = count(1, 100);
    else usage(2);
  }
  if (o.data.empty()) o.data = bench::default_cgal_data();
  return o;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

DenoiseParams params_for(const std::string& method) {
  DenoiseParams p;  // Table 1's Fandisk row, ParamMode::Manual
  if (method == "auto") p.mode = ParamMode::Auto;
  return p;
}

void msae_rows(const Options& o) {
  const std::vector<int> sweep = {1, 2, 3, 5, 8, 12, 20, 30, 50};
  std::printf("mesh\tfaces\tsigma\tseed\tmethod\tmsae\tev\tseconds\n");
  for (const std::string& name : o.meshes) {
    const TriMesh truth = bench::load_off(bench::cgal_meshes(o.data) / (name + ".off"));
    const Topology topo = Topology::build(truth.F, static_cast<std::int32_t>(truth.num_vertices()));
    auto row = [&](double sigma, int seed, const char* method, const TriMesh& mesh, double seconds) {
      std::printf("%s\t%lld\t%g\t%d\t%s\t%.6g\t%.6g\t%.4f\n", name.c_str(), static_cast<long long>(truth.num_faces()),
                  sigma, seed, method, msae(mesh, truth), vertex_error(mesh, truth), seconds);
      std::fflush(stdout);
    };
    for (const double sigma : o.sigmas) {
      for (int seed = 1; seed <= o.seeds; ++seed) {
        const TriMesh noisy{add_noise(truth, {NoiseKind::AlongNormal, sigma, static_cast<std::uint64_t>(seed), 0}), truth.F};
        row(sigma, seed, "noisy", noisy, 0);
        for (const char* method : {"auto", "paper"}) {
          const auto t0 = std::chrono::steady_clock::now();
          const DenoiseResult r = denoise(noisy, params_for(method), {o.threads, nullptr});
          row(sigma, seed, method, r.mesh, seconds_since(t0));
        }
        // Explicit steps compose: the sweep continues from the last count.
        TriMesh lap = noisy, best = noisy;
        double best_msae = -1, best_s = 0, elapsed = 0;
        int done = 0;
        for (const int n : sweep) {
          const auto t0 = std::chrono::steady_clock::now();
          lap.V = laplacian_smoothing(lap.V, topo, n - done);
          elapsed += seconds_since(t0);
          done = n;
          const double m = msae(lap, truth);
          if (best_msae < 0 || m < best_msae) {
            best_msae = m;
            best = lap;
            best_s = elapsed;
          }
        }
        row(sigma, seed, "laplacian", best, best_s);
      }
    }
  }
}

void time_rows(const Options& o) {
  std::printf("mesh\tlevel\tfaces\tmethod\tthreads\tseconds\n");
  for (const std::string& name : o.meshes) {
    TriMesh truth = bench::load_off(bench::cgal_meshes(o.data) / (name + ".off"));
    int level = 0;
    for (const int target : o.levels) {
      for (; level < target; ++level) truth = bench::midpoint_subdivide(truth);
      const TriMesh noisy{add_noise(truth, {NoiseKind::AlongNormal, 0.3, 1, 0}), truth.F};
      for (const char* method : {"auto", "paper"}) {
        std::vector<double> times;
        for (int run = 0; run < o.runs; ++run) {
          const auto t0 = std::chrono::steady_clock::now();
          (void)denoise(noisy, params_for(method), {o.threads, nullptr});
          times.push_back(seconds_since(t0));
        }
        std::sort(times.begin(), times.end());
        std::printf("%s\t%d\t%lld\t%s\t%d\t%.4f\n", name.c_str(), target, static_cast<long long>(truth.num_faces()), method,
                    o.threads, times[times.size() / 2]);
        std::fflush(stdout);
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  try {
    if (o.what == "msae") msae_rows(o);
    else time_rows(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "figures_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
