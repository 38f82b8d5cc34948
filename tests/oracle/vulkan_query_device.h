// vulkan_query_device.h: a cullide::QueryDevice on lavapipe (Vulkan), so the CULLIDE pipeline's very
// same pass sequence runs on the Vulkan-rules oracle. Tests and benchmarks only.
#pragma once

#include <memory>
#include <string>

#include "cullide/query_device.h"

namespace cullide_oracle {

// The Vulkan device is re-created when clear() asks for another size or format. Exact-bounds draws
// and double input are refused (Vulkan has no such mode): execute() then fails naming the command.
// The batches it runs must be recorded for the Vulkan rules (clip-space z in [0, w]). `device` picks
// the Vulkan device as VulkanDevice::create does (empty: lavapipe). See oracle_query_device.h.
[[nodiscard]] cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_vulkan_query_device(
    const std::string& device = {});

}  // namespace cullide_oracle
