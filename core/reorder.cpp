#include "core/reorder.h"

#include <algorithm>
#include <array>

namespace mdn {

namespace {

// Spreads the low 16 bits of x so that bit i lands on bit 3i.
std::uint64_t spread3(std::uint64_t x) {
  x &= 0xffff;
  x = (x | (x << 32)) & 0x1f00000000ffffULL;
  x = (x | (x << 16)) & 0x1f0000ff0000ffULL;
  x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
  x = (x | (x << 2)) & 0x1249249249249249ULL;
  return x;
}

// Faces sorted by the 48-bit Morton code of their centroid, quantised to 2^16 cells per axis
// of the centroids' bounding box. LSD radix sort, 4 passes of 12 bits: stable, so faces in one
// cell keep their input order (subdivided children stay together).
std::vector<std::int32_t> curve_order(const Vertices& V, const Triangles& F) {
  const auto nf = static_cast<std::size_t>(F.rows());
  Vertices C(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) C.row(f) = V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2));
  const Eigen::RowVector3d lo = C.colwise().minCoeff(), hi = C.colwise().maxCoeff();
  const double extent = (hi - lo).maxCoeff();
  const double scale = extent > 0 ? 65535.0 / extent : 0.0;  // one scale for all axes: cells stay cubes
  std::vector<std::uint64_t> key(nf), key_tmp(nf);
  std::vector<std::int32_t> order(nf), order_tmp(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    std::uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double q = (C(static_cast<Eigen::Index>(f), a) - lo(a)) * scale;
      code |= spread3(static_cast<std::uint64_t>(std::clamp(q, 0.0, 65535.0))) << a;
    }
    key[f] = code;
    order[f] = static_cast<std::int32_t>(f);
  }
  constexpr int kBits = 12;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  for (int shift = 0; shift < 48; shift += kBits) {
    std::array<std::size_t, kBuckets + 1> start{};
    for (std::size_t i = 0; i < nf; ++i) ++start[((key[i] >> shift) & (kBuckets - 1)) + 1];
    for (std::size_t b = 0; b < kBuckets; ++b) start[b + 1] += start[b];
    for (std::size_t i = 0; i < nf; ++i) {
      const std::size_t slot = start[(key[i] >> shift) & (kBuckets - 1)]++;
      key_tmp[slot] = key[i];
      order_tmp[slot] = order[i];
    }
    key.swap(key_tmp);
    order.swap(order_tmp);
  }
  return order;
}

// Faces breadth-first over vertex adjacency (faces sharing a vertex), each component from its
// lowest-numbered face, neighbours in the order of the vertex -> face lists.
std::vector<std::int32_t> breadth_first_order(const Triangles& F, std::int64_t nv) {
  const auto nf = static_cast<std::size_t>(F.rows());
  std::vector<std::int32_t> offsets(static_cast<std::size_t>(nv) + 1, 0), faces(3 * nf);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) ++offsets[static_cast<std::size_t>(F(f, c)) + 1];
  for (std::size_t v = 0; v + 1 < offsets.size(); ++v) offsets[v + 1] += offsets[v];
  {
    std::vector<std::int32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int c = 0; c < 3; ++c)
        faces[static_cast<std::size_t>(cursor[static_cast<std::size_t>(F(f, c))]++)] = static_cast<std::int32_t>(f);
  }
  // A vertex's list is walked once: after that every face on it is already queued, so a later
  // walk would add nothing (the order is the same; a third of the face checks).
  std::vector<std::int32_t> order;
  order.reserve(nf);
  std::vector<std::uint8_t> seen(nf, 0), walked(static_cast<std::size_t>(nv), 0);
  for (std::size_t root = 0; root < nf; ++root) {
    if (seen[root]) continue;
    seen[root] = 1;
    order.push_back(static_cast<std::int32_t>(root));
    for (std::size_t head = order.size() - 1; head < order.size(); ++head) {
      const std::int32_t f = order[head];
      for (int c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(F(f, c));
        if (walked[v]) continue;
        walked[v] = 1;
        for (std::int32_t k = offsets[v]; k < offsets[v + 1]; ++k) {
          const auto g = static_cast<std::size_t>(faces[static_cast<std::size_t>(k)]);
          if (!seen[g]) {
            seen[g] = 1;
            order.push_back(static_cast<std::int32_t>(g));
          }
        }
      }
    }
  }
  return order;
}

}  // namespace

LocalityOrder LocalityOrder::of(const TriMesh& mesh, OrderKind kind) {
  const auto nf = static_cast<std::size_t>(mesh.num_faces());
  const auto nv = static_cast<std::size_t>(mesh.num_vertices());
  LocalityOrder o;
  if (kind == OrderKind::Auto) kind = mesh.num_faces() >= kReorderMinFaces ? OrderKind::BreadthFirst : OrderKind::Input;
  if (kind == OrderKind::SpaceFillingCurve) {
    o.face_of_ = curve_order(mesh.V, mesh.F);
  } else if (kind == OrderKind::BreadthFirst) {
    o.face_of_ = breadth_first_order(mesh.F, mesh.num_vertices());
  } else {  // the identity, vertices included
    o.face_of_.resize(nf);
    o.vertex_of_.resize(nv);
    for (std::size_t f = 0; f < nf; ++f) o.face_of_[f] = static_cast<std::int32_t>(f);
    for (std::size_t v = 0; v < nv; ++v) o.vertex_of_[v] = static_cast<std::int32_t>(v);
    o.F_ = mesh.F;
    return o;
  }
  // Vertices in the order the ordered faces first reference them; then the unreferenced ones.
  std::vector<std::int32_t> new_id(nv, -1);
  o.vertex_of_.reserve(nv);
  o.F_.resize(mesh.F.rows(), 3);
  for (std::size_t k = 0; k < nf; ++k)
    for (int c = 0; c < 3; ++c) {
      const std::int32_t v = mesh.F(o.face_of_[k], c);
      std::int32_t& id = new_id[static_cast<std::size_t>(v)];
      if (id < 0) {
        id = static_cast<std::int32_t>(o.vertex_of_.size());
        o.vertex_of_.push_back(v);
      }
      o.F_(static_cast<Eigen::Index>(k), c) = id;
    }
  for (std::size_t v = 0; v < nv; ++v)
    if (new_id[v] < 0) o.vertex_of_.push_back(static_cast<std::int32_t>(v));
  return o;
}

Vertices LocalityOrder::to_order(const Vertices& V) const {
  Vertices W(V.rows(), 3);
  for (std::size_t k = 0; k < vertex_of_.size(); ++k) W.row(static_cast<Eigen::Index>(k)) = V.row(vertex_of_[k]);
  return W;
}

Vertices LocalityOrder::to_input(const Vertices& W) const {
  Vertices V(W.rows(), 3);
  for (std::size_t k = 0; k < vertex_of_.size(); ++k) V.row(vertex_of_[k]) = W.row(static_cast<Eigen::Index>(k));
  return V;
}

}  // namespace mdn
