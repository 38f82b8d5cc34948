// exact_bounds.h (private): the conservative "exact bounds" mode (docs/reliable-raster.md).
//
// Front end: one input triangle (double clip space, w = 1) is clipped against the clip volume grown
// by a margin, in double, and mapped to window coordinates: a convex polygon of at most 9 vertices
// (a segment or a point for degenerate input). Back end: a pixel is covered when its closed square
// grown by a margin meets the polygon, and [zmin, zmax] bounds the polygon's depth over that part,
// widened by a margin and rounded outward to the depth format. Four traversals compute it (chosen
// per triangle): the general one (per-row clipping and per-column edge crossings: the exact
// polygon-square depth range), the plane path (separating-axis coverage and the plane's range over
// the square, with computed error bounds), and the column / row paths for triangles one or two
// pixels thin. The margins and bounds exceed every rounding error of those steps
// (docs/reliable-raster.md, "Why every rounding is covered"), so the result contains the exact one.
// Every pixel is computed from the polygon alone (never accumulated), so traversal order, tiling and
// thread count cannot change a bit.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "pipeline.h"
#include "raster/types.h"

namespace raster::detail {

inline constexpr int kBoundsMaxVerts = 16;  // 3 + 6 clip planes + 4 square planes, rounded up

// Margins (docs/reliable-raster.md): each is at least 2^8 times the rounding error it covers.
inline constexpr double kClipMarginRel = 0x1p-40;  // clip units per unit of the triangle's magnitude M
inline constexpr double kPixelMargin = 0x1p-20;    // pixels, for the window-space steps (|X| < 2^16)
inline constexpr double kDepthMargin = 0x1p-40;    // window depth, for the window-space steps

// floor and ceil without a libm call on baseline x86-64 (equal to std::floor / std::ceil for every
// finite x, up to the sign of a zero result: |x| >= 2^52 is already an integer).
inline double exact_floor(double x) {
    if (!(std::fabs(x) < 0x1p52)) return x;
    const double t = static_cast<double>(static_cast<std::int64_t>(x));
    return t > x ? t - 1.0 : t;
}
inline double exact_ceil(double x) {
    if (!(std::fabs(x) < 0x1p52)) return x;
    const double t = static_cast<double>(static_cast<std::int64_t>(x));
    return t < x ? t + 1.0 : t;
}

// The pixels whose closed square [px, px + 1] grown by m meets [x0, x1] x [y0, y1]: ceil(lo - m) - 1
// <= px <= floor(hi + m), before cutting to a target (setup_bounds_triangle's pixel box, and
// bounds_reach's from the same operations).
struct GrownBox {
    double bx0, by0, bx1, by1;
    // No pixel of a width x height target.
    [[nodiscard]] bool outside(int width, int height) const {
        return bx1 < 0.0 || by1 < 0.0 || bx0 > static_cast<double>(width - 1) || by0 > static_cast<double>(height - 1);
    }
    // Cut to the target (not outside it): inclusive pixels.
    void cut(int width, int height, int& x0, int& y0, int& x1, int& y1) const {
        x0 = static_cast<int>(std::max(bx0, 0.0));
        y0 = static_cast<int>(std::max(by0, 0.0));
        x1 = static_cast<int>(std::min(bx1, static_cast<double>(width - 1)));
        y1 = static_cast<int>(std::min(by1, static_cast<double>(height - 1)));
    }
};
inline GrownBox grown_box(double x0, double x1, double y0, double y1, double m) {
    return {exact_ceil(x0 - m) - 1.0, exact_ceil(y0 - m) - 1.0, exact_floor(x1 + m), exact_floor(y1 + m)};
}

// One vertex of a clipped polygon in window coordinates.
struct BoundsVertex {
    double x, y, z;
};

// A clipped polygon: vertices [first, first + n) of its draw's vertex pool (most polygons are the
// unclipped triangle, so a pool keeps memory at ~3 vertices per triangle).
struct BoundsTri {
    std::uint32_t first = 0;
    int n = 0;
    double margin_xy = 0;                  // pixels: the square is grown by this on every side
    double margin_z = 0;                   // window depth: the interval is widened by this
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive pixel box, inside the target
    std::uint32_t draw = 0;
    // The box (grown by margin_xy, before clamping to the target) is one pixel: that pixel's grown
    // square holds the whole polygon, so its range is the polygon's vertex depth range.
    bool single = false;
    // Encoded depth bounds of every pixel's zmin (>= zq_lo) and zmax (<= zq_hi), for callers that
    // fill them in (the fused visibility pass: bounds_depth_range, then the outward quantization).
    std::uint32_t zq_lo = 0, zq_hi = 0xffffffffu;
    // Which per-pixel path bounds_pixels takes (chosen once by setup_bounds_triangle):
    //  General:  per-row Sutherland-Hodgman clip + per-column edge crossings (any polygon);
    //  Plane:    separating-axis coverage + plane depth, closed form per pixel (a polygon of 3
    //            vertices, box > 4 pixels, certain orientation, well-conditioned plane; BoundsPlane);
    //  Column:   every vertex has the same X (an edge-on triangle seen as a vertical segment, e.g.
    //            the sides of CULLIDE's axis-aligned boxes), or the polygon lies inside every box
    //            column's grown interval (thin triangles one or two columns wide): per row, the
    //            polygon's depth range over the row slab; the same for the one or two columns.
    //  Row:      the same with X and Y exchanged.
    enum class Kind : std::uint8_t { General, Plane, Column, Row };
    Kind kind = Kind::General;
    // Kind::Plane keeps its BoundsPlane in the pool right after the polygon (kPlaneSlots vertex
    // slots), so that BoundsTri stays small for the other kinds (load_plane).
};

// Plane-path data, in coordinates local to the anchor pixel (x0, y0) (see docs/reliable-raster.md,
// "Why every rounding is covered", 8-9): pixel (px, py) is (lx, ly) = (px - x0, py - y0), exact
// small integers.
struct BoundsPlane {
    // Edge i: the pixel's grown square misses the triangle when ea * lx + (eb * ly + ek) < et.
    double ea[3], eb[3], ek[3], et[3];
    double inv_a[3];  // 1 / ea (0 when ea = 0): only to estimate where a row crosses the edge
    // Depth: centre value pz + pgx * lx + pgy * ly, widened by pw, clamped to [pzlo, pzhi].
    double pz, pgx, pgy, pw, pzlo, pzhi;
    // Widening of a slab depth range (slab_depth_range) for its rounding (tightening only).
    double sw;
};
inline constexpr int kPlaneSlots = static_cast<int>((sizeof(BoundsPlane) + sizeof(BoundsVertex) - 1) / sizeof(BoundsVertex));

inline BoundsPlane load_plane(const BoundsTri& t, const BoundsVertex* pool) {
    BoundsPlane d;
    std::memcpy(&d, pool + t.first + static_cast<std::uint32_t>(t.n), sizeof d);
    return d;
}


// Appends 0 or 1 BoundsTri for the triangle (a, b, c) to `out` and its polygon to `pool`. Inputs
// were validated (finite, w = 1, |coordinate| <= kMaxExactBoundsCoordinate).
void setup_bounds_triangle(const FrontEndParams& params, const Double4& a, const Double4& b, const Double4& c,
                           std::uint32_t draw, std::vector<BoundsTri>& out, std::vector<BoundsVertex>& pool);

// setup_bounds_triangle for triangles (indices[3k], indices[3k + 1], indices[3k + 2]) of `vertices`,
// k in order (the same records in the same order; validated input). With allow_simd and AVX2, four
// triangles at a time share the common front (absolute maximum, viewport, box; setup_avx2.cpp);
// clipped ones take the scalar path.
void setup_bounds_range(const FrontEndParams& params, std::span<const Double4> vertices,
                        std::span<const std::uint32_t> indices, std::uint32_t draw, std::vector<BoundsTri>& out,
                        std::vector<BoundsVertex>& pool, bool allow_simd = true);

// Rasterizes `tri` (polygon in `pool`) over `rect` (inside the target): per covered pixel the depth
// test state.func of zmin (write) or zmax (!write) against the stored value, and the write of zmin
// when state.write. Returns the covered pixels that passed.
std::uint64_t bounds_rect(const BoundsTri& tri, const BoundsVertex* pool, const DepthState& state, DepthRows depth,
                          PixelRect rect);

// Outward quantization of a window depth in [0, 1] to the stored encoding (exposed for tests):
// down = the largest representable value <= z, up = the smallest >= z. Inline: with the plane path
// every pixel has its own depth, so these run per pixel.
inline constexpr double kQuantFracGuard = 0x1p-27;  // > 2^-29, the rounding error of z * n for n < 2^24

inline std::uint32_t quantize_down(double z, DepthFormat format) {
    z = z > 0.0 ? z : 0.0;
    z = z < 1.0 ? z : 1.0;
    if (format == DepthFormat::D32F) {
        float f = static_cast<float>(z);
        if (static_cast<double>(f) > z) f = std::nextafter(f, -1.0f);
        return std::bit_cast<std::uint32_t>(f);
    }
    const double n = format == DepthFormat::D16 ? 65535.0 : 16777215.0;
    const double q = z * n;
    // 0 <= q < 2^24: truncation is the floor (and avoids a libm call on baseline x86-64).
    double v = static_cast<double>(static_cast<std::int64_t>(q));
    // q errs by <= 2^-29 (half an ulp below 2^24), so unless q is that close to an integer its floor
    // is the exact one (q - v is exact). Otherwise correct exactly: the sign of fma(z, n, -v) is
    // the sign of z * n - v.
    const double frac = q - v;
    if (frac >= kQuantFracGuard && frac <= 1.0 - kQuantFracGuard) return static_cast<std::uint32_t>(v);
    if (std::fma(z, n, -v) < 0.0) v -= 1.0;
    if (std::fma(z, n, -(v + 1.0)) >= 0.0) v += 1.0;
    v = std::clamp(v, 0.0, n);
    return static_cast<std::uint32_t>(v);
}

inline std::uint32_t quantize_up(double z, DepthFormat format) {
    z = z > 0.0 ? z : 0.0;
    z = z < 1.0 ? z : 1.0;
    if (format == DepthFormat::D32F) {
        float f = static_cast<float>(z);
        if (static_cast<double>(f) < z) f = std::nextafter(f, 2.0f);
        return std::bit_cast<std::uint32_t>(f);
    }
    const double n = format == DepthFormat::D16 ? 65535.0 : 16777215.0;
    const double q = z * n;
    double v = static_cast<double>(static_cast<std::int64_t>(q));
    if (v < q) v += 1.0;        // the ceiling
    const double frac = v - q;  // exact, as above
    if (frac >= kQuantFracGuard && frac <= 1.0 - kQuantFracGuard) return static_cast<std::uint32_t>(v);
    if (std::fma(z, n, -v) > 0.0) v += 1.0;
    if (std::fma(z, n, -(v - 1.0)) <= 0.0) v -= 1.0;
    v = std::clamp(v, 0.0, n);
    return static_cast<std::uint32_t>(v);
}

// Where a list of triangles can reach, from its vertices alone (no setup, no clipping): for a
// pre-pass that decides which triangles need setting up at all (the fused visibility pass's items
// alone in the view). bounds_reach calls box(x0, y0, x1, y1) (inclusive pixels inside the target)
// for boxes whose union holds the pixel box of every BoundsTri that setup_bounds_triangle makes of
// the triangles: their common box, or one box per triangle when the common one would be more than
// kReachSpread times the triangles' count in cells of 2^shift pixels (scattered triangles). It
// returns whether it made one box (`single`) and an encoded depth at least every zmax of their
// fragments (quantize_up(zhi + margin_z) as bounds_depth_range bounds zhi). ok = false when an index
// or vertex fails the input checks (nothing is marked; the front end reports it).
struct BoundsReach {
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // the one box (single and not empty), the box() call's
    std::uint32_t zq_hi = 0xffffffffu;
    bool ok = true;
    bool single = true;  // one box (or none: nothing reaches the target)
    bool empty = true;   // no box at all
};
inline constexpr int kReachSpread = 4;
inline constexpr int kReachMaxIndices = 96;  // per-triangle boxes for lists up to this many indices

template <class Box>
BoundsReach bounds_reach(const FrontEndParams& params, const MeshViewD& mesh, DepthFormat format, int shift,
                         Box&& box) {
    BoundsReach r;
    const std::size_t nv = mesh.vertices.size();
    const std::size_t n = mesh.indices.size() - mesh.indices.size() % 3;
    if (n == 0) return r;
    constexpr double kInf = __builtin_inf();
    double absmax = 0.0, cx0 = kInf, cx1 = -kInf, cy0 = kInf, cy1 = -kInf, cz0 = kInf, cz1 = -kInf;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t i = mesh.indices[k];
        if (i >= nv) return BoundsReach{0, 0, -1, -1, 0xffffffffu, false, true, true};
        const Double4& v = mesh.vertices[i];
        // (Each coordinate compared on its own: std::max drops a NaN in its second argument.)
        if (v.w != 1.0 || !(std::fabs(v.x) <= kMaxExactBoundsCoordinate && std::fabs(v.y) <= kMaxExactBoundsCoordinate &&
                            std::fabs(v.z) <= kMaxExactBoundsCoordinate))
            return BoundsReach{0, 0, -1, -1, 0xffffffffu, false, true, true};
        const double m = std::max(std::max(std::fabs(v.x), std::fabs(v.y)), std::fabs(v.z));
        absmax = m > absmax ? m : absmax;
        cx0 = std::min(cx0, v.x), cx1 = std::max(cx1, v.x);
        cy0 = std::min(cy0, v.y), cy1 = std::max(cy1, v.y);
        cz0 = std::min(cz0, v.z), cz1 = std::max(cz1, v.z);
    }
    // A triangle's clip keeps nothing when all its vertices are beyond one plane of the volume
    // grown to lim = 1 + M 2^-40 (lim - v < 0 for each: the sign of the rounded difference is the
    // exact one); M <= max(1, absmax), so lim <= the item's `lim` (the same rounded sum).
    const double mc = std::max(1.0, absmax) * kClipMarginRel;
    const double lim = 1.0 + mc;
    if (cx0 > lim || cx1 < -lim || cy0 > lim || cy1 < -lim || cz0 > lim || cz1 < -lim) return r;
    const Viewport& vp = params.viewport;
    const double hw = static_cast<double>(vp.width) * 0.5;
    const double hh = static_cast<double>(vp.height) * 0.5;
    const double tx = static_cast<double>(vp.x) + hw;
    const double ty = static_cast<double>(vp.y) + hh;
    r.empty = false;
    if (absmax > 2.0) {  // large magnitudes: clipping's rounding scales with M; the whole target
        r.x0 = 0, r.y0 = 0, r.x1 = params.target_width - 1, r.y1 = params.target_height - 1;
        box(r.x0, r.y0, r.x1, r.y1);
        return r;  // (zq_hi stays the largest value: never alone)
    }
    // Every triangle's margins are at most m and mz (its M <= max(1, absmax)). With |v| <= 1 < lim
    // setup_bounds_triangle takes each triangle unclipped with window coordinates v * (w / 2) + (x0 +
    // w / 2) and depth z * 0.5 + 0.5: the same operations below give the same values, and rounding
    // is monotone, so ceil(min X - m) - 1 over more vertices and a larger margin is at most each
    // triangle's, and so on. With 1 < |v| <= 2 a triangle may be clipped: its polygon lies in its
    // hull cut to [-lim, lim] up to clipping's rounding (< 2^-43 clip units, < 2^-30 pixels and
    // 2^-44 in depth at every target size), far inside the extra pixel and 2^-30 added then.
    const bool clipped = absmax > 1.0;
    const double extra = clipped ? 1.0 : 0.0;
    const double m = kPixelMargin + mc * std::max(hw, hh) + extra;
    const auto clamp_c = [&](double c) { return clipped ? std::clamp(c, -lim, lim) : c; };
    // The depth bound: every zhi is at most the largest vertex depth (bounds_depth_range), widened
    // for the general path by 2^-40 max|z| + 2^-1000; then the margin, then the outward quantization.
    {
        const double z0 = clamp_c(cz0) * 0.5 + 0.5, z1 = clamp_c(cz1) * 0.5 + 0.5;
        const double slack = 0x1p-40 * std::max(std::fabs(z0), std::fabs(z1)) + 0x1p-1000 + (clipped ? 0x1p-30 : 0.0);
        r.zq_hi = quantize_up((z1 + slack) + (kDepthMargin + mc), format);
    }
    // The box of window extremes [x0, x1] x [y0, y1] grown by m, in the target; false when outside.
    const auto pixel_box = [&](double x0, double x1, double y0, double y1, int* b) {
        const GrownBox g = grown_box(x0, x1, y0, y1, m);
        if (g.outside(params.target_width, params.target_height)) return false;
        g.cut(params.target_width, params.target_height, b[0], b[1], b[2], b[3]);
        return true;
    };
    int all[4];
    if (!pixel_box(clamp_c(cx0) * hw + tx, clamp_c(cx1) * hw + tx, clamp_c(cy0) * hh + ty, clamp_c(cy1) * hh + ty,
                   all)) {
        r.empty = true;
        return r;
    }
    const std::size_t cells = static_cast<std::size_t>((all[2] >> shift) - (all[0] >> shift) + 1) *
                              static_cast<std::size_t>((all[3] >> shift) - (all[1] >> shift) + 1);
    if (cells <= static_cast<std::size_t>(kReachSpread) * (n / 3) || n > static_cast<std::size_t>(kReachMaxIndices)) {
        box(all[0], all[1], all[2], all[3]);
        r.x0 = all[0], r.y0 = all[1], r.x1 = all[2], r.y1 = all[3];
        return r;
    }
    r.single = false;
    r.empty = true;
    for (std::size_t k = 0; k < n; k += 3) {
        const Double4& a = mesh.vertices[mesh.indices[k]];
        const Double4& b = mesh.vertices[mesh.indices[k + 1]];
        const Double4& c = mesh.vertices[mesh.indices[k + 2]];
        const double xa = clamp_c(a.x) * hw + tx, xb = clamp_c(b.x) * hw + tx, xc = clamp_c(c.x) * hw + tx;
        const double ya = clamp_c(a.y) * hh + ty, yb = clamp_c(b.y) * hh + ty, yc = clamp_c(c.y) * hh + ty;
        int t[4];
        if (pixel_box(std::min(std::min(xa, xb), xc), std::max(std::max(xa, xb), xc), std::min(std::min(ya, yb), yc),
                      std::max(std::max(ya, yb), yc), t)) {
            box(t[0], t[1], t[2], t[3]);
            r.empty = false;
        }
    }
    return r;
}

// Cheap bounds of the outward quantizations, for the settling pre-pass (a looser bound settles
// fewer items, never a wrong one). Let c(z) be fl(z' * n) truncated (D16, D24) or the bits of
// float(z') rounded to nearest (D32F), z' = z clamped to [0, 1] as both quantizations clamp. Both
// are monotone, and c(z) >= quantize_down(z) (floor(z' n) is representable and rounding is
// monotone; round to nearest gives the float below or the one above) and c(z) <= quantize_up(z)
// (likewise). So c(z) bounds quantize_down from above and quantize_up from below, and c(z) - 1 and
// c(z) + 1 (kept inside the encodings) bound quantize_down from below and quantize_up from above
// (c is at most one step from either).
inline std::uint32_t encode_near(double z, DepthFormat format) {
    z = z > 0.0 ? z : 0.0;
    z = z < 1.0 ? z : 1.0;
    if (format == DepthFormat::D32F) return std::bit_cast<std::uint32_t>(static_cast<float>(z));
    const double n = format == DepthFormat::D16 ? 65535.0 : 16777215.0;
    return static_cast<std::uint32_t>(static_cast<std::int64_t>(z * n));
}
inline std::uint32_t encode_below_down(double z, DepthFormat format) {
    const std::uint32_t c = encode_near(z, format);
    return c > 0 ? c - 1 : 0;
}
inline std::uint32_t encode_above_up(double z, DepthFormat format) {
    const std::uint32_t c = encode_near(z, format);
    const std::uint32_t top = format == DepthFormat::D32F ? 0x3f800000u : format == DepthFormat::D16 ? 65535u : 16777215u;
    return c < top ? c + 1 : top;
}

// Bounds of triangles from their vertices alone, without setting them up, for the fused visibility
// pass's settling pre-pass (visibility.cpp, State::presettle): for triangles whose every
// |coordinate| is <= 1, given the extremes of their window positions (WindowMap below), box(x0, y0,
// x1, y1, lo, hi) (inclusive pixels inside the target; none when the box is outside) such that
// every BoundsTri record that setup_bounds_triangle makes of them lies in the box, with the encoded
// zmin of each of its fragments >= lo and its zmax <= hi (the draw's quantization is
// quantize_down(zlo - margin_z) and quantize_up(zhi + margin_z); lo and hi are the cheap bounds of
// those, encode_below_down and encode_above_up). With spread_limit > 0 it calls nothing and returns
// false when the box holds more pixels than that (the caller then boxes each triangle).
// Why: with every |coordinate| <= 1 < lim setup takes the unclipped path with M = 1, so each
// triangle's margins are kPixelMargin + kClipMarginRel * max(w / 2, h / 2) and kDepthMargin +
// kClipMarginRel, and its box is grown_box of its window extremes. The window map x * (w / 2) +
// (x0 + w / 2) is monotone in x (so is its rounding), so the extremes of more vertices are at least
// as far out, and grown_box is monotone too. Every (zlo, zhi) a path reports lies in the triangle's
// vertex depth range widened by 2^-40 max|z| + 2^-1000 (bounds_depth_range, which widens only the
// general path; the others stay inside the vertex range), and subtraction, addition and both
// quantizations are monotone. (Triangles with a larger coordinate may be clipped: the pre-pass
// takes bounds_reach's boxes for them, with the widest encoded range.)
struct WindowBoxer {
    int width, height;
    double m, mz;
    DepthFormat format;
    WindowBoxer(const FrontEndParams& params, DepthFormat f)
        : width(params.target_width),
          height(params.target_height),
          m(kPixelMargin + kClipMarginRel * std::max(static_cast<double>(params.viewport.width) * 0.5,
                                                     static_cast<double>(params.viewport.height) * 0.5)),
          mz(kDepthMargin + kClipMarginRel),
          format(f) {}
    template <class Box>
    bool operator()(double x0, double x1, double y0, double y1, double z0, double z1, std::size_t spread_limit,
                    Box&& box) const {
        const GrownBox g = grown_box(x0, x1, y0, y1, m);
        if (g.outside(width, height)) return true;  // no fragment
        int b[4];
        g.cut(width, height, b[0], b[1], b[2], b[3]);
        if (spread_limit > 0 &&
            static_cast<std::size_t>(b[2] - b[0] + 1) * static_cast<std::size_t>(b[3] - b[1] + 1) > spread_limit)
            return false;
        const double slack = 0x1p-40 * std::max(std::fabs(z0), std::fabs(z1)) + 0x1p-1000;
        box(b[0], b[1], b[2], b[3], encode_below_down((z0 - slack) - mz, format),
            encode_above_up((z1 + slack) + mz, format));
        return true;
    }
};

// The window position of a vertex with every |coordinate| <= 1: the very values that
// setup_bounds_triangle computes for it, clipped or not (the same operations on the same inputs;
// the clip keeps such a vertex unchanged).
struct WindowMap {
    double hw, hh, tx, ty;
    explicit WindowMap(const FrontEndParams& params)
        : hw(static_cast<double>(params.viewport.width) * 0.5),
          hh(static_cast<double>(params.viewport.height) * 0.5),
          tx(static_cast<double>(params.viewport.x) + hw),
          ty(static_cast<double>(params.viewport.y) + hh) {}
    [[nodiscard]] BoundsVertex operator()(const Double4& v) const { return {v.x * hw + tx, v.y * hh + ty, v.z * 0.5 + 0.5}; }
};

// How far a reported depth range may lie from a window vertex's depth z inside the pixel: every
// (zlo, zhi) reported for a pixel whose square holds the window position of a vertex with every
// |coordinate| <= 1 has zlo <= z + kVertexSlack and zhi >= z - kVertexSlack, for every triangle
// with that vertex. Such a vertex lies inside the grown clip volume, so every clip keeps it unchanged
// and it is a vertex of the triangle's polygon, clipped or not, at WindowMap's position; the paths
// are conservative (each range holds the polygon's depths over the grown square, up to roundings
// below 2^-40 of the depth range, far smaller than this), and the vertex's own pixel is always
// reported (its square holds a point of the polygon). Used only to settle answers early, so a
// larger slack loses speed, never an answer.
inline constexpr double kVertexSlack = 0x1p-30;

// The pixels of a flat triangle that are certainly reported, with its depth: for a triangle whose
// three window positions (WindowMap, every |coordinate| <= 1, so never clipped) have one depth z
// (the same double: faces of boxes seen along an axis), every point of the triangle has depth z,
// so kVertexSlack's argument holds at every pixel whose square holds a point of it, not only at
// its vertices' pixels. f(pixel index) for each pixel of the target whose square, shrunk by
// kFaceShrink on each side, the triangle certainly meets: separating-axis tests on the square's two
// axes and the triangle's three edge normals, each passed with a margin far above the doubles'
// roundings (window positions below 2^15, edges of at least kFaceMinEdge pixels; thinner or
// smaller triangles give nothing). Missing a pixel loses speed, never an answer.
inline constexpr double kFaceShrink = 0x1p-12;
inline constexpr double kFaceMinEdge = 0x1p-4;
template <class F>
void flat_triangle_pixels(const BoundsVertex& a, const BoundsVertex& b, const BoundsVertex& c, int width, int height,
                          F&& f) {
    const double x0 = std::min(std::min(a.x, b.x), c.x), x1 = std::max(std::max(a.x, b.x), c.x);
    const double y0 = std::min(std::min(a.y, b.y), c.y), y1 = std::max(std::max(a.y, b.y), c.y);
    // Pixels whose shrunk square [p + s, p + 1 - s] overlaps [x0, x1] (and likewise in y).
    const int px0 = std::max(0, static_cast<int>(std::ceil(x0 - 1.0 + kFaceShrink)));
    const int px1 = std::min(width - 1, static_cast<int>(std::floor(x1 - kFaceShrink)));
    const int py0 = std::max(0, static_cast<int>(std::ceil(y0 - 1.0 + kFaceShrink)));
    const int py1 = std::min(height - 1, static_cast<int>(std::floor(y1 - kFaceShrink)));
    if (px0 > px1 || py0 > py1) return;
    // Edge u -> v with the third vertex w: the normal n toward w; the square's largest n . (q - u)
    // over its corners, shrunk by s, is n . (centre - u) + (0.5 - s) (|n.x| + |n.y|). The test
    // below shrinks by 2s: the extra s (at least 2^-16 for edges of 1/16 pixel) dwarfs the
    // roundings of these products (below 2^-17 at |window| < 2^15), so passing it in doubles
    // means passing the exact test for the square shrunk by s, as the pixel range above does.
    struct Edge {
        double nx, ny, ux, uy, reach;
    };
    Edge e[3];
    const BoundsVertex* v[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
        const BoundsVertex& u = *v[k];
        const BoundsVertex& t = *v[(k + 1) % 3];
        const BoundsVertex& w = *v[(k + 2) % 3];
        double nx = -(t.y - u.y), ny = t.x - u.x;
        const double l1 = std::fabs(nx) + std::fabs(ny);
        if (!(l1 >= kFaceMinEdge)) return;
        if (nx * (w.x - u.x) + ny * (w.y - u.y) < 0.0) nx = -nx, ny = -ny;
        // The third vertex must lie clearly off the edge: a sliver gives nothing.
        if (!(nx * (w.x - u.x) + ny * (w.y - u.y) >= kFaceMinEdge * l1)) return;
        e[k] = {nx, ny, u.x, u.y, (0.5 - 2.0 * kFaceShrink) * l1};
    }
    for (int py = py0; py <= py1; ++py)
        for (int px = px0; px <= px1; ++px) {
            const double cx = px + 0.5, cy = py + 0.5;
            bool meets = true;
            for (const Edge& g : e) meets = meets && g.nx * (cx - g.ux) + g.ny * (cy - g.uy) + g.reach > 0.0;
            if (meets) f(static_cast<std::uint32_t>(py) * static_cast<std::uint32_t>(width) + static_cast<std::uint32_t>(px));
        }
}

// ---- the per-pixel traversal shared by bounds_rect and the fused visibility pass ----

struct BoundsP3 {
    double v[3];
};

// Sutherland-Hodgman against the closed half-space s * p[axis] <= bound (s = +1 or -1): keeps the
// points with d = bound - s * p[axis] >= 0. A point or a segment (degenerate input) goes through the
// same loop and stays a point or a segment. New points lie on the edge between the two points they
// came from (0 <= t <= 1 in floating point too), so their depth never leaves the edge's range.
//
// A convex polygon gains at most one vertex per plane (<= 13 in all), but rounding can make a
// computed polygon very slightly non-convex; should the output ever not fit kBoundsMaxVerts, the
// input is returned unclipped: a superset, so still conservative (the margins are sized from the
// input magnitude, so they hold for unclipped coordinates too). Inline: the general path clips
// every row with a constant axis and sign (s * p is then a negation or nothing: exact either way).
inline int bounds_clip_axis(const BoundsP3* in, int n, BoundsP3* out, int axis, double s, double bound) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const BoundsP3& cur = in[i];
        const BoundsP3& nxt = in[i + 1 == n ? 0 : i + 1];
        const double dc = bound - s * cur.v[axis];
        const double dn = bound - s * nxt.v[axis];
        if (m + 2 > kBoundsMaxVerts) {
            std::copy(in, in + n, out);
            return n;
        }
        if (dc >= 0.0) out[m++] = cur;
        if ((dc >= 0.0) != (dn >= 0.0)) {
            const double t = dc / (dc - dn);
            BoundsP3 p{};
            for (int k = 0; k < 3; ++k) p.v[k] = cur.v[k] + t * (nxt.v[k] - cur.v[k]);
            out[m++] = p;
        }
    }
    return m;
}

// Pixel boxes at most this wide also clamp the plane path's depth to each column slab's range.
inline constexpr int kTightColumns = 32;

// The plane path's pixels of one row (local row ly) inside the local columns [lo, hi]: narrows
// [lo, hi] to the pixels that no edge test drops (empty: lo > hi). Each edge's computed test
// fl(fl(ea * lx) + r) >= et is monotone in lx (rounding is monotone), so its pixels are a prefix or
// a suffix of the row, and their intersection is an interval. Each end is estimated by a division
// and then settled with the test itself, so the interval holds exactly the pixels that the
// per-pixel test keeps, whatever the estimate's rounding.
__attribute__((always_inline)) inline void plane_row_span(const BoundsPlane& d, double ly, int& lo_io,
                                                          int& hi_io) {
    int lo = lo_io, hi = hi_io;
    for (int i = 0; i < 3 && lo <= hi; ++i) {
        const double a = d.ea[i], r = d.eb[i] * ly + d.ek[i], et = d.et[i];
        const auto keep = [&](int lx) { return !(a * static_cast<double>(lx) + r < et); };
        if (a == 0.0) {
            if (!keep(lo)) hi = lo - 1;
            continue;
        }
        double est = (et - r) * d.inv_a[i];  // the crossing, roughly (settled below)
        est = est > -4.0 ? est : -4.0;
        est = est < static_cast<double>(hi) + 4.0 ? est : static_cast<double>(hi) + 4.0;
        int k = static_cast<int>(est);
        if (a > 0.0) {  // kept: a suffix [k, ...]
            k = std::clamp(k, lo, hi + 1);
            while (k > lo && keep(k - 1)) --k;
            while (k <= hi && !keep(k)) ++k;
            lo = k;
        } else {  // kept: a prefix [..., k]
            k = std::clamp(k, lo - 1, hi);
            while (k < hi && keep(k + 1)) ++k;
            while (k >= lo && !keep(k)) --k;
            hi = k;
        }
    }
    lo_io = lo;
    hi_io = hi;
}

// One polygon edge prepared for slab depth ranges along t (t = Y or X): its ends, depth at p,
// dz/dt (0 when the edge is perpendicular to t: it then never crosses a slab side strictly) and its
// depth range. Computed once per bounds_pixels call, not per row or pixel.
struct SlabEdge {
    double tp, tq, zp, slope, emin, emax;
};

template <bool ByY>
inline void slab_edges(const BoundsVertex* v, int n, SlabEdge* e) {
    for (int i = 0; i < n; ++i) {
        const BoundsVertex& p = v[i];
        const BoundsVertex& q = v[i + 1 == n ? 0 : i + 1];
        const double tp = ByY ? p.y : p.x, tq = ByY ? q.y : q.x;
        e[i] = {tp, tq, p.z, tq != tp ? (q.z - p.z) / (tq - tp) : 0.0, std::min(p.z, q.z), std::max(p.z, q.z)};
    }
}

// The depth range over the slab lo <= t <= hi of the polygon (edges e[0..n)) taken in (t, z): the
// vertices inside the slab and the edges' crossings of its two sides (a linear function's extremes
// over a convex set lie on its boundary); crossings are interpolated along the edge and clamped to
// its depth range. Empty (zlo > zhi) when nothing of the polygon is inside.
__attribute__((always_inline)) inline void slab_depth_range(const SlabEdge* e, int n, double lo, double hi,
                                                            double& zlo, double& zhi) {
    zlo = __builtin_inf();
    zhi = -__builtin_inf();
    for (int i = 0; i < n; ++i) {
        const SlabEdge& g = e[i];
        if (g.tp >= lo && g.tp <= hi) {
            zlo = std::min(zlo, g.zp);
            zhi = std::max(zhi, g.zp);
        }
        if ((g.tp < lo && g.tq > lo) || (g.tp > lo && g.tq < lo)) {
            const double z = std::clamp(g.zp + (lo - g.tp) * g.slope, g.emin, g.emax);
            zlo = std::min(zlo, z);
            zhi = std::max(zhi, z);
        }
        if ((g.tp < hi && g.tq > hi) || (g.tp > hi && g.tq < hi)) {
            const double z = std::clamp(g.zp + (hi - g.tp) * g.slope, g.emin, g.emax);
            zlo = std::min(zlo, z);
            zhi = std::max(zhi, z);
        }
    }
}

namespace bounds_paths {

// A box of one pixel (BoundsTri::single), whatever the kind.
template <class F>
inline void single(const BoundsTri& tri, const BoundsVertex* pool, PixelRect rect, F& f) {
    // One row and one column: no clip is needed (every vertex lies inside the slab and the
    // column) and no edge crosses a side strictly, so the general path below would take exactly
    // the vertices' depths.
    if (tri.x0 < rect.x0 || tri.x0 > rect.x1 || tri.y0 < rect.y0 || tri.y0 > rect.y1) return;
    double zlo = pool[tri.first].z, zhi = zlo;
    for (int i = 1; i < tri.n; ++i) {
        const double z = pool[tri.first + static_cast<std::uint32_t>(i)].z;
        zlo = z < zlo ? z : zlo;
        zhi = z > zhi ? z : zhi;
    }
    f(tri.x0, tri.y0, zlo, zhi);
}

// BoundsTri::Kind::Plane.
template <class F>
inline void plane(const BoundsTri& tri, const BoundsVertex* pool, PixelRect rect, F& f) {
    // Separating axes (the idea of conservative rasterization on GPUs: Hasselgren, Akenine-Moller
    // and Ohlsson, GPU Gems 2 ch. 42): a convex triangle and a square are disjoint iff one of the
    // square's two axes or the triangle's three edge normals separates them. The pixel box
    // already handles the square's axes; per edge, the grown square is dropped only when the
    // edge function, at the square's corner that maximizes it, is below a threshold that covers
    // every rounding (setup). Depth: the plane over the grown square, widened by its error
    // bound and clamped to the vertex depth range. Closed form per pixel, nothing carried from
    // pixel to pixel: a pixel gets the same values in any rectangle (tile).
    //
    // Tightening (not needed for correctness): the plane's range over the whole square is loose
    // where the square sticks out of the triangle (most pixels of a sliver), so it is also
    // clamped to the triangle's depth range over the pixel's row slab and, for boxes at most
    // kTightColumns wide, over its column slab (each read off the boundary, slab_depth_range,
    // widened by sw for its rounding). Each range is a function of py or px alone.
    const BoundsPlane d = load_plane(tri, pool);
    const int ys = std::max(rect.y0, tri.y0), ye = std::min(rect.y1, tri.y1);
    const int xs = std::max(rect.x0, tri.x0), xe = std::min(rect.x1, tri.x1);
    if (xs > xe || ys > ye) return;
    const double m = tri.margin_xy;
    const BoundsVertex* v = pool + tri.first;
    const bool tight = d.pzlo != d.pzhi;  // constant depth: [z, z] already
    const bool tight_cols = tight && tri.x1 - tri.x0 < kTightColumns;
    double col_lo[kTightColumns], col_hi[kTightColumns];
    SlabEdge ex[3], ey[3];
    if (tight) slab_edges<true>(v, 3, ey);
    if (tight_cols) {
        slab_edges<false>(v, 3, ex);
        for (int px = xs; px <= xe; ++px) {
            const double fx = static_cast<double>(px);
            double a = 0, b = 0;
            slab_depth_range(ex, 3, fx - m, fx + 1.0 + m, a, b);
            col_lo[px - xs] = a - d.sw;
            col_hi[px - xs] = b + d.sw;
        }
    }
    for (int py = ys; py <= ye; ++py) {
        const double ly = static_cast<double>(py - tri.y0);
        const double rz = d.pz + d.pgy * ly;
        int lo = xs - tri.x0, hi = xe - tri.x0;  // local pixel columns
        plane_row_span(d, ly, lo, hi);
        if (lo > hi) continue;
        double rlo = d.pzlo, rhi = d.pzhi;
        if (tight) {
            const double fy = static_cast<double>(py);
            double a = 0, b = 0;
            slab_depth_range(ey, 3, fy - m, fy + 1.0 + m, a, b);
            rlo = std::max(rlo, a - d.sw);
            rhi = std::min(rhi, b + d.sw);
        }
        for (int px = tri.x0 + lo; px <= tri.x0 + hi; ++px) {
            const double lx = static_cast<double>(px - tri.x0);
            const double zc = rz + d.pgx * lx;
            const double zl = zc - d.pw, zh = zc + d.pw;
            double zlo = zl > rlo ? zl : rlo;
            double zhi = zh < rhi ? zh : rhi;
            if (tight_cols) {
                zlo = std::max(zlo, col_lo[px - xs]);
                zhi = std::min(zhi, col_hi[px - xs]);
            }
            // An empty interval proves that the square misses the triangle (a point of it
            // would have its depth in every range): nothing to report.
            if (zlo <= zhi) f(px, py, zlo, zhi);
        }
    }
}

// BoundsTri::Kind::Column and Row.
template <class F>
inline void slab(const BoundsTri& tri, const BoundsVertex* pool, PixelRect rect, F& f) {
    const double m = tri.margin_xy;
    // Column: every column of the box contains the polygon's X range in its grown interval
    // (or every vertex has the same X), so the polygon's part above pixel (px, py)'s grown
    // square is its part over the row slab [py - m, py + 1 + m], whatever px: its depth range
    // is read off its boundary (slab_depth_range: the general path's column code with Y for X,
    // without clipping) once per row and reported for the box's columns (one or two). Row: the
    // same with X and Y exchanged.
    const int ys = std::max(rect.y0, tri.y0), ye = std::min(rect.y1, tri.y1);
    const int xs = std::max(rect.x0, tri.x0), xe = std::min(rect.x1, tri.x1);
    if (xs > xe || ys > ye) return;
    const BoundsVertex* v = pool + tri.first;
    double zlo = 0, zhi = 0;
    SlabEdge e[kBoundsMaxVerts];
    if (tri.kind == BoundsTri::Kind::Column) {
        slab_edges<true>(v, tri.n, e);
        for (int py = ys; py <= ye; ++py) {
            const double fy = static_cast<double>(py);
            slab_depth_range(e, tri.n, fy - m, fy + 1.0 + m, zlo, zhi);
            if (!(zlo <= zhi)) continue;
            for (int px = xs; px <= xe; ++px) f(px, py, zlo, zhi);
        }
    } else {
        slab_edges<false>(v, tri.n, e);
        for (int py = ys; py <= ye; ++py) {  // one or two rows: recomputed per row, in order
            for (int px = xs; px <= xe; ++px) {
                const double fx = static_cast<double>(px);
                slab_depth_range(e, tri.n, fx - m, fx + 1.0 + m, zlo, zhi);
                if (zlo <= zhi) f(px, py, zlo, zhi);
            }
        }
    }
}

// BoundsTri::Kind::General, per row: the polygon is clipped to the row's slab (skipped when it
// already lies inside it: the clip would return it unchanged); then the depth range over each
// pixel's column is the range over the row polygon's boundary inside the column (a linear
// function's extremes over a convex set lie on its boundary): its vertices inside the column and
// its edges' crossings of the column's sides. Constant-depth polygons take a shortcut that gives the
// same values (see the comment there and docs/reliable-raster.md).
template <class F>
inline void general(const BoundsTri& tri, const BoundsVertex* pool, PixelRect rect, F& f) {
    const double m = tri.margin_xy;
    BoundsP3 poly[kBoundsMaxVerts];
    double py_lo = 1e308, py_hi = -1e308;
    for (int i = 0; i < tri.n; ++i) {
        const BoundsVertex& v = pool[tri.first + static_cast<std::uint32_t>(i)];
        poly[i] = {{v.x, v.y, v.z}};
        py_lo = py_lo < v.y ? py_lo : v.y;
        py_hi = py_hi > v.y ? py_hi : v.y;
    }
    // A polygon of constant depth (every vertex the same z: screen-parallel faces, common in the
    // orthographic views of CULLIDE) keeps it exactly through clipping (z + t * 0) and in every
    // crossing (slope 0), so each covered pixel gets zlo = zhi = z; and a pixel is covered (some
    // vertex inside its column, or some edge crossing a side of it strictly) exactly when the row
    // polygon's X range [lo, hi] meets the column [xl, xr] (if no vertex lies inside, vertices lie
    // on both sides, and the closed boundary crosses xl strictly). Same values, fewer steps.
    bool flat = true;
    for (int i = 1; i < tri.n; ++i) flat = flat && poly[i].v[2] == poly[0].v[2];
    BoundsP3 row_a[kBoundsMaxVerts];
    BoundsP3 row_b[kBoundsMaxVerts];
    constexpr double kInf = __builtin_inf();
    for (int py = rect.y0; py <= rect.y1; ++py) {
        const double fy = static_cast<double>(py);
        // Y >= py - m, then Y <= py + 1 + m; a clip that keeps every vertex is the identity.
        const BoundsP3* rp = poly;
        int rn = tri.n;
        if (!(py_lo >= fy - m)) {
            rn = bounds_clip_axis(rp, rn, row_a, 1, -1.0, -(fy - m));
            if (rn == 0) continue;
            rp = row_a;
        }
        if (!(py_hi <= fy + 1.0 + m)) {
            rn = bounds_clip_axis(rp, rn, row_b, 1, 1.0, fy + 1.0 + m);
            if (rn == 0) continue;
            rp = row_b;
        }
        double lo = kInf, hi = -kInf;
        for (int i = 0; i < rn; ++i) {
            lo = lo < rp[i].v[0] ? lo : rp[i].v[0];
            hi = hi > rp[i].v[0] ? hi : rp[i].v[0];
        }
        const double xs_d = std::max(std::ceil(lo - m) - 1.0, -1.0);
        const int xs = std::max(rect.x0, static_cast<int>(xs_d));
        const int xe = std::min(rect.x1, static_cast<int>(std::min(std::floor(hi + m), static_cast<double>(rect.x1))));
        if (flat) {
            const double z = poly[0].v[2];
            for (int px = xs; px <= xe; ++px) {
                const double fx = static_cast<double>(px);
                if (fx - m <= hi && fx + 1.0 + m >= lo) f(px, py, z, z);
            }
            continue;
        }
        // Per edge once per row: its ends in X, dz/dX (0 when vertical) and depth range; per pixel,
        // the range over the column is read off them by slab_depth_range, as the column path does
        // (each vertex starts one edge of the closed row polygon, so every vertex is seen).
        SlabEdge edges[kBoundsMaxVerts];
        for (int i = 0; i < rn; ++i) {
            const BoundsP3& p = rp[i];
            const BoundsP3& q = rp[i + 1 == rn ? 0 : i + 1];
            const double tp = p.v[0], tq = q.v[0];
            edges[i] = {tp, tq, p.v[2], tq != tp ? (q.v[2] - p.v[2]) / (tq - tp) : 0.0, std::min(p.v[2], q.v[2]),
                        std::max(p.v[2], q.v[2])};
        }
        for (int px = xs; px <= xe; ++px) {
            const double fx = static_cast<double>(px);
            double zlo, zhi;
            slab_depth_range(edges, rn, fx - m, fx + 1.0 + m, zlo, zhi);
            if (zlo <= zhi) f(px, py, zlo, zhi);
        }
    }
}

}  // namespace bounds_paths

// A range [lo, hi] that holds every (zlo, zhi) that bounds_pixels reports for `tri`, over any
// rectangle: a per-triangle bound that lets a caller settle a depth test for a whole block of
// pixels without visiting them (the fused visibility pass). Per path:
//  - single, Column, Row: each value is a vertex depth or an edge crossing clamped to the edge's
//    depth range (slab_depth_range), so the polygon's vertex depth range holds it exactly;
//  - Plane: zlo = max(..., pzlo) and zhi = min(..., pzhi), so [pzlo, pzhi];
//  - General: the row clips (bounds_clip_axis, at most two per row) interpolate new vertices as
//    a + t * (b - a) with 0 <= t <= 1, which in floating point can leave the edge's depth range by
//    a few roundings: each clip by at most 5u max|z| (u = 2^-53) plus subnormal absolute errors, so
//    two by < 2^-49 max|z|. The vertex range is widened by 2^-40 max|z| + 2^-1000, far more.
// Returned widened values only loosen the bound (a caller may skip less, never wrongly).
inline void bounds_depth_range(const BoundsTri& tri, const BoundsVertex* pool, double& lo, double& hi) {
    if (!tri.single && tri.kind == BoundsTri::Kind::Plane) {
        const BoundsPlane d = load_plane(tri, pool);
        lo = d.pzlo;
        hi = d.pzhi;
        return;
    }
    lo = pool[tri.first].z;
    hi = lo;
    for (int i = 1; i < tri.n; ++i) {
        const double z = pool[tri.first + static_cast<std::uint32_t>(i)].z;
        lo = z < lo ? z : lo;
        hi = z > hi ? z : hi;
    }
    if (!tri.single && tri.kind == BoundsTri::Kind::General) {
        const double slack = 0x1p-40 * std::max(std::fabs(lo), std::fabs(hi)) + 0x1p-1000;
        lo -= slack;
        hi += slack;
    }
}

// Calls f(px, py, zlo, zhi) for every pixel of `rect` whose square (grown by
// tri.margin_xy) meets the polygon (the plane path may add pixels that a rounding-error bound
// cannot rule out), with a range containing the polygon's depths over that part (before margin_z
// and quantization): see docs/reliable-raster.md. Rows in increasing order, pixels of a row in
// increasing order. The values do not depend on the rectangle: a pixel gets the same (zlo, zhi)
// whichever rectangle (tile) contains it.
//
// The four per-pixel paths are the functions of bounds_paths (BoundsTri::Kind); each gives a pixel
// the values the general path would (or, for the plane path, a proven superset).
template <class F>
inline void bounds_pixels(const BoundsTri& tri, const BoundsVertex* pool, PixelRect rect, F&& f) {
    if (tri.single) return bounds_paths::single(tri, pool, rect, f);
    switch (tri.kind) {
        case BoundsTri::Kind::Plane: return bounds_paths::plane(tri, pool, rect, f);
        case BoundsTri::Kind::Column:
        case BoundsTri::Kind::Row: return bounds_paths::slab(tri, pool, rect, f);
        case BoundsTri::Kind::General: return bounds_paths::general(tri, pool, rect, f);
    }
}

}  // namespace raster::detail
