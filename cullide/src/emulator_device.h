// emulator_device.h (private): the built-in QueryDevice, declared here so that a FrameContext
// (pipeline.h) can hold one across frames and change its thread count between them.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cullide/query_device.h"
#include "raster/depth_target.h"

namespace cullide::detail {

// raster::execute on a raster::DepthTarget, with the fused visibility pass (raster::VisibilityPass)
// as its native visibility_pass. The target is kept from one clear to the next while its size and
// format stay the same, so a device held across frames allocates it once; and a clear restores
// only the pixels that draws with the depth mask on may have written since the last one (per row,
// a span of x), because filling a 1024 x 1024 target costs as much as the passes drawn into it.
class EmulatorDevice final : public QueryDevice {
   public:
    explicit EmulatorDevice(int threads);

    // Worker count for later calls (0 = all hardware threads); results never depend on it.
    void set_threads(int threads);

    Status clear(int width, int height, raster::DepthFormat format) override;
    Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override;
    Result<std::vector<std::uint8_t>> visibility_pass(ViewSize size, raster::DepthFormat format,
                                                      std::span<const raster::VisibilityItem> items) override;
    std::string name() const override { return "emulator"; }

    // The current target (nullptr before the first clear), for tests of the partial clear.
    [[nodiscard]] const raster::DepthTarget* target() const { return target_ ? &*target_ : nullptr; }

   private:
    // Widens row y's written span to [x0, x1] (clamped to the target).
    void mark(int y, int x0, int x1);
    void mark_all();
    // Marks every pixel a written triangle of `batch` may touch (conservative).
    void mark_writes(const raster::CommandBatch& batch);

    int threads_;
    std::optional<raster::DepthTarget> target_;
    // Per row of the target: the x span [written_lo_, written_hi_] that may differ from the clear
    // value (empty when lo > hi).
    std::vector<int> written_lo_, written_hi_;
};

}  // namespace cullide::detail
