// kernel_select.cpp: which GL-exact kernel runs a rectangle (raster_rect, pipeline.h): the AVX-512
// one, else the AVX2 one, when the caller, the CPU and the environment allow it, else the portable
// one (all bit-identical).
#include <cstdlib>

#include "pipeline.h"
#include "raster/command_batch.h"

namespace raster::detail {
namespace {
// A switch variable that is unset, empty or "0" (off).
bool env_switch_off(const char* name) {
    const char* v = std::getenv(name);
    return v == nullptr || v[0] == '\0' || (v[0] == '0' && v[1] == '\0');
}
}  // namespace

bool simd_allowed_by_environment() {
    static const bool ok = env_switch_off("CULLIDE_RASTER_NO_SIMD");
    return ok;
}

bool avx512_allowed_by_environment() {
    static const bool ok = env_switch_off("CULLIDE_RASTER_NO_AVX512");
    return ok;
}

namespace {
enum class Kernel { Portable, Avx2, Avx512 };
Kernel kernel_for(bool allow_simd) {
    if (!allow_simd || !simd_allowed_by_environment()) return Kernel::Portable;
    if (kernel_avx512_available() && avx512_allowed_by_environment()) return Kernel::Avx512;
    return kernel_avx2_available() ? Kernel::Avx2 : Kernel::Portable;
}
}  // namespace

RectKernel select_rect_kernel(const DepthState& state, bool allow_simd, bool hiz) {
    switch (kernel_for(allow_simd)) {
        case Kernel::Avx512: return select_rect_kernel_avx512(state, hiz);
        case Kernel::Avx2: return select_rect_kernel_avx2(state, hiz);
        case Kernel::Portable: break;
    }
    return select_rect_kernel_portable(state, hiz);
}

std::uint64_t raster_rect(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                          bool allow_simd, bool stop_at_first) {
    switch (kernel_for(allow_simd)) {
        case Kernel::Avx512: return raster_rect_avx512(tri, state, depth, rect, stop_at_first);
        case Kernel::Avx2: return raster_rect_avx2(tri, state, depth, rect, stop_at_first);
        case Kernel::Portable: break;
    }
    return raster_rect_portable(tri, state, depth, rect, stop_at_first);
}

std::uint64_t raster_rect_hiz(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                              HizTile& hiz, bool allow_simd, bool stop_at_first) {
    switch (kernel_for(allow_simd)) {
        case Kernel::Avx512: return raster_rect_hiz_avx512(tri, state, depth, rect, hiz, stop_at_first);
        case Kernel::Avx2: return raster_rect_hiz_avx2(tri, state, depth, rect, hiz, stop_at_first);
        case Kernel::Portable: break;
    }
    return raster_rect_hiz_portable(tri, state, depth, rect, hiz, stop_at_first);
}

}  // namespace raster::detail

namespace raster {

const char* simd_kernel_name() {
    switch (detail::kernel_for(true)) {
        case detail::Kernel::Avx512: return "AVX-512";
        case detail::Kernel::Avx2: return "AVX2";
        case detail::Kernel::Portable: break;
    }
    return "portable";
}

}  // namespace raster
