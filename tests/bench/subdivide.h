// 1-to-4 midpoint subdivision for the benchmarks' large meshes (table1_bench --scale,
// scale_bench): Loop subdivision's connectivity with midpoint positions, so the surface is
// unchanged and #F grows x4 per level. New vertices are appended after the old ones and each
// face's four children are consecutive, as subdivision tools and exporters write them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/mesh.h"

namespace mdn::bench {

inline TriMesh midpoint_subdivide(const TriMesh& m) {
  std::unordered_map<std::uint64_t, std::int32_t> mid;
  mid.reserve(static_cast<std::size_t>(m.num_faces()) * 2);
  TriMesh out;
  out.V.resize(m.num_vertices() + 2 * m.num_faces(), 3);  // an upper bound (#E <= 1.5 #F), trimmed below
  out.V.topRows(m.num_vertices()) = m.V;
  Eigen::Index count = m.num_vertices();
  auto midpoint = [&](std::int32_t a, std::int32_t b) {
    const auto [lo, hi] = std::minmax(a, b);
    const std::uint64_t key = (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi);
    const auto [it, inserted] = mid.emplace(key, static_cast<std::int32_t>(count));
    if (inserted) out.V.row(count++) = 0.5 * (m.V.row(a) + m.V.row(b));
    return it->second;
  };
  out.F.resize(4 * m.num_faces(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const std::int32_t a = m.F(f, 0), b = m.F(f, 1), c = m.F(f, 2);
    const std::int32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.F.row(4 * f) << a, ab, ca;
    out.F.row(4 * f + 1) << ab, b, bc;
    out.F.row(4 * f + 2) << ca, bc, c;
    out.F.row(4 * f + 3) << ab, bc, ca;
  }
  out.V.conservativeResize(count, 3);
  return out;
}

}  // namespace mdn::bench
