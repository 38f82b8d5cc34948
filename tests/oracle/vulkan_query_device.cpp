// vulkan_query_device.cpp: see vulkan_query_device.h.
#include "vulkan_query_device.h"

#include <string>

#include "vulkan_device.h"

namespace cullide_oracle {
namespace {

class VulkanQueryDevice final : public cullide::QueryDevice {
   public:
    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        if (!vk_ || vk_->width() != width || vk_->height() != height || format != format_) {
            vk_.reset();  // one lavapipe device at a time
            raster::Result<std::unique_ptr<VulkanDevice>> d = VulkanDevice::create(width, height, format);
            if (!d) return cullide::Error{"vulkan device: " + d.error().message};
            vk_ = std::move(d).value();
            format_ = format;
        }
        vk_->clear(1.0);
        return {};
    }

    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        if (!vk_) return cullide::Error{"vulkan device: execute before clear (no framebuffer yet)"};
        const auto& commands = batch.commands();
        for (std::size_t i = 0; i < commands.size(); ++i) {
            if (commands[i].kind == raster::Command::Kind::Draw &&
                (commands[i].state.mode != raster::RasterMode::GLExact || commands[i].double_input))
                return cullide::Error{"vulkan device: command " + std::to_string(i) +
                                      " uses the exact-bounds mode or double input, which Vulkan does not have"};
        }
        if (batch.target_width() != vk_->width() || batch.target_height() != vk_->height())
            return cullide::Error{"vulkan device: batch built for another target size"};
        raster::Result<raster::QueryResults> r = vk_->run(batch);
        if (!r) return cullide::Error{"vulkan device: " + r.error().message};
        return std::move(r).value();
    }

    std::string name() const override { return vk_ ? "vulkan (" + vk_->renderer() + ")" : "vulkan"; }

   private:
    std::unique_ptr<VulkanDevice> vk_;
    raster::DepthFormat format_ = raster::DepthFormat::D24;
};

}  // namespace

cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_vulkan_query_device() {
    return std::unique_ptr<cullide::QueryDevice>(std::make_unique<VulkanQueryDevice>());
}

}  // namespace cullide_oracle
