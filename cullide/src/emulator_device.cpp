// emulator_device.cpp: the built-in QueryDevice, raster::execute on a raster::DepthTarget, with the
// fused visibility pass (raster::VisibilityPass) as its native visibility_pass.
#include <optional>

#include "cullide/query_device.h"
#include "parallel.h"
#include "raster/depth_target.h"
#include "raster/visibility.h"

namespace cullide {
namespace {

class EmulatorDevice final : public QueryDevice {
   public:
    explicit EmulatorDevice(int threads) : threads_(detail::effective_threads(threads)) {}

    Status clear(int width, int height, raster::DepthFormat format) override {
        if (!target_ || target_->width() != width || target_->height() != height || target_->format() != format) {
            raster::Result<raster::DepthTarget> t = raster::DepthTarget::create(width, height, format);
            if (!t) return Error{"emulator device: " + t.error().message};
            target_.emplace(std::move(t).value());
            return Status{};  // a new target is created cleared to 1.0
        }
        if (raster::Status s = target_->clear(1.0); !s) return Error{"emulator device: " + s.error().message};
        return Status{};
    }

    Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        if (!target_) return Error{"emulator device: execute before clear (no depth target yet)"};
        raster::ExecuteOptions eo;
        eo.threads = threads_;
        raster::Result<raster::QueryResults> r = raster::execute(*target_, batch, eo);
        if (!r) return Error{"emulator device: " + r.error().message};
        return std::move(r).value();
    }

    // Both passes in one rasterization per item (raster/visibility.h), bit-identical to the
    // recorded passes (tests/cullide/fused_visibility_test.cpp).
    Result<std::vector<std::uint8_t>> visibility_pass(ViewSize size, raster::DepthFormat format,
                                                      std::span<const raster::VisibilityItem> items) override {
        // One per calling thread, shared by every device and frame: process_frame makes a device
        // per frame, and a pass owned by the device would fault its buffers in afresh each frame.
        // It keeps no answer from one call to the next, so results cannot depend on what ran before.
        thread_local raster::VisibilityPass pass;
        raster::Result<std::vector<std::uint8_t>> r = pass.run(size.width(), size.height(), format, items, threads_);
        if (!r) return Error{"emulator device: " + r.error().message};
        return std::move(r).value();
    }

    std::string name() const override { return "emulator"; }

   private:
    int threads_;
    std::optional<raster::DepthTarget> target_;
};

}  // namespace

std::unique_ptr<QueryDevice> make_emulator_device(int threads) { return std::make_unique<EmulatorDevice>(threads); }

}  // namespace cullide
