// Internal to mdn_io: welding of vertex copies by position.
//
// Real assets split a surface vertex into several copies wherever an attribute is
// discontinuous (UV seams, hard normals, per-primitive materials), and those copies often
// differ in the last bits of their float32 coordinates. Denoising each copy on its own
// would tear the surface open at every seam, so copies are welded first and every copy
// gets its welded vertex's new position back.
#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"

namespace mdn::io::detail {

struct Weld {
  Vertices V;                        // #unique by 3, the first copy's position
  std::vector<std::int32_t> map;     // #P: input point -> welded vertex
};

// Two points weld when they are within `relative_tolerance` x max(bounding-box diagonal,
// largest |coordinate|) of each other (a few float32 ulps at the default of 1e-6).
// Deterministic: the result depends only on the input order.
// `cancel` (the job's time limit and DELETE) is polled every few thousand points.
Weld weld_positions(const Vertices& P, double relative_tolerance = 1e-6, ProgressObserver* cancel = nullptr);

// Area-weighted normals accumulated per "slot": corner k of face f contributes the
// (unnormalised) face normal to slot corner_slot[3 f + k] (or to none if negative). Used to
// recompute normals while keeping the input's splits (hard edges): each slot is one normal
// of the file. Returns #slots by 3 unit vectors, zero rows for slots no face used.
Vertices accumulate_normals(const Vertices& V, const Triangles& F, const std::vector<std::int64_t>& corner_slot,
                            std::int64_t slots);

}  // namespace mdn::io::detail
