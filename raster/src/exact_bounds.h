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

}  // namespace raster::detail
