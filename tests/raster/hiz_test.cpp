// hiz_test.cpp: hierarchical Z (raster/src/pipeline.h, HizTile) changes no bit. The tiled executor
// with per-block depth bounds is compared with the scalar reference (which tests every pixel) and
// with itself without them, on scenes made to hit the bound's edge cases: large triangles over many
// 8 x 8 blocks, constant-depth planes drawn at the very depths already stored (ties for every
// function), slanted planes crossing the stored depth, all eight functions for queries and writes,
// queries after writes in the same batch and batches on a buffer left by earlier ones or filled
// with arbitrary values (D16/D24 bounds are over any stored uint32).
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <vector>

#include "raster/raster.h"
#include "scene_gen.h"

namespace {

struct Mesh {
    std::vector<raster::Float4> v;
    std::vector<std::uint32_t> i;
};

// A random big triangle (or a whole-target quad) with depth from a small set of values so that
// later draws land exactly on stored depths, sometimes slanted.
void random_mesh(raster_test::SplitMix64& rng, Mesh& m) {
    static const float levels[] = {-1.0f, -0.5f, 0.0f, 0.25f, 0.3f, 0.75f, 1.0f};
    const float base = levels[rng.below(7)];
    const bool slanted = rng.chance(40);
    const auto z = [&]() { return slanted ? std::clamp(base + rng.uniform(-0.3f, 0.3f), -1.2f, 1.2f) : base; };
    if (rng.chance(20)) {  // a quad over the whole target
        m.v = {{-1, -1, z(), 1}, {1, -1, z(), 1}, {1, 1, z(), 1}, {-1, 1, z(), 1}};
        m.i = {0, 1, 2, 0, 2, 3};
        return;
    }
    for (int k = 0; k < 3; ++k) m.v.push_back({rng.uniform(-1.3f, 1.3f), rng.uniform(-1.3f, 1.3f), z(), 1});
    m.i = {0, 1, 2};
}

raster::DepthFunc random_func(raster_test::SplitMix64& rng) {
    return static_cast<raster::DepthFunc>(rng.below(8));
}

// One batch: writes and queries (mask off, both kinds), queries often right after the writes.
void build_batch(raster_test::SplitMix64& rng, raster::CommandBatch& batch, std::deque<Mesh>& meshes, int commands) {
    for (int c = 0; c < commands; ++c) {
        meshes.emplace_back();
        random_mesh(rng, meshes.back());
        const raster::MeshView view{meshes.back().v, meshes.back().i};
        raster::DrawState s;
        s.depth_func = random_func(rng);
        if (rng.chance(35)) {
            s.depth_write = true;
            batch.draw(view, s);
        } else {
            s.depth_write = false;
            batch.begin_query(rng.chance(50) ? raster::QueryKind::AnySamplesPassed : raster::QueryKind::SamplesPassed);
            batch.draw(view, s);
            if (rng.chance(30)) {  // a second draw in the same query
                s.depth_func = random_func(rng);
                batch.draw(view, s);
            }
            batch.end_query();
        }
    }
}

}  // namespace

TEST_CASE("Hierarchical Z gives the reference's queries and buffer, for every function and format") {
    raster_test::SplitMix64 rng(1717);
    struct Size {
        int w, h;
    };
    const Size sizes[] = {{64, 64}, {200, 130}, {131, 67}};
    std::uint64_t nonzero = 0, zero = 0;
    for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
        for (const auto& sz : sizes) {
            for (int rep = 0; rep < 12; ++rep) {
                CAPTURE(static_cast<int>(f));
                CAPTURE(sz.w);
                CAPTURE(rep);
                auto ref = raster::DepthTarget::create(sz.w, sz.h, f).value();
                auto hiz1 = raster::DepthTarget::create(sz.w, sz.h, f).value();
                auto hiz2 = raster::DepthTarget::create(sz.w, sz.h, f).value();
                auto plain = raster::DepthTarget::create(sz.w, sz.h, f).value();
                if (rep % 4 == 3 && f != raster::DepthFormat::D32F) {
                    // Arbitrary stored values, beyond the format's bits too.
                    auto r = ref.mutable_values();
                    for (auto& v : r) v = rng.chance(50) ? static_cast<std::uint32_t>(rng.next()) : 0xffffu * rng.below(3);
                    for (auto* t : {&hiz1, &hiz2, &plain}) std::copy(r.begin(), r.end(), t->mutable_values().begin());
                }
                // Several batches on the same buffers: later ones start from what earlier ones left.
                for (int b = 0; b < 3; ++b) {
                    std::deque<Mesh> meshes;
                    raster::CommandBatch batch(sz.w, sz.h);
                    build_batch(rng, batch, meshes, 40);
                    const bool simd = rng.chance(50);
                    auto want = raster::execute_reference(ref, batch, raster::ExecuteOptions{1, simd});
                    raster::ExecuteOptions on1{1, simd};
                    raster::ExecuteOptions on2{2, !simd};
                    raster::ExecuteOptions off{1, simd};
                    off.hierarchical_z = false;
                    auto got1 = raster::execute(hiz1, batch, on1);
                    auto got2 = raster::execute(hiz2, batch, on2);
                    auto got_off = raster::execute(plain, batch, off);
                    REQUIRE(want.ok());
                    REQUIRE(got1.ok());
                    REQUIRE(got2.ok());
                    REQUIRE(got_off.ok());
                    CHECK(got1.value() == want.value());
                    CHECK(got2.value() == want.value());
                    CHECK(got_off.value() == want.value());
                    const auto r = ref.values();
                    CHECK(std::equal(r.begin(), r.end(), hiz1.values().begin(), hiz1.values().end()));
                    CHECK(std::equal(r.begin(), r.end(), hiz2.values().begin(), hiz2.values().end()));
                    CHECK(std::equal(r.begin(), r.end(), plain.values().begin(), plain.values().end()));
                    for (const auto q : want.value()) (q != 0 ? nonzero : zero)++;
                }
            }
        }
    }
    // The scenes have both answers in numbers (not all queries empty, not all passing).
    CHECK(nonzero > 500);
    CHECK(zero > 500);
}
