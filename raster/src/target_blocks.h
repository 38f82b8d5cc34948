// target_blocks.h (private): a target's 8 x 8 blocks filled with a clear value, and the executor's
// access to DepthTarget's fast-clear record (raster/depth_target.h): which blocks may differ from
// the value the target was last cleared to.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "depth_dispatch.h"
#include "raster/command_batch.h"
#include "raster/depth_target.h"

namespace raster::detail {

// Fills the blocks of `tile` (one kExecuteTileSize tile, clipped to the target) flagged in `mask`
// (ExecuteOptions::written_blocks' layout) with copies of `clear_row` (kExecuteTileSize values).
// Each row part by memcpy (wide stores on any target; the element loop of std::fill stored one
// value per instruction): each block row's runs of flagged blocks (a whole row of the tile when
// every block is flagged). A target of 4096^2 holds 64 MB and raster_bench SmallTris writes one
// block in 13 there: restoring only those is most of the difference (docs/raster.md, session 16).
inline void clear_blocks(DepthRows depth, const std::uint32_t* clear_row, PixelRect tile,
                         std::uint64_t mask) {
    constexpr int B = kExecuteBlockSize;
    static_assert(kExecuteTileSize == 8 * B, "one bit per block of a tile in a 64-bit mask");
    for (int by = 0; mask != 0; ++by, mask >>= 8) {
        unsigned bits = static_cast<unsigned>(mask & 0xffu);
        const int ya = tile.y0 + by * B;
        if (bits == 0 || ya > tile.y1) continue;
        const int yb = std::min(ya + B - 1, tile.y1);
        while (bits != 0) {  // each run of flagged blocks [b0, b1)
            const int b0 = std::countr_zero(bits);
            const int b1 = b0 + std::countr_one(bits >> b0);
            bits &= ~((1u << b1) - (1u << b0));
            const int xa = tile.x0 + b0 * B;
            if (xa > tile.x1) break;
            const int xb = std::min(tile.x0 + b1 * B - 1, tile.x1);
            for (int y = ya; y <= yb; ++y)
                std::memcpy(depth.row(y) + xa, clear_row,
                            static_cast<std::size_t>(xb - xa + 1) * sizeof(std::uint32_t));
        }
    }
}

// The tile count of ExecuteOptions::written_blocks for a width x height target.
[[nodiscard]] inline std::size_t block_mask_count(int width, int height) {
    return static_cast<std::size_t>((width + kExecuteTileSize - 1) / kExecuteTileSize) *
           static_cast<std::size_t>((height + kExecuteTileSize - 1) / kExecuteTileSize);
}

struct TargetBlocks {
    // The values, writable, without dropping the record (the executor flags what it writes).
    [[nodiscard]] static std::uint32_t* values(DepthTarget& t) { return t.values_.data(); }
    static void forget(DepthTarget& t) { t.clear_known_ = false; }

    // The record as the written-block flags of a batch that clears to `clear` (encoded) when
    // `clears`, or only draws: each flag set means "fill before drawing" when the batch clears
    // and "may differ from the clear value" after it. nullptr: the target has no record and the
    // batch does not clear (its writes are not tracked). The record is marked unknown until
    // commit() (a batch stopped half way leaves flags that do not hold).
    [[nodiscard]] static std::uint64_t* begin_batch(DepthTarget& t, bool clears, std::uint32_t clear) {
        const std::size_t n = block_mask_count(t.width_, t.height_);
        if (!t.clear_known_) {
            if (!clears) return nullptr;
            t.blocks_.assign(n, ~std::uint64_t{0});  // content unknown: every block is filled
            t.clear_value_ = clear;
        } else {
            if (t.blocks_.size() != n) t.blocks_.assign(n, 0);  // (empty: nothing flagged)
            if (clears && clear != t.clear_value_) {
                std::fill(t.blocks_.begin(), t.blocks_.end(), ~std::uint64_t{0});
                t.clear_value_ = clear;
            }
        }
        t.clear_known_ = false;
        return t.blocks_.data();
    }
    static void commit(DepthTarget& t) { t.clear_known_ = true; }
};

}  // namespace raster::detail
