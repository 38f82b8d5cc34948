// depth_target.cpp: DepthTarget storage, clear and read-back.
#include "raster/depth_target.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <string>

#include "target_blocks.h"

namespace raster {

DepthTarget::DepthTarget(int width, int height, DepthFormat format)
    : width_(width),
      height_(height),
      format_(format),
      values_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), encode_clear(1.0, format)),
      clear_value_(encode_clear(1.0, format)) {}

Result<DepthTarget> DepthTarget::create(int width, int height, DepthFormat format) {
    if (width < 1 || height < 1 || width > kMaxTargetSize || height > kMaxTargetSize) {
        return Error{"depth target size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxTargetSize) + " per side"};
    }
    if (format != DepthFormat::D16 && format != DepthFormat::D24 && format != DepthFormat::D32F) {
        return Error{"depth target format " + std::to_string(static_cast<int>(format)) + " is not D16, D24 or D32F"};
    }
    return DepthTarget(width, height, format);
}

// Mesa's util_pack_z: 0 and 1 exact, otherwise round to nearest of depth * (2^n - 1) in double.
std::uint32_t DepthTarget::encode_clear(double depth, DepthFormat format) {
    depth = depth < 0.0 ? 0.0 : (depth > 1.0 ? 1.0 : depth);
    switch (format) {
        case DepthFormat::D16:
            return depth == 1.0 ? 0xffffu : static_cast<std::uint32_t>(std::lrint(depth * 65535.0));
        case DepthFormat::D24:
            return depth == 1.0 ? 0xffffffu : static_cast<std::uint32_t>(std::lrint(depth * 16777215.0));
        case DepthFormat::D32F:
            return std::bit_cast<std::uint32_t>(static_cast<float>(depth));
    }
    return 0;
}

Status DepthTarget::clear(double depth) {
    if (!std::isfinite(depth)) return Error{"clear depth is not finite"};
    const std::uint32_t v = encode_clear(depth, format_);
    if (clear_known_ && clear_value_ == v) {
        // Only the blocks that may differ (the fast clear: raster/depth_target.h).
        std::array<std::uint32_t, kExecuteTileSize> row;
        row.fill(v);
        const int tiles_x = (width_ + kExecuteTileSize - 1) / kExecuteTileSize;
        for (std::size_t i = 0; i < blocks_.size(); ++i) {
            if (blocks_[i] == 0) continue;
            const int x0 = static_cast<int>(i % static_cast<std::size_t>(tiles_x)) * kExecuteTileSize;
            const int y0 = static_cast<int>(i / static_cast<std::size_t>(tiles_x)) * kExecuteTileSize;
            detail::clear_blocks({values_.data(), width_}, row.data(),
                                 {x0, y0, std::min(x0 + kExecuteTileSize, width_) - 1,
                                  std::min(y0 + kExecuteTileSize, height_) - 1},
                                 blocks_[i]);
            blocks_[i] = 0;
        }
        return {};
    }
    std::fill(values_.begin(), values_.end(), v);
    std::fill(blocks_.begin(), blocks_.end(), std::uint64_t{0});
    clear_value_ = v;
    clear_known_ = true;
    return {};
}

std::uint32_t DepthTarget::value(int x, int y) const {
    assert(x >= 0 && x < width_ && y >= 0 && y < height_);
    return values_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
}

double DepthTarget::depth(int x, int y) const {
    const std::uint32_t v = value(x, y);
    switch (format_) {
        case DepthFormat::D16: return static_cast<double>(v) / 65535.0;
        case DepthFormat::D24: return static_cast<double>(v) / 16777215.0;
        case DepthFormat::D32F: return static_cast<double>(std::bit_cast<float>(v));
    }
    return 0.0;
}

}  // namespace raster
