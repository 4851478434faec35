// Cost per face from ten thousand to five million faces: denoise() on CGAL meshes subdivided
// 1-to-4 and given
// along-normal noise 0.2 l (seed 1), with the automatic choice and fixed parameter sets. Prints
// one row per run: per-stage ns per face per iteration, whole-run time, peak RSS and MSAE.
// Asserts nothing (never part of ctest). Compare figures only within one run on one machine.
//
//   scale_bench [--data DIR] [--meshes LIST] [--params LIST] [--threads LIST] [--order LIST] [--runs N] [--cg]
//
//   --meshes LIST   comma-separated NAME:LEVELS (a CGAL demo mesh, subdivided LEVELS times);
//                   default fandisk:0,bunny00:0,bunny00:2 (13k, 75k, 1.2M faces)
//   --big           also bunny00:3 (4.8M faces; minutes per run on two cores), or MDN_SCALE_BIG=1
//   --params LIST   auto (ParamMode::Auto, the CLI's and the service's default), heavy (issue 36's
//                   fixed heavy set: the paper's row with n_aniso 16, n_normal 100, n_vertex 30),
//                   paper (DenoiseParams{}, Table 1's Fandisk row) and/or cad (the heavy CAD
//                   prototype: alpha 0.06, sigma_theta 70, n_aniso 2, sigma_gamma 60,
//                   n_normal 100, n_vertex 80); default auto,heavy. "auto" also runs its choice
//                   as manual parameters (the "pick" row) and prints how much of the run choosing
//                   took and auto's time over the pick's; every per-iteration column divides by
//                   the iteration counts that ran (auto: the chosen ones)
//   --threads LIST  default 2
//   --order LIST    RunOptions::order: auto (the default), input, curve and/or bfs (decision 16)
//   --runs N        runs per configuration, round-robin over the configurations of a mesh;
//                   medians printed (default 3)
//   --cg            also print the pre-filter's CG iteration counts (Eq. 1 and each Eq. 3 step)
//   --jitter EPS    displace the noisy input once more along the normals by N(0, (EPS l)^2)
//                   (seed 2): how far MSAE moves under a perturbation far below the noise
//   --allocator cli|glibc  how the child allocates: as meshdenoise does (decision 52: freed
//                   memory kept for the next stage; the default) or with glibc's defaults (as
//                   the server does)
//
// Each run is a forked child that holds only the noisy input, so its peak RSS (VmHWM, reset
// through /proc/self/clear_refs before denoise()) is that of a process that read the mesh and
// denoises it: input, every internal array and the output. The child shares the parent's
// resident pages, so the figure also carries the parent's heap (printed: RSS at start).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "bench_stats.h"
#include "cgal_data.h"
#include "core/metrics.h"
#include "core/noise.h"
#include "core/parallel.h"
#include "core/auto/denoise.h"
#include "core/prefilter.h"
#include "core/topology.h"
#include "service/process_memory.h"
#include "subdivide.h"

namespace fs = std::filesystem;
using namespace mdn;

namespace {

struct Options {
  fs::path data;
  std::vector<std::pair<std::string, int>> meshes = {{"fandisk", 0}, {"bunny00", 0}, {"bunny00", 2}};
  std::vector<std::string> params = {"auto", "heavy"};
  std::vector<int> threads = {2};
  std::vector<std::string> orders = {"auto"};
  int runs = 3;
  bool cg = false;
  double jitter = 0;
  bool keep_freed_memory = true;  // --allocator cli (decision 52)
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

[[noreturn]] void usage(const char* argv0, int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: %s [--data DIR] [--meshes NAME:LEVELS,...] [--big] [--params auto,heavy,paper,cad] [--threads 1,2]\n"
               "          [--order auto,input,curve,bfs] [--runs N] [--cg] [--jitter EPS] [--allocator cli|glibc]\n",
               argv0);
  std::exit(code);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(argv[0], 2);
      return argv[++i];
    };
    if (a == "--data") {
      o.data = value();
    } else if (a == "--meshes") {
      o.meshes.clear();
      for (const std::string& m : split(value())) {
        const auto colon = m.find(':');
        o.meshes.emplace_back(m.substr(0, colon), colon == std::string::npos ? 0 : std::stoi(m.substr(colon + 1)));
      }
    } else if (a == "--params") {
      o.params = split(value());
      for (const std::string& p : o.params)
        if (p != "paper" && p != "cad" && p != "auto" && p != "heavy") usage(argv[0], 2);
    } else if (a == "--threads") {
      o.threads.clear();
      for (const std::string& t : split(value())) o.threads.push_back(std::max(1, std::stoi(t)));
    } else if (a == "--order") {
      o.orders = split(value());
      for (const std::string& k : o.orders)
        if (k != "auto" && k != "input" && k != "curve" && k != "bfs") usage(argv[0], 2);
    } else if (a == "--big") {
      o.meshes.emplace_back("bunny00", 3);
    } else if (a == "--runs") {
      o.runs = std::max(1, std::stoi(value()));
    } else if (a == "--jitter") {
      o.jitter = std::stod(value());
    } else if (a == "--allocator") {
      const std::string kind = value();
      if (kind != "cli" && kind != "glibc") usage(argv[0], 2);
      o.keep_freed_memory = kind == "cli";
    } else if (a == "--cg") {
      o.cg = true;
    } else if (a == "--help" || a == "-h") {
      usage(argv[0], 0);
    } else {
      usage(argv[0], 2);
    }
  }
  if (o.data.empty()) o.data = bench::default_cgal_data();
  if (const char* big = std::getenv("MDN_SCALE_BIG"); big && std::string(big) == "1") o.meshes.emplace_back("bunny00", 3);
  return o;
}

// "paper": DenoiseParams{} (Table 1's Fandisk row: 0.1, 30, 2, 30, 20, 10); "cad": the heavy
// CAD prototype. Manual either way.
DenoiseParams params_named(const std::string& name) {
  if (name == "auto") return {.mode = ParamMode::Auto};  // the default of the CLI and the service
  if (name == "heavy") return {.mode = ParamMode::Manual, .n_aniso = 16, .n_normal = 100, .n_vertex = 30};
  if (name == "cad")
    return {.mode = ParamMode::Manual, .alpha = 0.06, .sigma_theta = 70, .n_aniso = 2, .sigma_gamma = 60,
            .n_normal = 100, .n_vertex = 80};
  return {.mode = ParamMode::Manual};
}

// VmHWM / VmRSS of this process in MiB (Linux).
double proc_status_mib(const char* key) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key, 0) == 0) return std::strtod(line.c_str() + std::strlen(key), nullptr) / 1024.0;
  return 0;
}

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// Process CPU time (all threads) at the stage boundaries the progress callbacks mark. On a
// shared machine a run's wall time counts the time it waited for a core; its CPU time does not.
// pre: Eq. 1 to the first normal-filter iteration (Eq. 1, Sec. 4.2, Eq. 3-4 and the normal
// filter's set-up); normal and vertex: their iterations only.
class CpuClock : public ProgressObserver {
 public:
  void on_progress(Stage stage, double fraction) override {
    const double now = cpu_seconds();
    if (stage == Stage::InitialPrefilter && pre0 < 0) pre0 = now;
    if (stage == Stage::NormalFilter && normal0 < 0) normal0 = now;
    if (stage == Stage::NormalFilter && fraction == 1.0) normal1 = now;
    if (stage == Stage::VertexUpdate && vertex0 < 0) vertex0 = now;
    if (stage == Stage::VertexUpdate && fraction == 1.0) vertex1 = now;
  }
  double pre0 = -1, normal0 = -1, normal1 = -1, vertex0 = -1, vertex1 = -1;
};

struct RunFigures {
  StageTimings t;
  double cpu_pre_s = 0, cpu_normal_s = 0, cpu_vertex_s = 0;
  double rss_before_mib = 0, peak_mib = 0;
  double cpu_s = 0;  // user + system CPU time of denoise(), all threads
  DenoiseParams params;  // the parameters that ran (auto: its choice, as manual parameters)
  bool peak_reset = false;
};
static_assert(std::is_trivially_copyable_v<RunFigures>, "sent through a pipe as bytes");

// Runs denoise() in a forked child that drops everything but the noisy input; the child sends
// back its figures and the output positions.
RunFigures run_child(std::unique_ptr<TriMesh>& truth, std::unique_ptr<TriMesh>& noisy, const DenoiseParams& params,
                     const RunOptions& options, bool keep_freed_memory, Vertices& output) {
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) throw std::runtime_error("pipe failed");
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    close(pipe_fd[0]);
    truth.reset();  // unmapped in the child only: its RSS is the noisy input's
    if (keep_freed_memory) service::keep_freed_memory();
    RunFigures fig;
    fig.rss_before_mib = proc_status_mib("VmRSS:");
    {
      std::ofstream clear("/proc/self/clear_refs");
      clear << "5";  // resets VmHWM to the current RSS
      clear.flush();
      fig.peak_reset = static_cast<bool>(clear);
    }
    CpuClock clock;
    RunOptions timed = options;
    timed.progress = &clock;
    const double cpu0 = cpu_seconds();
    DenoiseResult r = denoise(*noisy, params, timed);
    fig.cpu_s = cpu_seconds() - cpu0;
    fig.cpu_pre_s = clock.normal0 - clock.pre0;
    fig.cpu_normal_s = clock.normal1 - clock.normal0;
    fig.cpu_vertex_s = clock.vertex1 - clock.vertex0;
    fig.peak_mib = proc_status_mib("VmHWM:");
    fig.t = r.report.timings;
    fig.params = r.report.params;
    fig.params.mode = ParamMode::Manual;
    fig.params.pinned = 0;
    auto write_all = [&](const void* data, std::size_t bytes) {
      const char* p = static_cast<const char*>(data);
      while (bytes > 0) {
        const ssize_t n = write(pipe_fd[1], p, bytes);
        if (n <= 0) _exit(3);
        p += n;
        bytes -= static_cast<std::size_t>(n);
      }
    };
    write_all(&fig, sizeof fig);
    write_all(r.mesh.V.data(), sizeof(double) * static_cast<std::size_t>(r.mesh.V.size()));
    close(pipe_fd[1]);
    _exit(0);
  }
  close(pipe_fd[1]);
  RunFigures fig;
  output.resize(noisy->V.rows(), 3);
  auto read_all = [&](void* data, std::size_t bytes) {
    char* p = static_cast<char*>(data);
    while (bytes > 0) {
      const ssize_t n = read(pipe_fd[0], p, bytes);
      if (n <= 0) throw std::runtime_error("the benchmark's child process failed");
      p += n;
      bytes -= static_cast<std::size_t>(n);
    }
  };
  read_all(&fig, sizeof fig);
  read_all(output.data(), sizeof(double) * static_cast<std::size_t>(output.size()));
  close(pipe_fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error("the benchmark's child process failed");
  return fig;
}

// CG iteration counts of the pre-filter (Eq. 1, then each Eq. 3 step) at this size.
void cg_section(const TriMesh& noisy, const DenoiseParams& params, const RunOptions& options) {
  const UnitBox box = UnitBox::of(noisy.V);
  const LocalityOrder order = LocalityOrder::of(noisy, options.order);  // as denoise() does
  const Vertices P0 = box.apply(order.to_order(noisy.V));
  const Topology topo = Topology::build(order.faces(), static_cast<std::int32_t>(P0.rows()));
  const int threads = options.threads;
  Executor executor(threads);
  ShapingSolver solver(topo, LinearSolver::ConjugateGradient, params.cg_tolerance, &executor);
  auto t0 = bench::Clock::now();
  const Vertices P = solver.solve(P0, params.alpha, {});
  std::printf("    cg: Eq. 1 %d iterations %.0f ms", solver.last_iterations(), bench::ms_since(t0));
  // Eq. 3 as the pipeline runs it (its start, decision 42); a pass's time includes Eq. 4.
  t0 = bench::Clock::now();
  anisotropic_prefilter(P, order.faces(), topo, params, &solver, nullptr, [&](int done, const Vertices&) {
    if (done > 0) std::printf(", Eq. 3 #%d %d iterations %.0f ms", done, solver.last_iterations(), bench::ms_since(t0));
    t0 = bench::Clock::now();
  });
  std::printf(" (%d rows, %lld edges)\n", topo.num_vertices, static_cast<long long>(topo.num_interior_edges()));
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);
  std::printf("machine: %u hardware threads, load average %.2f %.2f %.2f; along_normal noise 0.2 l seed 1; "
              "%d runs per configuration (round-robin), medians; allocator %s\n",
              std::thread::hardware_concurrency(), load[0], load[1], load[2], o.runs,
              o.keep_freed_memory ? "cli (decision 52)" : "glibc's defaults");
  // Per stage, wall time of the stage per face per pass (setup, measure and Eq. 1 once; Eq. 3 per
  // anisotropic pass, the filters per iteration, over the counts that ran), in ns.
  // cpu: process CPU time (all threads; a loaded machine's waits excluded): the whole run, the
  // pre-filter (Eq. 1 to the first normal-filter iteration) and the two filters per iteration.
  std::printf("%-11s %8s %-5s %-5s %3s | %7s %7s %7s %7s %7s %7s %7s | %6s %6s %7s %7s | %7s %7s | %9s | %s\n", "", "", "",
              "", "", "wall:", "setup", "measure", "eq1", "eq3", "normal", "vertex", "cpu:", "pre", "normal", "vertex", "peak",
              "per MF", "MSAE", "ran");
  std::printf("%-11s %8s %-5s %-5s %3s | %7s %7s %7s %7s %7s %7s %7s | %6s %6s %7s %7s | %7s %7s | %9s | %s\n", "mesh",
              "faces", "param", "order", "thr", "total s", "ns/f", "ns/f", "ns/f", "ns/f/it", "ns/f/it", "ns/f/it", "tot s",
              "s", "ns/f/it", "ns/f/it", "MiB", "MiB", "x1e-2", "aniso/normal/vertex");
  try {
    const fs::path dir = bench::cgal_meshes(o.data);
    for (const auto& [name, levels] : o.meshes) {
      auto truth = std::make_unique<TriMesh>(bench::load_off(dir / (name + ".off")));
      for (int l = 0; l < levels; ++l) *truth = bench::midpoint_subdivide(*truth);
      auto noisy = std::make_unique<TriMesh>(TriMesh{add_noise(*truth, {NoiseKind::AlongNormal, 0.2, 1, 0}), truth->F});
      if (o.jitter > 0) noisy->V = add_noise(*noisy, {NoiseKind::AlongNormal, o.jitter, 2, 0});
      std::string label = name;
      if (levels > 0) label += 'x' + std::to_string(levels);
      const double nf = static_cast<double>(noisy->num_faces());

      struct Config {
        std::string params_name, order_name;
        DenoiseParams params;
        RunOptions options;
        std::vector<RunFigures> runs;
        Vertices output;
      };
      std::vector<Config> configs;
      for (const std::string& p : o.params)
        for (const std::string& k : o.orders)
          for (const int t : o.threads) {
            RunOptions options;
            options.threads = t;
            options.order = k == "input" ? OrderKind::Input
                            : k == "bfs"   ? OrderKind::BreadthFirst
                            : k == "curve" ? OrderKind::SpaceFillingCurve
                                           : OrderKind::Auto;
            configs.push_back({p, k, params_named(p), options, {}, {}});
          }
      // Each auto configuration's choice also runs as manual parameters ("pick"), from the first
      // round on, round-robin with the rest: issue 31's cost of auto against one run of its pick.
      const std::size_t given = configs.size();
      for (int run = 0; run < o.runs; ++run) {
        for (Config& c : configs) c.runs.push_back(run_child(truth, noisy, c.params, c.options, o.keep_freed_memory, c.output));
        for (std::size_t i = 0; run == 0 && i < given; ++i) {
          if (configs[i].params.mode != ParamMode::Auto) continue;
          Config pick{"pick", configs[i].order_name, configs[i].runs.front().params, configs[i].options, {}, {}};
          pick.runs.push_back(run_child(truth, noisy, pick.params, pick.options, o.keep_freed_memory, pick.output));
          configs.push_back(std::move(pick));
        }
      }

      for (const Config& c : configs) {
        auto median_of = [](const Config& k, double (*get)(const RunFigures&)) {
          std::vector<double> v;
          for (const RunFigures& r : k.runs) v.push_back(get(r));
          return bench::median(v);
        };
        auto med = [&](double (*get)(const RunFigures&)) { return median_of(c, get); };
        const RunFigures& ran = c.runs.front();  // the counts are those of every run (deterministic)
        const double per_face = 1e6 / nf;  // ms -> ns/f
        const double per_aniso = per_face / std::max(1, ran.params.n_aniso);
        const double per_normal = per_face / std::max(1, ran.params.n_normal);
        const double per_vertex = per_face / std::max(1, ran.params.n_vertex);
        const double peak = med([](const RunFigures& r) { return r.peak_mib; });
        const TriMesh out{c.output, truth->F};
        std::printf("%-11s %8.0f %-5s %-5s %3d | %7.3f %7.0f %7.0f %7.0f %7.1f %7.1f %7.1f | %6.2f %6.2f %7.1f %7.1f | %7.0f %7.0f | "
                    "%9.6f | %d/%d/%d (RSS at start %.0f MiB)%s\n",
                    label.c_str(), nf, c.params_name.c_str(), c.order_name.c_str(), c.options.threads,
                    med([](const RunFigures& r) { return r.t.total_ms; }) / 1e3,
                    med([](const RunFigures& r) { return r.t.setup_ms; }) * per_face,
                    med([](const RunFigures& r) { return r.t.measure_ms; }) * per_face,
                    med([](const RunFigures& r) { return r.t.initial_ms; }) * per_face,
                    med([](const RunFigures& r) { return r.t.anisotropic_ms; }) * per_aniso,
                    med([](const RunFigures& r) { return r.t.normal_ms; }) * per_normal,
                    med([](const RunFigures& r) { return r.t.vertex_ms; }) * per_vertex,
                    med([](const RunFigures& r) { return r.cpu_s; }), med([](const RunFigures& r) { return r.cpu_pre_s; }),
                    med([](const RunFigures& r) { return r.cpu_normal_s; }) * 1e3 * per_normal,
                    med([](const RunFigures& r) { return r.cpu_vertex_s; }) * 1e3 * per_vertex, peak, peak / (nf / 1e6),
                    msae(out, *truth) * 1e2,
                    ran.params.n_aniso, ran.params.n_normal, ran.params.n_vertex, med([](const RunFigures& r) { return r.rss_before_mib; }),
                    ran.peak_reset ? "" : " (peak not reset)");
        if (c.params.mode == ParamMode::Auto) {
          const double select = med([](const RunFigures& r) { return r.t.measure_ms; });
          const double total = med([](const RunFigures& r) { return r.t.total_ms; });
          // Issue 31's measure: auto against its pick run as manual parameters (the "pick" row).
          const auto pick = std::find_if(configs.begin(), configs.end(), [&](const Config& k) {
            return k.params_name == "pick" && k.order_name == c.order_name && k.options.threads == c.options.threads;
          });
          if (pick == configs.end()) continue;  // not reached: every auto configuration has one
          const double one_run = median_of(*pick, [](const RunFigures& r) { return r.t.total_ms; });
          std::printf("%-11s %8s   auto: measuring and choosing %.0f ms of %.0f ms; its pick as manual parameters %.0f ms: "
                      "%.2f x (output %s)\n",
                      "", "", select, total, one_run, total / std::max(1e-3, one_run),
                      pick->output == c.output ? "identical" : "differs");
        }
      }
      if (o.cg)
        for (const std::string& p : o.params) cg_section(*noisy, params_named(p), configs.back().options);
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scale_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
