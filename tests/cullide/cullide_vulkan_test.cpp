// The CULLIDE and Quick-CULLIDE pipelines' pass sequences on Vulkan (Mesa's lavapipe) against the
// emulator under the Vulkan rules (RunOptions::gpu_rules): cullide and qcullide-gl (GL-exact views)
// must give the same PCS at every view and the same pairs, since the emulator's Vulkan rules are
// bit-identical to lavapipe (tests/raster/vulkan_conformance_test.cpp).
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "vulkan_query_device.h"
#include "same_frame.h"

using cullide_test::check_same_frame;

TEST_CASE("cullide and qcullide-gl prune the same on lavapipe as on the emulator's Vulkan rules, every scene") {
    auto device = cullide_oracle::make_vulkan_query_device();
    REQUIRE(device.ok());
    std::uint64_t pruned = 0;
    // Format and resolution outermost: the device re-creates its Vulkan device when either changes.
    for (raster::DepthFormat f : {raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
        for (int resolution : {64, 200}) {
            for (const std::string& name : cullide::scene_names()) {
                cullide::SceneOptions so;
                so.scale = 0.05;
                so.mesh_dir = "";
                auto scene = cullide::make_scene(name, so);
                REQUIRE(scene.ok());
                const cullide::Frame objects = scene.value()->frame(3);
                for (cullide::Method m : {cullide::Method::Cullide, cullide::Method::QCullideGL}) {
                    for (bool self : {false, true}) {
                        if (self && m == cullide::Method::Cullide) continue;  // cullide has no self pairs
                        CAPTURE(name);
                        CAPTURE(resolution);
                        CAPTURE(cullide::to_string(m));
                        CAPTURE(cullide::to_string(f));
                        CAPTURE(self);
                        cullide::RunOptions o;
                        o.method = m;
                        o.self = self;
                        o.resolution = resolution;
                        o.depth_format = f;
                        o.threads = 2;
                        o.gpu_rules = raster::RasterRules::Vulkan;
                        auto emu = cullide::process_frame(objects, o);
                        REQUIRE_MESSAGE(emu.ok(), (emu.ok() ? "" : emu.error().message));
                        o.device = device.value().get();
                        auto vk = cullide::process_frame(objects, o);
                        REQUIRE_MESSAGE(vk.ok(), (vk.ok() ? "" : vk.error().message));
                        check_same_frame(vk.value(), emu.value());
                        for (const auto& v : emu.value().stats.views) pruned += v.items_before - v.items_after;
                    }
                }
            }
        }
    }
    CHECK(pruned > 1000);  // the passes must decide something, or agreement proves little
}

TEST_CASE("the Vulkan device refuses batches recorded for the GL rules and the exact-bounds mode") {
    auto device = cullide_oracle::make_vulkan_query_device();
    REQUIRE(device.ok());
    cullide::SceneOptions so;
    so.scale = 0.05;
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);
    cullide::RunOptions o;
    o.method = cullide::Method::Cullide;
    o.resolution = 64;
    o.device = device.value().get();
    auto gl = cullide::process_frame(objects, o);  // gpu_rules defaults to GL
    REQUIRE_FALSE(gl.ok());
    CHECK(gl.error().message.find("GL rules") != std::string::npos);
    o.method = cullide::Method::RCullide;
    o.gpu_rules = raster::RasterRules::Vulkan;
    auto eb = cullide::process_frame(objects, o);
    REQUIRE_FALSE(eb.ok());
    CHECK(eb.error().message.find("exact-bounds mode") != std::string::npos);
}
