// setup_simd.h (private): GL-exact triangle setup for 8 triangles at once (setup_avx2.cpp; used by
// triangle_setup.cpp when kernel_avx2_available()): the float part, then the integer part.
#pragma once

#include <cstdint>

namespace raster::detail {

// Eight triangles, lane t = triangle t; per corner slot k (0, 1, 2) of the triangle.
struct SetupLanes8 {
    float win[3][3][8];  // window x, y, z: the input of setup_lanes8, the output of viewport_lanes8
    // viewport_lanes8: bit t set when a corner of triangle t is outside the clip volume (clip_mask
    // is not zero: the scalar front end clips it).
    std::uint32_t clipped = 0;
    // setup_lanes8: the depth plane of the corners in the given order ([0]) and in the order setup
    // uses for a negative triangle ([1]: corners 0 and 1 swapped, or 1 and 2 when the provoking
    // vertex is the first).
    float z0[2][8], dzdx[2][8], dzdy[2][8];
    // setup_lanes8, the integer part of setup (triangle_setup.cpp, setup_snapped) on the corners
    // snapped to 16.8. keep bit t: triangle t makes a SetupTri (every corner in the fixed-point
    // range, area not 0, not culled, box not empty); then its box, its edges in setup's vertex order
    // (after the swap of a negative triangle) with the fill-rule bias in bias_bits (bit t of [e]: add
    // 1 to c[e][t]), swapped bit t: the plane is [1], front bit t: front-facing, and the snapped
    // extents for fits32.
    std::uint32_t keep = 0, swapped = 0, front = 0;
    std::uint32_t bias_bits[3] = {0, 0, 0};
    std::int32_t box[4][8];  // x0, y0, x1, y1, inside the target
    std::int64_t c[3][8];
    std::int32_t dcdx[3][8], dcdy[3][8];
    std::int32_t span_x[8], span_y[8];
};

// What setup_lanes8 needs of the rules and the draw (triangle_setup.cpp's RuleSet and
// FrontEndParams).
struct SetupIntRules {
    bool bottom_edge_rule;
    bool lp_positive_is_ccw;
    bool provoking_first;
    bool front_is_ccw;  // FrontFace::CCW
    int cull;           // 0: none, 1: cull front-facing, 2: cull back-facing
    int target_width, target_height;
};

// Setup of the 8 triangles whose window corners are in win: the snap and range test, the depth
// planes (z0 .. dzdy), then the integer part (keep .. span_y) with 64-bit products from 32-bit
// lanes (|snapped| < 2^30, so every difference fits 32 bits and every product 62). Call only
// where kernel_avx2_available(): a build without AVX2 code has an empty stub.
void setup_lanes8_avx2(SetupLanes8& io, const SetupIntRules& rules);
// The clip test and the viewport of 8 triangles' corners: corners[3 t + k] is corner k of
// triangle t (x, y, z, w). Fills win and clipped (the same condition as setup_lanes8_avx2).
void viewport_lanes8_avx2(SetupLanes8& io, const float* const corners[24], const float scale[3],
                          const float translate[3], bool half_z);

// The clip test and the viewport of 8 consecutive vertices (x, y, z, w each): clip_mask's six
// bits per vertex into mask, the window position into win[c][vertex] (the same condition).
void vertices8_avx2(const float* vertices, const float scale[3], const float translate[3], bool half_z,
                    float win[3][8], std::uint32_t mask[8]);

// Exact-bounds setup's common front for four unclipped triangles at once (exact_bounds.cpp,
// setup_bounds_range): lane t = triangle t. Per lane the operations of setup_bounds_triangle in the
// same order, each correctly rounded (no contraction), so the same doubles: the largest |coordinate|
// and the clip margin, whether the triangle needs clipping (inside: it does not), and for the
// unclipped ones the window corners, their ranges, the margins and the grown pixel box cut to the
// target (exact_ceil / exact_floor as roundpd: equal but for the sign of a zero, which neither the
// box's integers nor its compares see).
struct BoundsLanes4 {
    double v[3][3][4];  // in: corner k's clip x, y, z
    double win[3][3][4];  // out: corner k's window x, y, z
    double minx[4], maxx[4], miny[4], maxy[4];
    double margin_xy[4], margin_z[4];
    std::int32_t x0[4], y0[4], x1[4], y1[4];
    std::uint32_t inside = 0, outside = 0, single = 0;  // bit t: lane t needs no clip / has no pixel / one pixel
};
struct BoundsViewport {
    double hw, hh, tx, ty, hmax;  // the viewport map's scale and offset, max(hw, hh)
    int width, height;            // the target
};
void bounds_lanes4_avx2(BoundsLanes4& io, const BoundsViewport& vp);

}  // namespace raster::detail
