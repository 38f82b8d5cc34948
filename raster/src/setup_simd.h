// setup_simd.h (private): GL-exact triangle setup's float part for 8 triangles at once
// (setup_avx2.cpp; used by triangle_setup.cpp when kernel_avx2_available()).
#pragma once

#include <cstdint>

namespace raster::detail {

// Eight triangles, lane t = triangle t; per corner slot k (0, 1, 2) of the triangle.
struct SetupLanes8 {
    float win[3][3][8];  // window x, y, z: the input of setup_lanes8, the output of viewport_lanes8
    // viewport_lanes8: bit t set when a corner of triangle t is outside the clip volume (clip_mask
    // is not zero: the scalar front end clips it).
    std::uint32_t clipped = 0;
    // setup_lanes8: bit t set when every corner of triangle t passes setup's fixed-point range
    // test; then sx, sy are its corners snapped to 16.8 (as setup_window_triangle snaps them).
    std::uint32_t in_range = 0;
    std::int32_t sx[3][8], sy[3][8];
    // setup_lanes8: the depth plane of the corners in the given order ([0]) and in the order setup
    // uses for a negative triangle ([1]: corners 0 and 1 swapped, or 1 and 2 when the provoking
    // vertex is the first).
    float z0[2][8], dzdx[2][8], dzdy[2][8];
};

// Fills in_range, sx, sy, z0, dzdx and dzdy from win. Call only where kernel_avx2_available():
// a build without AVX2 code has empty stubs.
void setup_lanes8_avx2(SetupLanes8& io, bool provoking_first);
// The clip test and the viewport of 8 triangles' corners: corners[3 t + k] is corner k of
// triangle t (x, y, z, w). Fills win and clipped (the same condition as setup_lanes8_avx2).
void viewport_lanes8_avx2(SetupLanes8& io, const float* const corners[24], const float scale[3],
                          const float translate[3], bool half_z);

// The clip test and the viewport of 8 consecutive vertices (x, y, z, w each): clip_mask's six
// bits per vertex into mask, the window position into win[c][vertex] (the same condition).
void vertices8_avx2(const float* vertices, const float scale[3], const float translate[3], bool half_z,
                    float win[3][8], std::uint32_t mask[8]);

}  // namespace raster::detail
