// kernel_avx512.cpp: the 16-wide AVX-512 GL-exact kernel. CMake compiles this file alone with
// -mavx512f -mavx512vl -mavx2 -mfma (x86-64 GCC/Clang, RASTER_KERNEL_AVX512=1); it is chosen at run
// time by kernel_avx512_available(). Elsewhere the same entry points build the scalar kernel of
// raster_kernel.inc and kernel_avx512_available() says false.
//
// The AVX2 kernel (kernel_avx2.cpp) with 16 pixels per step instead of 8, for the same bits: the same
// coverage (exact integer edge functions: 32-bit lanes for narrow rectangles when the bound holds,
// else each row's span from the 64-bit edge functions, stepped row to row) and the same per-pixel
// IEEE operations on the depth plane (one fma per axis, max with 0 then min with 1, the format's
// encoding with MXCSR round-to-nearest-even). What differs is the width: CULLIDE's writes at 1024^2
// cover about 9 pixels of a row in rectangles 9 (narrow) or 35 (wide) pixels wide (a count over
// pipeline_bench cylinders / qcullide-gl), so one 16-lane step replaces one or two 8-lane ones; and
// the masks: a partial step is a mask register on a load and a store (AVX-512's masked memory
// operations touch no pixel outside the mask), and the depth test is one unsigned compare into a
// mask, where AVX2 needed a max and an equality.
// stop_at_first (any-samples queries, mask off): return after the first row with a passing sample,
// as the AVX2 kernel does.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>

#include "pipeline.h"

#if defined(RASTER_KERNEL_AVX512)
// GCC 12 warns that the undefined vectors its AVX-512 headers use as pass-through operands "may be
// used uninitialized" (GCC bug 105593, fixed in 13); they are never read.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>
#endif

namespace raster::detail {
namespace avx512 {
#include "raster_kernel.inc"
}  // namespace avx512

#if defined(RASTER_KERNEL_AVX512)
namespace {

template <DepthFormat Fmt>
inline __m512i encode16(__m512 z) {
    if constexpr (Fmt == DepthFormat::D24) {
        return _mm512_cvtps_epi32(_mm512_mul_ps(z, _mm512_set1_ps(16777215.0f)));
    } else if constexpr (Fmt == DepthFormat::D16) {
        const __m512 t = _mm512_mul_ps(z, _mm512_set1_ps(65535.0f / 65536.0f));
        const __m512 u = _mm512_add_ps(t, _mm512_set1_ps(128.0f));
        return _mm512_and_si512(_mm512_castps_si512(u), _mm512_set1_epi32(0xffff));
    } else {
        return _mm512_castps_si512(z);
    }
}

// GL's depth functions as AVX-512 compare predicates: unsigned integers (D16 / D24, whose stored
// values order as unsigned 32-bit integers) and floats (D32F: ordered, and NotEqual unordered, as
// C++'s operators). Never and Always compare nothing.
template <DepthFunc F>
constexpr int kIntPredicate = F == DepthFunc::Less       ? _MM_CMPINT_LT
                              : F == DepthFunc::Equal    ? _MM_CMPINT_EQ
                              : F == DepthFunc::LEqual   ? _MM_CMPINT_LE
                              : F == DepthFunc::Greater  ? _MM_CMPINT_NLE
                              : F == DepthFunc::NotEqual ? _MM_CMPINT_NE
                                                         : _MM_CMPINT_NLT;  // GEqual
template <DepthFunc F>
constexpr int kFloatPredicate = F == DepthFunc::Less       ? _CMP_LT_OQ
                                : F == DepthFunc::Equal    ? _CMP_EQ_OQ
                                : F == DepthFunc::LEqual   ? _CMP_LE_OQ
                                : F == DepthFunc::Greater  ? _CMP_GT_OQ
                                : F == DepthFunc::NotEqual ? _CMP_NEQ_UQ
                                                           : _CMP_GE_OQ;  // GEqual

// The lanes of `cover` where depth_pass<F>(incoming, stored) holds.
template <DepthFormat Fmt, DepthFunc F>
inline __mmask16 pass16(__mmask16 cover, __m512i incoming, __m512i stored) {
    if constexpr (F == DepthFunc::Never) return 0;
    else if constexpr (F == DepthFunc::Always) return cover;
    else if constexpr (Fmt == DepthFormat::D32F)
        return _mm512_mask_cmp_ps_mask(cover, _mm512_castsi512_ps(incoming), _mm512_castsi512_ps(stored),
                                       kFloatPredicate<F>);
    else return _mm512_mask_cmp_epu32_mask(cover, incoming, stored, kIntPredicate<F>);
}

// encode16 and pass16 for 8 lanes (narrow_rows8).
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
template <DepthFormat Fmt, DepthFunc F>
inline __mmask8 pass8(__mmask8 cover, __m256i incoming, __m256i stored) {
    if constexpr (F == DepthFunc::Never) return 0;
    else if constexpr (F == DepthFunc::Always) return cover;
    else if constexpr (Fmt == DepthFormat::D32F)
        return _mm256_mask_cmp_ps_mask(cover, _mm256_castsi256_ps(incoming), _mm256_castsi256_ps(stored),
                                       kFloatPredicate<F>);
    else return _mm256_mask_cmp_epu32_mask(cover, incoming, stored, kIntPredicate<F>);
}

struct Plane16 {
    __m512 z0, dzdx, dzdy;
    explicit Plane16(const SetupTri& t)
        : z0(_mm512_set1_ps(t.z0)), dzdx(_mm512_set1_ps(t.dzdx)), dzdy(_mm512_set1_ps(t.dzdy)) {}
};

inline __m512i iota16() { return _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15); }

// The x coordinates px..px+15 as floats (exact: |px| < 2^24).
inline __m512 lane_x16(int px) { return _mm512_cvtepi32_ps(_mm512_add_epi32(_mm512_set1_epi32(px), iota16())); }

// Depth test (and write) of the pixels px + lane (lanes in `cover`) of `row` at row centre fy; zx:
// fma(dzdx, x, z0) of the 16 pixels. Returns the passing lanes.
template <DepthFormat Fmt, DepthFunc F, bool Write>
inline __mmask16 chunk16(const Plane16& plane, std::uint32_t* row, int px, __m512 fy, __mmask16 cover, __m512 zx) {
    __m512 z = _mm512_fmadd_ps(plane.dzdy, fy, zx);
    z = _mm512_max_ps(z, _mm512_setzero_ps());  // NaN -> 0, -0 -> +0: the second operand, as maxps
    z = _mm512_min_ps(z, _mm512_set1_ps(1.0f));
    const __m512i incoming = encode16<Fmt>(z);
    std::uint32_t* p = row + px;
    const __m512i stored = _mm512_maskz_loadu_epi32(cover, p);
    const __mmask16 pass = pass16<Fmt, F>(cover, incoming, stored);
    if constexpr (Write) _mm512_mask_storeu_epi32(p, pass, incoming);
    return pass;
}

// Narrow rectangles (at most 16 pixels wide) whose edge values fit 32 bits (the AVX2 kernel's rule,
// kernel_avx2.cpp): per row, the 16 lanes' edge values (stepped by the y steps) give the coverage.
// Lanes beyond the rectangle are outside `in_rect` and never used (their products may wrap).
template <DepthFormat Fmt, DepthFunc F, bool Write>
std::uint64_t narrow_rows16(const SetupTri& t, DepthRows depth, PixelRect rect, const std::int64_t (&e_row)[3],
                            const std::int64_t (&sx)[3], const std::int64_t (&sy)[3], bool stop_at_first) {
    const int rx0 = rect.x0, ry0 = rect.y0, rx1 = rect.x1, ry1 = rect.y1;
    const Plane16 plane(t);
    const __m512i iota = iota16();
    const __mmask16 in_rect = static_cast<__mmask16>((1u << (rx1 - rx0 + 1)) - 1u);
    const __m512 zx = _mm512_fmadd_ps(plane.dzdx, lane_x16(rx0), plane.z0);
    __m512i e[3], step_y[3];
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        step_y[i] = _mm512_set1_epi32(static_cast<std::int32_t>(sy[i]));
        e[i] = _mm512_sub_epi32(_mm512_set1_epi32(static_cast<std::int32_t>(e_row[i])),
                                _mm512_mullo_epi32(_mm512_set1_epi32(static_cast<std::int32_t>(sx[i])), iota));
    }
    const __m512i zero = _mm512_setzero_si512();
    std::uint64_t passed = 0;
    std::uint32_t* row = depth.row(ry0);
    for (int py = ry0; py <= ry1; ++py, row += depth.stride) {
        __mmask16 cover = _mm512_mask_cmpgt_epi32_mask(in_rect, e[0], zero);
        cover = _mm512_mask_cmpgt_epi32_mask(cover, e[1], zero);
        cover = _mm512_mask_cmpgt_epi32_mask(cover, e[2], zero);
#pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) e[i] = _mm512_add_epi32(e[i], step_y[i]);  // the next row
        if (cover == 0) continue;
        const __m512 fy = _mm512_set1_ps(static_cast<float>(py));
        passed += static_cast<unsigned>(std::popcount(static_cast<unsigned>(chunk16<Fmt, F, Write>(plane, row, rx0, fy, cover, zx))));
        if (stop_at_first && passed != 0) return passed;
    }
    return passed;
}

// The same for rectangles at most 8 pixels wide, in 8 lanes (256-bit registers with AVX-512VL's mask
// compares, loads and stores): 16 lanes for 1 to 8 pixels cost more than they save (raster_bench
// SmallTris, triangles of about 8 px^2: 3-11% slower than the AVX2 kernel with 16 lanes).
template <DepthFormat Fmt, DepthFunc F, bool Write>
std::uint64_t narrow_rows8(const SetupTri& t, DepthRows depth, PixelRect rect, const std::int64_t (&e_row)[3],
                           const std::int64_t (&sx)[3], const std::int64_t (&sy)[3], bool stop_at_first) {
    const int rx0 = rect.x0, ry0 = rect.y0, rx1 = rect.x1, ry1 = rect.y1;
    const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256 z0 = _mm256_set1_ps(t.z0), dzdx = _mm256_set1_ps(t.dzdx), dzdy = _mm256_set1_ps(t.dzdy);
    const auto in_rect = static_cast<__mmask8>((1u << (rx1 - rx0 + 1)) - 1u);
    const __m256 zx = _mm256_fmadd_ps(dzdx, _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(rx0), iota)), z0);
    __m256i e[3], step_y[3];
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        step_y[i] = _mm256_set1_epi32(static_cast<std::int32_t>(sy[i]));
        e[i] = _mm256_sub_epi32(_mm256_set1_epi32(static_cast<std::int32_t>(e_row[i])),
                                _mm256_mullo_epi32(_mm256_set1_epi32(static_cast<std::int32_t>(sx[i])), iota));
    }
    const __m256i zero = _mm256_setzero_si256();
    std::uint64_t passed = 0;
    std::uint32_t* row = depth.row(ry0);
    for (int py = ry0; py <= ry1; ++py, row += depth.stride) {
        __mmask8 cover = _mm256_mask_cmpgt_epi32_mask(in_rect, e[0], zero);
        cover = _mm256_mask_cmpgt_epi32_mask(cover, e[1], zero);
        cover = _mm256_mask_cmpgt_epi32_mask(cover, e[2], zero);
#pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) e[i] = _mm256_add_epi32(e[i], step_y[i]);
        if (cover == 0) continue;
        __m256 z = _mm256_fmadd_ps(dzdy, _mm256_set1_ps(static_cast<float>(py)), zx);
        z = _mm256_max_ps(z, _mm256_setzero_ps());
        z = _mm256_min_ps(z, _mm256_set1_ps(1.0f));
        const __m256i incoming = encode8<Fmt>(z);
        const __m256i stored = _mm256_maskz_loadu_epi32(cover, row + rx0);
        const __mmask8 pass = pass8<Fmt, F>(cover, incoming, stored);
        if constexpr (Write) _mm256_mask_storeu_epi32(row + rx0, pass, incoming);
        passed += static_cast<unsigned>(std::popcount(static_cast<unsigned>(pass)));
        if (stop_at_first && passed != 0) return passed;
    }
    return passed;
}

constexpr int kNarrow16 = 16;

template <DepthFormat Fmt, DepthFunc F, bool Write>
std::uint64_t raster_rect16(const SetupTri& t, DepthRows depth, PixelRect rect, bool stop_at_first) {
    const int rx0 = rect.x0, rx1 = rect.x1;
    if (rx1 - rx0 < kNarrow16) {  // the AVX2 kernel's rule (raster_kernel.inc)
        std::int64_t e_row[3], sx[3], sy[3];
        if (avx512::narrow_lanes_fit(t, rect, e_row, sx, sy))
            return rx1 - rx0 < 8 ? narrow_rows8<Fmt, F, Write>(t, depth, rect, e_row, sx, sy, stop_at_first)
                                 : narrow_rows16<Fmt, F, Write>(t, depth, rect, e_row, sx, sy, stop_at_first);
    }
    avx512::RowSpans spans;
    if (!spans.init(t, rect)) return 0;
    const __m512 sixteen = _mm512_set1_ps(16.0f);
    const Plane16 plane(t);
    std::uint64_t passed = 0;
    for (int py = static_cast<int>(spans.y0); py <= spans.y1; ++py) {
        std::int64_t lo, hi;
        spans.next(rx0, rx1, lo, hi);
        if (lo > hi) continue;
        std::uint32_t* row = depth.row(py);
        const __m512 fy = _mm512_set1_ps(static_cast<float>(py));
        const int ihi = static_cast<int>(hi);
        int px = static_cast<int>(lo);
        __m512 fx = lane_x16(px);  // stepped by 16 per step: exact, |px| < 2^24
        unsigned row_passed = 0;
        for (; px + 15 <= ihi; px += 16, fx = _mm512_add_ps(fx, sixteen))
            row_passed += static_cast<unsigned>(std::popcount(static_cast<unsigned>(
                chunk16<Fmt, F, Write>(plane, row, px, fy, 0xffff, _mm512_fmadd_ps(plane.dzdx, fx, plane.z0)))));
        if (px <= ihi) {
            const auto cover = static_cast<__mmask16>((1u << (ihi - px + 1)) - 1u);
            row_passed += static_cast<unsigned>(std::popcount(static_cast<unsigned>(
                chunk16<Fmt, F, Write>(plane, row, px, fy, cover, _mm512_fmadd_ps(plane.dzdx, fx, plane.z0)))));
        }
        passed += row_passed;
        if (stop_at_first && passed != 0) return passed;
    }
    return passed;
}

}  // namespace
#endif

namespace {
#if defined(RASTER_KERNEL_AVX512)
struct Avx512Kernel {
    template <DepthFormat Fmt, DepthFunc F, bool Write>
    static std::uint64_t rect(const SetupTri& tri, DepthRows depth, PixelRect r, bool stop_at_first) {
        return raster_rect16<Fmt, F, Write>(tri, depth, r, stop_at_first);
    }
    static void scan(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
        stored_bounds_avx2(d, x0, y0, x1, y1, lo, hi);
    }
};
#else
struct Avx512Kernel {  // the scalar kernel, built in this file's namespace
    template <DepthFormat Fmt, DepthFunc F, bool Write>
    static std::uint64_t rect(const SetupTri& tri, DepthRows depth, PixelRect r, bool stop_at_first) {
        return avx512::raster_rect_t<Fmt, F, Write>(tri, depth, r, stop_at_first);
    }
    static void scan(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi) {
        avx512::stored_bounds(d, x0, y0, x1, y1, lo, hi);
    }
};
#endif
}  // namespace

RectKernel select_rect_kernel_avx512(const DepthState& state, bool hiz) {
    return avx512::select_rect_kernel_with<Avx512Kernel>(state, hiz);
}

std::uint64_t raster_rect_avx512(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                                 bool stop_at_first) {
    return select_rect_kernel_avx512(state, false)(tri, depth, rect, nullptr, stop_at_first);
}

std::uint64_t raster_rect_hiz_avx512(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                                     HizTile& hiz, bool stop_at_first) {
    return select_rect_kernel_avx512(state, true)(tri, depth, rect, &hiz, stop_at_first);
}

bool kernel_avx512_available() {
#if defined(RASTER_KERNEL_AVX512) && (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
    static const bool ok = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                           __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return ok;
#else
    return false;
#endif
}

bool kernel_avx512_callable() {
#if defined(RASTER_KERNEL_AVX512)
    return kernel_avx512_available();
#else
    return true;  // the scalar build of the same entry points
#endif
}

}  // namespace raster::detail
