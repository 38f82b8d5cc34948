// conformance_test.cpp: the raster module against real GL (Mesa llvmpipe via OSMesa), bit for bit.
//
// Random scenes (scene_gen.h: triangles with vertices on pixel centres and on the 1/256 grid,
// edges through centres, fans and grids with shared edges, slivers, off-screen, near/far-crossing
// and w < 0 triangles, culling, small viewports, equal-depth ties under every depth function) are
// run through raster::execute_reference and through OSMesa; every query result and every depth
// value must be equal, in D16, D24 and D32F (conformance_harness.h; the tiled executor must give the
// reference's bits as well). CULLIDE_CONFORMANCE_SCALE=<n> multiplies the number
// of scenes (default 1: about 110,000 queries).
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "osmesa_device.h"
#include "raster/raster.h"
#include "conformance_harness.h"

namespace {

using raster_test::ConformanceTally;
using raster_test::format_name;

ConformanceTally run_format(raster::DepthFormat format, int width, int height, int scenes, std::uint64_t seed) {
    return raster_test::run_conformance<cullide_oracle::OsmesaDevice>("GL", raster::RasterRules::GlLlvmpipe, format,
                                                                      width, height, scenes, seed);
}

}  // namespace

TEST_CASE("Random scenes give exactly OSMesa llvmpipe's query counts and depth buffers in every format") {
    const int scale = raster_test::conformance_scale();
    struct Size {
        int w, h, scenes;
    };
    // Small targets give many edge and tie cases per pixel; the large one exercises the depth
    // plane far from the origin (float precision of z0 + dzdx * x).
    const Size sizes[] = {{64, 64, 100}, {97, 61, 100}, {128, 96, 100}, {1024, 768, 10}};
    const raster::DepthFormat formats[] = {raster::DepthFormat::D16, raster::DepthFormat::D24,
                                           raster::DepthFormat::D32F};
    ConformanceTally total;
    std::uint64_t seed = 1234;
    for (const auto f : formats) {
        for (const auto& sz : sizes) {
            CAPTURE(format_name(f));
            CAPTURE(sz.w);
            CAPTURE(sz.h);
            const ConformanceTally t = run_format(f, sz.w, sz.h, sz.scenes * scale, seed++);
            CHECK(t.query_mismatches == 0);
            CHECK(t.pixel_mismatches == 0);
            total.add(t);
        }
    }
    std::printf("conformance: %zu queries (%zu differ), %zu depth values (%zu differ)\n", total.queries,
                total.query_mismatches, total.pixels, total.pixel_mismatches);
    CHECK(total.queries >= 100000 * static_cast<std::size_t>(scale));
}

TEST_CASE("Clearing to any depth stores what OSMesa stores in every format") {
    raster_test::SplitMix64 rng(4321);
    for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
        auto dev = cullide_oracle::OsmesaDevice::create(4, 4, f);
        REQUIRE(dev.ok());
        std::size_t differ = 0;
        for (int i = 0; i < 400; ++i) {
            // Random doubles, plus values exactly half-way between two codes of each format.
            double d = static_cast<double>(rng.next() >> 11) * (1.0 / 9007199254740992.0);
            if (i % 4 == 1) d = (static_cast<double>(rng.below(65535)) + 0.5) / 65535.0;
            if (i % 4 == 2) d = (static_cast<double>(rng.below(16777215)) + 0.5) / 16777215.0;
            if (i == 0) d = 0.0;
            if (i == 3) d = 1.0;
            dev.value()->clear(d);
            const auto gl = dev.value()->read_depth();
            const std::uint32_t ours = raster::DepthTarget::encode_clear(d, f);
            if (gl[5] != ours) {
                if (differ == 0) std::printf("[%s] clear %.17g: ours %08x, GL %08x\n", format_name(f), d, ours, gl[5]);
                ++differ;
            }
        }
        CAPTURE(format_name(f));
        CHECK(differ == 0);
    }
}
