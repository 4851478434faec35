// Reproduces the Fandisk row of Table 1 (MSAE, E_v) and Table 2's timings of Lu, Chen,
// Schaefer, and measures the implementation's own choices (threads, linear solver) and its
// behaviour on a ~1M-face mesh. Prints tables; asserts nothing (never part of ctest).
//
//   table1_bench [--data DIR] [--seeds N] [--runs N] [--scale] [--no-table] [--no-timing]
//
// DIR holds CGAL's demo data (DIR/data/meshes/fandisk.off); default $MDN_CGAL_DATA, else
// <source>/third_party_data/cgal. If the mesh is missing, scripts/fetch-cgal-data.sh DIR
// is run first. Compare figures only within one run on one machine.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cgal_data.h"
#include "subdivide.h"
#include "core/io/document.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/params.h"
#include "core/parallel.h"
#include "core/auto/denoise.h"
#include "core/smoothing.h"
#include "core/topology.h"

namespace fs = std::filesystem;
using namespace mdn;

namespace {

// The paper's figures (Table 1 Fandisk row, sigma = 0.2 l per Figure 10; Table 2, i7-3770).
constexpr double kPaperMsae = 0.337;  // x 1e-2
constexpr double kPaperEv = 8.974;    // x 1e-3, frame unstated
constexpr double kPaperPrefilterS = 0.399, kPaperNormalS = 0.342, kPaperVertexS = 0.018, kPaperTotalS = 0.759;

struct Options {
  fs::path data;
  int seeds = 5;
  int runs = 11;
  bool scale = false;
  bool table = true;
  bool timing = true;
};

[[noreturn]] void usage(const char* argv0, int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: %s [--data DIR] [--seeds N] [--runs N] [--scale] [--no-table] [--no-timing]\n"
               "  --data DIR   CGAL demo data (DIR/data/meshes/fandisk.off); default $MDN_CGAL_DATA or\n"
               "               <source>/third_party_data/cgal, fetched by scripts/fetch-cgal-data.sh if absent\n"
               "  --seeds N    noise seeds per Table 1 cell (default 5)\n"
               "  --runs N     runs per timing configuration, median reported (default 11)\n"
               "  --scale      also run the ~1M-face section (fandisk subdivided 3 times)\n",
               argv0);
  std::exit(code);
}

Options parse(int argc, char** argv) {
  Options o;
  if (const char* env = std::getenv("MDN_CGAL_DATA")) o.data = env;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(argv[0], 2);
      return argv[++i];
    };
    auto count = [&]() {
      const std::string v = value();
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || n < 1 || n > 1000) usage(argv[0], 2);
      return static_cast<int>(n);
    };
    if (a == "--data") o.data = value();
    else if (a == "--seeds") o.seeds = count();
    else if (a == "--runs") o.runs = count();
    else if (a == "--scale") o.scale = true;
    else if (a == "--no-table") o.table = false;
    else if (a == "--no-timing") o.timing = false;
    else if (a == "--help" || a == "-h") usage(argv[0], 0);
    else usage(argv[0], 2);
  }
  if (o.data.empty()) o.data = bench::default_cgal_data();
  return o;
}

TriMesh load_fandisk(const fs::path& dir) {
  const fs::path path = bench::cgal_meshes(dir) / "fandisk.off";
  TriMesh mesh = bench::load_off(path);
  std::printf("mesh: %s (%lld vertices, %lld faces)\n", path.c_str(), static_cast<long long>(mesh.num_vertices()),
              static_cast<long long>(mesh.num_faces()));
  return mesh;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}
double stddev(const std::vector<double>& v) {
  if (v.size() < 2) return 0;
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}
double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// ---------------------------------------------------------------------------------------
// Table 1 (Fandisk row) across noise levels and conventions, with a Laplacian floor.

void table_section(const TriMesh& truth, const Options& o) {
  const std::vector<double> sigmas = {0.1, 0.2, 0.3, 0.5};
  const std::vector<int> lap_sweep = {1, 2, 3, 5, 8, 12, 20, 30, 50};
  const Topology topo = Topology::build(truth.F, static_cast<std::int32_t>(truth.num_vertices()));
  const DenoiseParams params;  // Table 1 Fandisk row: (0.1, 30, 2, 30, 20, 10)

  std::printf("\n== Table 1, Fandisk: MSAE (x1e-2) and E_v (x1e-3, ground truth's unit box) ==\n");
  std::printf("DenoiseParams defaults (alpha %.2f, sigma_theta %.0f, n_aniso %d, sigma_gamma %.0f, n_normal %d, "
              "n_vertex %d), region_mode %s, solver %s, threads 1, %d seeds per row (mean +- sd; times: median)\n",
              params.alpha, params.sigma_theta, params.n_aniso, params.sigma_gamma, params.n_normal, params.n_vertex,
              std::string(to_string(params.region_mode)).c_str(), std::string(to_string(params.solver)).c_str(), o.seeds);
  std::printf("paper (sigma = 0.2 l, Figure 10; noise convention unstated): MSAE %.3f, E_v %.3f (frame unstated); "
              "Table 2 (i7-3770): pre-filter %.3f s, normal %.3f s, vertex %.3f s, total %.3f s\n",
              kPaperMsae, kPaperEv, kPaperPrefilterS, kPaperNormalS, kPaperVertexS, kPaperTotalS);
  std::printf("%-15s %5s | %7s %7s | %14s %13s %6s | %6s %7s %7s | %8s %8s %8s %8s\n", "noise", "sigma", "in MSAE",
              "in E_v", "MSAE", "E_v", "region", "lap it", "lapMSAE", "lap E_v", "pre ms", "normal", "vertex",
              "total");

  for (const NoiseKind kind : {NoiseKind::AlongNormal, NoiseKind::PerCoordinate}) {
    for (const double sigma : sigmas) {
      std::vector<double> in_msae, in_ev, out_msae, out_ev, pre, nrm, vtx, tot;
      std::vector<std::vector<double>> lap_msae(lap_sweep.size()), lap_ev(lap_sweep.size());
      int region = 0;
      for (int seed = 1; seed <= o.seeds; ++seed) {
        const TriMesh noisy{add_noise(truth, {kind, sigma, static_cast<std::uint64_t>(seed), 0}), truth.F};
        in_msae.push_back(msae(noisy, truth) * 1e2);
        in_ev.push_back(vertex_error(noisy, truth) * 1e3);

        const DenoiseResult r = denoise(noisy, params, {1, nullptr});
        out_msae.push_back(msae(r.mesh, truth) * 1e2);
        out_ev.push_back(vertex_error(r.mesh, truth) * 1e3);
        region += r.report.region_prefilter_applied ? 1 : 0;
        pre.push_back(r.report.timings.prefilter_ms());
        nrm.push_back(r.report.timings.normal_ms);
        vtx.push_back(r.report.timings.vertex_ms);
        tot.push_back(r.report.timings.total_ms);

        // Laplacian floor: explicit steps compose, so the sweep continues from the last count.
        TriMesh lap = noisy;
        int done = 0;
        for (std::size_t k = 0; k < lap_sweep.size(); ++k) {
          lap.V = laplacian_smoothing(lap.V, topo, lap_sweep[k] - done);
          done = lap_sweep[k];
          lap_msae[k].push_back(msae(lap, truth) * 1e2);
          lap_ev[k].push_back(vertex_error(lap, truth) * 1e3);
        }
      }
      std::size_t best = 0;
      for (std::size_t k = 1; k < lap_sweep.size(); ++k)
        if (mean(lap_msae[k]) < mean(lap_msae[best])) best = k;
      std::printf("%-15s %5.2f | %7.3f %7.3f | %6.3f +- %5.3f %5.3f +- %5.3f %3d/%-2d | %6d %7.3f %7.3f | %8.1f %8.1f %8.1f %8.1f\n",
                  std::string(to_string(kind)).c_str(), sigma, mean(in_msae), mean(in_ev), mean(out_msae),
                  stddev(out_msae), mean(out_ev), stddev(out_ev), region, o.seeds, lap_sweep[best],
                  mean(lap_msae[best]), mean(lap_ev[best]), median(pre), median(nrm), median(vtx), median(tot));
      std::fflush(stdout);
    }
  }
  std::printf("(in = the noisy input; region = seeds where the Sec. 4.2 region pre-filter ran; lap = uniform Laplacian,\n"
              " lambda 0.5, best iteration count of {1,2,3,5,8,12,20,30,50} by mean MSAE)\n");
}

// ---------------------------------------------------------------------------------------
// Timing: threads and linear solver, median of o.runs full runs each (round-robin order so
// that drift of a shared machine hits every configuration alike).

void timing_section(const TriMesh& truth, const Options& o) {
  const TriMesh noisy{add_noise(truth, {NoiseKind::AlongNormal, 0.2, 1, 0}), truth.F};
  struct Config {
    const char* name;
    int threads;
    LinearSolver solver;
    std::vector<StageTimings> times;
    TriMesh last;
  };
  std::vector<Config> configs = {{"ldlt, 1 thread", 1, LinearSolver::Ldlt, {}, {}},
                                 {"ldlt, 2 threads", 2, LinearSolver::Ldlt, {}, {}},
                                 {"cg, 1 thread", 1, LinearSolver::ConjugateGradient, {}, {}},
                                 {"cg, 2 threads", 2, LinearSolver::ConjugateGradient, {}, {}}};
  std::printf("\n== Timing, Fandisk, along_normal sigma 0.2 seed 1: median of %d runs (ms) ==\n", o.runs);
  for (int run = -1; run < o.runs; ++run) {  // run -1: warm-up, not recorded
    for (Config& c : configs) {
      DenoiseParams p;
      p.solver = c.solver;
      DenoiseResult r = denoise(noisy, p, {c.threads, nullptr});
      if (run >= 0) c.times.push_back(r.report.timings);
      c.last = std::move(r.mesh);
    }
  }
  std::printf("%-16s %7s %8s %7s %8s %8s %8s %8s %8s | %8s %8s\n", "config", "setup", "initial", "region", "aniso",
              "pre", "normal", "vertex", "total", "MSAE", "E_v");
  for (const Config& c : configs) {
    auto med = [&](const std::function<double(const StageTimings&)>& get) {
      std::vector<double> v;
      for (const StageTimings& t : c.times) v.push_back(get(t));
      return median(v);
    };
    std::printf("%-16s %7.1f %8.1f %7.1f %8.1f %8.1f %8.1f %8.1f %8.1f | %8.4f %8.4f\n", c.name,
                med([](const StageTimings& t) { return t.setup_ms; }),
                med([](const StageTimings& t) { return t.initial_ms; }),
                med([](const StageTimings& t) { return t.region_ms; }),
                med([](const StageTimings& t) { return t.anisotropic_ms; }),
                med([](const StageTimings& t) { return t.prefilter_ms(); }),
                med([](const StageTimings& t) { return t.normal_ms; }),
                med([](const StageTimings& t) { return t.vertex_ms; }),
                med([](const StageTimings& t) { return t.total_ms; }), msae(c.last, truth) * 1e2,
                vertex_error(c.last, truth) * 1e3);
  }
  const double thread_diff = (configs[0].last.V - configs[1].last.V).cwiseAbs().maxCoeff();
  const double solver_diff = (configs[0].last.V - configs[2].last.V).cwiseAbs().maxCoeff();
  std::printf("max |vertex difference|: 1 vs 2 threads %.3g, ldlt vs cg %.3g (input frame; bounding box side %.3g)\n",
              thread_diff, solver_diff, (truth.V.colwise().maxCoeff() - truth.V.colwise().minCoeff()).maxCoeff());
  std::printf("paper Table 2 (i7-3770, one run): pre-filter %.0f, normal %.0f, vertex %.0f, total %.0f ms\n",
              kPaperPrefilterS * 1e3, kPaperNormalS * 1e3, kPaperVertexS * 1e3, kPaperTotalS * 1e3);
}

// ---------------------------------------------------------------------------------------
// Scale: fandisk subdivided three times (~828k faces), one run, time and peak memory.

void scale_section(const TriMesh& fandisk) {
  std::printf("\n== Scale: fandisk, 1-to-4 midpoint subdivision x3, along_normal sigma 0.2 seed 1 ==\n");
  std::printf("peak RSS before: %.1f MiB\n", peak_rss_mib());
  auto t0 = std::chrono::steady_clock::now();
  TriMesh truth = fandisk;
  for (int level = 0; level < 3; ++level) truth = bench::midpoint_subdivide(truth);
  const TriMesh noisy{add_noise(truth, {NoiseKind::AlongNormal, 0.2, 1, 0}), truth.F};
  std::printf("mesh: %lld vertices, %lld faces (built in %.2f s)\n", static_cast<long long>(truth.num_vertices()),
              static_cast<long long>(truth.num_faces()), seconds_since(t0));
  std::fflush(stdout);
  for (const int threads : {2}) {
    const DenoiseResult r = denoise(noisy, DenoiseParams{}, {threads, nullptr});
    const StageTimings& t = r.report.timings;
    std::printf("denoise, %d threads: setup %.2f s, pre-filter %.2f s (initial %.2f, region %.2f, aniso %.2f), "
                "normal %.2f s, vertex %.2f s, total %.2f s; region pre-filter %s\n",
                threads, t.setup_ms / 1e3, t.prefilter_ms() / 1e3, t.initial_ms / 1e3, t.region_ms / 1e3,
                t.anisotropic_ms / 1e3, t.normal_ms / 1e3, t.vertex_ms / 1e3, t.total_ms / 1e3,
                r.report.region_prefilter_applied ? "applied" : "not applied");
    std::printf("peak RSS after denoise: %.1f MiB\n", peak_rss_mib());
    std::fflush(stdout);
    t0 = std::chrono::steady_clock::now();
    const double m = msae(r.mesh, truth);
    Executor executor(threads);
    const double ev = vertex_error(r.mesh, truth, &executor);
    std::printf("MSAE %.4f x1e-2 (input %.4f), E_v %.4f x1e-3; metrics took %.2f s (AABB tree over %lld faces)\n",
                m * 1e2, msae(noisy, truth) * 1e2, ev * 1e3, seconds_since(t0),
                static_cast<long long>(truth.num_faces()));
  }
  std::printf("peak RSS at end: %.1f MiB\n", peak_rss_mib());
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);  // timings on a shared machine mean little without it
  std::printf("machine: %u hardware threads, load average %.2f %.2f %.2f\n", std::thread::hardware_concurrency(),
              load[0], load[1], load[2]);
  try {
    const TriMesh fandisk = load_fandisk(o.data);
    if (o.table) table_section(fandisk, o);
    if (o.timing) timing_section(fandisk, o);
    if (o.scale) scale_section(fandisk);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "table1_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
