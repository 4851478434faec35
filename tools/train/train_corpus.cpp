// The corpus, its labels and its descriptors for the trained parameter choice (issue 31).
// Never part of the service; tools/train/README.md says how the pieces fit.
//
//   train_corpus shapes   [--data DIR]                      every shape: faces, family, split
//   train_corpus label    [--data DIR] [--jobs N] [--limit N] [--shapes A,B] OUT.tsv
//       every case's true MSAE under every set of the label grid (label_grid.h) and the
//       identity; appends, and skips the cases OUT already holds (resumable).
//   train_corpus describe [--data DIR] [--jobs N] [--limit N] [--shapes A,B] OUT.tsv
//       every case's run-time descriptors (core/auto/descriptors.h); resumable the same way.
//
// DIR: CGAL's demo data (scripts/fetch-cgal-data.sh; default $MDN_CGAL_DATA or
// third_party_data/cgal). --limit N keeps the first N cases of each split's shapes in turn
// (CI's tiny run).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../../tests/bench/cgal_data.h"
#include "core/auto/descriptors.h"
#include "core/auto/measures.h"
#include "core/metrics.h"
#include "core/normal_filter.h"
#include "core/parallel.h"
#include "core/auto/denoise.h"
#include "core/prefilter.h"
#include "core/topology.h"
#include "core/vertex_update.h"
#include "corpus.h"
#include "label_grid.h"
#include "labels.h"

namespace fs = std::filesystem;
using namespace mdn;
using namespace mdn::train;

namespace {

struct Options {
  fs::path data = bench::default_cgal_data();
  int jobs = 2;
  int limit = 0;
  std::set<std::string> shapes;
  std::vector<std::string> positional;
};

struct CaseRef {
  std::string shape, noise;
  std::string name() const { return shape + "/" + noise; }
};

// The cases of the corpus in a fixed order: shape by shape, each shape's noise list.
std::vector<CaseRef> all_cases(const fs::path& cgal, const Options& o, std::map<std::string, Shape>& shapes) {
  std::vector<CaseRef> out;
  for (const std::string& name : shape_names(cgal)) {
    if (!o.shapes.empty() && !o.shapes.count(name)) continue;
    Shape s = make_shape(name, cgal);
    for (const std::string& noise : noise_names_for(s)) out.push_back({name, noise});
    shapes.emplace(name, std::move(s));
  }
  if (o.limit > 0) {  // a few cases spread over the shapes and noise kinds, a quarter of them holdout
    std::vector<CaseRef> few;
    for (const std::string split : {"train", "holdout"}) {
      std::vector<CaseRef> in;
      for (const CaseRef& c : out)
        if (split_of(c.shape) == split) in.push_back(c);
      const int want = split == "train" ? o.limit - o.limit / 4 : o.limit / 4;
      if (in.empty() || want <= 0) continue;
      const std::size_t stride = std::max<std::size_t>(1, in.size() / static_cast<std::size_t>(want));
      for (std::size_t i = 0, n = 0; i < in.size() && static_cast<int>(n) < want; i += stride, ++n) few.push_back(in[i]);
    }
    out = few;
  }
  return out;
}

std::set<std::string> done_cases(const fs::path& file) {
  std::set<std::string> done;
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line))
    if (!line.empty()) done.insert(line.substr(0, line.find('\t')));
  return done;
}

template <class Body>
void run_parallel(std::size_t n, int jobs, Body body) {
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < std::max(1, jobs); ++t)
    pool.emplace_back([&] {
      for (std::size_t i = next++; i < n; i = next++) body(i);
    });
  for (auto& th : pool) th.join();
}

// Appends one row per case not yet in `out`, computed by `row` (tab-separated values).
// `row` gets the case's noisy/clean pair (make_noisy_case); the faces column is the case's mesh's.
int fill_table(const Options& o, const std::string& header, const std::function<std::string(const NoisyCase&)>& row) {
  const fs::path cgal = bench::cgal_meshes(o.data);
  std::map<std::string, Shape> shapes;
  const std::vector<CaseRef> cases = all_cases(cgal, o, shapes);
  const fs::path out = o.positional.at(0);
  const std::set<std::string> done = done_cases(out);
  std::vector<CaseRef> todo;
  for (const CaseRef& c : cases)
    if (!done.count(c.name())) todo.push_back(c);
  // A fixed shuffle, so that a run stopped early still covers every shape and noise kind.
  std::sort(todo.begin(), todo.end(),
            [](const CaseRef& a, const CaseRef& b) { return hash_name(a.name()) < hash_name(b.name()); });
  const bool fresh = !fs::exists(out) || fs::file_size(out) == 0;
  std::ofstream file(out, std::ios::app);
  if (fresh) file << header << '\n' << std::flush;
  std::printf("%zu cases, %zu already in %s, %zu to go\n", cases.size(), done.size(), out.c_str(), todo.size());
  std::fflush(stdout);
  std::mutex mutex;
  std::atomic<int> finished{0};
  const auto t0 = std::chrono::steady_clock::now();
  run_parallel(todo.size(), o.jobs, [&](std::size_t i) {
    const CaseRef& c = todo[i];
    const Shape& s = shapes.at(c.shape);
    const NoisyCase pair = make_noisy_case(s, c.noise, hash_name(s.name + "/" + c.noise));
    const std::string line = c.name() + '\t' + c.shape + '\t' + s.family + '\t' + split_of(c.shape) + '\t' + c.noise + '\t' +
                             std::to_string(pair.clean.num_faces()) + '\t' + row(pair);
    std::lock_guard lock(mutex);
    file << line << '\n' << std::flush;
    const int k = ++finished;
    if (k % 20 == 0 || k == static_cast<int>(todo.size())) {
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("%d / %zu (%.0f s)\n", k, todo.size(), secs);
      std::fflush(stdout);
    }
  });
  return 0;
}

std::string join(const std::vector<double>& v, const char* fmt) {
  std::string s;
  char buf[64];
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof buf, fmt, v[i]);
    if (i) s += '\t';
    s += buf;
  }
  return s;
}

int cmd_label(const Options& o) {
  std::string header = "case\tshape\tfamily\tsplit\tnoise\tfaces\tregion\tidentity";
  for (const DenoiseParams& p : label_sets()) header += '\t' + set_name(p);
  return fill_table(o, header, [](const NoisyCase& pair) {
    const Prepared p = prepare(pair.clean, pair.noisy);
    const RegionMode region = auto_region_mode(p);
    return std::string(region == RegionMode::On ? "1" : "0") + '\t' + join(label_case(p, region), "%.5g");
  });
}

int cmd_describe(const Options& o) {
  std::string header = "case\tshape\tfamily\tsplit\tnoise\tfaces";
  for (const std::string& name : descriptor_names()) header += '\t' + name;
  return fill_table(o, header, [](const NoisyCase& pair) {
    const Prepared p = prepare(pair.clean, pair.noisy);
    Executor ex(1);
    return join(describe_input(p.P, p.F, p.topo, ex).values, "%.6g");
  });
}

int cmd_shapes(const Options& o) {
  const fs::path cgal = bench::cgal_meshes(o.data);
  int cases = 0;
  for (const std::string& name : shape_names(cgal)) {
    const Shape s = make_shape(name, cgal);
    validate_mesh(s.mesh);
    const Topology topo = Topology::build(s.mesh.F, static_cast<std::int32_t>(s.mesh.num_vertices()));
    const auto n = noise_names_for(s).size();
    cases += static_cast<int>(n);
    std::printf("%-28s %-8s %-8s %7lld faces %3zu cases  %zu boundary edges\n", name.c_str(), s.family.c_str(),
                split_of(name).c_str(), static_cast<long long>(s.mesh.num_faces()), n, topo.boundary_edges.rows() > 0 ? static_cast<std::size_t>(topo.boundary_edges.rows()) : 0);
  }
  std::printf("%d cases\n", cases);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: train_corpus shapes|label|describe [--data DIR] [--jobs N] [--limit N] [--shapes A,B] [OUT.tsv]\n");
    return 2;
  }
  const std::string verb = argv[1];
  Options o;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--data") o.data = value();
    else if (a == "--jobs") o.jobs = std::stoi(value());
    else if (a == "--limit") o.limit = std::stoi(value());
    else if (a == "--shapes") {
      std::stringstream ss(value());
      for (std::string s; std::getline(ss, s, ',');) o.shapes.insert(s);
    } else o.positional.push_back(a);
  }
  try {
    if (verb == "shapes") return cmd_shapes(o);
    if (o.positional.size() != 1) throw std::invalid_argument(verb + " needs OUT.tsv");
    if (verb == "label") return cmd_label(o);
    if (verb == "describe") return cmd_describe(o);
    throw std::invalid_argument("unknown verb " + verb);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "train_corpus: %s\n", e.what());
    return 1;
  }
}
