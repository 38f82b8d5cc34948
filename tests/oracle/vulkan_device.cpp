// vulkan_device.cpp: see vulkan_device.h. Everything is kept simple and synchronous: the depth image
// lives in VK_IMAGE_LAYOUT_GENERAL for its whole life (valid for the attachment, clears and copies),
// every submission is followed by a fence wait, and full memory barriers separate the steps.
#include "vulkan_device.h"

#include "batch_geometry.h"

#include <vulkan/vulkan.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <string>
#include <utility>

#include <cstdint>

#include "vulkan_passthrough_vert.h"  // kVulkanPassthroughVert: SPIR-V words made by glslangValidator

namespace cullide_oracle {

struct VulkanDevice::Impl {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    std::uint32_t queue_family = 0;
    VkPhysicalDeviceMemoryProperties memory{};
    std::string name;
    VkFormat format = VK_FORMAT_UNDEFINED;
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory image_memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
    VkRenderPass pass = VK_NULL_HANDLE;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    VkShaderModule shader = VK_NULL_HANDLE;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    VkPipeline pipeline = VK_NULL_HANDLE;
    VkCommandPool pool = VK_NULL_HANDLE;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;
    struct HostBuffer {
        VkBuffer buffer = VK_NULL_HANDLE;
        VkDeviceMemory memory = VK_NULL_HANDLE;
        VkDeviceSize size = 0;
        void* mapped = nullptr;
    };
    HostBuffer vertices, indices, readback;

    ~Impl();
    [[nodiscard]] raster::Status make_buffer(HostBuffer& b, VkDeviceSize size, VkBufferUsageFlags usage);
    void free_buffer(HostBuffer& b);
    [[nodiscard]] int memory_type(std::uint32_t bits, VkMemoryPropertyFlags want) const;
    // Begins the command buffer for one submission.
    void begin();
    // Ends, submits and waits for it.
    [[nodiscard]] raster::Status submit();
    void full_barrier();
};

namespace {

// A zeroed Vulkan create-info struct with its sType set.
template <class T>
T vk_struct(VkStructureType type) {
    T s{};
    s.sType = type;
    return s;
}

std::string vk_error(const char* what, VkResult r) {
    std::string s(what);
    s.append(" failed (VkResult ");
    s.append(std::to_string(static_cast<int>(r)));
    s.append(")");
    return s;
}

VkCompareOp vk_compare(raster::DepthFunc f) {
    switch (f) {
        case raster::DepthFunc::Never: return VK_COMPARE_OP_NEVER;
        case raster::DepthFunc::Less: return VK_COMPARE_OP_LESS;
        case raster::DepthFunc::Equal: return VK_COMPARE_OP_EQUAL;
        case raster::DepthFunc::LEqual: return VK_COMPARE_OP_LESS_OR_EQUAL;
        case raster::DepthFunc::Greater: return VK_COMPARE_OP_GREATER;
        case raster::DepthFunc::NotEqual: return VK_COMPARE_OP_NOT_EQUAL;
        case raster::DepthFunc::GEqual: return VK_COMPARE_OP_GREATER_OR_EQUAL;
        case raster::DepthFunc::Always: return VK_COMPARE_OP_ALWAYS;
    }
    return VK_COMPARE_OP_LESS;
}

bool is_depth_attachment(VkPhysicalDevice pd, VkFormat f) {
    VkFormatProperties p{};
    vkGetPhysicalDeviceFormatProperties(pd, f, &p);
    return (p.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT) != 0;
}

}  // namespace

VulkanDevice::Impl::~Impl() {
    if (device != VK_NULL_HANDLE) {
        vkDeviceWaitIdle(device);
        free_buffer(vertices);
        free_buffer(indices);
        free_buffer(readback);
        if (fence) vkDestroyFence(device, fence, nullptr);
        if (pool) vkDestroyCommandPool(device, pool, nullptr);
        if (pipeline) vkDestroyPipeline(device, pipeline, nullptr);
        if (layout) vkDestroyPipelineLayout(device, layout, nullptr);
        if (shader) vkDestroyShaderModule(device, shader, nullptr);
        if (framebuffer) vkDestroyFramebuffer(device, framebuffer, nullptr);
        if (pass) vkDestroyRenderPass(device, pass, nullptr);
        if (view) vkDestroyImageView(device, view, nullptr);
        if (image) vkDestroyImage(device, image, nullptr);
        if (image_memory) vkFreeMemory(device, image_memory, nullptr);
        vkDestroyDevice(device, nullptr);
    }
    if (instance != VK_NULL_HANDLE) vkDestroyInstance(instance, nullptr);
}

int VulkanDevice::Impl::memory_type(std::uint32_t bits, VkMemoryPropertyFlags want) const {
    for (std::uint32_t i = 0; i < memory.memoryTypeCount; ++i)
        if ((bits & (1u << i)) != 0 && (memory.memoryTypes[i].propertyFlags & want) == want) return static_cast<int>(i);
    return -1;
}

raster::Status VulkanDevice::Impl::make_buffer(HostBuffer& b, VkDeviceSize size, VkBufferUsageFlags usage) {
    if (b.size >= size && b.buffer != VK_NULL_HANDLE) return {};
    free_buffer(b);
    size = std::max<VkDeviceSize>(size, 256);
    auto bi = vk_struct<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
    bi.size = size;
    bi.usage = usage;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    if (VkResult r = vkCreateBuffer(device, &bi, nullptr, &b.buffer); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateBuffer", r)};
    VkMemoryRequirements req{};
    vkGetBufferMemoryRequirements(device, b.buffer, &req);
    const int type = memory_type(req.memoryTypeBits,
                                 VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    if (type < 0) return raster::Error{"no host-visible coherent memory type"};
    auto ai = vk_struct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = static_cast<std::uint32_t>(type);
    if (VkResult r = vkAllocateMemory(device, &ai, nullptr, &b.memory); r != VK_SUCCESS)
        return raster::Error{vk_error("vkAllocateMemory (buffer)", r)};
    vkBindBufferMemory(device, b.buffer, b.memory, 0);
    if (VkResult r = vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped); r != VK_SUCCESS)
        return raster::Error{vk_error("vkMapMemory", r)};
    b.size = size;
    return {};
}

void VulkanDevice::Impl::free_buffer(HostBuffer& b) {
    if (b.buffer) vkDestroyBuffer(device, b.buffer, nullptr);
    if (b.memory) vkFreeMemory(device, b.memory, nullptr);
    b = HostBuffer{};
}

void VulkanDevice::Impl::begin() {
    vkResetCommandBuffer(cmd, 0);
    auto bi = vk_struct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    vkBeginCommandBuffer(cmd, &bi);
}

raster::Status VulkanDevice::Impl::submit() {
    if (VkResult r = vkEndCommandBuffer(cmd); r != VK_SUCCESS) return raster::Error{vk_error("vkEndCommandBuffer", r)};
    auto si = vk_struct<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    vkResetFences(device, 1, &fence);
    if (VkResult r = vkQueueSubmit(queue, 1, &si, fence); r != VK_SUCCESS)
        return raster::Error{vk_error("vkQueueSubmit", r)};
    if (VkResult r = vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX); r != VK_SUCCESS)
        return raster::Error{vk_error("vkWaitForFences", r)};
    return {};
}

void VulkanDevice::Impl::full_barrier() {
    auto mb = vk_struct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
    mb.srcAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 1, &mb, 0,
                         nullptr, 0, nullptr);
}

raster::Result<std::unique_ptr<VulkanDevice>> VulkanDevice::create(int width, int height, raster::DepthFormat format,
                                                                        const std::string& device) {
    if (width < 1 || height < 1 || width > raster::kMaxTargetSize || height > raster::kMaxTargetSize)
        return raster::Error{"vulkan device: bad target size"};
    std::unique_ptr<VulkanDevice> d(new VulkanDevice());
    d->impl_ = std::make_unique<Impl>();
    d->width_ = width;
    d->height_ = height;
    d->format_ = format;
    Impl& g = *d->impl_;

    auto app = vk_struct<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
    app.pApplicationName = "cullide vulkan oracle";
    app.apiVersion = VK_API_VERSION_1_3;
    auto ii = vk_struct<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
    ii.pApplicationInfo = &app;
    if (VkResult r = vkCreateInstance(&ii, nullptr, &g.instance); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateInstance", r)};
    std::uint32_t n = 0;
    vkEnumeratePhysicalDevices(g.instance, &n, nullptr);
    std::vector<VkPhysicalDevice> pds(n);
    vkEnumeratePhysicalDevices(g.instance, &n, pds.data());
    auto lower = [](std::string t) {
        for (char& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return t;
    };
    const std::string wanted = lower(device);
    std::string seen;
    for (VkPhysicalDevice pd : pds) {
        auto drv = vk_struct<VkPhysicalDeviceDriverProperties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES);
        auto props = vk_struct<VkPhysicalDeviceProperties2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2);
        props.pNext = &drv;
        vkGetPhysicalDeviceProperties2(pd, &props);
        const std::string name = props.properties.deviceName;
        seen += (seen.empty() ? "" : "; ") + name;
        const bool match = wanted.empty() ? drv.driverID == VK_DRIVER_ID_MESA_LLVMPIPE
                                          : lower(name).find(wanted) != std::string::npos;
        if (match && props.properties.apiVersion >= VK_API_VERSION_1_3) {
            g.physical = pd;
            g.name = name;
            g.name.append(", ");
            g.name.append(drv.driverName);
            g.name.append(" ");
            g.name.append(drv.driverInfo);
            break;
        }
    }
    if (g.physical == VK_NULL_HANDLE) {
        if (wanted.empty())
            return raster::Error{"vulkan device: no Vulkan 1.3 lavapipe device (install mesa-vulkan-drivers)"};
        return raster::Error{"vulkan device: no Vulkan 1.3 device named like '" + device + "' (there are: " +
                             (seen.empty() ? std::string("none") : seen) + ")"};
    }
    VkPhysicalDeviceFeatures features{};
    vkGetPhysicalDeviceFeatures(g.physical, &features);
    if (!features.occlusionQueryPrecise) return raster::Error{"vulkan device: no occlusionQueryPrecise"};
    vkGetPhysicalDeviceMemoryProperties(g.physical, &g.memory);

    std::uint32_t nq = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(g.physical, &nq, nullptr);
    std::vector<VkQueueFamilyProperties> qf(nq);
    vkGetPhysicalDeviceQueueFamilyProperties(g.physical, &nq, qf.data());
    bool found_queue = false;
    for (std::uint32_t i = 0; i < nq && !found_queue; ++i)
        if ((qf[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) != 0) {
            g.queue_family = i;
            found_queue = true;
        }
    if (!found_queue) return raster::Error{"vulkan device: no graphics queue"};
    const float priority = 1.0f;
    auto qi = vk_struct<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
    qi.queueFamilyIndex = g.queue_family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkPhysicalDeviceFeatures enable{};
    enable.occlusionQueryPrecise = VK_TRUE;
    auto di = vk_struct<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.pEnabledFeatures = &enable;
    if (VkResult r = vkCreateDevice(g.physical, &di, nullptr, &g.device); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateDevice", r)};
    vkGetDeviceQueue(g.device, g.queue_family, 0, &g.queue);

    switch (format) {
        case raster::DepthFormat::D16: g.format = VK_FORMAT_D16_UNORM; break;
        case raster::DepthFormat::D24:
            g.format = is_depth_attachment(g.physical, VK_FORMAT_X8_D24_UNORM_PACK32) ? VK_FORMAT_X8_D24_UNORM_PACK32
                                                                                    : VK_FORMAT_D24_UNORM_S8_UINT;
            break;
        case raster::DepthFormat::D32F: g.format = VK_FORMAT_D32_SFLOAT; break;
    }
    if (!is_depth_attachment(g.physical, g.format))
        return raster::Error{"vulkan device: the depth format cannot be a depth attachment"};
    const bool has_stencil = g.format == VK_FORMAT_D24_UNORM_S8_UINT;
    g.name.append(g.format == VK_FORMAT_D16_UNORM              ? ", D16_UNORM"
                  : g.format == VK_FORMAT_X8_D24_UNORM_PACK32 ? ", X8_D24_UNORM_PACK32"
                  : has_stencil                               ? ", D24_UNORM_S8_UINT"
                                                              : ", D32_SFLOAT");
    VkImageAspectFlags aspects = VK_IMAGE_ASPECT_DEPTH_BIT;
    if (has_stencil) aspects |= VK_IMAGE_ASPECT_STENCIL_BIT;

    auto ic = vk_struct<VkImageCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO);
    ic.imageType = VK_IMAGE_TYPE_2D;
    ic.format = g.format;
    ic.extent = {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height), 1};
    ic.mipLevels = 1;
    ic.arrayLayers = 1;
    ic.samples = VK_SAMPLE_COUNT_1_BIT;
    ic.tiling = VK_IMAGE_TILING_OPTIMAL;
    ic.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
               VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    ic.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ic.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    if (VkResult r = vkCreateImage(g.device, &ic, nullptr, &g.image); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateImage", r)};
    VkMemoryRequirements req{};
    vkGetImageMemoryRequirements(g.device, g.image, &req);
    int type = g.memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type < 0) type = g.memory_type(req.memoryTypeBits, 0);
    if (type < 0) return raster::Error{"vulkan device: no memory type for the depth image"};
    auto ai = vk_struct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = static_cast<std::uint32_t>(type);
    if (VkResult r = vkAllocateMemory(g.device, &ai, nullptr, &g.image_memory); r != VK_SUCCESS)
        return raster::Error{vk_error("vkAllocateMemory (image)", r)};
    vkBindImageMemory(g.device, g.image, g.image_memory, 0);
    auto vi = vk_struct<VkImageViewCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO);
    vi.image = g.image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = g.format;
    vi.subresourceRange = {aspects, 0, 1, 0, 1};
    if (VkResult r = vkCreateImageView(g.device, &vi, nullptr, &g.view); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateImageView", r)};

    // Depth-only render pass: load and store the attachment, which stays in GENERAL layout.
    VkAttachmentDescription att{};
    att.format = g.format;
    att.samples = VK_SAMPLE_COUNT_1_BIT;
    att.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
    att.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    att.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
    att.stencilStoreOp = VK_ATTACHMENT_STORE_OP_STORE;
    att.initialLayout = VK_IMAGE_LAYOUT_GENERAL;
    att.finalLayout = VK_IMAGE_LAYOUT_GENERAL;
    VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_GENERAL};
    VkSubpassDescription sub{};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.pDepthStencilAttachment = &ref;
    auto rp = vk_struct<VkRenderPassCreateInfo>(VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO);
    rp.attachmentCount = 1;
    rp.pAttachments = &att;
    rp.subpassCount = 1;
    rp.pSubpasses = &sub;
    if (VkResult r = vkCreateRenderPass(g.device, &rp, nullptr, &g.pass); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateRenderPass", r)};
    auto fb = vk_struct<VkFramebufferCreateInfo>(VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO);
    fb.renderPass = g.pass;
    fb.attachmentCount = 1;
    fb.pAttachments = &g.view;
    fb.width = static_cast<std::uint32_t>(width);
    fb.height = static_cast<std::uint32_t>(height);
    fb.layers = 1;
    if (VkResult r = vkCreateFramebuffer(g.device, &fb, nullptr, &g.framebuffer); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateFramebuffer", r)};

    // Pipeline: vertex stage only, everything the batch changes per draw dynamic (core in 1.3).
    auto sm = vk_struct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
    sm.codeSize = sizeof(kVulkanPassthroughVert);
    sm.pCode = kVulkanPassthroughVert;
    if (VkResult r = vkCreateShaderModule(g.device, &sm, nullptr, &g.shader); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateShaderModule", r)};
    auto pl = vk_struct<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
    if (VkResult r = vkCreatePipelineLayout(g.device, &pl, nullptr, &g.layout); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreatePipelineLayout", r)};
    auto stage = vk_struct<VkPipelineShaderStageCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO);
    stage.stage = VK_SHADER_STAGE_VERTEX_BIT;
    stage.module = g.shader;
    stage.pName = "main";
    VkVertexInputBindingDescription binding{0, 16, VK_VERTEX_INPUT_RATE_VERTEX};
    VkVertexInputAttributeDescription attr{0, 0, VK_FORMAT_R32G32B32A32_SFLOAT, 0};
    auto vin = vk_struct<VkPipelineVertexInputStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO);
    vin.vertexBindingDescriptionCount = 1;
    vin.pVertexBindingDescriptions = &binding;
    vin.vertexAttributeDescriptionCount = 1;
    vin.pVertexAttributeDescriptions = &attr;
    auto ia = vk_struct<VkPipelineInputAssemblyStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO);
    ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    auto vps = vk_struct<VkPipelineViewportStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO);
    vps.viewportCount = 1;
    vps.scissorCount = 1;
    auto rs = vk_struct<VkPipelineRasterizationStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO);
    rs.depthClampEnable = VK_FALSE;  // depth clip in [0, w]
    rs.polygonMode = VK_POLYGON_MODE_FILL;
    rs.lineWidth = 1.0f;
    auto ms = vk_struct<VkPipelineMultisampleStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO);
    ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    auto ds = vk_struct<VkPipelineDepthStencilStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO);
    ds.depthTestEnable = VK_TRUE;
    auto cb = vk_struct<VkPipelineColorBlendStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO);
    const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT,          VK_DYNAMIC_STATE_SCISSOR,
                                  VK_DYNAMIC_STATE_CULL_MODE,         VK_DYNAMIC_STATE_FRONT_FACE,
                                  VK_DYNAMIC_STATE_DEPTH_COMPARE_OP,  VK_DYNAMIC_STATE_DEPTH_WRITE_ENABLE};
    auto dy = vk_struct<VkPipelineDynamicStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO);
    dy.dynamicStateCount = static_cast<std::uint32_t>(std::size(dyn));
    dy.pDynamicStates = dyn;
    auto gp = vk_struct<VkGraphicsPipelineCreateInfo>(VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO);
    gp.stageCount = 1;
    gp.pStages = &stage;
    gp.pVertexInputState = &vin;
    gp.pInputAssemblyState = &ia;
    gp.pViewportState = &vps;
    gp.pRasterizationState = &rs;
    gp.pMultisampleState = &ms;
    gp.pDepthStencilState = &ds;
    gp.pColorBlendState = &cb;
    gp.pDynamicState = &dy;
    gp.layout = g.layout;
    gp.renderPass = g.pass;
    gp.subpass = 0;
    if (VkResult r = vkCreateGraphicsPipelines(g.device, VK_NULL_HANDLE, 1, &gp, nullptr, &g.pipeline); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateGraphicsPipelines", r)};

    auto cp = vk_struct<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
    cp.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cp.queueFamilyIndex = g.queue_family;
    if (VkResult r = vkCreateCommandPool(g.device, &cp, nullptr, &g.pool); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateCommandPool", r)};
    auto ca = vk_struct<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
    ca.commandPool = g.pool;
    ca.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ca.commandBufferCount = 1;
    if (VkResult r = vkAllocateCommandBuffers(g.device, &ca, &g.cmd); r != VK_SUCCESS)
        return raster::Error{vk_error("vkAllocateCommandBuffers", r)};
    auto fi = vk_struct<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
    if (VkResult r = vkCreateFence(g.device, &fi, nullptr, &g.fence); r != VK_SUCCESS)
        return raster::Error{vk_error("vkCreateFence", r)};
    const VkDeviceSize texel = format == raster::DepthFormat::D16 ? 2 : 4;
    if (raster::Status s = g.make_buffer(g.readback, texel * static_cast<VkDeviceSize>(width) * height,
                                         VK_BUFFER_USAGE_TRANSFER_DST_BIT);
        !s)
        return raster::Error{"vulkan device: " + s.error().message};

    // UNDEFINED -> GENERAL once; the image stays there.
    g.begin();
    auto ib = vk_struct<VkImageMemoryBarrier>(VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER);
    ib.srcAccessMask = 0;
    ib.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    ib.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    ib.newLayout = VK_IMAGE_LAYOUT_GENERAL;
    ib.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    ib.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    ib.image = g.image;
    ib.subresourceRange = {aspects, 0, 1, 0, 1};
    vkCmdPipelineBarrier(g.cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0,
                         nullptr, 1, &ib);
    if (raster::Status s = g.submit(); !s) return raster::Error{"vulkan device: " + s.error().message};
    d->clear(1.0);
    return d;
}

VulkanDevice::~VulkanDevice() = default;

void VulkanDevice::clear(double depth) {
    Impl& g = *impl_;
    g.begin();
    g.full_barrier();
    VkClearDepthStencilValue v{static_cast<float>(depth), 0};
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdClearDepthStencilImage(g.cmd, g.image, VK_IMAGE_LAYOUT_GENERAL, &v, 1, &range);
    g.full_barrier();
    (void)g.submit();
}

raster::Result<raster::QueryResults> VulkanDevice::run(const raster::CommandBatch& batch) {
    Impl& g = *impl_;
    if (batch.rules() != raster::RasterRules::Vulkan)
        return raster::Error{"vulkan device: the batch is recorded for the GL rules (clip z in [-w, w])"};
    for (const auto& c : batch.commands())
        if (c.kind == raster::Command::Kind::Draw && (c.double_input || c.state.mode != raster::RasterMode::GLExact))
            return raster::Error{"vulkan device: exact-bounds draws and double input have no Vulkan counterpart"};
    const BatchGeometry geometry(batch);  // one copy of each vertex span (batch_geometry.h)
    const auto& verts = geometry.vertices;
    const auto& idx = geometry.indices;
    const auto& ranges = geometry.draws;
    if (raster::Status s = g.make_buffer(g.vertices, verts.size() * sizeof(raster::Float4),
                                         VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
        !s)
        return raster::Error{"vulkan device: " + s.error().message};
    if (raster::Status s = g.make_buffer(g.indices, idx.size() * 4, VK_BUFFER_USAGE_INDEX_BUFFER_BIT); !s)
        return raster::Error{"vulkan device: " + s.error().message};
    if (!verts.empty()) std::memcpy(g.vertices.mapped, verts.data(), verts.size() * sizeof(raster::Float4));
    if (!idx.empty()) std::memcpy(g.indices.mapped, idx.data(), idx.size() * 4);

    const auto& kinds = batch.query_kinds();
    VkQueryPool qpool = VK_NULL_HANDLE;
    if (!kinds.empty()) {
        auto qi = vk_struct<VkQueryPoolCreateInfo>(VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO);
        qi.queryType = VK_QUERY_TYPE_OCCLUSION;
        qi.queryCount = static_cast<std::uint32_t>(kinds.size());
        if (VkResult r = vkCreateQueryPool(g.device, &qi, nullptr, &qpool); r != VK_SUCCESS)
            return raster::Error{vk_error("vkCreateQueryPool", r)};
    }
    g.begin();
    if (qpool) vkCmdResetQueryPool(g.cmd, qpool, 0, static_cast<std::uint32_t>(kinds.size()));
    g.full_barrier();
    auto rb = vk_struct<VkRenderPassBeginInfo>(VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO);
    rb.renderPass = g.pass;
    rb.framebuffer = g.framebuffer;
    rb.renderArea = {{0, 0}, {static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_)}};
    vkCmdBeginRenderPass(g.cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(g.cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, g.pipeline);
    const VkDeviceSize zero = 0;
    vkCmdBindVertexBuffers(g.cmd, 0, 1, &g.vertices.buffer, &zero);
    vkCmdBindIndexBuffer(g.cmd, g.indices.buffer, 0, VK_INDEX_TYPE_UINT32);
    const VkRect2D scissor{{0, 0}, {static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_)}};
    vkCmdSetScissor(g.cmd, 0, 1, &scissor);
    std::uint32_t active = 0;
    std::size_t draw = 0;
    for (const auto& c : batch.commands()) {
        switch (c.kind) {
            case raster::Command::Kind::BeginQuery:
                active = c.query;
                vkCmdBeginQuery(g.cmd, qpool, active, VK_QUERY_CONTROL_PRECISE_BIT);
                break;
            case raster::Command::Kind::EndQuery: vkCmdEndQuery(g.cmd, qpool, active); break;
            case raster::Command::Kind::Draw: {
                const raster::DrawState& s = c.state;
                vkCmdSetDepthCompareOp(g.cmd, vk_compare(s.depth_func));
                vkCmdSetDepthWriteEnable(g.cmd, s.depth_write ? VK_TRUE : VK_FALSE);
                vkCmdSetCullMode(g.cmd, s.cull_face == raster::CullFace::None    ? VK_CULL_MODE_NONE
                                        : s.cull_face == raster::CullFace::Front ? VK_CULL_MODE_FRONT_BIT
                                                                                 : VK_CULL_MODE_BACK_BIT);
                vkCmdSetFrontFace(g.cmd, s.front_face == raster::FrontFace::CCW ? VK_FRONT_FACE_COUNTER_CLOCKWISE
                                                                               : VK_FRONT_FACE_CLOCKWISE);
                const raster::Viewport vp = s.viewport ? *s.viewport : raster::Viewport{0, 0, width_, height_};
                const VkViewport v{static_cast<float>(vp.x),     static_cast<float>(vp.y),
                                   static_cast<float>(vp.width), static_cast<float>(vp.height),
                                   0.0f,                         1.0f};
                vkCmdSetViewport(g.cmd, 0, 1, &v);
                const BatchGeometry::Range& r = ranges[draw++];
                if (r.count > 0)
                    vkCmdDrawIndexed(g.cmd, static_cast<std::uint32_t>(r.count), 1,
                                     static_cast<std::uint32_t>(r.first_index), static_cast<std::int32_t>(r.base_vertex),
                                     0);
                break;
            }
        }
    }
    vkCmdEndRenderPass(g.cmd);
    g.full_barrier();
    raster::Status submitted = g.submit();
    raster::QueryResults out(kinds.size(), 0);
    if (qpool) {
        if (submitted) {
            VkResult r = vkGetQueryPoolResults(g.device, qpool, 0, static_cast<std::uint32_t>(kinds.size()),
                                               out.size() * sizeof(std::uint64_t), out.data(), sizeof(std::uint64_t),
                                               VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
            if (r != VK_SUCCESS) submitted = raster::Error{vk_error("vkGetQueryPoolResults", r)};
        }
        vkDestroyQueryPool(g.device, qpool, nullptr);
    }
    if (!submitted) return raster::Error{"vulkan device: " + submitted.error().message};
    for (std::size_t q = 0; q < out.size(); ++q)
        if (kinds[q] == raster::QueryKind::AnySamplesPassed) out[q] = out[q] != 0 ? 1 : 0;
    return out;
}

std::vector<std::uint32_t> VulkanDevice::read_depth() {
    Impl& g = *impl_;
    g.begin();
    g.full_barrier();
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
    region.imageExtent = {static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_), 1};
    vkCmdCopyImageToBuffer(g.cmd, g.image, VK_IMAGE_LAYOUT_GENERAL, g.readback.buffer, 1, &region);
    g.full_barrier();
    const std::size_t n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
    std::vector<std::uint32_t> out(n, 0);
    if (!g.submit()) return out;
    if (format_ == raster::DepthFormat::D16) {
        const auto* s = static_cast<const std::uint16_t*>(g.readback.mapped);
        for (std::size_t i = 0; i < n; ++i) out[i] = s[i];
    } else {
        std::memcpy(out.data(), g.readback.mapped, n * 4);
        // The depth aspect of the two D24 formats copies as 32 bits, the top 8 undefined.
        if (format_ == raster::DepthFormat::D24)
            for (auto& v : out) v &= 0xFFFFFFu;
    }
    return out;
}

std::string VulkanDevice::renderer() const { return impl_->name; }

}  // namespace cullide_oracle
