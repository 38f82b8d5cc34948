// fused_visibility_test.cpp: R-CULLIDE (VisibilityMode::ExactBounds) on the emulator with the fused
// visibility pass (raster/visibility.h, the default) against the two recorded passes per view
// (CullideOptions::fused_visibility = false): the very same PCS after every view, the same pairs and
// the same statistics, on every built-in scene, at several resolutions, in every depth format.
// The quick build covers every scene at one resolution and format plus all formats on cylinders;
// the slow build (FUSED_VISIBILITY_SLOW) every scene x {32, 128, 512} x {D16, D24, D32F}.
#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "cullide/cullide.h"
#include "cullide/query_device.h"
#include "cullide/scenes.h"

namespace {

struct Outcome {
    std::vector<cullide::TrianglePair> pairs;
    cullide::CullideStats stats;
};

Outcome run(const cullide::Frame& frame, int resolution, raster::DepthFormat f, bool fused, int threads) {
    std::vector<std::uint32_t> active(frame.size());
    for (std::size_t i = 0; i < active.size(); ++i) active[i] = static_cast<std::uint32_t>(i);
    cullide::CullideOptions o;
    o.mode = cullide::VisibilityMode::ExactBounds;
    o.resolution = resolution;
    o.depth_format = f;
    o.threads = threads;
    o.fused_visibility = fused;
    auto device = cullide::make_emulator_device(threads);
    Outcome out;
    auto r = cullide::cullide_pairs(frame, active, o, *device, &out.stats);
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
    out.pairs = std::move(r).value();
    return out;
}

void compare(const std::string& scene, int resolution, raster::DepthFormat f) {
    CAPTURE(scene);
    CAPTURE(resolution);
    CAPTURE(static_cast<int>(f));
    auto gen = cullide::make_scene(scene, cullide::SceneOptions{});
    REQUIRE(gen.ok());
    const cullide::Frame frame = gen.value()->frame(0);
    const Outcome want = run(frame, resolution, f, false, 2);
    for (const int threads : {1, 3}) {
        CAPTURE(threads);
        const Outcome got = run(frame, resolution, f, true, threads);
        CHECK(got.pairs == want.pairs);
        CHECK(got.stats.pcs_boxes == want.stats.pcs_boxes);
        CHECK(got.stats.pcs_objects == want.stats.pcs_objects);
        CHECK(got.stats.pcs_subobjects == want.stats.pcs_subobjects);
        CHECK(got.stats.queries == want.stats.queries);
        CHECK(got.stats.triangles_rasterized == want.stats.triangles_rasterized);
        REQUIRE(got.stats.views.size() == want.stats.views.size());
        for (std::size_t v = 0; v < want.stats.views.size(); ++v) {
            CAPTURE(v);
            CHECK(got.stats.views[v].items_before == want.stats.views[v].items_before);
            CHECK(got.stats.views[v].items_after == want.stats.views[v].items_after);
            CHECK(got.stats.views[v].queries == want.stats.views[v].queries);
        }
    }
    // The comparison means something: views ran and pruned.
    CHECK(!want.stats.views.empty());
}

}  // namespace

#if defined(FUSED_VISIBILITY_SLOW)
TEST_CASE("Fused and recorded R-CULLIDE passes agree on every scene, resolution and depth format") {
    for (const std::string& scene : cullide::scene_names())
        for (const int res : {32, 128, 512})
            for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F})
                compare(scene, res, f);
}
#else
TEST_CASE("Fused and recorded R-CULLIDE passes agree on every scene (32 px, D24) and in every format (cylinders)") {
    for (const std::string& scene : cullide::scene_names()) compare(scene, 32, raster::DepthFormat::D24);
    for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D32F}) compare("cylinders", 64, f);
}
#endif
