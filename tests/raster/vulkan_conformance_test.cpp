// vulkan_conformance_test.cpp: the raster module's Vulkan rules (raster::RasterRules::Vulkan) against
// a real Vulkan implementation (Mesa's lavapipe, tests/oracle/vulkan_device.h), bit for bit.
//
// The random scenes of the OSMesa conformance test (scene_gen.h: vertices on pixel centres and on the
// 1/256 grid, edges through centres, fans and grids with shared edges, slivers, off-screen,
// near/far-crossing and w < 0 triangles, culling with both front faces, small viewports, equal-depth
// ties under every depth function), recorded for Vulkan (clip z in [0, w]), run through
// raster::execute_reference and through lavapipe; every query result and every depth value must be
// equal, in D16, D24 and D32F. The default suite runs a tenth of the scenes (label oracle); the
// `slow` program runs them all (about 112,000 queries and 30 million depth values).
// CULLIDE_CONFORMANCE_SCALE=<n> multiplies the number of scenes of either.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "raster/raster.h"
#include "conformance_harness.h"
#include "vulkan_device.h"

#ifndef CULLIDE_VULKAN_CONFORMANCE_FULL
#define CULLIDE_VULKAN_CONFORMANCE_FULL 0
#endif

namespace {

using raster_test::ConformanceTally;
using raster_test::format_name;

ConformanceTally run_format(raster::DepthFormat format, int width, int height, int scenes, std::uint64_t seed) {
    if (width == 64) {
        auto dev = cullide_oracle::VulkanDevice::create(width, height, format);
        if (dev.ok()) std::printf("lavapipe: %s\n", dev.value()->renderer().c_str());
    }
    return raster_test::run_conformance<cullide_oracle::VulkanDevice>("lavapipe", raster::RasterRules::Vulkan, format,
                                                                      width, height, scenes, seed);
}

}  // namespace

TEST_CASE("Random Vulkan-rules scenes give exactly lavapipe's query counts and depth buffers in every format") {
    const int scale = raster_test::conformance_scale();
    // The OSMesa suite's sizes and scene counts; the default (non-slow) program runs a tenth.
    const int divisor = CULLIDE_VULKAN_CONFORMANCE_FULL ? 1 : 10;
    struct Size {
        int w, h, scenes;
    };
    const Size sizes[] = {{64, 64, 100}, {97, 61, 100}, {128, 96, 100}, {1024, 768, 10}};
    const raster::DepthFormat formats[] = {raster::DepthFormat::D16, raster::DepthFormat::D24,
                                           raster::DepthFormat::D32F};
    ConformanceTally total;
    std::uint64_t seed = CULLIDE_VULKAN_CONFORMANCE_FULL ? 5678 : 8765;
    for (const auto f : formats) {
        for (const auto& sz : sizes) {
            CAPTURE(format_name(f));
            CAPTURE(sz.w);
            CAPTURE(sz.h);
            const int scenes = std::max(1, sz.scenes * scale / divisor);
            const ConformanceTally t = run_format(f, sz.w, sz.h, scenes, seed++);
            CHECK(t.query_mismatches == 0);
            CHECK(t.pixel_mismatches == 0);
            total.add(t);
        }
    }
    std::printf("vulkan conformance: %zu queries (%zu differ), %zu depth values (%zu differ)\n", total.queries,
                total.query_mismatches, total.pixels, total.pixel_mismatches);
    CHECK(total.queries >= 100000 * static_cast<std::size_t>(scale) / static_cast<std::size_t>(divisor));
}

TEST_CASE("The same scenes under the GL rules differ from lavapipe (the comparison can fail)") {
    // Each of the Vulkan rules (z mapping and near plane, provoking vertex, facing) changes results on
    // these scenes, so a comparison that cannot tell the rule sets apart would show up here.
    auto dev = cullide_oracle::VulkanDevice::create(64, 64, raster::DepthFormat::D24);
    REQUIRE_MESSAGE(dev.ok(), (dev.ok() ? "" : dev.error().message));
    raster_test::SplitMix64 rng(2468);
    raster_test::Scene scene;
    std::size_t differ = 0;
    for (int s = 0; s < 10; ++s) {
        raster_test::SceneOptions o;
        o.rules = raster::RasterRules::Vulkan;
        raster_test::build_scene(scene, rng, o);
        dev.value()->clear(scene.clear_depth);
        auto vk = dev.value()->run(scene.batch);
        REQUIRE(vk.ok());
        raster::CommandBatch gl(64, 64, raster::RasterRules::GlLlvmpipe);
        for (const raster::Command& c : scene.batch.commands()) {
            if (c.kind == raster::Command::Kind::BeginQuery) gl.begin_query(scene.batch.query_kinds()[c.query]);
            if (c.kind == raster::Command::Kind::EndQuery) gl.end_query();
            if (c.kind == raster::Command::Kind::Draw) gl.draw(c.mesh, c.state);
        }
        CHECK_FALSE(dev.value()->run(gl).ok());  // the oracle refuses a batch of the other rules
        auto target = raster::DepthTarget::create(64, 64, raster::DepthFormat::D24);
        REQUIRE(target.ok());
        REQUIRE(target.value().clear(scene.clear_depth).ok());
        auto ours = raster::execute_reference(target.value(), gl);
        REQUIRE(ours.ok());
        for (std::size_t q = 0; q < ours.value().size(); ++q) differ += ours.value()[q] != vk.value()[q] ? 1 : 0;
    }
    CHECK(differ > 0);
}

TEST_CASE("Clearing to any depth stores what lavapipe stores in every format") {
    raster_test::SplitMix64 rng(4321);
    for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
        auto dev = cullide_oracle::VulkanDevice::create(4, 4, f);
        REQUIRE_MESSAGE(dev.ok(), (dev.ok() ? "" : dev.error().message));
        std::size_t differ = 0;
        for (int i = 0; i < 400; ++i) {
            // Random floats (Vulkan clears take a float), plus values half-way between two codes.
            double d = static_cast<double>(static_cast<float>(static_cast<double>(rng.next() >> 40) / 16777216.0));
            if (i % 4 == 1) d = static_cast<float>((static_cast<double>(rng.below(65535)) + 0.5) / 65535.0);
            if (i % 4 == 2) d = static_cast<float>((static_cast<double>(rng.below(16777215)) + 0.5) / 16777215.0);
            if (i == 0) d = 0.0;
            if (i == 3) d = 1.0;
            dev.value()->clear(d);
            const auto vk = dev.value()->read_depth();
            const std::uint32_t ours = raster::DepthTarget::encode_clear(d, f);
            if (vk[5] != ours) {
                if (differ == 0)
                    std::printf("[%s] clear %.9g: ours %08x, lavapipe %08x\n", format_name(f), d, ours, vk[5]);
                ++differ;
            }
        }
        CAPTURE(format_name(f));
        CHECK(differ == 0);
    }
}
