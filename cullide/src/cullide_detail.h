// cullide_detail.h (private): view helpers of cullide.cpp shared with quick_cullide.cpp.
#pragma once

#include "cullide/cullide.h"
#include "cullide/mesh.h"
#include "cullide/result.h"
#include "raster/transform.h"

namespace cullide::detail {

// The smallest box holding both (an empty box is the identity).
[[nodiscard]] Aabb unite(const Aabb& a, const Aabb& b);
// Grows [lo, hi] by a margin that keeps geometry on its faces inside the clip volume after the
// clip coordinates are rounded to float.
void widen(double& lo, double& hi);
// The orthographic view along `axis` fitted to `bounds` (widened as above), with `extra_depth` more
// world units before and after along the axis; resolution and depth format from `o`.
[[nodiscard]] Result<raster::OrthoView> make_view(int axis, const Aabb& bounds, double extra_depth,
                                                  const CullideOptions& o);

}  // namespace cullide::detail
