// setup_avx2.cpp: GL-exact triangle setup for 8 triangles at once (AVX2 + FMA), for the triangles
// that need no clipping: the float part (viewport, snap, depth planes) and, since session 15, the
// integer part (area, culling, the orientation swap, box, edge functions: setup_ints8). CMake
// compiles this file alone with -mavx2 -mfma -ffp-contract=off (x86-64 GCC/Clang,
// RASTER_KERNEL_AVX2=1); triangle_setup.cpp calls it only when kernel_avx2_available() says so.
// Elsewhere it builds to a stub.
//
// Why: a triangle's setup is a chain of dependent float operations with a division per corner
// (1/w through the viewport) and one for the depth plane; one triangle at a time, those chains were
// most of setup's time on small triangles (raster_bench SmallTris: setup 29% and the per-corner
// viewport 8% at 2 threads). Eight triangles in the lanes of one register run them side by side.
//
// Every operation is the scalar code's (triangle_setup.cpp) on the same floats, in the same order,
// each correctly rounded by IEEE: division, multiplication, subtraction, and the viewport's one
// fused multiply-add (std::fma there, _mm256_fmadd_ps here); -ffp-contract=off keeps the compiler
// from fusing the others, as the scalar code is never fused on x86-64. The snap to 16.8 is cvtps2dq
// (the scalar code's cvtss2si: the same MXCSR rounding) behind the same range test. So each lane's
// values are the scalar code's bits; tests/raster/simd_test.cpp compares whole SetupTri lists.
// The integer part is exact integer arithmetic (32-bit lanes, 64-bit products), so it is the same
// values whatever the instruction order.
#include "setup_simd.h"

#include "exact_bounds.h"  // the margins (kClipMarginRel, kPixelMargin, kDepthMargin)

#if defined(RASTER_KERNEL_AVX2)
#include <immintrin.h>
#endif

namespace raster::detail {

#if defined(RASTER_KERNEL_AVX2)
namespace {

struct Plane8 {
    __m256 z0, dzdx, dzdy;
};

// The depth plane of triangles (v0, v1, v2) in llvmpipe's operation order (depth_plane).
Plane8 plane8(const __m256* v0, const __m256* v1, const __m256* v2) {
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256 x0c = _mm256_sub_ps(v0[0], half);
    const __m256 y0c = _mm256_sub_ps(v0[1], half);
    const __m256 dx01 = _mm256_sub_ps(v0[0], v1[0]);
    const __m256 dy01 = _mm256_sub_ps(v0[1], v1[1]);
    const __m256 dx20 = _mm256_sub_ps(v2[0], v0[0]);
    const __m256 dy20 = _mm256_sub_ps(v2[1], v0[1]);
    const __m256 e = _mm256_mul_ps(dx01, dy20);
    const __m256 f = _mm256_mul_ps(dy01, dx20);
    const __m256 ooa = _mm256_div_ps(_mm256_set1_ps(1.0f), _mm256_sub_ps(e, f));
    const __m256 dy20_ooa = _mm256_mul_ps(dy20, ooa);
    const __m256 dy01_ooa = _mm256_mul_ps(dy01, ooa);
    const __m256 dx20_ooa = _mm256_mul_ps(dx20, ooa);
    const __m256 dx01_ooa = _mm256_mul_ps(dx01, ooa);
    const __m256 da01 = _mm256_sub_ps(v0[2], v1[2]);
    const __m256 da20 = _mm256_sub_ps(v2[2], v0[2]);
    const __m256 dadx = _mm256_sub_ps(_mm256_mul_ps(da01, dy20_ooa), _mm256_mul_ps(da20, dy01_ooa));
    const __m256 dady = _mm256_sub_ps(_mm256_mul_ps(da20, dx01_ooa), _mm256_mul_ps(da01, dx20_ooa));
    const __m256 a0 =
        _mm256_sub_ps(v0[2], _mm256_add_ps(_mm256_mul_ps(dadx, x0c), _mm256_mul_ps(dady, y0c)));
    return {a0, dadx, dady};
}

// Bit t of `bits` as lane t's all-ones / zero 32-bit mask.
__m256i lane_mask(std::uint32_t bits) {
    const __m256i b = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    return _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits)), b), b);
}

// The 64-bit products a * b of 8 signed 32-bit lanes, as the even lanes (0, 2, 4, 6) and the odd
// ones (1, 3, 5, 7): vpmuldq multiplies the low 32 bits of each 64-bit lane, exactly.
struct Wide {
    __m256i even, odd;
};
Wide mul_wide(__m256i a, __m256i b) {
    return {_mm256_mul_epi32(a, b), _mm256_mul_epi32(_mm256_srli_epi64(a, 32), _mm256_srli_epi64(b, 32))};
}
Wide sub_wide(Wide a, Wide b) { return {_mm256_sub_epi64(a.even, b.even), _mm256_sub_epi64(a.odd, b.odd)}; }

// Lane order 0..7 again: out[0] = lanes 0-3, out[1] = lanes 4-7.
void store_wide(const Wide& w, std::int64_t* out) {
    const __m256i lo = _mm256_unpacklo_epi64(w.even, w.odd);  // 0 1 | 4 5
    const __m256i hi = _mm256_unpackhi_epi64(w.even, w.odd);  // 2 3 | 6 7
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_permute2x128_si256(lo, hi, 0x20));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 4), _mm256_permute2x128_si256(lo, hi, 0x31));
}

// An 8-bit lane mask from 64-bit compare masks of the even and the odd lanes.
std::uint32_t wide_bits(__m256i even, __m256i odd) {
    const auto e = static_cast<std::uint32_t>(_mm256_movemask_pd(_mm256_castsi256_pd(even)));
    const auto o = static_cast<std::uint32_t>(_mm256_movemask_pd(_mm256_castsi256_pd(odd)));
    std::uint32_t r = 0;
    for (int k = 0; k < 4; ++k) r |= (((e >> k) & 1u) << (2 * k)) | (((o >> k) & 1u) << (2 * k + 1));
    return r;
}

// setup_snapped (triangle_setup.cpp) for 8 triangles, from their corners snapped to 16.8 (x, y)
// and the lanes that passed the range test: the same integer operations, each exact, so the same
// values; the per-lane writer there turns each kept lane into its SetupTri.
void setup_ints8(SetupLanes8& io, const SetupIntRules& r, __m256i* x, __m256i* y, std::uint32_t in_range) {
    // llvmpipe's area: (x0 - x1) (y2 - y0) - (x2 - x0) (y0 - y1), in 64 bits.
    const Wide area = sub_wide(mul_wide(_mm256_sub_epi32(x[0], x[1]), _mm256_sub_epi32(y[2], y[0])),
                               mul_wide(_mm256_sub_epi32(x[2], x[0]), _mm256_sub_epi32(y[0], y[1])));
    const __m256i zero = _mm256_setzero_si256();
    const std::uint32_t nonzero = ~wide_bits(_mm256_cmpeq_epi64(area.even, zero), _mm256_cmpeq_epi64(area.odd, zero)) & 0xffu;
    const std::uint32_t positive = wide_bits(_mm256_cmpgt_epi64(area.even, zero), _mm256_cmpgt_epi64(area.odd, zero));
    const std::uint32_t gl_ccw = r.lp_positive_is_ccw ? positive : ~positive & 0xffu;
    const std::uint32_t front = r.front_is_ccw ? gl_ccw : ~gl_ccw & 0xffu;
    std::uint32_t keep = in_range & nonzero;
    if (r.cull == 2) keep &= front;
    if (r.cull == 1) keep &= ~front;
    // The swap of a negative triangle: vertices 0 and 1, or 1 and 2 with the provoking vertex first.
    const __m256i neg = lane_mask(~positive & 0xffu);
    const int a = r.provoking_first ? 1 : 0;
    {
        const __m256i xa = x[a], xb = x[a + 1], ya = y[a], yb = y[a + 1];
        x[a] = _mm256_blendv_epi8(xa, xb, neg);
        x[a + 1] = _mm256_blendv_epi8(xb, xa, neg);
        y[a] = _mm256_blendv_epi8(ya, yb, neg);
        y[a + 1] = _mm256_blendv_epi8(yb, ya, neg);
    }
    // Bounding box, llvmpipe's rounding, cut to the target.
    const __m256i one = _mm256_set1_epi32(1);
    const __m256i adj = _mm256_set1_epi32(r.bottom_edge_rule ? 1 : 0);
    const __m256i minx = _mm256_min_epi32(_mm256_min_epi32(x[0], x[1]), x[2]);
    const __m256i maxx = _mm256_max_epi32(_mm256_max_epi32(x[0], x[1]), x[2]);
    const __m256i miny = _mm256_min_epi32(_mm256_min_epi32(y[0], y[1]), y[2]);
    const __m256i maxy = _mm256_max_epi32(_mm256_max_epi32(y[0], y[1]), y[2]);
    const __m256i bx0 = _mm256_max_epi32(_mm256_srai_epi32(minx, 8), zero);
    const __m256i bx1 = _mm256_min_epi32(_mm256_srai_epi32(_mm256_sub_epi32(maxx, one), 8), _mm256_set1_epi32(r.target_width - 1));
    const __m256i by0 = _mm256_max_epi32(_mm256_srai_epi32(_mm256_add_epi32(miny, adj), 8), zero);
    const __m256i by1 = _mm256_min_epi32(_mm256_srai_epi32(_mm256_sub_epi32(_mm256_add_epi32(maxy, adj), one), 8),
                                         _mm256_set1_epi32(r.target_height - 1));
    const __m256i empty = _mm256_or_si256(_mm256_cmpgt_epi32(bx0, bx1), _mm256_cmpgt_epi32(by0, by1));
    keep &= ~static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(empty))) & 0xffu;
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.box[0]), bx0);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.box[1]), by0);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.box[2]), bx1);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.box[3]), by1);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.span_x), _mm256_sub_epi32(maxx, minx));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.span_y), _mm256_sub_epi32(maxy, miny));
    // Edges: dcdx = y_i - y_j, dcdy = x_i - x_j, c = dcdx x_i - dcdy y_i, and the fill-rule bias
    // (dcdx < 0, or dcdx = 0 and the horizontal edge on the convention's side).
    for (int i = 0; i < 3; ++i) {
        const int j = i == 2 ? 0 : i + 1;
        const __m256i dcdx = _mm256_sub_epi32(y[i], y[j]);
        const __m256i dcdy = _mm256_sub_epi32(x[i], x[j]);
        store_wide(sub_wide(mul_wide(dcdx, x[i]), mul_wide(dcdy, y[i])), io.c[i]);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.dcdx[i]), dcdx);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(io.dcdy[i]), dcdy);
        const __m256i horizontal_in = r.bottom_edge_rule ? _mm256_cmpgt_epi32(zero, dcdy)                          // dcdy < 0
                                                         : _mm256_xor_si256(_mm256_cmpgt_epi32(zero, dcdy), _mm256_set1_epi32(-1));  // dcdy >= 0
        const __m256i bias = _mm256_or_si256(_mm256_cmpgt_epi32(zero, dcdx),
                                             _mm256_and_si256(_mm256_cmpeq_epi32(dcdx, zero), horizontal_in));
        io.bias_bits[i] = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(bias)));
    }
    io.keep = keep;
    io.swapped = ~positive & 0xffu;
    io.front = front;
}

}  // namespace

void setup_lanes8_avx2(SetupLanes8& io, const SetupIntRules& rules) {
    __m256 v[3][3];
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) v[k][c] = _mm256_loadu_ps(io.win[k][c]);
    // Range test and 16.8 snap of x and y: |(w - 0.5) * 256| < 2^30 (false for NaN), then
    // cvtps2dq of the same product.
    const __m256 half = _mm256_set1_ps(0.5f), fixed_one = _mm256_set1_ps(256.0f);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 limit = _mm256_set1_ps(0x1p30f);
    __m256 ok = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    __m256i snapped[2][3];  // [0] x, [1] y of each corner
    for (int k = 0; k < 3; ++k) {
        for (int c = 0; c < 2; ++c) {
            const __m256 s = _mm256_mul_ps(_mm256_sub_ps(v[k][c], half), fixed_one);
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_and_ps(s, abs_mask), limit, _CMP_LT_OQ));
            snapped[c][k] = _mm256_cvtps_epi32(s);
        }
    }
    const auto in_range = static_cast<std::uint32_t>(_mm256_movemask_ps(ok));
    // The plane for the vertex order as given and for setup's swap of a negative triangle:
    // vertices 0 and 1 (provoking vertex last) or 1 and 2 (provoking vertex first).
    const Plane8 given = plane8(v[0], v[1], v[2]);
    const Plane8 swapped = rules.provoking_first ? plane8(v[0], v[2], v[1]) : plane8(v[1], v[0], v[2]);
    _mm256_storeu_ps(io.z0[0], given.z0);
    _mm256_storeu_ps(io.dzdx[0], given.dzdx);
    _mm256_storeu_ps(io.dzdy[0], given.dzdy);
    _mm256_storeu_ps(io.z0[1], swapped.z0);
    _mm256_storeu_ps(io.dzdx[1], swapped.dzdx);
    _mm256_storeu_ps(io.dzdy[1], swapped.dzdy);
    setup_ints8(io, rules, snapped[0], snapped[1], in_range);
}

namespace {

// Eight rows of (x, y, z, w) as four registers of x, y, z and w.
void transpose8x4(const __m128* r, __m256* a) {
    const __m256 r04 = _mm256_insertf128_ps(_mm256_castps128_ps256(r[0]), r[4], 1);
        const __m256 r15 = _mm256_insertf128_ps(_mm256_castps128_ps256(r[1]), r[5], 1);
        const __m256 r26 = _mm256_insertf128_ps(_mm256_castps128_ps256(r[2]), r[6], 1);
        const __m256 r37 = _mm256_insertf128_ps(_mm256_castps128_ps256(r[3]), r[7], 1);
        const __m256 t0 = _mm256_unpacklo_ps(r04, r15);  // x0 x1 y0 y1 | x4 x5 y4 y5
        const __m256 t1 = _mm256_unpackhi_ps(r04, r15);  // z0 z1 w0 w1 | z4 z5 w4 w5
        const __m256 t2 = _mm256_unpacklo_ps(r26, r37);  // x2 x3 y2 y3 | x6 x7 y6 y7
        const __m256 t3 = _mm256_unpackhi_ps(r26, r37);  // z2 z3 w2 w3 | z6 z7 w6 w7
    a[0] = _mm256_shuffle_ps(t0, t2, 0x44);
    a[1] = _mm256_shuffle_ps(t0, t2, 0xee);
    a[2] = _mm256_shuffle_ps(t1, t3, 0x44);
    a[3] = _mm256_shuffle_ps(t1, t3, 0xee);
}

// clip_mask's six tests in its bit order (ordered compares: false for NaN, as there), one
// movemask per bit.
void clip_bits8(const __m256* a, bool half_z, int bits[6]) {
    const __m256 zero = _mm256_setzero_ps();
    bits[0] = _mm256_movemask_ps(_mm256_cmp_ps(a[0], a[3], _CMP_GT_OQ));
    bits[1] = _mm256_movemask_ps(_mm256_cmp_ps(zero, _mm256_add_ps(a[0], a[3]), _CMP_GT_OQ));
    bits[2] = _mm256_movemask_ps(_mm256_cmp_ps(a[1], a[3], _CMP_GT_OQ));
    bits[3] = _mm256_movemask_ps(_mm256_cmp_ps(zero, _mm256_add_ps(a[1], a[3]), _CMP_GT_OQ));
    bits[4] = _mm256_movemask_ps(half_z ? _mm256_cmp_ps(zero, a[2], _CMP_GT_OQ)
                                        : _mm256_cmp_ps(zero, _mm256_add_ps(a[2], a[3]), _CMP_GT_OQ));
    bits[5] = _mm256_movemask_ps(_mm256_cmp_ps(a[2], a[3], _CMP_GT_OQ));
}

// shader_viewport: one division, then ndc * scale + translate as one fma.
void viewport8(const __m256* a, const float scale[3], const float translate[3], float win[3][8]) {
    const __m256 oow = _mm256_div_ps(_mm256_set1_ps(1.0f), a[3]);
    for (int c = 0; c < 3; ++c) {
        const __m256 ndc = _mm256_mul_ps(a[c], oow);
        _mm256_storeu_ps(win[c], _mm256_fmadd_ps(ndc, _mm256_set1_ps(scale[c]), _mm256_set1_ps(translate[c])));
    }
}

}  // namespace

void viewport_lanes8_avx2(SetupLanes8& io, const float* const corners[24], const float scale[3],
                          const float translate[3], bool half_z) {
    std::uint32_t clipped = 0;
    for (int k = 0; k < 3; ++k) {  // corner slot k of the 8 triangles
        __m128 r[8];
        for (int t = 0; t < 8; ++t) r[t] = _mm_loadu_ps(corners[3 * t + k]);
        __m256 a[4];
        transpose8x4(r, a);
        int bits[6];
        clip_bits8(a, half_z, bits);
        clipped |= static_cast<std::uint32_t>(bits[0] | bits[1] | bits[2] | bits[3] | bits[4] | bits[5]);
        viewport8(a, scale, translate, io.win[k]);
    }
    io.clipped = clipped;
}

void vertices8_avx2(const float* vertices, const float scale[3], const float translate[3], bool half_z,
                    float win[3][8], std::uint32_t mask[8]) {
    __m128 r[8];
    for (int t = 0; t < 8; ++t) r[t] = _mm_loadu_ps(vertices + 4 * t);
    __m256 a[4];
    transpose8x4(r, a);
    int bits[6];
    clip_bits8(a, half_z, bits);
    for (int t = 0; t < 8; ++t) {
        std::uint32_t m = 0;
        for (int b = 0; b < 6; ++b) m |= static_cast<std::uint32_t>((bits[b] >> t) & 1) << b;
        mask[t] = m;
    }
    viewport8(a, scale, translate, win);
}

// (setup_simd.h, BoundsLanes4; exact_bounds.cpp's setup_bounds_triangle is the scalar original.)
void bounds_lanes4_avx2(BoundsLanes4& io, const BoundsViewport& vp) {
    __m256d v[3][3];
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffll));
    __m256d absmax = _mm256_setzero_pd();  // every |v| is >= +0
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) {
            v[k][c] = _mm256_loadu_pd(io.v[k][c]);
            absmax = _mm256_max_pd(absmax, _mm256_and_pd(v[k][c], abs_mask));
        }
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d mc = _mm256_mul_pd(_mm256_max_pd(absmax, one), _mm256_set1_pd(kClipMarginRel));
    const __m256d lim = _mm256_add_pd(one, mc);
    io.inside = static_cast<std::uint32_t>(_mm256_movemask_pd(_mm256_cmp_pd(absmax, lim, _CMP_LE_OQ)));
    const __m256d hw = _mm256_set1_pd(vp.hw), hh = _mm256_set1_pd(vp.hh), tx = _mm256_set1_pd(vp.tx),
                  ty = _mm256_set1_pd(vp.ty), half = _mm256_set1_pd(0.5);
    __m256d w[3][3];
    for (int k = 0; k < 3; ++k) {
        w[k][0] = _mm256_add_pd(_mm256_mul_pd(v[k][0], hw), tx);
        w[k][1] = _mm256_add_pd(_mm256_mul_pd(v[k][1], hh), ty);
        w[k][2] = _mm256_add_pd(_mm256_mul_pd(v[k][2], half), half);
        for (int c = 0; c < 3; ++c) _mm256_storeu_pd(io.win[k][c], w[k][c]);
    }
    // std::min(std::min(a, b), c): window coordinates are never -0 (x * hw + tx with tx >= 1/2 gives
    // +0 for a zero sum) nor NaN, so minpd / maxpd give the same values in any operand order.
    const __m256d minx = _mm256_min_pd(_mm256_min_pd(w[0][0], w[1][0]), w[2][0]);
    const __m256d maxx = _mm256_max_pd(_mm256_max_pd(w[0][0], w[1][0]), w[2][0]);
    const __m256d miny = _mm256_min_pd(_mm256_min_pd(w[0][1], w[1][1]), w[2][1]);
    const __m256d maxy = _mm256_max_pd(_mm256_max_pd(w[0][1], w[1][1]), w[2][1]);
    _mm256_storeu_pd(io.minx, minx);
    _mm256_storeu_pd(io.maxx, maxx);
    _mm256_storeu_pd(io.miny, miny);
    _mm256_storeu_pd(io.maxy, maxy);
    const __m256d mxy = _mm256_add_pd(_mm256_set1_pd(kPixelMargin), _mm256_mul_pd(mc, _mm256_set1_pd(vp.hmax)));
    _mm256_storeu_pd(io.margin_xy, mxy);
    _mm256_storeu_pd(io.margin_z, _mm256_add_pd(_mm256_set1_pd(kDepthMargin), mc));
    // grown_box: ceil(lo - m) - 1 <= px <= floor(hi + m).
    constexpr int kCeil = _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC, kFloor = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
    const __m256d bx0 = _mm256_sub_pd(_mm256_round_pd(_mm256_sub_pd(minx, mxy), kCeil), one);
    const __m256d by0 = _mm256_sub_pd(_mm256_round_pd(_mm256_sub_pd(miny, mxy), kCeil), one);
    const __m256d bx1 = _mm256_round_pd(_mm256_add_pd(maxx, mxy), kFloor);
    const __m256d by1 = _mm256_round_pd(_mm256_add_pd(maxy, mxy), kFloor);
    const __m256d zero = _mm256_setzero_pd();
    const __m256d last_x = _mm256_set1_pd(static_cast<double>(vp.width - 1));
    const __m256d last_y = _mm256_set1_pd(static_cast<double>(vp.height - 1));
    const __m256d out = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(bx1, zero, _CMP_LT_OQ), _mm256_cmp_pd(by1, zero, _CMP_LT_OQ)),
                                     _mm256_or_pd(_mm256_cmp_pd(bx0, last_x, _CMP_GT_OQ), _mm256_cmp_pd(by0, last_y, _CMP_GT_OQ)));
    io.outside = static_cast<std::uint32_t>(_mm256_movemask_pd(out));
    io.single = static_cast<std::uint32_t>(_mm256_movemask_pd(
        _mm256_and_pd(_mm256_cmp_pd(bx0, bx1, _CMP_EQ_OQ), _mm256_cmp_pd(by0, by1, _CMP_EQ_OQ))));
    // GrownBox::cut (only read for lanes inside the target, where every value is a small integer).
    _mm_storeu_si128(reinterpret_cast<__m128i*>(io.x0), _mm256_cvttpd_epi32(_mm256_max_pd(bx0, zero)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(io.y0), _mm256_cvttpd_epi32(_mm256_max_pd(by0, zero)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(io.x1), _mm256_cvttpd_epi32(_mm256_min_pd(bx1, last_x)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(io.y1), _mm256_cvttpd_epi32(_mm256_min_pd(by1, last_y)));
}

#else

void setup_lanes8_avx2(SetupLanes8&, const SetupIntRules&) {}
void viewport_lanes8_avx2(SetupLanes8&, const float* const[24], const float[3], const float[3], bool) {}
void vertices8_avx2(const float*, const float[3], const float[3], bool, float[3][8], std::uint32_t[8]) {}
void bounds_lanes4_avx2(BoundsLanes4&, const BoundsViewport&) {}

#endif

}  // namespace raster::detail
