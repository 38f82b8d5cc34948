// kernel_select.cpp: which GL-exact kernel runs a rectangle (raster_rect, pipeline.h): the AVX2 one
// when the caller, the CPU and the environment allow it, else the portable one (bit-identical).
#include <cstdlib>

#include "pipeline.h"

namespace raster::detail {

bool simd_allowed_by_environment() {
    static const bool ok = [] {
        const char* v = std::getenv("CULLIDE_RASTER_NO_SIMD");
        return v == nullptr || v[0] == '\0' || (v[0] == '0' && v[1] == '\0');
    }();
    return ok;
}

RectKernel select_rect_kernel(const DepthState& state, bool allow_simd, bool hiz) {
    if (allow_simd && kernel_avx2_available() && simd_allowed_by_environment())
        return select_rect_kernel_avx2(state, hiz);
    return select_rect_kernel_portable(state, hiz);
}

std::uint64_t raster_rect(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                          bool allow_simd, bool stop_at_first) {
    if (allow_simd && kernel_avx2_available() && simd_allowed_by_environment())
        return raster_rect_avx2(tri, state, depth, rect, stop_at_first);
    return raster_rect_portable(tri, state, depth, rect, stop_at_first);
}

std::uint64_t raster_rect_hiz(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                              HizTile& hiz, bool allow_simd, bool stop_at_first) {
    if (allow_simd && kernel_avx2_available() && simd_allowed_by_environment())
        return raster_rect_hiz_avx2(tri, state, depth, rect, hiz, stop_at_first);
    return raster_rect_hiz_portable(tri, state, depth, rect, hiz, stop_at_first);
}

}  // namespace raster::detail
