#include "core/io/weld.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/io/detail.h"

namespace mdn::io::detail {

Weld weld_positions(const Vertices& P, double relative_tolerance, ProgressObserver* cancel) {
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
  // Grid hashing with cells a little wider than 2 tol: along each axis a point's partners
  // (within tol) lie in its own cell or in the neighbour on the side of the cell's nearer
  // half, so 8 cells hold them all. The table is open-addressed on the exact cell; each cell
  // chains its representatives (head, next).
  const double cell = tol > 0 && std::isfinite(tol) ? 2 * tol * (1 + 1e-6) : 1.0;
  struct Slot {  // 16 bytes: four to a cache line
    std::int32_t x, y, z;
    std::int32_t head = -1;  // -1: empty slot
  };
  std::size_t capacity = 16;
  while (capacity < 2 * static_cast<std::size_t>(n)) capacity *= 2;
  std::vector<Slot> table(capacity);
  const auto home_of = [&](std::int32_t x, std::int32_t y, std::int32_t z) {
    std::uint64_t h = (static_cast<std::uint64_t>(x) * 73856093ULL) ^ (static_cast<std::uint64_t>(y) * 19349663ULL) ^
                      (static_cast<std::uint64_t>(z) * 83492791ULL);
    h ^= h >> 29;
    return static_cast<std::size_t>(h * 0x9E3779B97F4A7C15ULL) & (capacity - 1);
  };
  const auto slot_at = [&](std::size_t k, std::int32_t x, std::int32_t y, std::int32_t z) -> Slot& {
    for (;; k = (k + 1) & (capacity - 1)) {
      Slot& s = table[k];
      if (s.head < 0 || (s.x == x && s.y == y && s.z == z)) return s;
    }
  };
  std::vector<Eigen::Index> representatives;
  std::vector<std::int32_t> next;  // per representative: the previous one in its cell, or -1
  representatives.reserve(static_cast<std::size_t>(n));
  next.reserve(static_cast<std::size_t>(n));
  CancelPoll poll(cancel);
  for (Eigen::Index i = 0; i < n; ++i) {
    poll.poll();
    std::int32_t c[3], side[3];
    for (int a = 0; a < 3; ++a) {
      // |u| <= 5e5 for finite coordinates and a finite tolerance; a non-finite one (which the
      // decoders refuse later) makes the tolerance infinite and the cell 1: clamp the cell index
      // so it and its neighbours stay representable (the distance test decides the weld).
      const double u = P(i, a) / cell, f = std::isfinite(u) ? std::clamp(std::floor(u), -0x1p30, 0x1p30) : 0;
      c[a] = static_cast<std::int32_t>(f);
      side[a] = u - f < 0.5 ? -1 : 1;
    }
    // The eight cells' home slots first, each prefetched: their cache misses overlap.
    std::size_t home[8];
    for (int corner = 0; corner < 8; ++corner) {
      home[corner] = home_of(c[0] + ((corner & 1) ? side[0] : 0), c[1] + ((corner & 2) ? side[1] : 0),
                             c[2] + ((corner & 4) ? side[2] : 0));
      __builtin_prefetch(&table[home[corner]]);
    }
    std::int32_t found = std::numeric_limits<std::int32_t>::max();
    for (int corner = 0; corner < 8; ++corner) {
      const Slot& s = slot_at(home[corner], c[0] + ((corner & 1) ? side[0] : 0), c[1] + ((corner & 2) ? side[1] : 0),
                              c[2] + ((corner & 4) ? side[2] : 0));
      for (std::int32_t w = s.head; w >= 0; w = next[static_cast<std::size_t>(w)])
        if (w < found && (P.row(representatives[static_cast<std::size_t>(w)]) - P.row(i)).norm() <= tol) found = w;
    }
    if (found == std::numeric_limits<std::int32_t>::max()) {
      found = static_cast<std::int32_t>(representatives.size());
      representatives.push_back(i);
      Slot& s = slot_at(home[0], c[0], c[1], c[2]);
      s.x = c[0], s.y = c[1], s.z = c[2];
      next.push_back(s.head);
      s.head = found;
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
