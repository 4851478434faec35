// The corpus, its labels and its descriptors for the trained parameter choice (issue 31).
// Never part of the service; tools/train/README.md says how the pieces fit.
//
//   train_corpus shapes   [--data DIR]                      every shape: faces, family, split
//   train_corpus export   [--data DIR] SHAPE/NOISE OUT       one case as OFF files to look at:
//       OUT.noisy.off and OUT.clean.off (same faces, same order)
//   train_corpus label    [--data DIR] [--jobs N] [--limit N] [--shapes A,B] OUT.tsv
//       every case's true MSAE under every set of the label grid (label_grid.h) and the
//       identity; appends, and skips the cases OUT already holds (resumable).
//   train_corpus describe [--data DIR] [--jobs N] [--limit N] [--shapes A,B] OUT.tsv
//       every case's run-time descriptors (core/auto/descriptors.h); resumable the same way.
//   train_corpus faces    [--data DIR] [--jobs N] [--cases N] [--rows N] OUT
//       the per-face prior's rows (issue 48; decisions 87-88): N cases (default 800) drawn by a
//       hash of their names, three in four from training-split shapes and the rest from
//       holdout-split shapes, each giving at most --rows faces (default 600), a quarter per
//       clean face class (flat, curved, crease, corner). Writes OUT.train.f32 and
//       OUT.holdout.f32 (float32 rows of kFaceRowWidth: the features, the clean normal in the
//       face's frame, the noisy-to-clean angle in radians, the class) and OUT.cases.tsv. The
//       same bytes for any --jobs.
//   train_corpus guided   [--data DIR] [--jobs N] [--cases N] [--max-faces N]
//       issue 48's paired check of the per-face prior on holdout-split shapes, where its rule
//       is chosen (never on tune_bench's validation set): N holdout cases (default 80) of at most
//       --max-faces (default 20,000), auto's pick held fixed, unguided, guided by the oracle
//       (clean normals turned by 6 degrees) and by the prior, for the pick, the pick with
//       sigma_gamma 20, 30 and 45 degrees and the paper's Table 1 row (and the diagnostic guidances
//       cmd_guided names); median ratios per group.
//   train_corpus fields   [--data DIR] [--jobs N] [--cases N] [--max-faces N]
//       issue 48's per-face parameter fields, bounded before they are built: the same holdout
//       cases, auto's pick with ten candidate normal fields (sigma_gamma, iterations), the normals
//       chosen with the clean surface in view for the whole case, per clean face class or per face
//       (cmd_fields); median ratios to the pick per group.
//
// DIR: CGAL's demo data (scripts/fetch-cgal-data.sh; default $MDN_CGAL_DATA or
// third_party_data/cgal). --limit N keeps the first N cases of each split's shapes in turn
// (CI's tiny run).
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../../tests/bench/cgal_data.h"
#include "../../tests/bench/oracle_guidance.h"
#include "core/auto/face_prior.h"
#include "core/auto/choice.h"
#include "core/auto/descriptors.h"
#include "core/auto/face_features.h"
#include "core/auto/measures.h"
#include "core/metrics.h"
#include "core/normal_filter.h"
#include "core/parallel.h"
#include "core/pipeline.h"
#include "core/auto/denoise.h"
#include "core/prefilter.h"
#include "core/topology.h"
#include "core/vertex_update.h"
#include "corpus.h"
#include "label_grid.h"
#include "labels.h"
#include "support/shapes.h"

namespace fs = std::filesystem;
using namespace mdn;
using namespace mdn::train;

namespace {

struct Options {
  fs::path data = bench::default_cgal_data();
  int jobs = 2;
  int limit = 0;
  int cases = 0;    // faces, guided: cases drawn (0: 800 and 80)
  int rows = 600;   // faces: rows per case at most
  std::int64_t max_faces = 20000;  // guided: larger cases left out
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

// One case's rows of `train_corpus faces` (decision 88): up to `cap` faces, a quarter per
// clean class in a fixed order (a hash of the case and the face), degenerate faces left out.
constexpr int kFaceRowWidth = kFaceFeatures + 5;
std::vector<float> face_rows(const NoisyCase& pair, const std::string& name, int cap) {
  Executor ex(1);
  const Topology topo = Topology::build(pair.clean.F, static_cast<std::int32_t>(pair.clean.num_vertices()));
  const FaceFeatures ff = face_features(pair.noisy, pair.clean.F, topo, ex);
  const std::vector<FaceClass> cls = face_classes(pair.clean.V, pair.clean.F, topo, ex);
  const Vertices clean = face_normals(pair.clean.V, pair.clean.F);
  std::array<std::vector<std::pair<std::uint64_t, std::int64_t>>, kFaceClasses> by_class;
  const std::uint64_t seed = hash_name(name);
  for (std::int64_t f = 0; f < pair.clean.num_faces(); ++f) {
    if (clean.row(f).squaredNorm() == 0 || ff.noisy.row(f).squaredNorm() == 0) continue;
    const std::uint64_t key = (seed ^ (static_cast<std::uint64_t>(f) * 0x9E3779B97F4A7C15ull)) * 0xBF58476D1CE4E5B9ull;
    by_class[static_cast<std::size_t>(cls[static_cast<std::size_t>(f)])].push_back({key, f});
  }
  std::vector<float> out;
  for (int c = 0; c < kFaceClasses; ++c) {
    auto& faces = by_class[static_cast<std::size_t>(c)];
    std::sort(faces.begin(), faces.end());
    const std::size_t take = std::min<std::size_t>(faces.size(), static_cast<std::size_t>(cap / kFaceClasses));
    for (std::size_t k = 0; k < take; ++k) {
      const std::int64_t f = faces[k].second;
      for (int j = 0; j < kFaceFeatures; ++j) out.push_back(static_cast<float>(ff.X(f, j)));
      const Vec3 target = to_frame(ff, f, clean.row(f).transpose());
      for (int j = 0; j < 3; ++j) out.push_back(static_cast<float>(target(j)));
      const Vec3 n0 = ff.noisy.row(f).transpose(), nc = clean.row(f).transpose();
      out.push_back(static_cast<float>(std::atan2(n0.cross(nc).norm(), n0.dot(nc))));
      out.push_back(static_cast<float>(c));
    }
  }
  return out;
}

// Every case of the corpus (no --limit), in the order of their names' hashes: the prior's
// commands draw their cases from its start (decision 88).
std::vector<CaseRef> cases_by_hash(const Options& o, std::map<std::string, Shape>& shapes) {
  Options all = o;
  all.limit = 0;
  std::vector<CaseRef> cases = all_cases(bench::cgal_meshes(o.data), all, shapes);
  std::sort(cases.begin(), cases.end(),
            [](const CaseRef& a, const CaseRef& b) { return hash_name(a.name()) < hash_name(b.name()); });
  return cases;
}

int cmd_faces(const Options& o, int wanted, int cap) {
  std::map<std::string, Shape> shapes;
  const std::vector<CaseRef> cases = cases_by_hash(o, shapes);
  std::vector<CaseRef> chosen;
  for (const std::string split : {"train", "holdout"}) {
    const int want = split == "train" ? wanted - wanted / 4 : wanted / 4;
    int n = 0;
    for (const CaseRef& c : cases)
      if (n < want && split_of(c.shape) == split) {
        chosen.push_back(c);
        ++n;
      }
  }
  std::vector<std::vector<float>> rows(chosen.size());
  std::atomic<int> finished{0};
  const auto t0 = std::chrono::steady_clock::now();
  run_parallel(chosen.size(), o.jobs, [&](std::size_t i) {
    const CaseRef& c = chosen[i];
    const Shape& s = shapes.at(c.shape);
    rows[i] = face_rows(make_noisy_case(s, c.noise, hash_name(s.name + "/" + c.noise)), c.name(), cap);
    const int k = ++finished;
    if (k % 50 == 0) {
      std::printf("%d / %zu (%.0f s)\n", k, chosen.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      std::fflush(stdout);
    }
  });
  const std::string prefix = o.positional.at(0);
  std::ofstream train(prefix + ".train.f32", std::ios::binary), holdout(prefix + ".holdout.f32", std::ios::binary),
      index(prefix + ".cases.tsv");
  index << "case\tshape\tsplit\tnoise\trows\n";
  std::array<std::size_t, 2> total{0, 0};
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    const bool is_train = split_of(chosen[i].shape) == "train";
    std::ofstream& file = is_train ? train : holdout;
    file.write(reinterpret_cast<const char*>(rows[i].data()), static_cast<std::streamsize>(rows[i].size() * sizeof(float)));
    const std::size_t n = rows[i].size() / kFaceRowWidth;
    total[is_train ? 0 : 1] += n;
    index << chosen[i].name() << '\t' << chosen[i].shape << '\t' << split_of(chosen[i].shape) << '\t' << chosen[i].noise << '\t' << n
          << '\n';
  }
  std::printf("%zu cases: %zu training rows, %zu holdout rows of %d floats\n", chosen.size(), total[0], total[1], kFaceRowWidth);
  return 0;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// The cases of the paired checks (guided, fields): the first `wanted` noisy cases of
// holdout-split shapes in the hash's order, of at most max_faces faces.
std::vector<CaseRef> paired_cases(const Options& o, int wanted, std::int64_t max_faces, std::map<std::string, Shape>& shapes) {
  std::vector<CaseRef> chosen;
  for (const CaseRef& c : cases_by_hash(o, shapes))
    if (static_cast<int>(chosen.size()) < wanted && split_of(c.shape) == "holdout" && c.noise != "clean" &&
        shapes.at(c.shape).mesh.num_faces() <= max_faces)
      chosen.push_back(c);
  return chosen;
}

// A paired check's ratios per case, gathered into groups ("all", "kind:...") and printed as the
// median per group with the worst (largest) or the best (smallest) in brackets.
struct GroupTable {
  std::map<std::string, std::vector<std::vector<double>>> groups;
  void add(const std::vector<std::string>& in, const std::vector<double>& ratios) {
    for (const std::string& g : in) {
      auto& cols = groups[g];
      cols.resize(ratios.size());
      for (std::size_t k = 0; k < ratios.size(); ++k) cols[k].push_back(ratios[k]);
    }
  }
  void print(const std::vector<std::string>& names, const char* bracket, bool largest) const {
    std::printf("\nMedian ratio per group (the same runs, paired per case; %s in brackets):\n%-26s %5s", bracket, "group",
                "cases");
    for (const std::string& n : names) std::printf(" %15s", n.c_str());
    std::printf("\n");
    for (const auto& [name, cols] : groups) {
      std::printf("%-26s %5zu", name.c_str(), cols[0].size());
      for (const auto& col : cols)
        std::printf("   %5.3f (%5.2f)", median_of(col),
                    largest ? *std::max_element(col.begin(), col.end()) : *std::min_element(col.begin(), col.end()));
      std::printf("\n");
    }
  }
};

int cmd_guided(const Options& o, int wanted, std::int64_t max_faces) {
  std::map<std::string, Shape> shapes;
  const std::vector<CaseRef> chosen = paired_cases(o, wanted, max_faces, shapes);
  // s30gF, s30gS: a diagnosis of where the prior falls short of the oracle: the oracle's guidance
  // at the clean surface's crease and corner faces and the prior's elsewhere (F), and the other
  // way round (S).
  // gP, s30gP, pgP: guided by the most consistent patch's normal (decision 87's reading, no
  // network: guided normal filtering's patch choice over one ring).
  enum Run { P, G6, GL, S20GL, S30, S30G6, S30GL, S45GL, PP, PG6, PGL, S30GF, S30GS, GP, S30GP, PGP, kRuns };
  const std::vector<std::string> names{"g6/p",   "gL/p",     "s20gL/p", "s30/p",   "s30g6/p", "s30gL/p", "s45gL/p",
                                       "pg6/pp", "pgL/pp",   "best3L/p", "s30gF/p", "s30gS/p", "gP/p",    "s30gP/p",
                                       "pgP/pp"};
  struct Out {
    std::array<double, kRuns> msae;
    std::string pick;
    double sigma_gamma = 0, reading = 0;
  };
  std::vector<Out> out(chosen.size());
  run_parallel(chosen.size(), o.jobs, [&](std::size_t i) {
    const CaseRef& c = chosen[i];
    const Shape& s = shapes.at(c.shape);
    const NoisyCase pair = make_noisy_case(s, c.noise, hash_name(s.name + "/" + c.noise));
    const TriMesh noisy{pair.noisy, pair.clean.F};
    DenoiseParams automatic;
    automatic.mode = ParamMode::Auto;
    const DenoiseResult r = denoise(noisy, automatic);
    const DenoiseParams pick = r.report.params;
    Executor one(1);
    const Topology topo = Topology::build(noisy.F, static_cast<std::int32_t>(noisy.V.rows()));
    const FacePrior prior = face_prior(noisy.V, noisy.F, topo, one);
    const Vertices g6 = bench::perturbed_normals(face_normals(pair.clean.V, pair.clean.F), 6, hash_name(c.name()) ^ 6);
    const auto run = [&](const DenoiseParams& q, const Vertices* guidance) {
      RunOptions options;
      options.guidance = guidance;
      return msae(denoise(noisy, q, options).mesh, pair.clean);
    };
    const auto with_gamma = [&](double g) {
      DenoiseParams q = pick;
      q.sigma_gamma = g;
      return q;
    };
    const Vertices* L = &prior.guidance;
    const std::vector<FaceClass> cls = face_classes(pair.clean.V, pair.clean.F, topo, one);
    Vertices patch(noisy.F.rows(), 3);
    {
      const FaceFeatures ff = face_features(noisy.V, noisy.F, topo, one);
      for (Eigen::Index f = 0; f < noisy.F.rows(); ++f) {
        const Vec3 local = ff.X.row(f).segment<3>(36).transpose();
        patch.row(f) = (local.norm() > 0 ? from_frame(ff, f, local.normalized()) : Vec3(ff.noisy.row(f).transpose())).transpose();
      }
    }
    Vertices at_features = prior.guidance, elsewhere = g6;
    for (Eigen::Index f = 0; f < noisy.F.rows(); ++f)
      if (cls[static_cast<std::size_t>(f)] == FaceClass::Crease || cls[static_cast<std::size_t>(f)] == FaceClass::Corner) {
        at_features.row(f) = g6.row(f);
        elsewhere.row(f) = prior.guidance.row(f);
      }
    out[i] = {{run(pick, nullptr), run(pick, &g6), run(pick, L), run(with_gamma(20), L), run(with_gamma(30), nullptr),
               run(with_gamma(30), &g6), run(with_gamma(30), L), run(with_gamma(45), L), run(DenoiseParams{}, nullptr),
               run(DenoiseParams{}, &g6), run(DenoiseParams{}, L), run(with_gamma(30), &at_features),
               run(with_gamma(30), &elsewhere), run(pick, &patch), run(with_gamma(30), &patch), run(DenoiseParams{}, &patch)},
              r.report.choice->chosen, pick.sigma_gamma, prior.summary.median_deg};
  });
  GroupTable table;
  std::printf("%-40s %7s %-24s %6s", "case", "faces", "pick", "read");
  for (const std::string& n : names) std::printf(" %8s", n.c_str());
  std::printf("\n");
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    const auto& m = out[i].msae;
    const std::vector<double> ratios{m[G6] / m[P],  m[GL] / m[P],  m[S20GL] / m[P], m[S30] / m[P],   m[S30G6] / m[P],
                                     m[S30GL] / m[P], m[S45GL] / m[P], m[PG6] / m[PP], m[PGL] / m[PP],
                                     std::min({m[GL], m[S30GL], m[PGL]}) / m[P], m[S30GF] / m[P], m[S30GS] / m[P],
                                     m[GP] / m[P], m[S30GP] / m[P], m[PGP] / m[PP]};
    const std::string kind = chosen[i].noise.substr(0, chosen[i].noise.find(':'));
    const std::string by_pick = out[i].pick == "identity" ? "identity" : out[i].sigma_gamma >= 90 ? "sigma_gamma 90" : "sigma_gamma <= 45";
    table.add({"all", "kind:" + kind, "pick:" + by_pick}, ratios);
    std::printf("%-40s %7lld %-24s %6.2f", chosen[i].name().c_str(), static_cast<long long>(shapes.at(chosen[i].shape).mesh.num_faces()),
                out[i].pick.c_str(), out[i].reading);
    for (const double x : ratios) std::printf(" %8.3f", x);
    std::printf("\n");
  }
  table.print(names, "worst", true);
  return 0;
}

// Issue 48's fallback, measured before anything is built: what a per-face field of sigma_gamma
// and normal iterations could give at most. Holdout cases as `guided` draws them, auto's pick
// held fixed: its pre-filter (Eq. 1-4), then ten candidate normal fields (Eq. 7: its own
// parameters; sigma_gamma 20, 30, 45 and 90 degrees; its sigma_gamma at 2, 5, 20, 40 and 100
// iterations), then the vertex update (Eq. 8) from normals chosen with the clean surface in
// view: "best1" the one candidate best for the whole case (a perfect per-mesh choice);
// "class" per clean face class (flat, curved, crease, corner: decision 88's), the candidate
// whose normals err least over the class's faces (four choices per case: what a per-face field
// driven by a perfect classifier gives); "face" per face the candidate nearest the clean normal
// (a bound that also profits from choosing among ten noisy estimates). Ratios to the pick's
// MSAE; cases auto leaves alone are skipped.
int cmd_fields(const Options& o, int wanted, std::int64_t max_faces) {
  std::map<std::string, Shape> shapes;
  const std::vector<CaseRef> chosen = paired_cases(o, wanted, max_faces, shapes);
  const std::vector<std::string> names{"best1/p", "class/p", "face/p", "class/best1"};
  struct Out {
    std::vector<double> ratios;
    std::string pick;
  };
  std::vector<Out> out(chosen.size());
  run_parallel(chosen.size(), o.jobs, [&](std::size_t i) {
    const CaseRef& c = chosen[i];
    const Shape& s = shapes.at(c.shape);
    const NoisyCase pair = make_noisy_case(s, c.noise, hash_name(s.name + "/" + c.noise));
    DenoiseParams automatic;
    automatic.mode = ParamMode::Auto;
    const DenoiseResult r = denoise(TriMesh{pair.noisy, pair.clean.F}, automatic);
    out[i].pick = r.report.choice->chosen;
    if (out[i].pick == "identity") return;
    const DenoiseParams& pick = r.report.params;
    const Prepared prepared = prepare(pair.clean, pair.noisy);
    Executor one(1);
    DenoiseReport report;
    const Vertices P = prefilter_stage(prepared.P, prepared.F, prepared.topo, pick, one, nullptr, report);
    std::vector<Vertices> N;
    for (const double gamma : {pick.sigma_gamma, 20.0, 30.0, 45.0, 90.0}) {
      NormalFilterSettings nfs = normal_filter_settings(pick);
      nfs.sigma_gamma_deg = gamma;
      N.push_back(l1_median_normal_filter(P, prepared.F, prepared.topo, nfs, &one));
    }
    {  // the pick's sigma_gamma at 2, 5, 20, 40 and 100 iterations
      const std::vector<int> counts{2, 5, 20, 40, 100};
      NormalFilterSettings nfs = normal_filter_settings(pick);
      nfs.iterations = counts.back();
      nfs.on_iteration = [&](int done, const Vertices& n) {
        if (std::find(counts.begin(), counts.end(), done) != counts.end()) N.push_back(n);
      };
      l1_median_normal_filter(P, prepared.F, prepared.topo, nfs, &one);
    }
    const auto result = [&](const Vertices& normals) {
      const Vertices V = vertex_update(P, prepared.F, prepared.topo, normals, pick.n_vertex, &one);
      return msae_of_normals(face_normals(V, prepared.F), prepared.truth_normals);
    };
    const auto angle2 = [&](std::size_t k, Eigen::Index f) {
      const Vec3 a = N[k].row(f).transpose(), b = prepared.truth_normals.row(f).transpose();
      const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
      return angle * angle;
    };
    const double p = result(N[0]);
    double best1 = p;
    for (std::size_t k = 1; k < N.size(); ++k) best1 = std::min(best1, result(N[k]));
    const std::vector<FaceClass> cls = face_classes(pair.clean.V, pair.clean.F, prepared.topo, one);
    std::array<std::vector<double>, 4> class_error;
    for (auto& e : class_error) e.assign(N.size(), 0.0);
    Vertices per_face = N[0];
    for (Eigen::Index f = 0; f < prepared.F.rows(); ++f) {
      std::size_t nearest = 0;
      double nearest_error = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k < N.size(); ++k) {
        const double e = angle2(k, f);
        class_error[static_cast<std::size_t>(cls[static_cast<std::size_t>(f)])][k] += e;
        if (e < nearest_error) nearest = k, nearest_error = e;
      }
      per_face.row(f) = N[nearest].row(f);
    }
    Vertices per_class = N[0];
    for (Eigen::Index f = 0; f < prepared.F.rows(); ++f) {
      const std::vector<double>& e = class_error[static_cast<std::size_t>(cls[static_cast<std::size_t>(f)])];
      per_class.row(f) = N[static_cast<std::size_t>(std::min_element(e.begin(), e.end()) - e.begin())].row(f);
    }
    const double by_class = result(per_class);
    out[i].ratios = {best1 / p, by_class / p, result(per_face) / p, by_class / best1};
  });
  GroupTable table;
  std::printf("%-40s %7s %-26s", "case", "faces", "pick");
  for (const std::string& n : names) std::printf(" %11s", n.c_str());
  std::printf("\n");
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    if (out[i].ratios.empty()) continue;
    table.add({"all", "kind:" + chosen[i].noise.substr(0, chosen[i].noise.find(':'))}, out[i].ratios);
    std::printf("%-40s %7lld %-26s", chosen[i].name().c_str(), static_cast<long long>(shapes.at(chosen[i].shape).mesh.num_faces()),
                out[i].pick.c_str());
    for (const double x : out[i].ratios) std::printf(" %11.3f", x);
    std::printf("\n");
  }
  table.print(names, "best", false);
  return 0;
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

int cmd_export(const Options& o) {
  const std::string name = o.positional.at(0);
  const std::size_t slash = name.find('/');
  if (slash == std::string::npos) throw std::invalid_argument("export needs SHAPE/NOISE, not " + name);
  const Shape s = make_shape(name.substr(0, slash), bench::cgal_meshes(o.data));
  const std::string noise = name.substr(slash + 1);
  const NoisyCase pair = make_noisy_case(s, noise, hash_name(s.name + "/" + noise));
  for (const auto& [suffix, V] : {std::pair<const char*, const Vertices*>{".clean.off", &pair.clean.V}, {".noisy.off", &pair.noisy}}) {
    const std::string path = o.positional.at(1) + suffix;
    std::ofstream out(path, std::ios::binary);
    out << test::off_text(TriMesh{*V, pair.clean.F});
    if (!out.flush()) throw std::runtime_error("cannot write " + path);
    std::printf("%s: %lld faces\n", path.c_str(), static_cast<long long>(pair.clean.num_faces()));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: train_corpus shapes|export|label|describe|faces|guided [--data DIR] [--jobs N] [--limit N] [--shapes A,B] [--cases N] [--rows N] [OUT]\n");
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
    else if (a == "--cases") o.cases = std::stoi(value());
    else if (a == "--rows") o.rows = std::stoi(value());
    else if (a == "--max-faces") o.max_faces = std::stoll(value());
    else if (a == "--shapes") {
      std::stringstream ss(value());
      for (std::string s; std::getline(ss, s, ',');) o.shapes.insert(s);
    } else o.positional.push_back(a);
  }
  try {
    if (verb == "shapes") return cmd_shapes(o);
    if (verb == "guided") return cmd_guided(o, o.cases > 0 ? o.cases : 80, o.max_faces);
    if (verb == "fields") return cmd_fields(o, o.cases > 0 ? o.cases : 80, o.max_faces);
    if (verb == "export") {
      if (o.positional.size() != 2) throw std::invalid_argument("export needs SHAPE/NOISE and OUT");
      return cmd_export(o);
    }
    if (o.positional.size() != 1) throw std::invalid_argument(verb + " needs OUT");
    if (verb == "label") return cmd_label(o);
    if (verb == "describe") return cmd_describe(o);
    if (verb == "faces") return cmd_faces(o, o.cases > 0 ? o.cases : 800, o.rows);
    throw std::invalid_argument("unknown verb " + verb);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "train_corpus: %s\n", e.what());
    return 1;
  }
}
