// exact_bounds_reference.h: the brute-force exact reference of RasterMode::ExactBounds, in GMP
// rationals (independent of the library: no floating point after the exact double -> rational
// conversion). A triangle's clip-space vertices (w = 1) are mapped with GL's viewport transform,
// clipped exactly against the closed clip volume, and, per pixel, against the closed pixel square;
// the pixel is covered when anything is left, and [zmin, zmax] is the min / max window depth of
// what is left (a convex polygon's extremes are at its vertices). Shared by the tests and the fuzzer.
#pragma once

#include <gmpxx.h>

#include <cstdint>
#include <vector>

#include "raster/raster.h"

namespace raster_ref {

struct QPoint {
    mpq_class x, y, z;
};

struct PixelRange {
    bool covered = false;
    mpq_class zmin;  // window depth, in [0, 1]
    mpq_class zmax;
};

class ExactTriangle {
 public:
    ExactTriangle(const raster::Viewport& viewport, const raster::Double4& a, const raster::Double4& b,
                  const raster::Double4& c);
    [[nodiscard]] bool empty() const { return poly_.empty(); }
    // Inclusive pixel box that can be covered (unclamped); meaningless when empty().
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    [[nodiscard]] PixelRange pixel(int px, int py) const;

 private:
    std::vector<QPoint> poly_;  // window coordinates
};

// The stored value of a depth target pixel as an exact rational depth.
mpq_class stored_depth(std::uint32_t value, raster::DepthFormat format);
// The largest / smallest representable stored value <= / >= z (z in [0, 1]), exactly.
std::uint32_t floor_value(const mpq_class& z, raster::DepthFormat format);
std::uint32_t ceil_value(const mpq_class& z, raster::DepthFormat format);

}  // namespace raster_ref
