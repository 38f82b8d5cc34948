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

std::uint64_t raster_rect_hiz_portable(const SetupTri& tri, const DepthState& state, DepthRows depth,
                                       PixelRect rect, HizTile& hiz, bool stop_at_first) {
    const auto plain = [&]<DepthFormat Fmt, DepthFunc F, bool Write>(PixelRect r) {
        return portable::raster_rect_t<Fmt, F, Write>(tri, depth, r, stop_at_first);
    };
    const auto scan = [](DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
        portable::stored_bounds(d, x0, y0, x1, y1, lo, hi);
    };
    return portable::raster_rect_hiz_with(tri, state, depth, rect, hiz, stop_at_first, plain, scan);
}

}  // namespace raster::detail
