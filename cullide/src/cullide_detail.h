// cullide_detail.h (private): view helpers of cullide.cpp shared with quick_cullide.cpp.
#pragma once

#include <cstdint>
#include <span>

#include "cullide/visibility.h"
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
// world units before and after along the axis, of `size` pixels and `format`.
[[nodiscard]] Result<raster::OrthoView> make_view(int axis, const Aabb& bounds, double extra_depth, ViewSize size,
                                                  raster::DepthFormat format);

// A GL-exact view's clip-space depth as the batch's rules want it, rounded to float once: GL's z
// in [-1, 1] as it is, Vulkan's (z + 1) / 2 in [0, 1] (the same window depth).
[[nodiscard]] inline float gl_exact_clip_depth(double clip_z, raster::RasterRules rules) {
    return static_cast<float>(rules == raster::RasterRules::Vulkan ? (clip_z + 1.0) * 0.5 : clip_z);
}

// The checks every visibility method makes before drawing anything: option ranges, a valid scene,
// `active` strictly increasing and in range, and every active object's coordinates inside the
// exact range (with the ground truth's message, so all methods refuse alike). Returns the views'
// size: the one place a method's resolution is checked and its default applied.
[[nodiscard]] Result<ViewSize> check_visibility_inputs(std::span<const Mesh> objects,
                                                       std::span<const std::uint32_t> active,
                                                       const VisibilityOptions& o, VisibilityMode mode);

}  // namespace cullide::detail
