// kernel_portable.cpp: the coverage + depth kernel for any CPU (see raster_kernel.inc).
#include <algorithm>
#include <bit>
#include <cmath>

#include "pipeline.h"

namespace raster::detail {
namespace portable {
#include "raster_kernel.inc"
}  // namespace portable

std::uint64_t raster_rect_portable(const SetupTri& tri, const DepthState& state, DepthRows depth,
                                   PixelRect rect, bool stop_at_first) {
    return portable::raster_rect_kernel(tri, state, depth, rect, stop_at_first);
}

}  // namespace raster::detail
