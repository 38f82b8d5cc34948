// float_step.h (private): float helpers without libm calls: the next float towards -inf or +inf
// by the bit pattern, and lrint for values that fit 32 bits.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#if defined(__x86_64__) || defined(_M_X64)
#include <immintrin.h>
#endif

namespace raster::detail {

// std::nextafter(f, -HUGE_VALF) / std::nextafter(f, HUGE_VALF) for a finite f, without the libm
// call (it was 1.7% of a leaves / rcullide-offset frame's instructions, callgrind): stepping the
// magnitude's bits moves by one ulp, through the subnormals and from +-FLT_MAX to the infinity;
// from zero of either sign the step is the smallest subnormal of the step's sign. Checked against
// std::nextafter in tests/raster/unit_test.cpp.
inline float next_down(float f) {
    const auto b = std::bit_cast<std::uint32_t>(f);
    if ((b & 0x7fffffffu) == 0) return -std::numeric_limits<float>::denorm_min();
    return std::bit_cast<float>((b & 0x80000000u) != 0 ? b + 1 : b - 1);
}
inline float next_up(float f) {
    const auto b = std::bit_cast<std::uint32_t>(f);
    if ((b & 0x7fffffffu) == 0) return std::numeric_limits<float>::denorm_min();
    return std::bit_cast<float>((b & 0x80000000u) != 0 ? b - 1 : b + 1);
}

// std::lrint(f) for |f| < 2^31 (the caller guarantees it): rounds in the current rounding mode,
// half to even by default. On x86-64 one cvtss2si, which rounds by MXCSR as lrintf does; lrintf
// itself is a libm call there unless math errno is off (six calls per triangle of GL-exact setup,
// issue #17). Checked against std::lrint in tests/raster/unit_test.cpp.
inline std::int32_t lrint32(float f) {
#if defined(__x86_64__) || defined(_M_X64)
    return _mm_cvtss_si32(_mm_set_ss(f));
#else
    return static_cast<std::int32_t>(std::lrint(f));
#endif
}

}  // namespace raster::detail
