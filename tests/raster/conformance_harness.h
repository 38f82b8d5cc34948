// conformance_harness.h: what the two oracle conformance suites share (conformance_test.cpp against
// OSMesa's llvmpipe, vulkan_conformance_test.cpp against lavapipe): run random scenes (scene_gen.h)
// of one format and size through an oracle device and through raster::execute_reference, and count
// every query result and every depth value that differs. The scalar reference is also checked against
// the tiled executor (3 threads, SIMD kernel where available), so the path the library runs is pinned
// to the oracle too. The first difference of each kind is printed with what reproduces it.
//
// Device: a type with static create(width, height, format) -> Result<std::unique_ptr<Device>>, and
// members clear(double), run(const raster::CommandBatch&) -> Result<std::vector<std::uint64_t>> and
// read_depth() -> std::vector<std::uint32_t> (tests/oracle/osmesa_device.h, vulkan_device.h).
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "raster/raster.h"
#include "scene_gen.h"

namespace raster_test {

// CULLIDE_CONFORMANCE_SCALE=<n> multiplies the number of scenes (default 1).
inline int conformance_scale() {
    const char* s = std::getenv("CULLIDE_CONFORMANCE_SCALE");
    if (s == nullptr) return 1;
    const int v = std::atoi(s);
    return v < 1 ? 1 : v;
}

inline const char* format_name(raster::DepthFormat f) {
    return f == raster::DepthFormat::D16 ? "D16" : f == raster::DepthFormat::D24 ? "D24" : "D32F";
}

struct ConformanceTally {
    std::size_t queries = 0, query_mismatches = 0, pixels = 0, pixel_mismatches = 0;

    void add(const ConformanceTally& t) {
        queries += t.queries;
        query_mismatches += t.query_mismatches;
        pixels += t.pixels;
        pixel_mismatches += t.pixel_mismatches;
    }
};

// Runs `scenes` random scenes of one format and size under `rules` through Device and the emulator.
template <typename Device>
ConformanceTally run_conformance(const char* oracle, raster::RasterRules rules, raster::DepthFormat format,
                                 int width, int height, int scenes, std::uint64_t seed) {
    ConformanceTally t;
    auto dev = Device::create(width, height, format);
    REQUIRE_MESSAGE(dev.ok(), (dev.ok() ? "" : dev.error().message));
    SplitMix64 rng(seed);
    Scene scene;
    bool reported_query = false, reported_pixel = false;
    for (int s = 0; s < scenes; ++s) {
        SceneOptions o;
        o.width = width;
        o.height = height;
        o.rules = rules;
        build_scene(scene, rng, o);
        dev.value()->clear(scene.clear_depth);
        auto theirs = dev.value()->run(scene.batch);
        REQUIRE_MESSAGE(theirs.ok(), (theirs.ok() ? "" : theirs.error().message));
        const auto their_depth = dev.value()->read_depth();

        auto target = raster::DepthTarget::create(width, height, format);
        REQUIRE(target.ok());
        REQUIRE(target.value().clear(scene.clear_depth).ok());
        auto ours = raster::execute_reference(target.value(), scene.batch);
        REQUIRE_MESSAGE(ours.ok(), (ours.ok() ? "" : ours.error().message));
        REQUIRE(ours.value().size() == theirs.value().size());

        auto tiled = raster::DepthTarget::create(width, height, format);
        REQUIRE(tiled.ok());
        REQUIRE(tiled.value().clear(scene.clear_depth).ok());
        auto tiled_results = raster::execute(tiled.value(), scene.batch, {3, true});
        REQUIRE(tiled_results.ok());
        CHECK(tiled_results.value() == ours.value());
        CHECK(std::equal(tiled.value().values().begin(), tiled.value().values().end(),
                         target.value().values().begin()));

        for (std::size_t q = 0; q < ours.value().size(); ++q) {
            ++t.queries;
            if (ours.value()[q] == theirs.value()[q]) continue;
            ++t.query_mismatches;
            if (reported_query) continue;
            reported_query = true;
            std::printf("[%s %dx%d seed %llu] scene %d query %zu: ours %llu, %s %llu\n", format_name(format), width,
                        height, static_cast<unsigned long long>(seed), s, q,
                        static_cast<unsigned long long>(ours.value()[q]), oracle,
                        static_cast<unsigned long long>(theirs.value()[q]));
        }
        const auto mine = target.value().values();
        for (std::size_t i = 0; i < mine.size(); ++i) {
            ++t.pixels;
            if (mine[i] == their_depth[i]) continue;
            ++t.pixel_mismatches;
            if (reported_pixel) continue;
            reported_pixel = true;
            std::printf("[%s %dx%d seed %llu] scene %d pixel (%zu, %zu): ours %08x, %s %08x\n", format_name(format),
                        width, height, static_cast<unsigned long long>(seed), s, i % static_cast<std::size_t>(width),
                        i / static_cast<std::size_t>(width), mine[i], oracle, their_depth[i]);
        }
    }
    return t;
}

}  // namespace raster_test
