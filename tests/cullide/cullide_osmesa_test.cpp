// The CULLIDE pipeline's pass sequence on real GL (Mesa llvmpipe through OSMesa) against the
// emulator: cullide (GL-exact) and rcullide-offset (the paper's offset solids, plain GL) must give
// the same PCS at every view and the same pairs, since the emulator is bit-identical to llvmpipe.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "osmesa_query_device.h"
#include "same_frame.h"

using cullide_test::check_same_frame;

TEST_CASE("cullide and rcullide-offset prune the same on OSMesa as on the emulator, on every built-in scene") {
    auto device = cullide_oracle::make_osmesa_query_device();
    REQUIRE(device.ok());
    std::uint64_t pruned = 0;
    // Format and resolution outermost: the device re-creates its GL context when either changes.
    for (raster::DepthFormat f : {raster::DepthFormat::D16, raster::DepthFormat::D24}) {
        for (int resolution : {64, 200}) {
            for (const std::string& name : cullide::scene_names()) {
                cullide::SceneOptions so;
                so.scale = 0.05;
                so.mesh_dir = "";
                auto scene = cullide::make_scene(name, so);
                REQUIRE(scene.ok());
                const cullide::Frame objects = scene.value()->frame(3);
                for (cullide::Method m : {cullide::Method::Cullide, cullide::Method::RCullideOffset}) {
                    // The offset solids are ~10x the triangles: one depth format is enough for them.
                    if (m == cullide::Method::RCullideOffset && f == raster::DepthFormat::D16) continue;
                    CAPTURE(name);
                    CAPTURE(resolution);
                    CAPTURE(cullide::to_string(m));
                    CAPTURE(cullide::to_string(f));
                    cullide::RunOptions o;
                    o.method = m;
                    o.resolution = resolution;
                    o.depth_format = f;
                    o.threads = 2;
                    auto emu = cullide::process_frame(objects, o);
                    REQUIRE(emu.ok());
                    o.device = device.value().get();
                    auto gl = cullide::process_frame(objects, o);
                    REQUIRE(gl.ok());
                    check_same_frame(gl.value(), emu.value());
                    for (const auto& v : emu.value().stats.views) pruned += v.items_before - v.items_after;
                }
            }
        }
    }
    CHECK(pruned > 1000);  // the passes must decide something, or agreement proves little
}

TEST_CASE("the OSMesa device refuses the exact-bounds mode, which real GL does not have") {
    auto device = cullide_oracle::make_osmesa_query_device();
    REQUIRE(device.ok());
    cullide::SceneOptions so;
    so.scale = 0.05;
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);
    cullide::RunOptions o;
    o.method = cullide::Method::RCullide;
    o.resolution = 64;
    o.device = device.value().get();
    auto r = cullide::process_frame(objects, o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("exact-bounds mode") != std::string::npos);
}

// Issue #17: whole CULLIDE frames at the methods' own 1024^2, where one batch holds thousands of
// queries. The OSMesa device gets every batch whole (its bounded scenes keep llvmpipe off the
// path that over-counts: tests/oracle/llvmpipe_scene_test.cpp); every view's PCS, the queries
// and the pairs must equal the emulator's.
TEST_CASE("whole CULLIDE frames at 1024^2: OSMesa and the emulator agree pass for pass") {
    auto device = cullide_oracle::make_osmesa_query_device();
    REQUIRE(device.ok());
    cullide::SceneOptions so;
    so.scale = 1.0;
    so.mesh_dir = "";
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);
    std::uint64_t queries = 0;
    for (cullide::Method m : {cullide::Method::Cullide, cullide::Method::QCullideGL, cullide::Method::RCullideOffset}) {
        CAPTURE(cullide::to_string(m));
        cullide::RunOptions o;
        o.method = m;
        o.resolution = 1024;
        o.threads = 2;
        auto emu = cullide::process_frame(objects, o);
        REQUIRE(emu.ok());
        o.device = device.value().get();
        auto gl = cullide::process_frame(objects, o);
        REQUIRE(gl.ok());
        check_same_frame(gl.value(), emu.value());
        queries += emu.value().stats.queries;
    }
    MESSAGE("queries compared: " << queries);
    CHECK(queries > 20000);  // batches of thousands of queries, as in pipeline_bench
}
