// raster/depth_target.h: a depth buffer (the only attachment the rasterizer has).
// Conventions: raster/raster.h.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "raster/result.h"
#include "raster/types.h"

namespace raster {

// A width x height depth buffer, row 0 at the bottom. Each pixel is one uint32: the unsigned
// normalized value for D16/D24 (low 16/24 bits), the IEEE float bits for D32F. Movable.
class DepthTarget {
   public:
    // Fails (and allocates nothing) when a side is < 1 or > kMaxTargetSize. Cleared to depth 1.0.
    [[nodiscard]] static Result<DepthTarget> create(int width, int height, DepthFormat format);

    // glClearDepth(depth) + glClear(GL_DEPTH_BUFFER_BIT) (ignores the write mask of draws, which is
    // per draw here). Fails on a non-finite depth; values outside [0, 1] are clamped, as GL does.
    [[nodiscard]] Status clear(double depth);

    [[nodiscard]] int width() const { return width_; }
    [[nodiscard]] int height() const { return height_; }
    [[nodiscard]] DepthFormat format() const { return format_; }

    // Stored value of pixel (x, y); x < width, y < height (asserts).
    [[nodiscard]] std::uint32_t value(int x, int y) const;
    // The stored value as a depth in [0, 1] (D16/D24: value / (2^n - 1) in double).
    [[nodiscard]] double depth(int x, int y) const;
    // All values, row-major from the bottom row.
    [[nodiscard]] std::span<const std::uint32_t> values() const { return values_; }
    [[nodiscard]] std::span<std::uint32_t> mutable_values() { return values_; }

    // What clear(depth) stores, for callers that compare buffers.
    [[nodiscard]] static std::uint32_t encode_clear(double depth, DepthFormat format);

   private:
    DepthTarget(int width, int height, DepthFormat format);
    int width_ = 0;
    int height_ = 0;
    DepthFormat format_ = DepthFormat::D24;
    std::vector<std::uint32_t> values_;
};

}  // namespace raster
