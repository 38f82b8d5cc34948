// exact_bounds.h (private): the conservative "exact bounds" mode (docs/reliable-raster.md).
//
// Front end: one input triangle (double clip space, w = 1) is clipped against the clip volume grown
// by a margin, in double, and mapped to window coordinates: a convex polygon of at most 9 vertices
// (a segment or a point for degenerate input). Back end: per pixel, the polygon is clipped against
// the pixel's closed square grown by a margin; if anything is left the pixel is covered, and the
// min / max depth of what is left, widened by a margin and rounded outward to the depth format,
// is the pixel's [zmin, zmax]. The margins exceed every rounding error of those steps
// (docs/reliable-raster.md, "Why every rounding is covered"), so the result contains the exact one.
// Every pixel is computed from the polygon alone (never accumulated), so traversal order, tiling and
// thread count cannot change a bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "pipeline.h"
#include "raster/types.h"

namespace raster::detail {

inline constexpr int kBoundsMaxVerts = 16;  // 3 + 6 clip planes + 4 square planes, rounded up

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
};

// Appends 0 or 1 BoundsTri for the triangle (a, b, c) to `out` and its polygon to `pool`. Inputs
// were validated (finite, w = 1, |coordinate| <= kMaxExactBoundsCoordinate).
void setup_bounds_triangle(const FrontEndParams& params, const Double4& a, const Double4& b, const Double4& c,
                           std::uint32_t draw, std::vector<BoundsTri>& out, std::vector<BoundsVertex>& pool);

// Rasterizes `tri` (polygon in `pool`) over [rx0, rx1] x [ry0, ry1] (inclusive, inside the target):
// per covered pixel the depth test `func` of zmin (write) or zmax (!write) against the stored
// value, and the write of zmin when `write`. Returns the covered pixels that passed.
std::uint64_t bounds_rect(const BoundsTri& tri, const BoundsVertex* pool, DepthFormat format, DepthFunc func,
                          bool write, std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1);

// Outward quantization of a window depth in [0, 1] to the stored encoding (exposed for tests):
// down = the largest representable value <= z, up = the smallest >= z.
std::uint32_t quantize_down(double z, DepthFormat format);
std::uint32_t quantize_up(double z, DepthFormat format);

// ---- the per-pixel traversal shared by bounds_rect and the fused visibility pass ----

struct BoundsP3 {
    double v[3];
};

// Sutherland-Hodgman against the closed half-space s * p[axis] <= bound (exact_bounds.cpp).
int bounds_clip_axis(const BoundsP3* in, int n, BoundsP3* out, int axis, double s, double bound);

// Calls f(px, py, zlo, zhi) for every pixel of [rx0, rx1] x [ry0, ry1] whose square (grown by
// tri.margin_xy) meets the polygon, with the polygon's exact-arithmetic-rounded depth range over
// that part (before margin_z and quantization): see docs/reliable-raster.md. Rows in increasing
// order, pixels of a row in increasing order. The values do not depend on the rectangle: a pixel
// gets the same (zlo, zhi) whichever rectangle (tile) contains it.
//
// Per row: the polygon is clipped to the row's slab (skipped when it already lies inside it: the
// clip would return it unchanged); then the depth range over each pixel's column is the range
// over the row polygon's boundary inside the column (a linear function's extremes over a convex
// set lie on its boundary): its vertices inside the column and its edges' crossings of the
// column's sides. Constant-depth polygons and one-pixel triangles take shortcuts that give the
// same values (see the comments there and docs/reliable-raster.md).
template <class F>
inline void bounds_pixels(const BoundsTri& tri, const BoundsVertex* pool, int rx0, int ry0, int rx1, int ry1,
                          F&& f) {
    if (tri.single) {
        // One row and one column: no clip is needed (every vertex lies inside the slab and the
        // column) and no edge crosses a side strictly, so the general path below would take exactly
        // the vertices' depths.
        if (tri.x0 < rx0 || tri.x0 > rx1 || tri.y0 < ry0 || tri.y0 > ry1) return;
        double zlo = pool[tri.first].z, zhi = zlo;
        for (int i = 1; i < tri.n; ++i) {
            const double z = pool[tri.first + static_cast<std::uint32_t>(i)].z;
            zlo = z < zlo ? z : zlo;
            zhi = z > zhi ? z : zhi;
        }
        f(tri.x0, tri.y0, zlo, zhi);
        return;
    }
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
    for (int py = ry0; py <= ry1; ++py) {
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
        const int xs = std::max(rx0, static_cast<int>(xs_d));
        const int xe = std::min(rx1, static_cast<int>(std::min(std::floor(hi + m), static_cast<double>(rx1))));
        if (flat) {
            const double z = poly[0].v[2];
            for (int px = xs; px <= xe; ++px) {
                const double fx = static_cast<double>(px);
                if (fx - m <= hi && fx + 1.0 + m >= lo) f(px, py, z, z);
            }
            continue;
        }
        // Per edge once per row: its ends, dz/dX (0 when vertical) and depth range.
        struct RowEdge {
            double xp, xq, zp, zq, slope, zmin, zmax;
        };
        RowEdge edges[kBoundsMaxVerts];
        for (int i = 0; i < rn; ++i) {
            const BoundsP3& p = rp[i];
            const BoundsP3& q = rp[i + 1 == rn ? 0 : i + 1];
            RowEdge& e = edges[i];
            e.xp = p.v[0];
            e.xq = q.v[0];
            e.zp = p.v[2];
            e.zq = q.v[2];
            e.slope = e.xq != e.xp ? (e.zq - e.zp) / (e.xq - e.xp) : 0.0;
            e.zmin = std::min(e.zp, e.zq);
            e.zmax = std::max(e.zp, e.zq);
        }
        for (int px = xs; px <= xe; ++px) {
            const double fx = static_cast<double>(px);
            const double xl = fx - m, xr = fx + 1.0 + m;
            double zlo = kInf, zhi = -kInf;
            for (int i = 0; i < rn; ++i) {
                const RowEdge& e = edges[i];
                if ((e.xp < xl && e.xq < xl) || (e.xp > xr && e.xq > xr)) continue;
                if (e.xp >= xl && e.xp <= xr) {
                    zlo = std::min(zlo, e.zp);
                    zhi = std::max(zhi, e.zp);
                }
                if (e.xq >= xl && e.xq <= xr) {
                    zlo = std::min(zlo, e.zq);
                    zhi = std::max(zhi, e.zq);
                }
                if ((e.xp < xl && e.xq > xl) || (e.xp > xl && e.xq < xl)) {
                    const double z = std::clamp(e.zp + (xl - e.xp) * e.slope, e.zmin, e.zmax);
                    zlo = std::min(zlo, z);
                    zhi = std::max(zhi, z);
                }
                if ((e.xp < xr && e.xq > xr) || (e.xp > xr && e.xq < xr)) {
                    const double z = std::clamp(e.zp + (xr - e.xp) * e.slope, e.zmin, e.zmax);
                    zlo = std::min(zlo, z);
                    zhi = std::max(zhi, z);
                }
            }
            if (zlo <= zhi) f(px, py, zlo, zhi);
        }
    }
}

}  // namespace raster::detail
