// emulator_device.h (private): the built-in QueryDevice, declared here so that a FrameContext
// (pipeline.h) can hold one across frames and change its thread count between them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cullide/query_device.h"
#include "raster/depth_target.h"

namespace cullide::detail {

// raster::execute on a raster::DepthTarget, with the fused visibility pass (raster::VisibilityPass)
// as its native visibility_pass. The target is kept from one clear to the next while its size and
// format stay the same, so a device held across frames allocates it once; and a clear restores
// only the 64 x 64 tiles where draws with the depth mask on ran since the last one (the executor
// reports them), because filling a 1024 x 1024 target costs as much as the passes drawn into it.
class EmulatorDevice final : public QueryDevice {
   public:
    explicit EmulatorDevice(int threads);

    // Worker count for later calls (0 = all hardware threads); results never depend on it.
    void set_threads(int threads);

    Status clear(int width, int height, raster::DepthFormat format) override;
    Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override;
    Result<std::vector<raster::QueryResults>> execute_cleared(
        int width, int height, raster::DepthFormat format,
        std::span<const raster::CommandBatch* const> batches) override;
    Result<std::vector<std::uint8_t>> visibility_pass(ViewSize size, raster::DepthFormat format,
                                                      std::span<const raster::VisibilityItem> items) override;
    // Natively (raster::WindowedPasses) on targets up to WindowedPasses::kMaxWindowedPixels, where
    // its per-pixel records stay small; recorded above that.
    Result<std::vector<std::uint8_t>> quick_view(ViewSize size, raster::DepthFormat format,
                                                 std::span<const raster::WindowedItem> items,
                                                 std::span<const std::uint8_t> tags) override;
    std::string name() const override { return "emulator"; }

    // The current target (nullptr before the first clear), for tests of the partial clear.
    [[nodiscard]] const raster::DepthTarget* target() const { return target_ ? &*target_ : nullptr; }

   private:
    // The executor's options for this device: its thread count. (The blocks a clear restores are
    // the target's own record: DepthTarget's fast clear.)
    [[nodiscard]] raster::ExecuteOptions execute_options() const;
    // Makes target_ a width x height target of `format`: true when it was created (cleared to 1.0,
    // no tile written), false when the current one already fits (its content kept).
    Result<bool> ensure_target(int width, int height, raster::DepthFormat format);

    int threads_;
    std::optional<raster::DepthTarget> target_;
};

}  // namespace cullide::detail
