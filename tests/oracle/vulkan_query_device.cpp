// vulkan_query_device.cpp: see vulkan_query_device.h.
#include "vulkan_query_device.h"

#include "oracle_query_device.h"
#include "vulkan_device.h"

namespace cullide_oracle {

cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_vulkan_query_device(const std::string& device) {
    return std::unique_ptr<cullide::QueryDevice>(std::make_unique<OracleQueryDevice<VulkanDevice>>(
        "vulkan", "Vulkan",
        [device](int w, int h, raster::DepthFormat f) { return VulkanDevice::create(w, h, f, device); }));
}

}  // namespace cullide_oracle
