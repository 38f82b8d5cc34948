// float_step.h (private): the next float towards -inf or +inf, by the bit pattern.
#pragma once

#include <bit>
#include <cstdint>
#include <limits>

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

}  // namespace raster::detail
