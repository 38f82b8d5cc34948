// oracle_query_device.h: a cullide::QueryDevice over any of the oracle devices (OsmesaDevice,
// EglDevice, VulkanDevice), so the CULLIDE pipeline's very same pass sequence runs on a real driver.
// The device is re-created when clear() asks for another size or format. Exact-bounds draws and
// double input are refused (no real driver has them): execute() then fails naming the command.
// Tests and benchmarks only.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "cullide/query_device.h"

namespace cullide_oracle {

template <typename Device>
class OracleQueryDevice final : public cullide::QueryDevice {
   public:
    using Make = std::function<raster::Result<std::unique_ptr<Device>>(int, int, raster::DepthFormat)>;

    // label: "osmesa", "egl", "vulkan" (messages and name()); api: what the refusals say lacks the
    // exact-bounds mode ("real GL", "Vulkan").
    OracleQueryDevice(std::string label, std::string api, Make make)
        : label_(std::move(label)), api_(std::move(api)), make_(std::move(make)) {}

    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        if (!dev_ || dev_->width() != width || dev_->height() != height || format != format_) {
            dev_.reset();  // one device at a time
            raster::Result<std::unique_ptr<Device>> d = make_(width, height, format);
            if (!d) return cullide::Error{label_ + " device: " + d.error().message};
            dev_ = std::move(d).value();
            format_ = format;
        }
        dev_->clear(1.0);
        return {};
    }

    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        if (!dev_) return cullide::Error{label_ + " device: execute before clear (no framebuffer yet)"};
        const auto& commands = batch.commands();
        for (std::size_t i = 0; i < commands.size(); ++i) {
            if (commands[i].kind == raster::Command::Kind::Draw &&
                (commands[i].state.mode != raster::RasterMode::GLExact || commands[i].double_input))
                return cullide::Error{label_ + " device: command " + std::to_string(i) +
                                      " uses the exact-bounds mode or double input, which " + api_ +
                                      " does not have"};
        }
        if (batch.target_width() != dev_->width() || batch.target_height() != dev_->height())
            return cullide::Error{label_ + " device: batch built for another target size"};
        raster::Result<raster::QueryResults> r = dev_->run(batch);
        if (!r) return cullide::Error{label_ + " device: " + r.error().message};
        return std::move(r).value();
    }

    std::string name() const override { return dev_ ? label_ + " (" + dev_->renderer() + ")" : label_; }

   private:
    std::string label_, api_;
    Make make_;
    std::unique_ptr<Device> dev_;
    raster::DepthFormat format_ = raster::DepthFormat::D24;
};

}  // namespace cullide_oracle
