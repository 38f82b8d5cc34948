// cullide_device.cpp: the emulator QueryDevice (raster::execute on a raster::DepthTarget).
#include <optional>

#include "cullide/query_device.h"
#include "emulator_device.h"
#include "parallel.h"
#include "raster/depth_target.h"

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

    std::string name() const override { return "emulator"; }
    int threads() const { return threads_; }

   private:
    int threads_;
    std::optional<raster::DepthTarget> target_;
};

}  // namespace

int detail::emulator_threads(const QueryDevice& device) {
    const auto* e = dynamic_cast<const EmulatorDevice*>(&device);
    return e != nullptr ? e->threads() : -1;
}

std::unique_ptr<QueryDevice> make_emulator_device(int threads) { return std::make_unique<EmulatorDevice>(threads); }

}  // namespace cullide
