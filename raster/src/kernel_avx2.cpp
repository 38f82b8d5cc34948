// kernel_avx2.cpp: the 8-wide AVX2 + FMA GL-exact kernel. CMake compiles this file alone with
// -mavx2 -mfma (x86-64 GCC/Clang, RASTER_KERNEL_AVX2=1); it is chosen at run time by
// kernel_avx2_available(). Elsewhere (aarch64, other compilers) the same entry point builds the
// scalar kernel of raster_kernel.inc, and kernel_avx2_available() says false.
//
// Layout: 8x1 pixels per step along a row. Coverage stays exact integer arithmetic on the same
// 16.8 edge functions (same snapping, same fill-rule bias folded into c): narrow rectangles test
// 8 pixels at once in 32-bit lanes when a bound proves no value overflows; wider ones solve each
// row's covered span from the 64-bit edge functions: the scalar code's floor divisions (edge_span
// of raster_kernel.inc), done once per rectangle and then stepped row to row (EdgeWalk).
// Either way the covered set is the scalar path's. The vector part is depth; per 8 pixels:
//   z = fma(dzdy, y, fma(dzdx, x, z0))   (_mm256_fmadd_ps: one correctly rounded fma, as std::fma)
//   clamp: max(z, 0) then min(z, 1)      (maxps returns its second operand when z is NaN: NaN -> 0,
//                                         -0 -> +0, exactly `z > 0 ? z : 0`; minps likewise;
//                                         left out on wide D16 / D24 rectangles where it changes no
//                                         encoded value: clamp_free)
//   D24: cvtps2dq(z * 16777215)          (MXCSR round-to-nearest-even, as lrint)
//   D16: bits(z * (65535/65536) + 128) & 0xffff
//   D32F: compare as floats with the ordered/unordered predicate equal to C++'s operator
// Partial chunks are read and written whole (plain load, blend, store: the lanes outside the span
// get their own values back) when the 8 pixels lie in the rectangle's column group of kHizTile
// (pipeline.h: the caller owns it), masked (maskload / maskstore) only where they would cross into
// the next group or past the row's end; full chunks are blended. So tiles on other threads are
// never read or written. A masked store of 8 lanes was the costliest instruction of the writing
// kernel on AMD Zen 3 (perf, Q-CULLIDE-GL's passes at 1024^2).
// Block-level trivial reject / accept: the three edge functions are evaluated at the four corner
// pixel centres of the rectangle (a linear function takes its extremes at corners): an edge <= 0 at
// all four rejects the whole rectangle; an edge > 0 at all four is dropped from the span work
// (wide rectangles; narrow ones go straight to the 8-lane coverage test, which rejects as cheaply).
// stop_at_first (any-samples queries, mask off): return after the first row with a passing sample.
// Wide rectangles count passing samples per lane and sum the lanes once (wide_rows); narrow ones
// count each chunk's bits (a per-rectangle sum and clamp test cost more than they save there:
// callgrind, raster_bench SmallTris). The AVX-512 kernel (kernel_avx512.cpp) has neither yet.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>

#include "pipeline.h"

#if defined(RASTER_KERNEL_AVX2)
#include <immintrin.h>
#endif

namespace raster::detail {
namespace avx2 {
#include "raster_kernel.inc"
}  // namespace avx2

#if defined(RASTER_KERNEL_AVX2)
namespace {

template <DepthFormat Fmt>
inline __m256i encode8(__m256 z) {
    if constexpr (Fmt == DepthFormat::D24) {
        return _mm256_cvtps_epi32(_mm256_mul_ps(z, _mm256_set1_ps(16777215.0f)));
    } else if constexpr (Fmt == DepthFormat::D16) {
        const __m256 t = _mm256_mul_ps(z, _mm256_set1_ps(65535.0f / 65536.0f));
        const __m256 u = _mm256_add_ps(t, _mm256_set1_ps(128.0f));
        return _mm256_and_si256(_mm256_castps_si256(u), _mm256_set1_epi32(0xffff));
    } else {
        return _mm256_castps_si256(z);
    }
}

// All-ones lanes where depth_pass<F>(incoming, stored) holds, for 8 lanes.
template <DepthFormat Fmt, DepthFunc F>
inline __m256i pass8(__m256i incoming, __m256i stored) {
    const __m256i ones = _mm256_set1_epi32(-1);
    if constexpr (F == DepthFunc::Never) return _mm256_setzero_si256();
    if constexpr (F == DepthFunc::Always) return ones;
    if constexpr (Fmt == DepthFormat::D32F) {
        const __m256 a = _mm256_castsi256_ps(incoming), b = _mm256_castsi256_ps(stored);
        if constexpr (F == DepthFunc::Less) return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_LT_OQ));
        if constexpr (F == DepthFunc::Equal) return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_EQ_OQ));
        if constexpr (F == DepthFunc::LEqual) return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_LE_OQ));
        if constexpr (F == DepthFunc::Greater) return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_GT_OQ));
        if constexpr (F == DepthFunc::NotEqual) return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_NEQ_UQ));
        if constexpr (F == DepthFunc::GEqual) return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_GE_OQ));
    } else {
        // Unsigned 32-bit order: a <= b exactly when the unsigned maximum of the two is b (two
        // instructions; a sign flip of both and the signed compare took three or four).
        const __m256i a = incoming, b = stored, top = _mm256_max_epu32(a, b);
        if constexpr (F == DepthFunc::Less) return _mm256_xor_si256(_mm256_cmpeq_epi32(top, a), ones);
        if constexpr (F == DepthFunc::Equal) return _mm256_cmpeq_epi32(a, b);
        if constexpr (F == DepthFunc::LEqual) return _mm256_cmpeq_epi32(top, b);
        if constexpr (F == DepthFunc::Greater) return _mm256_xor_si256(_mm256_cmpeq_epi32(top, b), ones);
        if constexpr (F == DepthFunc::NotEqual) return _mm256_xor_si256(_mm256_cmpeq_epi32(a, b), ones);
        if constexpr (F == DepthFunc::GEqual) return _mm256_cmpeq_epi32(top, a);
    }
    return _mm256_setzero_si256();
}

inline unsigned lanes(__m256i m) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(m)));
}

// The depth plane's coefficients in every lane, read from the SetupTri once per rectangle (a
// store through __m256i may alias anything, so loops that read them from `t` reload them after
// every store).
struct Plane8 {
    __m256 z0, dzdx, dzdy;
    explicit Plane8(const SetupTri& t)
        : z0(_mm256_set1_ps(t.z0)), dzdx(_mm256_set1_ps(t.dzdx)), dzdy(_mm256_set1_ps(t.dzdy)) {}
};

// The x coordinates px..px+7 as floats (exact: |px| < 2^24).
inline __m256 lane_x8(int px) {
    const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    return _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(px), iota));
}

// The inner fma of the depth plane for the 8 pixels at x = fx: fma(dzdx, x, z0), the same in every row.
inline __m256 plane_x8(const Plane8& p, __m256 fx) { return _mm256_fmadd_ps(p.dzdx, fx, p.z0); }

// Depth test (and write) of the 8 pixels px..px+7 of `row` at row centre fy; `cover` marks the
// pixels to process (full: all 8). `whole`: the 8 pixels may be read and rewritten (own_chunk;
// true when full), so a plain load and a blended store serve a partial chunk too. Returns the
// passing lanes (all ones), within `cover`.
// zx: plane_x8 of the 8 pixels, computed once per column of chunks by callers that visit it in many rows.
// Clamp false: the caller knows that the clamp changes no encoded value in the lanes that `cover`
// marks (clamp_free below).
template <DepthFormat Fmt, DepthFunc F, bool Write, bool Clamp = true>
inline __m256i pass_chunk8(const Plane8& plane, std::uint32_t* row, int px, __m256 fy, __m256i cover,
                           bool whole, __m256 zx) {
    __m256 z = _mm256_fmadd_ps(plane.dzdy, fy, zx);
    if constexpr (Clamp) {
        z = _mm256_max_ps(z, _mm256_setzero_ps());
        z = _mm256_min_ps(z, _mm256_set1_ps(1.0f));
    }
    const __m256i incoming = encode8<Fmt>(z);
    std::uint32_t* p = row + px;
    const __m256i stored = whole ? _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))
                                 : _mm256_maskload_epi32(reinterpret_cast<const int*>(p), cover);
    const __m256i pass = _mm256_and_si256(pass8<Fmt, F>(incoming, stored), cover);
    if constexpr (Write) {
        // A whole chunk is stored whether or not a lane passed (unchanged pixels rewritten with
        // their own value): the pass/fail pattern of writing draws is data, and a branch on it
        // mispredicted (perf, cylinders frame).
        if (whole)
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), _mm256_blendv_epi8(stored, incoming, pass));
        else if (!_mm256_testz_si256(pass, pass))
            _mm256_maskstore_epi32(reinterpret_cast<int*>(p), pass, incoming);
    }
    return pass;
}

// pass_chunk8 as the passing-lane bits.
template <DepthFormat Fmt, DepthFunc F, bool Write>
inline unsigned chunk8(const Plane8& plane, std::uint32_t* row, int px, __m256 fy, __m256i cover, bool whole,
                       __m256 zx) {
    return lanes(pass_chunk8<Fmt, F, Write>(plane, row, px, fy, cover, whole, zx));
}

// The sum of the 8 unsigned lanes.
inline std::uint64_t sum8(__m256i v) {
    __m128i s = _mm_add_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    s = _mm_add_epi32(s, _mm_shuffle_epi32(s, 0x4e));
    s = _mm_add_epi32(s, _mm_shuffle_epi32(s, 0xb1));
    return static_cast<std::uint32_t>(_mm_cvtsi128_si32(s));
}

// Whether the chunk px..px+7 of a row of `stride` pixels lies in one column group of kHizTile and
// inside the row: then it is in the group of the rectangle it meets, which the caller owns
// (pipeline.h, at raster_rect), and may be read and written whole.
inline bool own_chunk(int px, int stride) {
    return (px & (kHizTile - 1)) <= kHizTile - 8 && px + 8 <= stride;
}

constexpr int kNarrow = 16;  // rectangles narrower than this take the per-chunk edge path when it fits

// The narrow path of raster_rect8 (below) for a rectangle of `Columns` chunks of 8 pixels (1 or
// 2), given each edge's value at (rx0, ry0) and its x and y steps, all known to fit in 32 bits over
// the rectangle padded to whole chunks. Per column, set up once: the lanes' edge values in the
// first row (stepped by the y steps per row, every value an edge value of a pixel of the padded
// rectangle, so within the bound), the in-rectangle lanes and the inner fma of the depth plane.
// The column count is a constant so that the edge vectors stay in registers across rows.
template <int Columns, DepthFormat Fmt, DepthFunc F, bool Write>
std::uint64_t narrow_rows(const SetupTri& t, DepthRows depth, PixelRect rect, const std::int64_t (&e_row)[3],
                          const std::int64_t (&sx)[3], const std::int64_t (&sy)[3], bool stop_at_first) {
    const int rx0 = rect.x0, ry0 = rect.y0, rx1 = rect.x1, ry1 = rect.y1;
    const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const Plane8 plane(t);
    __m256i e[Columns][3], in_rect[Columns], step_y[3];
    __m256 zx[Columns];
    bool own[Columns];
    #pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) step_y[i] = _mm256_set1_epi32(static_cast<std::int32_t>(sy[i]));
    #pragma GCC unroll 2
    for (int k = 0; k < Columns; ++k) {
        const int px = rx0 + 8 * k;
        in_rect[k] = _mm256_cmpgt_epi32(_mm256_set1_epi32(rx1 - px + 1), iota);
        own[k] = own_chunk(px, depth.stride);
        zx[k] = plane_x8(plane, lane_x8(px));
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) {
            const __m256i lane_sx = _mm256_mullo_epi32(_mm256_set1_epi32(static_cast<std::int32_t>(sx[i])), iota);
            e[k][i] = _mm256_sub_epi32(_mm256_set1_epi32(static_cast<std::int32_t>(e_row[i] - sx[i] * 8 * k)), lane_sx);
        }
    }
    const __m256i zero_i = _mm256_setzero_si256();
    std::uint64_t passed = 0;
    std::uint32_t* row = depth.row(ry0);
    for (int py = ry0; py <= ry1; ++py, row += depth.stride) {
        const __m256 fy = _mm256_set1_ps(static_cast<float>(py));
        #pragma GCC unroll 2
        for (int k = 0; k < Columns; ++k) {
            __m256i cover = in_rect[k];
            #pragma GCC unroll 3
            for (int i = 0; i < 3; ++i) {
                cover = _mm256_and_si256(cover, _mm256_cmpgt_epi32(e[k][i], zero_i));
                e[k][i] = _mm256_add_epi32(e[k][i], step_y[i]);  // the next row (unused after the last)
            }
            const unsigned m = lanes(cover);
            if (m == 0) continue;
            passed += static_cast<unsigned>(
                std::popcount(chunk8<Fmt, F, Write>(plane, row, rx0 + 8 * k, fy, cover, m == 0xffu || own[k], zx[k])));
        }
        if (stop_at_first && passed != 0) return passed;
    }
    return passed;
}

// Whether the depth clamp (max with 0, min with 1) changes no encoded value on any pixel centre of
// `rect`, so that the kernel may skip it there: D16 / D24 only, finite plane coefficients, and the
// unclamped value in [0, 1] at the two corners that bound it. The bound is the one of pipeline.h
// (raster_rect_hiz): each correctly rounded fma is monotone in its addend and in x or y, so over
// the rectangle the value lies between its values at the corner against the signs of dzdx, dzdy
// and the corner with them; then it is finite and in [0, 1] everywhere, where the clamp is the
// identity except that it turns -0 into +0, which both encodings map to the same value
// (cvtps2dq(-0 * 16777215) = 0; -0 * (65535 / 65536) + 128 = 128). D32F stores the float's bits,
// so there -0 would differ: it always clamps. Lanes outside the rectangle are computed but never
// stored or counted (the cover mask), whatever they hold.
template <DepthFormat Fmt>
inline bool clamp_free(const SetupTri& t, PixelRect r) {
    if constexpr (Fmt == DepthFormat::D32F) {
        return false;
    } else {
        if (!(std::isfinite(t.z0) && std::isfinite(t.dzdx) && std::isfinite(t.dzdy))) return false;
        const bool x_up = !(t.dzdx < 0.0f), y_up = !(t.dzdy < 0.0f);
        const auto z = [&t](int x, int y) {
            return std::fma(t.dzdy, static_cast<float>(y), std::fma(t.dzdx, static_cast<float>(x), t.z0));
        };
        const float lo = z(x_up ? r.x0 : r.x1, y_up ? r.y0 : r.y1);
        const float hi = z(x_up ? r.x1 : r.x0, y_up ? r.y1 : r.y0);
        return lo >= 0.0f && hi <= 1.0f;
    }
}

// The wide path of raster_rect8: each row's covered span (RowSpans) in chunks of 8 from its first
// pixel. Clamp false when clamp_free holds for the rectangle. The passing lanes are counted per
// lane (subtracting the all-ones pass mask, one instruction per chunk instead of a movemask, a
// popcount and an add) and summed once at the end; a lane's count is at most the rectangle's rows
// times its chunks per row, far below 2^31.
template <DepthFormat Fmt, DepthFunc F, bool Write, bool Clamp>
std::uint64_t wide_rows(const SetupTri& t, DepthRows depth, PixelRect rect, avx2::RowSpans& spans,
                        bool stop_at_first) {
    const int rx0 = rect.x0, rx1 = rect.x1;
    const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i all = _mm256_set1_epi32(-1);
    const __m256 eight = _mm256_set1_ps(8.0f);
    const Plane8 plane(t);
    __m256i count = _mm256_setzero_si256();
    for (int py = static_cast<int>(spans.y0); py <= spans.y1; ++py) {
        std::int64_t lo, hi;
        spans.next(rx0, rx1, lo, hi);
        if (lo > hi) continue;
        std::uint32_t* row = depth.row(py);
        const __m256 fy = _mm256_set1_ps(static_cast<float>(py));
        const int ihi = static_cast<int>(hi);
        int px = static_cast<int>(lo);
        __m256 fx = lane_x8(px);  // stepped by 8 per chunk: exact, |px| < 2^24
        for (; px + 7 <= ihi; px += 8, fx = _mm256_add_ps(fx, eight))
            count = _mm256_sub_epi32(
                count, pass_chunk8<Fmt, F, Write, Clamp>(plane, row, px, fy, all, true, plane_x8(plane, fx)));
        if (px <= ihi) {
            const __m256i cover = _mm256_cmpgt_epi32(_mm256_set1_epi32(ihi - px + 1), iota);
            count = _mm256_sub_epi32(
                count, pass_chunk8<Fmt, F, Write, Clamp>(plane, row, px, fy, cover,
                                                         own_chunk(px, depth.stride), plane_x8(plane, fx)));
        }
        if (stop_at_first && !_mm256_testz_si256(count, count)) break;
    }
    return sum8(count);
}

template <DepthFormat Fmt, DepthFunc F, bool Write>
std::uint64_t raster_rect8(const SetupTri& t, DepthRows depth, PixelRect rect, bool stop_at_first) {
    const int rx0 = rect.x0, rx1 = rect.x1;
    if (rx1 - rx0 < kNarrow) {
        std::int64_t e_row[3], sx[3], sy[3];
        if (avx2::narrow_lanes_fit(t, rect, e_row, sx, sy)) {
            return rx1 - rx0 < 8
                       ? narrow_rows<1, Fmt, F, Write>(t, depth, rect, e_row, sx, sy, stop_at_first)
                       : narrow_rows<2, Fmt, F, Write>(t, depth, rect, e_row, sx, sy, stop_at_first);
        }
    }
    avx2::RowSpans spans;
    if (!spans.init(t, rect)) return 0;
    return clamp_free<Fmt>(t, rect) ? wide_rows<Fmt, F, Write, false>(t, depth, rect, spans, stop_at_first)
                                    : wide_rows<Fmt, F, Write, true>(t, depth, rect, spans, stop_at_first);
}

}  // namespace
#endif

namespace {
#if defined(RASTER_KERNEL_AVX2)
struct Avx2Kernel {
    template <DepthFormat Fmt, DepthFunc F, bool Write>
    static std::uint64_t rect(const SetupTri& tri, DepthRows depth, PixelRect r, bool stop_at_first) {
        return raster_rect8<Fmt, F, Write>(tri, depth, r, stop_at_first);
    }
    // Unsigned min / max of 8 pixels per row (whole 8-pixel blocks; the scalar loop otherwise).
    static void scan(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
        if (x1 - x0 != 7) return avx2::stored_bounds(d, x0, y0, x1, y1, lo, hi);
        __m256i l = _mm256_set1_epi32(-1), h = _mm256_setzero_si256();
        for (int y = y0; y <= y1; ++y) {
            const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d.row(y) + x0));
            l = _mm256_min_epu32(l, v);
            h = _mm256_max_epu32(h, v);
        }
        __m128i l4 = _mm_min_epu32(_mm256_castsi256_si128(l), _mm256_extracti128_si256(l, 1));
        __m128i h4 = _mm_max_epu32(_mm256_castsi256_si128(h), _mm256_extracti128_si256(h, 1));
        l4 = _mm_min_epu32(l4, _mm_shuffle_epi32(l4, 0x4e));
        h4 = _mm_max_epu32(h4, _mm_shuffle_epi32(h4, 0x4e));
        l4 = _mm_min_epu32(l4, _mm_shuffle_epi32(l4, 0xb1));
        h4 = _mm_max_epu32(h4, _mm_shuffle_epi32(h4, 0xb1));
        lo = static_cast<std::uint32_t>(_mm_cvtsi128_si32(l4));
        hi = static_cast<std::uint32_t>(_mm_cvtsi128_si32(h4));
    }
};
#else
struct Avx2Kernel {  // the scalar kernel, built in this file's namespace
    template <DepthFormat Fmt, DepthFunc F, bool Write>
    static std::uint64_t rect(const SetupTri& tri, DepthRows depth, PixelRect r, bool stop_at_first) {
        return avx2::raster_rect_t<Fmt, F, Write>(tri, depth, r, stop_at_first);
    }
    static void scan(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
        avx2::stored_bounds(d, x0, y0, x1, y1, lo, hi);
    }
};
#endif
}  // namespace

void stored_bounds_avx2(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
    Avx2Kernel::scan(d, x0, y0, x1, y1, lo, hi);
}

RectKernel select_rect_kernel_avx2(const DepthState& state, bool hiz) {
    return avx2::select_rect_kernel_with<Avx2Kernel>(state, hiz);
}

std::uint64_t raster_rect_avx2(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                               bool stop_at_first) {
    return select_rect_kernel_avx2(state, false)(tri, depth, rect, nullptr, stop_at_first);
}

std::uint64_t raster_rect_hiz_avx2(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                                   HizTile& hiz, bool stop_at_first) {
    return select_rect_kernel_avx2(state, true)(tri, depth, rect, &hiz, stop_at_first);
}

bool kernel_avx2_available() {
#if defined(RASTER_KERNEL_AVX2) && (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
    static const bool ok = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return ok;
#else
    return false;
#endif
}

bool kernel_avx2_callable() {
#if defined(RASTER_KERNEL_AVX2)
    return kernel_avx2_available();
#else
    return true;  // the scalar build of the same entry points
#endif
}

}  // namespace raster::detail
