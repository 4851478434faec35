// What the libFuzzer harnesses share: how a finding is reported, the formats they write, and
// the checks every decoded document must pass.
#pragma once

#include <cstdio>
#include <cstdlib>

#include "core/io/document.h"

namespace mdn::fuzz {

// A finding: printed, then abort() so that libFuzzer keeps the input.
[[noreturn]] inline void finding(const char* what, const char* detail) {
  std::fprintf(stderr, "FINDING: %s: %s\n", what, detail);
  std::abort();
}

inline constexpr io::Format kFormats[] = {io::Format::Off, io::Format::Obj, io::Format::Ply, io::Format::Drc,
                                          io::Format::Glb, io::Format::Gltf, io::Format::Stl};

// Every surface #V x 3 and #F x 3, finite, its indices in range.
inline void check_surfaces(io::MeshDocument& doc, const char* stage) {
  for (const TriMesh& m : doc.surfaces()) {
    if (m.V.cols() != 3 || m.F.cols() != 3) finding(stage, "a surface is not #V x 3 / #F x 3");
    if (!m.V.allFinite()) finding(stage, "a surface has a non-finite coordinate");
    if (m.F.size() > 0 && (m.F.minCoeff() < 0 || m.F.maxCoeff() >= m.V.rows())) finding(stage, "a face index is out of range");
  }
}

}  // namespace mdn::fuzz
