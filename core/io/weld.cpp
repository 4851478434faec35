#include "core/io/weld.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace mdn::io::detail {

Weld weld_positions(const Vertices& P, double relative_tolerance) {
  Weld weld;
  const Eigen::Index n = P.rows();
  weld.map.assign(static_cast<std::size_t>(n), 0);
  if (n == 0) {
    weld.V.resize(0, 3);
    return weld;
  }
  const double diagonal = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
  const double magnitude = P.cwiseAbs().maxCoeff();
  const double tol = relative_tolerance * std::max(diagonal, magnitude);
  // Grid hashing with cells of size `tol`: a point's partners lie in the 27 cells around it.
  const double cell = tol > 0 && std::isfinite(tol) ? tol : 1.0;
  auto key_of = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x) * 73856093ULL) ^ (static_cast<std::uint64_t>(y) * 19349663ULL) ^
           (static_cast<std::uint64_t>(z) * 83492791ULL);
  };
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> grid;
  grid.reserve(static_cast<std::size_t>(n));
  std::vector<Eigen::Index> representatives;
  representatives.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::int64_t cx = static_cast<std::int64_t>(std::floor(P(i, 0) / cell));
    const std::int64_t cy = static_cast<std::int64_t>(std::floor(P(i, 1) / cell));
    const std::int64_t cz = static_cast<std::int64_t>(std::floor(P(i, 2) / cell));
    std::int32_t found = std::numeric_limits<std::int32_t>::max();
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key_of(cx + dx, cy + dy, cz + dz));
          if (it == grid.end()) continue;
          for (const std::int32_t w : it->second)
            if (w < found && (P.row(representatives[static_cast<std::size_t>(w)]) - P.row(i)).norm() <= tol) found = w;
        }
    if (found == std::numeric_limits<std::int32_t>::max()) {
      found = static_cast<std::int32_t>(representatives.size());
      representatives.push_back(i);
      grid[key_of(cx, cy, cz)].push_back(found);
    }
    weld.map[static_cast<std::size_t>(i)] = found;
  }
  weld.V.resize(static_cast<Eigen::Index>(representatives.size()), 3);
  for (std::size_t w = 0; w < representatives.size(); ++w) weld.V.row(static_cast<Eigen::Index>(w)) = P.row(representatives[w]);
  return weld;
}

Vertices accumulate_normals(const Vertices& V, const Triangles& F, const std::vector<std::int64_t>& corner_slot,
                            std::int64_t slots) {
  Vertices N = Vertices::Zero(slots, 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Vec3 n = (b - a).cross(c - a);  // length = twice the area: area weighting
    for (int k = 0; k < 3; ++k) {
      const std::int64_t s = corner_slot[static_cast<std::size_t>(f * 3 + k)];
      if (s >= 0) N.row(s) += n.transpose();
    }
  }
  for (Eigen::Index s = 0; s < N.rows(); ++s) {
    const double len = N.row(s).norm();
    if (len > 0 && std::isfinite(len)) N.row(s) /= len;
    else N.row(s).setZero();
  }
  return N;
}

}  // namespace mdn::io::detail
