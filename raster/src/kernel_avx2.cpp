// kernel_avx2.cpp: the same kernel compiled with AVX2 + FMA (CMake sets -mavx2 -mfma on this file
// only, x86-64 GCC/Clang), so std::fma is one instruction instead of a libm call. Chosen at run
// time by kernel_avx2_available(); elsewhere this file builds the portable kernel under this name.
#include <algorithm>
#include <bit>
#include <cmath>

#include "pipeline.h"

namespace raster::detail {
namespace avx2 {
#include "raster_kernel.inc"
}  // namespace avx2

std::uint64_t raster_rect_avx2(const SetupTri& tri, DepthFormat format, DepthFunc func, bool write,
                               std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1) {
    return avx2::raster_rect_kernel(tri, format, func, write, depth, stride, rx0, ry0, rx1, ry1);
}

bool kernel_avx2_available() {
#if defined(RASTER_KERNEL_AVX2) && (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
    static const bool ok = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return ok;
#else
    return false;
#endif
}

}  // namespace raster::detail
