// raster/depth_target.h: a depth buffer (the only attachment the rasterizer has).
// Conventions: raster/raster.h.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "raster/result.h"
#include "raster/types.h"

namespace raster {

namespace detail {
struct TargetBlocks;  // the executor's access to the fast-clear record (raster/src/target_blocks.h)
}

// A width x height depth buffer, row 0 at the bottom. Each pixel is one uint32: the unsigned
// normalized value for D16/D24 (low 16/24 bits), the IEEE float bits for D32F. Movable.
class DepthTarget {
   public:
    // Fails (and allocates nothing) when a side is < 1 or > kMaxTargetSize. Cleared to depth 1.0.
    [[nodiscard]] static Result<DepthTarget> create(int width, int height, DepthFormat format);

    // glClearDepth(depth) + glClear(GL_DEPTH_BUFFER_BIT) (ignores the write mask of draws, which is
    // per draw here). Fails on a non-finite depth; values outside [0, 1] are clamped, as GL does.
    // Fills only the 8 x 8 blocks that may hold another value (the fast clear, below): after a
    // clear or create() to the same depth, the blocks where execute()'s writing draws passed.
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
    // The same, writable until the next clear() or execute*() on this target. Calling it makes the
    // target forget which blocks hold its clear value, so the next clear fills every pixel.
    [[nodiscard]] std::span<std::uint32_t> mutable_values() {
        clear_known_ = false;
        return values_;
    }

    // What clear(depth) stores, for callers that compare buffers.
    [[nodiscard]] static std::uint32_t encode_clear(double depth, DepthFormat format);

   private:
    DepthTarget(int width, int height, DepthFormat format);
    int width_ = 0;
    int height_ = 0;
    DepthFormat format_ = DepthFormat::D24;
    std::vector<std::uint32_t> values_;
    // The fast clear (ours; a GPU keeps such clear state per tile): while clear_known_, every 8 x 8
    // block not flagged in blocks_ holds clear_value_. blocks_ has ExecuteOptions::written_blocks'
    // layout (one mask per 64 x 64 tile; empty: no block flagged). create() and clear() set the
    // record; execute() and execute_sequence() flag the blocks where their writing draws pass and,
    // when they clear to clear_value_, fill only the flagged blocks; mutable_values() and a call
    // with the caller's own written_blocks drop it. A clear of a 4096^2 target is 64 MB written;
    // small triangles write about one block in 13 of it (raster_bench SmallTris).
    friend struct detail::TargetBlocks;
    bool clear_known_ = true;
    std::uint32_t clear_value_ = 0;
    std::vector<std::uint64_t> blocks_;
};

}  // namespace raster
