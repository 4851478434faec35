#include "labels.h"

#include <algorithm>
#include <map>

#include "core/auto/measures.h"
#include "core/metrics.h"
#include "core/normal_filter.h"
#include "core/parallel.h"
#include "core/auto/denoise.h"
#include "core/vertex_update.h"
#include "label_grid.h"

namespace mdn::train {

Prepared prepare(const TriMesh& clean, const Vertices& noisy) {
  const UnitBox box = UnitBox::of(noisy);
  return {box.apply(noisy), clean.F, Topology::build(clean.F, static_cast<std::int32_t>(noisy.rows())),
          face_normals(clean.V, clean.F)};
}

RegionMode auto_region_mode(const Prepared& c) {
  Executor ex(1);
  const DenoiseParams base;
  const InputMeasures m = measure_input(c.P, c.F, c.topo, base, &ex);
  return m.cluster_area_ratio >= base.irregular_area_ratio ? RegionMode::On : RegionMode::Off;
}

std::vector<double> label_case(const Prepared& c, RegionMode region) {
  Executor ex(1);
  std::vector<double> out{msae_of_normals(face_normals(c.P, c.F), c.truth_normals)};
  const auto& gammas = label_sigma_gamma();
  const auto& normals = label_n_normal();
  const auto& verts = label_n_vertex();
  for (const PrefilterFamily& fam : label_families()) {
    DenoiseParams q;
    q.mode = ParamMode::Manual;
    q.alpha = fam.alpha;
    q.sigma_theta = fam.sigma_theta;
    q.n_aniso = *std::max_element(fam.n_aniso.begin(), fam.n_aniso.end());
    q.region_mode = region;
    std::map<int, Vertices> pre;
    DenoiseReport report;
    prefilter_stage(c.P, c.F, c.topo, q, ex, nullptr, report, [&](int done, const Vertices& V) {
      if (std::find(fam.n_aniso.begin(), fam.n_aniso.end(), done) != fam.n_aniso.end()) pre[done] = V;
    });
    for (const int aniso : fam.n_aniso) {
      const Vertices& P = pre.at(aniso);
      for (const double gamma : gammas) {
        std::vector<Vertices> N(normals.size());
        NormalFilterSettings nfs = normal_filter_settings(q);
        nfs.sigma_gamma_deg = gamma;
        nfs.iterations = normals.back();
        nfs.on_iteration = [&](int done, const Vertices& n) {
          for (std::size_t k = 0; k < normals.size(); ++k)
            if (normals[k] == done) N[k] = n;
        };
        l1_median_normal_filter(P, c.F, c.topo, nfs, &ex);
        for (std::size_t k = 0; k < normals.size(); ++k) {
          std::vector<double> row(verts.size());
          vertex_update(P, c.F, c.topo, N[k], verts.back(), &ex, nullptr, [&](int done, const Vertices& V) {
            for (std::size_t j = 0; j < verts.size(); ++j)
              if (verts[j] == done) row[j] = msae_of_normals(face_normals(V, c.F), c.truth_normals);
          });
          out.insert(out.end(), row.begin(), row.end());
        }
      }
    }
  }
  return out;
}

}  // namespace mdn::train
