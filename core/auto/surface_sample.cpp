#include "core/auto/surface_sample.h"

#include <algorithm>
#include <deque>
#include <numeric>

namespace mdn {

namespace {

// 10 bits per axis, interleaved.
std::uint32_t spread_bits(std::uint32_t x) {
  x &= 0x3ff;
  x = (x | (x << 16)) & 0x030000ff;
  x = (x | (x << 8)) & 0x0300f00f;
  x = (x | (x << 4)) & 0x030c30c3;
  x = (x | (x << 2)) & 0x09249249;
  return x;
}

// Which faces the sample takes: `patches` patches of about max_faces / patches faces each,
// grown breadth-first over vertex-sharing faces from seeds spread evenly along a Morton order
// of the face centroids.
std::vector<std::uint8_t> patch_faces(const Vertices& P, const Triangles& F, const Topology& topo, std::int64_t max_faces, int patches) {
  const std::int64_t nf = F.rows();
  std::vector<std::uint8_t> take(static_cast<std::size_t>(nf), 0);
  const Vertices C = face_centroids(P, F);
  const Eigen::RowVector3d lo = C.colwise().minCoeff();
  const double extent = std::max((C.colwise().maxCoeff() - lo).maxCoeff(), 1e-300);
  std::vector<std::pair<std::uint32_t, std::int32_t>> order(static_cast<std::size_t>(nf));
  for (std::int64_t f = 0; f < nf; ++f) {
    std::uint32_t code = 0;
    for (int a = 0; a < 3; ++a) code |= spread_bits(static_cast<std::uint32_t>((C(f, a) - lo[a]) / extent * 1023.0)) << a;
    order[static_cast<std::size_t>(f)] = {code, static_cast<std::int32_t>(f)};
  }
  std::sort(order.begin(), order.end());
  const std::int64_t per_patch = std::max<std::int64_t>(1, max_faces / patches);
  std::deque<std::int32_t> queue;
  for (int k = 0; k < patches; ++k) {
    const auto seed = order[static_cast<std::size_t>((2 * k + 1) * nf / (2 * patches))].second;
    if (take[static_cast<std::size_t>(seed)]) continue;
    std::int64_t grown = 0;
    queue.assign(1, seed);
    take[static_cast<std::size_t>(seed)] = 1;
    ++grown;
    while (!queue.empty() && grown < per_patch) {
      const std::int32_t f = queue.front();
      queue.pop_front();
      for (auto a = topo.ff_offsets[static_cast<std::size_t>(f)]; a < topo.ff_offsets[static_cast<std::size_t>(f) + 1] && grown < per_patch; ++a) {
        const std::int32_t g = topo.ff_faces[static_cast<std::size_t>(a)];
        if (take[static_cast<std::size_t>(g)]) continue;
        take[static_cast<std::size_t>(g)] = 1;
        ++grown;
        queue.push_back(g);
      }
    }
  }
  return take;
}

// Each sampled vertex's distance in rings from the cut, capped at `margin` (a vertex is on the
// cut if one of its surface faces was left out).
std::vector<int> cut_depth(const SurfaceSample& s, const Topology& topo, const std::vector<std::uint8_t>& take, int margin) {
  const auto nv = static_cast<std::int32_t>(s.vertex.size());
  std::vector<int> depth(static_cast<std::size_t>(nv), margin);
  if (s.whole) return depth;
  std::vector<std::int32_t> frontier;
  for (std::int32_t v = 0; v < nv; ++v) {
    const std::int32_t g = s.vertex[static_cast<std::size_t>(v)];
    for (auto a = topo.vf_offsets[static_cast<std::size_t>(g)]; a < topo.vf_offsets[static_cast<std::size_t>(g) + 1]; ++a)
      if (!take[static_cast<std::size_t>(topo.vf_faces[static_cast<std::size_t>(a)])]) {
        depth[static_cast<std::size_t>(v)] = 0;
        frontier.push_back(v);
        break;
      }
  }
  for (int d = 1; d < margin; ++d) {
    std::vector<std::int32_t> next;
    for (const std::int32_t v : frontier)
      for (auto a = s.topo.vv_offsets[static_cast<std::size_t>(v)]; a < s.topo.vv_offsets[static_cast<std::size_t>(v) + 1]; ++a) {
        const std::int32_t w = s.topo.vv_vertices[static_cast<std::size_t>(a)];
        if (depth[static_cast<std::size_t>(w)] > d) {
          depth[static_cast<std::size_t>(w)] = d;
          next.push_back(w);
        }
      }
    frontier.swap(next);
  }
  return depth;
}

}  // namespace

SurfaceSample sample_surface(const Vertices& P, const Triangles& F, const Topology& topo, std::int64_t max_faces,
                             int patches, int margin) {
  SurfaceSample s;
  const std::int64_t nf = F.rows();
  s.whole = nf <= max_faces;
  const std::vector<std::uint8_t> take =
      s.whole ? std::vector<std::uint8_t>(static_cast<std::size_t>(nf), 1) : patch_faces(P, F, topo, max_faces, std::max(1, patches));

  // The sample's vertices, in the surface's order, and its faces.
  std::vector<std::int32_t> local(static_cast<std::size_t>(P.rows()), -1);
  std::int64_t faces = 0;
  for (std::int64_t f = 0; f < nf; ++f)
    if (take[static_cast<std::size_t>(f)]) {
      ++faces;
      for (int c = 0; c < 3; ++c) local[static_cast<std::size_t>(F(f, c))] = 0;
    }
  for (std::int32_t v = 0; v < static_cast<std::int32_t>(P.rows()); ++v)
    if (local[static_cast<std::size_t>(v)] == 0) {
      local[static_cast<std::size_t>(v)] = static_cast<std::int32_t>(s.vertex.size());
      s.vertex.push_back(v);
    }
  s.P.resize(static_cast<Eigen::Index>(s.vertex.size()), 3);
  for (std::size_t v = 0; v < s.vertex.size(); ++v) s.P.row(static_cast<Eigen::Index>(v)) = P.row(s.vertex[v]);
  s.F.resize(faces, 3);
  for (std::int64_t f = 0, k = 0; f < nf; ++f)
    if (take[static_cast<std::size_t>(f)]) {
      for (int c = 0; c < 3; ++c) s.F(k, c) = local[static_cast<std::size_t>(F(f, c))];
      ++k;
    }
  s.topo = Topology::build(s.F, static_cast<std::int32_t>(s.vertex.size()));

  const std::vector<int> depth = cut_depth(s, topo, take, margin);
  s.scored.assign(static_cast<std::size_t>(faces), 0);
  std::vector<std::uint8_t> used(s.vertex.size(), 0);
  for (std::int64_t f = 0; f < faces; ++f) {
    bool ok = true;
    for (int c = 0; c < 3; ++c) ok = ok && depth[static_cast<std::size_t>(s.F(f, c))] >= margin;
    if (!ok) continue;
    s.scored[static_cast<std::size_t>(f)] = 1;
    for (int c = 0; c < 3; ++c) used[static_cast<std::size_t>(s.F(f, c))] = 1;
  }
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) s.scored_vertices.push_back(static_cast<std::int32_t>(v));
  return s;
}

}  // namespace mdn
