#include "core/orient.h"

#include <algorithm>

#include "core/topology.h"

namespace mdn {

namespace {

// Vertex -> faces, compressed rows (core/topology.h).
struct VertexFaces {
  std::vector<std::int32_t> offsets, faces;
};

// The face across edge (a -> b) of face f, if exactly one other face has that edge; `same` says
// whether it runs the edge the same way (a -> b: wound against f).
struct Across {
  std::int32_t face = -1;
  bool same = false;
};

Across across(const Triangles& F, const VertexFaces& vf, std::int32_t f, std::int32_t a, std::int32_t b) {
  Across found;
  int count = 0;
  for (std::int32_t k = vf.offsets[static_cast<std::size_t>(a)]; k < vf.offsets[static_cast<std::size_t>(a) + 1]; ++k) {
    const std::int32_t g = vf.faces[static_cast<std::size_t>(k)];
    if (g == f) continue;
    for (int c = 0; c < 3; ++c) {
      if (F(g, c) != a) continue;
      const bool forward = F(g, (c + 1) % 3) == b, backward = F(g, (c + 2) % 3) == b;
      if (forward || backward) {
        found = {g, forward};
        ++count;
      }
      break;
    }
  }
  return count == 1 ? found : Across{};
}

}  // namespace

std::vector<std::int32_t> faces_to_turn(const Triangles& F, std::int32_t num_vertices) {
  VertexFaces vf;
  build_vertex_faces(F, num_vertices, vf.offsets, vf.faces);
  const auto f_count = static_cast<std::int32_t>(F.rows());
  // Most meshes are consistent: one look at every edge, nothing else.
  bool consistent = true;
  for (std::int32_t f = 0; f < f_count && consistent; ++f)
    for (int c = 0; c < 3 && consistent; ++c) consistent = !across(F, vf, f, F(f, c), F(f, (c + 1) % 3)).same;
  if (consistent) return {};
  // Breadth-first over each piece: a neighbour wound the same way as its edge is turned
  // relative to the face it was reached from.
  std::vector<std::int8_t> turn(static_cast<std::size_t>(f_count), -1);
  std::vector<std::int32_t> piece, out;
  for (std::int32_t seed = 0; seed < f_count; ++seed) {
    if (turn[static_cast<std::size_t>(seed)] >= 0) continue;
    piece.assign(1, seed);
    turn[static_cast<std::size_t>(seed)] = 0;
    std::size_t turned = 0;
    for (std::size_t q = 0; q < piece.size(); ++q) {
      const std::int32_t f = piece[q];
      const bool f_turned = turn[static_cast<std::size_t>(f)] == 1;
      for (int c = 0; c < 3; ++c) {
        const Across x = across(F, vf, f, F(f, c), F(f, (c + 1) % 3));
        if (x.face < 0 || turn[static_cast<std::size_t>(x.face)] >= 0) continue;
        turn[static_cast<std::size_t>(x.face)] = static_cast<std::int8_t>(f_turned != x.same);
        turned += f_turned != x.same;
        piece.push_back(x.face);
      }
    }
    // Keep the winding of most of the piece.
    const bool invert = 2 * turned > piece.size();
    for (const std::int32_t f : piece)
      if ((turn[static_cast<std::size_t>(f)] == 1) != invert) out.push_back(f);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace mdn
