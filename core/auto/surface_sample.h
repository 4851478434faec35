// A bounded piece of a surface (Search scores its candidates there and Auto reads the descriptors
// of a large surface there; docs/design/decisions.md, decisions 21 and 33).
#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

struct SurfaceSample {
  Vertices P;                          // #v by 3, the sampled vertices' positions (the caller's frame)
  Triangles F;                         // #f by 3, indices into P
  Topology topo;                       // of F
  std::vector<std::int32_t> vertex;    // sampled vertex -> vertex of the surface
  std::vector<std::uint8_t> scored;    // #f: 1 for faces away from the sample's cut (scored)
  std::vector<std::int32_t> scored_vertices;  // sample vertices of scored faces, ascending
  bool whole = true;                   // the sample is the whole surface
};

// The whole surface if it has at most max_faces faces; otherwise `patches` patches of about
// max_faces / patches faces each, grown breadth-first over vertex-sharing faces from seeds
// spread evenly along a Morton order of the face centroids. Faces within `margin` rings of
// the cut are not scored (their neighbourhoods are truncated). Deterministic.
SurfaceSample sample_surface(const Vertices& P, const Triangles& F, const Topology& topo, std::int64_t max_faces,
                             int patches = 16, int margin = 2);

}  // namespace mdn
