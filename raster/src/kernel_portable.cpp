// kernel_portable.cpp: the coverage + depth kernel for any CPU (see raster_kernel.inc).
#include <algorithm>
#include <bit>
#include <cmath>

#include "pipeline.h"

namespace raster::detail {
namespace portable {
#include "raster_kernel.inc"
}  // namespace portable

namespace {
struct PortableKernel {
    template <DepthFormat Fmt, DepthFunc F, bool Write>
    static std::uint64_t rect(const SetupTri& tri, DepthRows depth, PixelRect r, bool stop_at_first) {
        return portable::raster_rect_t<Fmt, F, Write>(tri, depth, r, stop_at_first);
    }
    static void scan(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
        portable::stored_bounds(d, x0, y0, x1, y1, lo, hi);
    }
};
}  // namespace

RectKernel select_rect_kernel_portable(const DepthState& state, bool hiz) {
    return portable::select_rect_kernel_with<PortableKernel>(state, hiz);
}

std::uint64_t raster_rect_portable(const SetupTri& tri, const DepthState& state, DepthRows depth,
                                   PixelRect rect, bool stop_at_first) {
    return select_rect_kernel_portable(state, false)(tri, depth, rect, nullptr, stop_at_first);
}

std::uint64_t raster_rect_hiz_portable(const SetupTri& tri, const DepthState& state, DepthRows depth,
                                       PixelRect rect, HizTile& hiz, bool stop_at_first) {
    return select_rect_kernel_portable(state, true)(tri, depth, rect, &hiz, stop_at_first);
}

}  // namespace raster::detail
