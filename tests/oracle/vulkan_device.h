// vulkan_device.h: the Vulkan-rules oracle of the raster tests and benchmarks (Mesa's lavapipe, the
// Vulkan driver on llvmpipe's rasterizer). It runs a raster::CommandBatch through Vulkan 1.3 with
// the same clip-space floats (a pass-through vertex shader and no fragment shader) into a depth-only
// render pass, counts samples with precise occlusion queries and reads the depth image back with
// exact bits. Headless: no window, no surface. Test and benchmark code only: never linked into a
// library. No Vulkan header leaks from here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace cullide_oracle {

class VulkanDevice {
   public:
    // One VkDevice on lavapipe (the physical device whose driver is Mesa's llvmpipe) with a width x
    // height depth image: D16 -> VK_FORMAT_D16_UNORM, D24 -> VK_FORMAT_X8_D24_UNORM_PACK32 (or
    // D24_UNORM_S8_UINT where X8 cannot be a depth attachment), D32F -> VK_FORMAT_D32_SFLOAT.
    // Fails with a message when there is no Vulkan 1.3 lavapipe device, no precise occlusion
    // queries, or the format cannot be a depth attachment. Cleared to depth 1.0.
    // `device`, when not empty, picks instead the first Vulkan 1.3 physical device whose name contains
    // it (case-insensitive), for example "NVIDIA": the real-driver runs of tests/raster/driver_report.cpp.
    // The error then lists the devices there are.
    [[nodiscard]] static raster::Result<std::unique_ptr<VulkanDevice>> create(int width, int height,
                                                                           raster::DepthFormat format,
                                                                           const std::string& device = {});
    ~VulkanDevice();
    VulkanDevice(const VulkanDevice&) = delete;
    VulkanDevice& operator=(const VulkanDevice&) = delete;

    // vkCmdClearDepthStencilImage with depth (as a float).
    void clear(double depth);
    // Fails unless the batch is recorded for RasterRules::Vulkan. Records every command in one render pass (viewport, cull mode, front face, compare op and
    // write enable as dynamic state; each query begun with VK_QUERY_CONTROL_PRECISE_BIT), submits,
    // waits, and returns the query results indexed like the batch's queries (any-samples queries:
    // count > 0). Cull and front face use Vulkan's names for the DrawState values: FrontFace::CCW is
    // VK_FRONT_FACE_COUNTER_CLOCKWISE.
    [[nodiscard]] raster::Result<raster::QueryResults> run(const raster::CommandBatch& batch);
    // The depth image, row 0 = framebuffer y 0, in raster::DepthTarget's encoding.
    [[nodiscard]] std::vector<std::uint32_t> read_depth();

    // "llvmpipe (LLVM ...), Mesa 22.3.6 (LLVM ...), X8_D24_UNORM_PACK32": device, driver, depth format.
    [[nodiscard]] std::string renderer() const;
    [[nodiscard]] int width() const { return width_; }
    [[nodiscard]] int height() const { return height_; }

   private:
    VulkanDevice() = default;
    struct Impl;
    std::unique_ptr<Impl> impl_;
    int width_ = 0;
    int height_ = 0;
    raster::DepthFormat format_ = raster::DepthFormat::D24;
};

}  // namespace cullide_oracle
