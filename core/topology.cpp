#include "core/topology.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <numeric>

#include "core/parallel.h"

namespace mdn {
namespace {

struct HalfEdge {
  std::int32_t lo, hi;      // undirected key
  std::int32_t from, to;    // as traversed by the face
  std::int32_t opposite;    // third vertex of the face
  std::int32_t face;
};

// Turns per-element counts into CSR offsets.
std::vector<std::int32_t> offsets_from_counts(const std::vector<std::int32_t>& counts) {
  std::vector<std::int32_t> offsets(counts.size() + 1, 0);
  std::partial_sum(counts.begin(), counts.end(), offsets.begin() + 1);
  return offsets;
}

// The half-edges of F (none for a repeated index), in (lo, hi, face) order: a counting sort
// by the smaller vertex (O(n), straight from F), then each small bucket by (hi, face). A bucket
// of up to 16 is sorted by insertion, as std::sort does below 16 elements (libstdc++), so the
// order is that of one comparison sort on (lo, hi, face) at a fraction of its cost.
std::vector<HalfEdge> sorted_half_edges(const Triangles& F, std::int32_t num_vertices, Executor* executor) {
  const auto num_faces = static_cast<std::int32_t>(F.rows());
  std::vector<std::int32_t> start(static_cast<std::size_t>(num_vertices) + 1, 0);
  for (std::int32_t f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) != F(f, (k + 1) % 3)) ++start[static_cast<std::size_t>(std::min(F(f, k), F(f, (k + 1) % 3))) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<HalfEdge> sorted(static_cast<std::size_t>(start.back()));
  std::vector<std::int32_t> cursor(start.begin(), start.end() - 1);
  for (std::int32_t f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = F(f, k), b = F(f, (k + 1) % 3), c = F(f, (k + 2) % 3);
      if (a == b) continue;  // a face with a repeated index has no edge here
      sorted[static_cast<std::size_t>(cursor[static_cast<std::size_t>(std::min(a, b))]++)] = {std::min(a, b), std::max(a, b), a, b, c, f};
    }
  const auto less = [](const HalfEdge& x, const HalfEdge& y) { return x.hi != y.hi ? x.hi < y.hi : x.face < y.face; };
  auto sort_buckets = [&](std::int64_t begin, std::int64_t end) {  // buckets are disjoint: any split
    for (auto v = static_cast<std::size_t>(begin); v < static_cast<std::size_t>(end); ++v) {
      HalfEdge* first = sorted.data() + start[v];
      HalfEdge* last = sorted.data() + start[v + 1];
      if (last - first < 2) continue;  // nothing to order (and first + 1 past an empty array is undefined)
      if (last - first > 16) {
        std::sort(first, last, less);
        continue;
      }
      for (HalfEdge* i = first + 1; i < last; ++i)  // stable insertion sort
        for (HalfEdge* j = i; j > first && less(*j, *(j - 1)); --j) std::swap(*j, *(j - 1));
    }
  };
  if (executor)
    executor->parallel_for(num_vertices, 65536, sort_buckets);
  else
    sort_buckets(0, num_vertices);
  return sorted;
}

// rows as an Eigen matrix, one row each.
template <std::size_t N>
Eigen::Matrix<std::int32_t, Eigen::Dynamic, static_cast<int>(N), Eigen::RowMajor> to_matrix(
    const std::vector<std::array<std::int32_t, N>>& rows) {
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, static_cast<int>(N), Eigen::RowMajor> m(static_cast<Eigen::Index>(rows.size()), N);
  static_assert(sizeof(std::array<std::int32_t, N>) == N * sizeof(std::int32_t));
  if (!rows.empty()) std::memcpy(m.data(), rows.data(), rows.size() * sizeof(rows[0]));  // the same row-major layout
  return m;
}

// The undirected edges, classified by multiplicity; unique_edges lists every edge once, in
// sorted order.
struct EdgeLists {
  std::vector<std::array<std::int32_t, 4>> interior;
  std::vector<std::array<std::int32_t, 2>> interior_faces, boundary, nonmanifold, unique_edges;
};

void classify_edges(const std::vector<HalfEdge>& half, EdgeLists& edges) {
  auto& [interior, interior_faces, boundary, nonmanifold, unique_edges] = edges;
  interior.reserve(half.size() / 2);  // a closed manifold mesh: two half-edges per edge
  interior_faces.reserve(half.size() / 2);
  unique_edges.reserve(half.size() / 2);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    const std::size_t count = j - i;
    unique_edges.push_back({half[i].lo, half[i].hi});
    const HalfEdge& h0 = half[i];
    const HalfEdge& h1 = half[std::min(i + 1, half.size() - 1)];
    // Two faces with four distinct vertices (e1, e2, e3, e4): a proper manifold edge.
    if (count == 2 && h0.opposite != h1.opposite && h0.opposite != h1.from && h0.opposite != h1.to &&
        h1.opposite != h0.from && h1.opposite != h0.to) {
      // S(e) = p_e1 - p_e2 + p_e3 - p_e4, (e1, e3) the edge, e2/e4 the opposite vertices.
      interior.push_back({h0.from, h0.opposite, h0.to, h1.opposite});
      interior_faces.push_back({h0.face, h1.face});
    } else if (count == 1) {
      boundary.push_back({h0.lo, h0.hi});
    } else {
      // Three or more faces, two copies of one triangle, or a degenerate face on the edge:
      // no shaping term (core/README.md, decision 2).
      nonmanifold.push_back({h0.lo, h0.hi});
    }
    i = j;
  }
}

// Vertex -> vertices from the unique edges (sorted, so deterministic); counts: #V scratch.
void build_vertex_vertices(const std::vector<std::array<std::int32_t, 2>>& unique_edges, Topology& t,
                           std::vector<std::int32_t>& counts) {
  std::fill(counts.begin(), counts.end(), 0);
  for (const auto& [a, b] : unique_edges) {
    ++counts[static_cast<std::size_t>(a)];
    ++counts[static_cast<std::size_t>(b)];
  }
  t.vv_offsets = offsets_from_counts(counts);
  t.vv_vertices.assign(static_cast<std::size_t>(t.vv_offsets.back()), 0);
  std::vector<std::int32_t> cursor(t.vv_offsets.begin(), t.vv_offsets.end() - 1);
  for (const auto& [a, b] : unique_edges) {
    t.vv_vertices[static_cast<std::size_t>(cursor[static_cast<std::size_t>(a)]++)] = b;
    t.vv_vertices[static_cast<std::size_t>(cursor[static_cast<std::size_t>(b)]++)] = a;
  }
}

// N(f) for the faces [begin, end), sorted, appended to `out`; each list's length into
// t.ff_offsets[f + 1]. The faces of each vertex are listed in ascending order, so N(f) is a
// three-way merge of f's vertices' lists, duplicates and f itself dropped: no sort, no mark.
void gather_face_faces(const Triangles& F, Topology& t, std::int64_t begin, std::int64_t end, std::vector<std::int32_t>& out) {
  out.reserve(static_cast<std::size_t>(end - begin) * 13);
  const std::int32_t* faces = t.vf_faces.data();
  const std::int32_t* offsets = t.vf_offsets.data();
  constexpr std::int32_t kDone = std::numeric_limits<std::int32_t>::max();
  for (std::int64_t ff = begin; ff < end; ++ff) {
    const auto f = static_cast<std::int32_t>(ff);
    const auto first = out.size();
    const std::int32_t *a = faces + offsets[F(f, 0)], *a_end = faces + offsets[F(f, 0) + 1];
    const std::int32_t *b = faces + offsets[F(f, 1)], *b_end = faces + offsets[F(f, 1) + 1];
    const std::int32_t *c = faces + offsets[F(f, 2)], *c_end = faces + offsets[F(f, 2) + 1];
    if (F(f, 1) == F(f, 0)) b = b_end;  // a repeated vertex: its list once
    if (F(f, 2) == F(f, 0) || F(f, 2) == F(f, 1)) c = c_end;
    for (;;) {
      const std::int32_t x = a < a_end ? *a : kDone, y = b < b_end ? *b : kDone, z = c < c_end ? *c : kDone;
      const std::int32_t g = std::min(x, std::min(y, z));
      if (g == kDone) break;
      a += x == g;
      b += y == g;
      c += z == g;
      if (g != f) out.push_back(g);
    }
    t.ff_offsets[static_cast<std::size_t>(f) + 1] = static_cast<std::int32_t>(out.size() - first);
  }
}

// Face -> vertex-adjacent faces N(i), itself excluded (core/README.md, decision 9).
// One pass over the faces, split into one contiguous range per thread when an executor is
// given (decision 28): each range gathers its lists into its own buffer, then the buffers are
// concatenated in order. The lists do not depend on the split.
void build_face_faces(const Triangles& F, Topology& t, Executor* executor) {
  t.ff_offsets.assign(static_cast<std::size_t>(t.num_faces) + 1, 0);
  const int parts = executor ? std::max(1, executor->threads()) : 1;
  std::vector<std::vector<std::int32_t>> lists(static_cast<std::size_t>(parts));
  if (parts > 1 && t.num_faces >= 2 * parts) {
    executor->parallel_for(t.num_faces, [&](std::int64_t begin, std::int64_t end) {
      // parallel_for(n, fn) cuts [0, n) into exactly threads() ranges: find ours by its start.
      const auto part = static_cast<std::size_t>((begin * parts) / t.num_faces);
      gather_face_faces(F, t, begin, end, lists[std::min(part, lists.size() - 1)]);
    });
  } else {
    gather_face_faces(F, t, 0, t.num_faces, lists[0]);
  }
  std::partial_sum(t.ff_offsets.begin(), t.ff_offsets.end(), t.ff_offsets.begin());
  t.ff_faces.reserve(static_cast<std::size_t>(t.ff_offsets.back()));
  for (auto& list : lists) {
    t.ff_faces.insert(t.ff_faces.end(), list.begin(), list.end());
    list = {};
  }
}

}  // namespace

void build_vertex_faces(const Triangles& F, std::int32_t num_vertices, std::vector<std::int32_t>& offsets,
                        std::vector<std::int32_t>& faces) {
  const auto num_faces = static_cast<std::int32_t>(F.rows());
  auto distinct = [&](std::int32_t f, int k) {
    for (int m = 0; m < k; ++m)
      if (F(f, m) == F(f, k)) return false;
    return true;
  };
  std::vector<std::int32_t> counts(static_cast<std::size_t>(num_vertices), 0);
  for (std::int32_t f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k)
      if (distinct(f, k)) ++counts[static_cast<std::size_t>(F(f, k))];
  offsets = offsets_from_counts(counts);
  faces.assign(static_cast<std::size_t>(offsets.back()), 0);
  std::vector<std::int32_t> cursor(offsets.begin(), offsets.end() - 1);
  for (std::int32_t f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k)
      if (distinct(f, k)) faces[static_cast<std::size_t>(cursor[static_cast<std::size_t>(F(f, k))]++)] = f;
}

Topology Topology::build(const Triangles& F, std::int32_t num_vertices, Executor* executor) {
  Topology t;
  t.num_vertices = num_vertices;
  t.num_faces = static_cast<std::int32_t>(F.rows());
  // Edges: sort half-edges by undirected key, classify by multiplicity. `half` and `edges`
  // live to the end, as in the single function this was: freeing them sooner shifts the heap
  // layout (peak RSS +3 MiB, a slower vertex update on a 300k-face mesh).
  const std::vector<HalfEdge> half = sorted_half_edges(F, num_vertices, executor);
  EdgeLists edges;
  classify_edges(half, edges);
  t.interior_edges = to_matrix<4>(edges.interior);
  t.edge_faces = to_matrix<2>(edges.interior_faces);
  t.boundary_edges = to_matrix<2>(edges.boundary);
  t.nonmanifold_edges = to_matrix<2>(edges.nonmanifold);
  build_vertex_faces(F, num_vertices, t.vf_offsets, t.vf_faces);
  std::vector<std::int32_t> counts(static_cast<std::size_t>(num_vertices), 0);
  build_vertex_vertices(edges.unique_edges, t, counts);
  build_face_faces(F, t, executor);
  return t;
}

double Topology::mean_edge_length(const Vertices& V) const {
  // vv lists a vertex's neighbours in the order of the sorted unique edges, so (i, j > i) for
  // ascending i visits the edges in mean_edge_length(V, F)'s order.
  double sum = 0;
  std::int64_t count = 0;
  for (std::size_t i = 0; i + 1 < vv_offsets.size(); ++i)
    for (std::int32_t k = vv_offsets[i]; k < vv_offsets[i + 1]; ++k) {
      const std::int32_t j = vv_vertices[static_cast<std::size_t>(k)];
      if (j <= static_cast<std::int32_t>(i)) continue;
      sum += (V.row(static_cast<Eigen::Index>(i)) - V.row(j)).norm();
      ++count;
    }
  return count ? sum / static_cast<double>(count) : 0;
}

std::vector<bool> Topology::boundary_vertex_mask() const {
  std::vector<bool> mask(static_cast<std::size_t>(num_vertices), false);
  for (Eigen::Index e = 0; e < boundary_edges.rows(); ++e)
    for (int k = 0; k < 2; ++k) mask[static_cast<std::size_t>(boundary_edges(e, k))] = true;
  for (Eigen::Index e = 0; e < nonmanifold_edges.rows(); ++e)
    for (int k = 0; k < 2; ++k) mask[static_cast<std::size_t>(nonmanifold_edges(e, k))] = true;
  return mask;
}

}  // namespace mdn
