// Consistent winding (decision 34). The method reads face normals: a face wound against its
// neighbours points its normal inwards, reads as a 180-degree crease and is "denoised" into a
// spike. Some exporters and soups write such faces.
#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace mdn {

// The faces to turn (swap two corners) so that every connected piece is wound one way across
// its manifold edges: the way most of its faces already are (ties: the way of its lowest face).
// Empty when the winding is consistent. Edges with three or more faces do not connect; a
// non-orientable piece (a Moebius strip) keeps the winding its breadth-first walk gives.
std::vector<std::int32_t> faces_to_turn(const Triangles& F, std::int32_t num_vertices);

}  // namespace mdn
