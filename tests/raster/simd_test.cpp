// simd_test.cpp: the 8-wide AVX2 GL-exact kernel equals the scalar (portable) kernel bit for bit.
// White box (raster/src/pipeline.h): random triangles through the real front end, random
// sub-rectangles (so block-level trivial reject / accept and every partial chunk are hit), random
// stored depth values (any 32-bit pattern, NaNs for D32F), every format x depth function x mask;
// then the public API: execute (1, 2, 3, 8 threads, SIMD on) against execute_reference with SIMD
// off on random scenes, and any-samples early exit against full counts.
// On a CPU or build without the AVX2 kernel the kernel-level cases compare the fallback with the
// portable kernel (still a real comparison, and said in a message).
#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "exact_bounds.h"
#include "pipeline.h"
#include "raster/raster.h"
#include "scene_gen.h"
#include "thread_runs.h"

namespace {

using raster::DepthFormat;
using raster::DepthFunc;
namespace detail = raster::detail;

// The AVX2 and AVX-512 kernels where this CPU can run them (kernel_*_callable: a SIMD build needs
// the instructions, a scalar fallback build always runs), else the portable kernel in their place,
// so that every comparison below still runs (session 25: on an AMD EPYC without AVX-512 the direct
// AVX-512 calls stopped this binary with SIGILL, three test cases failing).
std::uint64_t rect_avx2(const detail::SetupTri& t, DepthFormat f, DepthFunc func, bool write, std::uint32_t* depth,
                        int stride, int rx0, int ry0, int rx1, int ry1, bool stop_at_first) {
    return detail::kernel_avx2_callable()
               ? detail::raster_rect_avx2(t, f, func, write, depth, stride, rx0, ry0, rx1, ry1, stop_at_first)
               : detail::raster_rect_portable(t, f, func, write, depth, stride, rx0, ry0, rx1, ry1, stop_at_first);
}
std::uint64_t rect_avx512(const detail::SetupTri& t, DepthFormat f, DepthFunc func, bool write, std::uint32_t* depth,
                          int stride, int rx0, int ry0, int rx1, int ry1, bool stop_at_first) {
    return detail::kernel_avx512_callable()
               ? detail::raster_rect_avx512(t, f, func, write, depth, stride, rx0, ry0, rx1, ry1, stop_at_first)
               : detail::raster_rect_portable(t, f, func, write, depth, stride, rx0, ry0, rx1, ry1, stop_at_first);
}

constexpr DepthFunc kFuncs[] = {DepthFunc::Never,   DepthFunc::Less,     DepthFunc::Equal,  DepthFunc::LEqual,
                                DepthFunc::Greater, DepthFunc::NotEqual, DepthFunc::GEqual, DepthFunc::Always};
constexpr DepthFormat kFormats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};

// A stored depth value: mostly valid for the format, near the triangle's depths so that ties and
// both outcomes of every compare occur; sometimes an arbitrary bit pattern.
std::uint32_t random_stored(raster_test::SplitMix64& rng, DepthFormat f, float near_z) {
    const std::uint32_t pick = rng.below(10);
    if (pick == 0) return static_cast<std::uint32_t>(rng.next());  // any bits (NaNs for D32F)
    const float z = std::clamp(near_z + rng.uniform(-0.05f, 0.05f), 0.0f, 1.0f);
    switch (f) {
        case DepthFormat::D16: return static_cast<std::uint32_t>(z * 65535.0f) + (rng.chance(50) ? 1u : 0u);
        case DepthFormat::D24: return static_cast<std::uint32_t>(z * 16777215.0f) + (rng.chance(50) ? 1u : 0u);
        case DepthFormat::D32F: return std::bit_cast<std::uint32_t>(z);
    }
    return 0;
}

// Front-end parameters of a whole w x h target: no culling, GL's counter-clockwise front faces.
detail::FrontEndParams whole_target(int w, int h) {
    detail::FrontEndParams p{};
    p.target_width = w;
    p.target_height = h;
    p.viewport = raster::Viewport{0, 0, w, h};
    p.cull_face = raster::CullFace::None;
    p.front_face = raster::FrontFace::CCW;
    return p;
}

}  // namespace

TEST_CASE("AVX2 and AVX-512 kernels == portable kernel on random triangles, rectangles and stored depths (every format, function, mask)") {
    if (!detail::kernel_avx2_available())
        MESSAGE("no AVX2+FMA kernel on this CPU/build: "
                << (detail::kernel_avx2_callable() ? "comparing its scalar fallback build with the portable one"
                                                   : "the portable kernel stands in for it"));
    if (!detail::kernel_avx512_available())
        MESSAGE("no AVX-512 kernel on this CPU/build: "
                << (detail::kernel_avx512_callable() ? "comparing its scalar fallback build with the portable one"
                                                     : "the portable kernel stands in for it"));
    raster_test::SplitMix64 rng(0x5eed51u);
    const int sizes[][2] = {{64, 64}, {203, 131}, {257, 67}, {13, 9}};
    std::uint64_t total_passed = 0, compared = 0, rejected_rects = 0;
    for (const auto& sz : sizes) {
        const int w = sz[0], h = sz[1];
        detail::FrontEndParams p = whole_target(w, h);
        for (int n = 0; n < 220; ++n) {
            std::vector<detail::SetupTri> tris;
            const int flavour = static_cast<int>(rng.below(5));
            raster::Float4 v[3];
            for (auto& x : v) x = raster_test::random_vertex(rng, w, h, flavour);
            if (rng.chance(30)) {  // large: a corner anywhere, others far away (whole-tile accepts)
                v[1] = {rng.uniform(-3.0f, 3.0f), rng.uniform(-3.0f, 3.0f), rng.uniform(-0.9f, 0.9f), 1.0f};
                v[2] = {rng.uniform(-3.0f, 3.0f), rng.uniform(-3.0f, 3.0f), rng.uniform(-0.9f, 0.9f), 1.0f};
            }
            detail::setup_triangle(p, v[0], v[1], v[2], 0, tris);
            for (const auto& t : tris) {
                // The whole box, and a random sub-rectangle of it.
                for (int sub = 0; sub < 2; ++sub) {
                    int rx0 = t.x0, ry0 = t.y0, rx1 = t.x1, ry1 = t.y1;
                    if (sub == 1) {
                        rx0 = t.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - t.x0 + 1)));
                        rx1 = rx0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - rx0 + 1)));
                        ry0 = t.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - t.y0 + 1)));
                        ry1 = ry0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - ry0 + 1)));
                    }
                    if (detail::rect_outside(t, rx0, ry0, rx1, ry1)) ++rejected_rects;
                    const DepthFormat f = kFormats[rng.below(3)];
                    const DepthFunc func = kFuncs[rng.below(8)];
                    const bool write = rng.chance(50);
                    std::vector<std::uint32_t> base(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
                    const float near_z = std::clamp(t.z0 + t.dzdx * static_cast<float>(rx0) +
                                                        t.dzdy * static_cast<float>(ry0), 0.0f, 1.0f);
                    for (auto& x : base) x = random_stored(rng, f, near_z);
                    auto a = base, b = base;
                    CAPTURE(w);
                    CAPTURE(static_cast<int>(f));
                    CAPTURE(static_cast<int>(func));
                    CAPTURE(write);
                    const std::uint64_t na =
                        detail::raster_rect_portable(t, f, func, write, a.data(), w, rx0, ry0, rx1, ry1, false);
                    const std::uint64_t nb =
                        rect_avx2(t, f, func, write, b.data(), w, rx0, ry0, rx1, ry1, false);
                    CHECK(na == nb);
                    REQUIRE(a == b);  // every depth value, including pixels outside the rectangle
                    auto b16 = base;
                    CHECK(na == rect_avx512(t, f, func, write, b16.data(), w, rx0, ry0, rx1, ry1, false));
                    REQUIRE(a == b16);
                    // Early exit: > 0 exactly when the full count is > 0, on every kernel.
                    auto c = base, d = base, d16 = base;
                    const std::uint64_t sa = detail::raster_rect_portable(t, f, func, false, c.data(), w, rx0, ry0,
                                                                          rx1, ry1, true);
                    const std::uint64_t sb =
                        rect_avx2(t, f, func, false, d.data(), w, rx0, ry0, rx1, ry1, true);
                    const std::uint64_t s16 =
                        rect_avx512(t, f, func, false, d16.data(), w, rx0, ry0, rx1, ry1, true);
                    std::vector<std::uint32_t> e = base;
                    const std::uint64_t full =
                        detail::raster_rect_portable(t, f, func, false, e.data(), w, rx0, ry0, rx1, ry1, false);
                    CHECK((sa > 0) == (full > 0));
                    CHECK((sb > 0) == (full > 0));
                    CHECK((s16 > 0) == (full > 0));
                    CHECK(sa <= full);
                    CHECK(sb <= full);
                    CHECK(s16 <= full);
                    CHECK(c == base);
                    CHECK(d == base);
                    CHECK(d16 == base);
                    total_passed += na;
                    ++compared;
                }
            }
        }
    }
    MESSAGE("rectangles compared: " << compared << ", samples passed: " << total_passed
                                    << ", rectangles trivially rejected: " << rejected_rects);
    CHECK(compared > 1000);
    CHECK(total_passed > 10000);
    CHECK(rejected_rects > 0);
}

TEST_CASE("rect_outside never rejects a rectangle with a covered pixel") {
    raster_test::SplitMix64 rng(4242);
    detail::FrontEndParams p{};
    p.target_width = 150;
    p.target_height = 140;
    p.viewport = raster::Viewport{0, 0, 150, 140};
    std::uint64_t rejected = 0;
    for (int n = 0; n < 3000; ++n) {
        std::vector<detail::SetupTri> tris;
        raster::Float4 v[3];
        for (auto& x : v) x = raster_test::random_vertex(rng, 150, 140, static_cast<int>(rng.below(5)));
        detail::setup_triangle(p, v[0], v[1], v[2], 0, tris);
        for (const auto& t : tris) {
            const int rx0 = t.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - t.x0 + 1)));
            const int ry0 = t.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - t.y0 + 1)));
            const int rx1 = rx0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - rx0 + 1)));
            const int ry1 = ry0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - ry0 + 1)));
            if (!detail::rect_outside(t, rx0, ry0, rx1, ry1)) continue;
            ++rejected;
            std::vector<std::uint32_t> buf(150u * 140u, 0xffffffu);
            CHECK(detail::raster_rect_portable(t, DepthFormat::D24, DepthFunc::Always, false, buf.data(), 150, rx0,
                                               ry0, rx1, ry1, false) == 0);
        }
    }
    CHECK(rejected > 100);
}

TEST_CASE("execute with SIMD on (1, 2, 3, 8 threads, spread schedule) == execute_reference with SIMD off, every bit") {
    raster_test::SplitMix64 rng(31337);
    const int sizes[][2] = {{64, 64}, {250, 170}, {333, 77}};
    for (const auto f : kFormats) {
        for (const auto& sz : sizes) {
            for (int rep = 0; rep < 3; ++rep) {
                raster_test::Scene scene;
                raster_test::SceneOptions o;
                o.width = sz[0];
                o.height = sz[1];
                o.objects = 150;
                raster_test::build_scene(scene, rng, o);
                auto ref = raster::DepthTarget::create(sz[0], sz[1], f).value();
                REQUIRE(ref.clear(scene.clear_depth).ok());
                auto want = raster::execute_reference(ref, scene.batch, raster::ExecuteOptions{1, false});
                REQUIRE(want.ok());
                for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
                    const int threads = run.threads;
                    const bool spread = run.spread;
                    CAPTURE(static_cast<int>(f));
                    CAPTURE(sz[0]);
                    CAPTURE(threads);
                    CAPTURE(spread);
                    const raster::detail::SpreadScheduleScope schedule(spread);
                    auto t = raster::DepthTarget::create(sz[0], sz[1], f).value();
                    REQUIRE(t.clear(scene.clear_depth).ok());
                    auto got = raster::execute(t, scene.batch, raster::ExecuteOptions{threads, true});
                    REQUIRE(got.ok());
                    CHECK(got.value() == want.value());
                    const auto va = ref.values(), vb = t.values();
                    CHECK(std::equal(va.begin(), va.end(), vb.begin(), vb.end()));
                }
            }
        }
    }
}

TEST_CASE("any-samples queries (early exit) agree with samples-passed counts, any thread count") {
    raster_test::SplitMix64 rng(777);
    for (int rep = 0; rep < 6; ++rep) {
        // The same geometry twice: once with every query counting, once with every query any-samples.
        std::vector<std::vector<raster::Float4>> meshes;
        std::vector<std::uint32_t> idx;
        const int size = 200;
        const int objects = 120;
        for (int k = 0; k < objects * 6; ++k) idx.push_back(static_cast<std::uint32_t>(k));
        for (int o = 0; o < objects; ++o) {
            auto& m = meshes.emplace_back();
            const int flavour = static_cast<int>(rng.below(5));
            for (int k = 0; k < 6; ++k) m.push_back(raster_test::random_vertex(rng, size, size, flavour));
        }
        raster::CommandBatch counts(size, size), any(size, size);
        for (int o = 0; o < objects; ++o) {
            const raster::MeshView m{meshes[static_cast<std::size_t>(o)], std::span<const std::uint32_t>(idx.data(), 6)};
            raster::DrawState q;
            q.depth_func = rng.chance(50) ? DepthFunc::GEqual : DepthFunc::Less;
            q.depth_write = false;
            raster::DrawState d;
            d.depth_func = DepthFunc::LEqual;
            for (auto* b : {&counts, &any}) {
                b->begin_query(b == &counts ? raster::QueryKind::SamplesPassed : raster::QueryKind::AnySamplesPassed);
                b->draw(m, q);
                b->draw(m, q);  // a second draw in the same query: skipped once answered
                b->end_query();
                b->draw(m, d);
            }
        }
        auto t0 = raster::DepthTarget::create(size, size, DepthFormat::D24).value();
        auto full = raster::execute_reference(t0, counts, raster::ExecuteOptions{1, false});
        REQUIRE(full.ok());
        std::size_t nonzero = 0;
        for (auto v : full.value()) nonzero += v > 0 ? 1 : 0;
        CHECK(nonzero > 0);
        CHECK(nonzero < full.value().size());
        for (const int threads : {1, 2, 3, 8}) {
            for (const bool simd : {false, true}) {
                CAPTURE(threads);
                CAPTURE(simd);
                auto t = raster::DepthTarget::create(size, size, DepthFormat::D24).value();
                auto got = raster::execute(t, any, raster::ExecuteOptions{threads, simd});
                REQUIRE(got.ok());
                REQUIRE(got.value().size() == full.value().size());
                for (std::size_t q = 0; q < full.value().size(); ++q)
                    CHECK(got.value()[q] == (full.value()[q] > 0 ? 1u : 0u));
                const auto va = t0.values(), vb = t.values();
                CHECK(std::equal(va.begin(), va.end(), vb.begin(), vb.end()));
            }
        }
    }
}

TEST_CASE("one big draw (split front end) and many-tile triangles: any thread count == reference") {
    raster_test::SplitMix64 rng(99991);
    const int size = 300;
    for (const int kind : {0, 1}) {
        // kind 0: 9000 small triangles in one draw (front end split in pieces with threads > 1);
        // kind 1: 300 large triangles in one draw (tile-level trivial reject in binning).
        std::vector<raster::Float4> v;
        std::vector<std::uint32_t> idx;
        const int count = kind == 0 ? 9000 : 300;
        const float r = kind == 0 ? 0.03f : 1.5f;
        for (int t = 0; t < count; ++t) {
            const float cx = rng.uniform(-1.1f, 1.1f), cy = rng.uniform(-1.1f, 1.1f);
            for (int k = 0; k < 3; ++k) {
                idx.push_back(static_cast<std::uint32_t>(v.size()));
                v.push_back({cx + rng.uniform(-r, r), cy + rng.uniform(-r, r), rng.uniform(-1.1f, 1.1f), 1.0f});
            }
        }
        raster::CommandBatch batch(size, size);
        raster::DrawState s;
        s.depth_func = DepthFunc::LEqual;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({v, idx}, s);
        batch.end_query();
        raster::DrawState q;
        q.depth_func = DepthFunc::Equal;
        q.depth_write = false;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({v, idx}, q);
        batch.end_query();
        for (const auto f : kFormats) {
            auto ref = raster::DepthTarget::create(size, size, f).value();
            auto want = raster::execute_reference(ref, batch, raster::ExecuteOptions{1, false});
            REQUIRE(want.ok());
            CHECK(want.value()[0] > 0);
            CHECK(want.value()[1] > 0);
            for (const int threads : {1, 2, 3, 8}) {
                CAPTURE(kind);
                CAPTURE(static_cast<int>(f));
                CAPTURE(threads);
                auto t = raster::DepthTarget::create(size, size, f).value();
                auto got = raster::execute(t, batch, raster::ExecuteOptions{threads, true});
                REQUIRE(got.ok());
                CHECK(got.value() == want.value());
                const auto va = ref.values(), vb = t.values();
                CHECK(std::equal(va.begin(), va.end(), vb.begin(), vb.end()));
            }
        }
    }
}

namespace {

// Covered pixel centres by the definition (pipeline.h, SetupTri): every edge > 0, each evaluated on
// its own in 64-bit integers, pixel by pixel.
bool covered_by_definition(const detail::SetupTri& t, int px, int py) {
    for (int i = 0; i < 3; ++i)
        if (t.c[i] - t.dcdx[i] * 256 * px + t.dcdy[i] * 256 * py <= 0) return false;
    return true;
}

}  // namespace

TEST_CASE("row spans (AVX2 walk, portable division) and shrink_rect == the per-pixel edge test") {
    // Coverage only: DepthFunc::Always with the mask on over a sentinel that no D24 value equals,
    // so the pixels a kernel wrote are exactly the pixels it found covered. Targets up to 16384
    // pixels wide or tall (edge constants near 2^45), thin slivers, long triangles cut to 64 x 64
    // tiles as the executor does, vertices on pixel centres and corners (ties of the fill rule).
    raster_test::SplitMix64 rng(0x5ba11u);
    const int sizes[][2] = {{64, 64}, {203, 131}, {16384, 20}, {20, 16384}, {700, 500}};
    constexpr std::uint32_t kSentinel = 0xffffffffu;
    std::uint64_t rects = 0, covered_total = 0, shrunk = 0, emptied = 0;
    for (const auto& sz : sizes) {
        const int w = sz[0], h = sz[1];
        detail::FrontEndParams p = whole_target(w, h);
        std::vector<std::uint32_t> a(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), kSentinel), b = a,
                                   c16 = a;
        for (int n = 0; n < 1500; ++n) {
            std::vector<detail::SetupTri> tris;
            raster::Float4 v[3];
            const int flavour = static_cast<int>(rng.below(5));
            for (auto& x : v) x = raster_test::random_vertex(rng, w, h, flavour);
            const std::uint32_t shape = rng.below(5);
            if (shape == 0) {  // sliver: the third vertex near the first
                v[2] = v[0];
                v[2].x += rng.uniform(-0.01f, 0.01f) * v[2].w;
                v[2].y += rng.uniform(-0.01f, 0.01f) * v[2].w;
            } else if (shape == 1) {  // long and thin: the third vertex near the middle of the first edge
                v[2] = {(v[0].x + v[1].x) * 0.5f + rng.uniform(-0.02f, 0.02f),
                        (v[0].y + v[1].y) * 0.5f + rng.uniform(-0.02f, 0.02f), v[0].z, 1.0f};
                v[0].w = v[1].w = 1.0f;
            } else if (shape == 2) {
                // Pixel centres on a coarse grid: every edge runs through pixel centres at steps of
                // (dx, dy) / gcd, where the fill rule alone decides (edge value 0 before the bias).
                const int g = 1 << rng.below(4);
                for (auto& x : v) {
                    const float px = static_cast<float>(static_cast<int>(rng.below(static_cast<std::uint32_t>(std::min(w, 512)))) / g * g) + 0.5f;
                    const float py = static_cast<float>(static_cast<int>(rng.below(static_cast<std::uint32_t>(std::min(h, 512)))) / g * g) + 0.5f;
                    x = {px * (2.0f / static_cast<float>(w)) - 1.0f, py * (2.0f / static_cast<float>(h)) - 1.0f,
                         rng.uniform(-0.9f, 0.9f), 1.0f};
                }
            }
            detail::setup_triangle(p, v[0], v[1], v[2], 0, tris);
            for (const auto& t : tris) {
                detail::PixelRect r{t.x0, t.y0, t.x1, t.y1};
                const std::uint32_t cut = rng.below(3);
                if (cut == 0 || static_cast<std::int64_t>(t.x1 - t.x0 + 1) * (t.y1 - t.y0 + 1) > 70000) {
                    // One 64 x 64 tile of the box, as the executor cuts it.
                    const int tx = (t.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - t.x0 + 1)))) / 64;
                    const int ty = (t.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - t.y0 + 1)))) / 64;
                    r = {std::max(t.x0, tx * 64), std::max(t.y0, ty * 64), std::min(t.x1, tx * 64 + 63),
                         std::min(t.y1, ty * 64 + 63)};
                } else if (cut == 1) {  // a random sub-rectangle of the box
                    r.x0 = t.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - t.x0 + 1)));
                    r.x1 = r.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.x1 - r.x0 + 1)));
                    r.y0 = t.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - t.y0 + 1)));
                    r.y1 = r.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(t.y1 - r.y0 + 1)));
                }
                std::uint64_t want = 0;
                for (int py = r.y0; py <= r.y1; ++py)
                    for (int px = r.x0; px <= r.x1; ++px) want += covered_by_definition(t, px, py) ? 1u : 0u;
                const std::uint64_t na = detail::raster_rect_portable(t, DepthFormat::D24, DepthFunc::Always, true,
                                                                      a.data(), w, r.x0, r.y0, r.x1, r.y1, false);
                const std::uint64_t nb = rect_avx2(t, DepthFormat::D24, DepthFunc::Always, true,
                                                                  b.data(), w, r.x0, r.y0, r.x1, r.y1, false);
                const std::uint64_t n16 = rect_avx512(t, DepthFormat::D24, DepthFunc::Always, true,
                                                                     c16.data(), w, r.x0, r.y0, r.x1, r.y1, false);
                CAPTURE(w);
                CAPTURE(n);
                CHECK(na == want);
                CHECK(nb == want);
                CHECK(n16 == want);
                detail::PixelRect s = r;
                const bool live = detail::shrink_rect(t, s);
                if (!live) {
                    ++emptied;
                    CHECK(want == 0);
                } else {
                    CHECK(s.x0 >= r.x0);
                    CHECK(s.y0 >= r.y0);
                    CHECK(s.x1 <= r.x1);
                    CHECK(s.y1 <= r.y1);
                    CHECK(s.x0 <= s.x1);
                    CHECK(s.y0 <= s.y1);
                    if (s.x0 != r.x0 || s.y0 != r.y0 || s.x1 != r.x1 || s.y1 != r.y1) ++shrunk;
                }
                // Pixel by pixel: written exactly where covered (and nothing outside the
                // rectangle), and covered only inside the shrunk rectangle. Restores the sentinel.
                bool same = true, inside = true;
                for (int py = r.y0; py <= r.y1; ++py) {
                    for (int px = r.x0; px <= r.x1; ++px) {
                        const std::size_t k = static_cast<std::size_t>(py) * static_cast<std::size_t>(w) +
                                              static_cast<std::size_t>(px);
                        const bool cov = covered_by_definition(t, px, py);
                        same = same && (a[k] != kSentinel) == cov && (b[k] != kSentinel) == cov && c16[k] == a[k];
                        inside = inside && (!cov || (live && px >= s.x0 && px <= s.x1 && py >= s.y0 && py <= s.y1));
                        a[k] = b[k] = c16[k] = kSentinel;
                    }
                }
                CHECK(same);
                CHECK(inside);
                ++rects;
                covered_total += want;
            }
        }
        CHECK(std::all_of(a.begin(), a.end(), [](std::uint32_t x) { return x == kSentinel; }));
        CHECK(std::all_of(b.begin(), b.end(), [](std::uint32_t x) { return x == kSentinel; }));
        CHECK(std::all_of(c16.begin(), c16.end(), [](std::uint32_t x) { return x == kSentinel; }));
    }
    MESSAGE("rectangles: " << rects << ", covered pixels: " << covered_total << ", shrunk: " << shrunk
                           << ", shrunk to nothing: " << emptied);
    CHECK(rects > 2000);
    CHECK(covered_total > 100000);
    CHECK(shrunk > 100);
    CHECK(emptied > 10);
}

TEST_CASE("kernels and shrink_rect on made-up edge functions that are -1, 0, 1 or 2 at pixel centres") {
    // Not triangles from the front end: any three edge functions (the kernels and shrink_rect must
    // be exact for any), each forced to a value next to the > 0 threshold at a random pixel centre
    // of the rectangle, with small, medium and large slopes (a 64-bit quotient/remainder walk meets
    // its wrap-around exactly there). Coverage as in the test above; every depth function on both
    // kernels too.
    raster_test::SplitMix64 rng(0xed6e5u);
    constexpr int W = 96, H = 80;
    constexpr std::uint32_t kSentinel = 0xffffffffu;
    std::vector<std::uint32_t> a(W * H, kSentinel), b = a, c16 = a;
    std::uint64_t covered_total = 0, partial_rows = 0, emptied = 0;
    const auto slope = [&]() -> std::int64_t {
        switch (rng.below(4)) {
            case 0: return static_cast<std::int64_t>(rng.below(9)) - 4;
            case 1: return static_cast<std::int64_t>(rng.below(601)) - 300;
            case 2: return static_cast<std::int64_t>(rng.below(1u << 21)) - (1 << 20);
            default: return 0;
        }
    };
    for (int n = 0; n < 6000; ++n) {
        detail::PixelRect r;
        r.x0 = static_cast<int>(rng.below(W));
        r.x1 = r.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(std::min(W - r.x0, rng.chance(50) ? 16 : 96))));
        r.y0 = static_cast<int>(rng.below(H));
        r.y1 = r.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(H - r.y0)));
        detail::SetupTri t{};
        for (int i = 0; i < 3; ++i) {
            t.dcdx[i] = slope();
            t.dcdy[i] = slope();
            const int px = r.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(r.x1 - r.x0 + 1)));
            const int py = r.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(r.y1 - r.y0 + 1)));
            const std::int64_t value = static_cast<std::int64_t>(rng.below(4)) - 1;
            t.c[i] = value + t.dcdx[i] * 256 * px - t.dcdy[i] * 256 * py;
        }
        t.x0 = r.x0;
        t.y0 = r.y0;
        t.x1 = r.x1;
        t.y1 = r.y1;
        t.z0 = rng.uniform(-0.2f, 1.2f);
        t.dzdx = rng.uniform(-0.01f, 0.01f);
        t.dzdy = rng.uniform(-0.01f, 0.01f);
        std::uint64_t want = 0;
        for (int py = r.y0; py <= r.y1; ++py) {
            int row = 0;
            for (int px = r.x0; px <= r.x1; ++px) row += covered_by_definition(t, px, py) ? 1 : 0;
            want += static_cast<std::uint64_t>(row);
            partial_rows += row > 0 && row <= r.x1 - r.x0 ? 1u : 0u;
        }
        CAPTURE(n);
        CHECK(detail::raster_rect_portable(t, DepthFormat::D24, DepthFunc::Always, true, a.data(), W, r.x0, r.y0, r.x1,
                                           r.y1, false) == want);
        CHECK(rect_avx2(t, DepthFormat::D24, DepthFunc::Always, true, b.data(), W, r.x0, r.y0, r.x1,
                                       r.y1, false) == want);
        CHECK(rect_avx512(t, DepthFormat::D24, DepthFunc::Always, true, c16.data(), W, r.x0, r.y0,
                                         r.x1, r.y1, false) == want);
        detail::PixelRect s = r;
        const bool live = detail::shrink_rect(t, s);
        emptied += live ? 0u : 1u;
        bool same = true, inside = true;
        for (int py = r.y0; py <= r.y1; ++py) {
            for (int px = r.x0; px <= r.x1; ++px) {
                const std::size_t k = static_cast<std::size_t>(py * W + px);
                const bool cov = covered_by_definition(t, px, py);
                same = same && (a[k] != kSentinel) == cov && (b[k] != kSentinel) == cov && c16[k] == a[k];
                inside = inside && (!cov || (live && px >= s.x0 && px <= s.x1 && py >= s.y0 && py <= s.y1));
                a[k] = b[k] = c16[k] = kSentinel;
            }
        }
        CHECK(same);
        CHECK(inside);
        if (live) {
            CHECK(s.x0 >= r.x0);
            CHECK(s.y0 >= r.y0);
            CHECK(s.x1 <= r.x1);
            CHECK(s.y1 <= r.y1);
        }
        covered_total += want;
        // Depth: both kernels, a random format, function and mask, over random stored values.
        const DepthFormat f = kFormats[rng.below(3)];
        const DepthFunc func = kFuncs[rng.below(8)];
        const bool write = rng.chance(50);
        std::vector<std::uint32_t> c(W * H), d, e;
        for (auto& x : c) x = random_stored(rng, f, std::clamp(t.z0, 0.0f, 1.0f));
        d = c;
        e = c;
        const std::uint64_t nc = detail::raster_rect_portable(t, f, func, write, c.data(), W, r.x0, r.y0, r.x1, r.y1, false);
        CHECK(nc == rect_avx2(t, f, func, write, d.data(), W, r.x0, r.y0, r.x1, r.y1, false));
        CHECK(nc == rect_avx512(t, f, func, write, e.data(), W, r.x0, r.y0, r.x1, r.y1, false));
        CHECK(c == d);
        CHECK(c == e);
    }
    CHECK(std::all_of(a.begin(), a.end(), [](std::uint32_t x) { return x == kSentinel; }));
    CHECK(std::all_of(b.begin(), b.end(), [](std::uint32_t x) { return x == kSentinel; }));
    MESSAGE("covered pixels: " << covered_total << ", rows partly covered: " << partial_rows
                               << ", rectangles shrunk to nothing: " << emptied);
    CHECK(covered_total > 100000);
    CHECK(partial_rows > 10000);
    CHECK(emptied > 100);
}

TEST_CASE(
    "kernels on depth planes that meet 0 and 1 inside wide rectangles: the skipped clamp changes no bit") {
    // The AVX2 kernel's wide path leaves out the clamp to [0, 1] on a D16 / D24 rectangle whose
    // unclamped depths are all in [0, 1] by its two bounding corners (kernel_avx2.cpp, clamp_free).
    // Planes here put a corner's depth exactly at 0, -0, the smallest floats either side of 0, 1 and
    // the floats either side of 1, or a little beyond, with slopes of either sign, zero, -0, tiny and
    // non-finite, so that the rule's edge cases decide; the result must be the portable kernel's
    // (which always clamps), count and every stored bit, for every format, function and mask.
    raster_test::SplitMix64 rng(0xc1a3bu);
    constexpr int W = 160, H = 48;
    const float kEdges[] = {0.0f,
                            -0.0f,
                            std::nextafter(0.0f, 1.0f),
                            std::nextafter(0.0f, -1.0f),
                            1.0f,
                            std::nextafter(1.0f, 2.0f),
                            std::nextafter(1.0f, 0.0f),
                            -1e-7f,
                            1e-7f,
                            1.0f - 1e-7f,
                            1.0f + 1e-7f};
    const float kInf = std::numeric_limits<float>::infinity();
    const auto slope = [&]() -> float {
        switch (rng.below(8)) {
            case 0:
                return 0.0f;
            case 1:
                return -0.0f;
            case 2:
                return rng.uniform(-1e-6f, 1e-6f);
            case 3:
                return rng.chance(50) ? kInf : std::numeric_limits<float>::quiet_NaN();
            default:
                return rng.uniform(-0.02f, 0.02f);
        }
    };
    std::uint64_t below_zero = 0, above_one = 0, inside = 0, checked = 0;
    for (int n = 0; n < 4000; ++n) {
        detail::PixelRect r;
        r.x0 = static_cast<int>(rng.below(W - 24));
        r.x1 = r.x0 + 16 +
               static_cast<int>(rng.below(static_cast<std::uint32_t>(W - r.x0 - 16)));  // the wide path
        r.y0 = static_cast<int>(rng.below(H));
        r.y1 = r.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(H - r.y0)));
        detail::SetupTri t{};
        // Two edges cover everything; the third is everything or a random line through the rectangle.
        for (int i = 0; i < 3; ++i) t.c[i] = 1;
        if (rng.chance(50)) {
            t.dcdx[2] = static_cast<std::int64_t>(rng.below(201)) - 100;
            t.dcdy[2] = static_cast<std::int64_t>(rng.below(201)) - 100;
            const int px = r.x0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(r.x1 - r.x0 + 1)));
            const int py = r.y0 + static_cast<int>(rng.below(static_cast<std::uint32_t>(r.y1 - r.y0 + 1)));
            t.c[2] = t.dcdx[2] * 256 * px - t.dcdy[2] * 256 * py;
        }
        t.x0 = r.x0;
        t.y0 = r.y0;
        t.x1 = r.x1;
        t.y1 = r.y1;
        t.dzdx = slope();
        t.dzdy = slope();
        // z0 so that a random corner's depth is (about) a value at the clamp's edges.
        const int cx = rng.chance(50) ? r.x0 : r.x1, cy = rng.chance(50) ? r.y0 : r.y1;
        const float target = kEdges[rng.below(static_cast<std::uint32_t>(std::size(kEdges)))];
        t.z0 = std::isfinite(t.dzdx) && std::isfinite(t.dzdy)
                   ? target - (t.dzdx * static_cast<float>(cx) + t.dzdy * static_cast<float>(cy))
                   : target;
        if (rng.chance(20)) t.z0 = target;  // exact at the origin-side corner when the slopes are 0
        for (int py = r.y0; py <= r.y1; ++py) {
            for (int px = r.x0; px <= r.x1; ++px) {
                const float z =
                    std::fma(t.dzdy, static_cast<float>(py), std::fma(t.dzdx, static_cast<float>(px), t.z0));
                below_zero += z < 0.0f || std::signbit(z) ? 1u : 0u;
                above_one += z > 1.0f ? 1u : 0u;
                inside += z >= 0.0f && z <= 1.0f ? 1u : 0u;
            }
        }
        const DepthFormat f = kFormats[rng.below(3)];
        const DepthFunc func = kFuncs[rng.below(8)];
        const bool write = rng.chance(50);
        std::vector<std::uint32_t> c(W * H), d, e;
        const float near_z = rng.chance(50) ? 0.0f : 1.0f;
        for (auto& x : c)
            x = rng.chance(30) ? (near_z == 0.0f ? 0u : 0xffffffu) : random_stored(rng, f, near_z);
        d = c;
        e = c;
        CAPTURE(n);
        const std::uint64_t nc =
            detail::raster_rect_portable(t, f, func, write, c.data(), W, r.x0, r.y0, r.x1, r.y1, false);
        CHECK(nc == rect_avx2(t, f, func, write, d.data(), W, r.x0, r.y0, r.x1, r.y1, false));
        CHECK(nc == rect_avx512(t, f, func, write, e.data(), W, r.x0, r.y0, r.x1, r.y1, false));
        CHECK(c == d);
        CHECK(c == e);
        ++checked;
    }
    MESSAGE("pixels with unclamped depth < 0 or -0: " << below_zero << ", > 1: " << above_one
                                                      << ", in [0, 1]: " << inside);
    CHECK(checked == 4000);
    CHECK(below_zero > 10000);
    CHECK(above_one > 10000);
    CHECK(inside > 100000);
}

// SetupTri::fits32 lets the AVX2 narrow path skip its per-rectangle 32-bit bound: when setup sets
// it, every edge value at a pixel centre of [x0, x1 + 7] x [y0, y1] must fit in 32 bits. Edges are
// linear, so the four corners carry the extremes. Triangles of every size (targets up to 16384 px,
// a vertex far outside, so clipping and the flag's false side both occur).
TEST_CASE("SetupTri::fits32 holds: every edge value over the box widened by 7 columns fits in 32 bits") {
    raster_test::SplitMix64 rng(0xf175u);
    std::uint64_t flagged = 0, unflagged = 0;
    for (const int side : {64, 1024, 16384}) {
        detail::FrontEndParams p = whole_target(side, side);
        for (int n = 0; n < 3000; ++n) {
            raster::Float4 v[3];
            const float spread = rng.chance(50) ? rng.uniform(0.0f, 0.05f) : rng.uniform(0.0f, 3.0f);
            const float cx = rng.uniform(-1.0f, 1.0f), cy = rng.uniform(-1.0f, 1.0f);
            for (auto& x : v)
                x = {cx + rng.uniform(-spread, spread), cy + rng.uniform(-spread, spread), rng.uniform(-0.9f, 0.9f), 1.0f};
            std::vector<detail::SetupTri> tris;
            detail::setup_triangle(p, v[0], v[1], v[2], 0, tris);
            for (const auto& t : tris) {
                if (!t.fits32) {
                    ++unflagged;
                    continue;
                }
                ++flagged;
                for (int i = 0; i < 3; ++i)
                    for (const int px : {t.x0, t.x1 + 7})
                        for (const int py : {t.y0, t.y1}) {
                            const std::int64_t e = t.c[i] - t.dcdx[i] * 256 * px + t.dcdy[i] * 256 * py;
                            CAPTURE(n);
                            CHECK(e < (std::int64_t{1} << 31));
                            CHECK(e >= -(std::int64_t{1} << 31));
                        }
            }
        }
    }
    // Both sides of the flag were exercised.
    CHECK(flagged > 1000);
    CHECK(unflagged > 100);
}

// Session 7's raster_gl_exact fuzz finding (fuzz/corpus/raster_gl_exact/avx2_vs_scalar_*): clipping
// can leave a window position outside the 16.8 fixed-point range, and setup's 64-bit edge functions
// then overflowed (undefined behaviour; the AVX2 and portable kernels drew different garbage). Setup
// drops such triangles (triangle_setup.cpp); llvmpipe draws what its 32-bit integer indefinite makes
// (docs/raster-known-differences.md). The two triangles are the findings' own, decoded.
TEST_CASE("window positions out of the fixed-point range: setup drops the triangle, every kernel and path agree") {
    // (1) A clipped vertex at (0, 0, 0, 0): the clipper's interpolation between a vertex with
    // x = y = z = w < 0 and one with x = y = z = w > 0 rounds to all zeros, so 1/w is infinite.
    const float a = 0x1.3851ecp+0f, b = 0x1.451eb8p+0f;
    const raster::Float4 w_zero[3] = {{-a, -a, -a, -a}, {-a, -a, -a, b}, {b, b, b, b}};
    // (2) x = -2^103 and 2^75 with w = 1: clipping to x >= -w rounds the new vertex's x at 2^79 (in
    // clip units), far outside any target.
    const raster::Float4 huge_x[3] = {{-0x1.6366cap+103f, -0x1.bp-2f, -0x1.147ae2p-2f, 1.0f},
                                      {-0x1.147ae2p-2f, -0x1.147ae2p-2f, -1.0f, 1.0f},
                                      {0x1.cb3534p+75f, -1.0f, -1.0f, 1.0f}};
    // A plain triangle across the target, drawn in the same batch.
    const raster::Float4 plain[3] = {{-0.9f, -0.9f, 0.2f, 1.0f}, {0.9f, -0.8f, -0.1f, 1.0f}, {0.1f, 0.9f, 0.4f, 1.0f}};
    const int w = 94, h = 96;

    detail::FrontEndParams p = whole_target(w, h);
    p.rules = raster::RasterRules::GlLlvmpipe;  // (the Vulkan rules clip these at z >= 0 instead)
    // The first clips to a fan of two: one in range (kept) and one with the NaN vertex (dropped);
    // the second's fan is out of range as a whole; the plain one is kept.
    std::vector<detail::SetupTri> tris;
    detail::setup_triangle(p, w_zero[0], w_zero[1], w_zero[2], 0, tris);
    CHECK(tris.size() == 1);
    detail::setup_triangle(p, huge_x[0], huge_x[1], huge_x[2], 0, tris);
    CHECK(tris.size() == 1);
    detail::setup_triangle(p, plain[0], plain[1], plain[2], 0, tris);
    CHECK(tris.size() == 2);
    for (const auto& t : tris)  // snapped |x|, |y| < 2^30: edge steps < 2^31, constants < 2^62
        for (int i = 0; i < 3; ++i) {
            CHECK(std::abs(t.dcdx[i]) < (std::int64_t{1} << 31));
            CHECK(std::abs(t.dcdy[i]) < (std::int64_t{1} << 31));
            CHECK(std::abs(t.c[i]) < (std::int64_t{1} << 62));
        }

    std::vector<raster::Float4> v;
    for (const auto* tri : {w_zero, huge_x, plain}) v.insert(v.end(), tri, tri + 3);
    const std::vector<std::uint32_t> bad_idx = {0, 1, 2, 3, 4, 5}, plain_idx = {6, 7, 8};
    raster::DrawState s;
    s.depth_func = DepthFunc::Always;
    raster::CommandBatch batch(w, h);
    batch.begin_query(raster::QueryKind::SamplesPassed);
    batch.draw(raster::MeshView{v, bad_idx}, s);
    batch.end_query();
    batch.begin_query(raster::QueryKind::SamplesPassed);
    batch.draw(raster::MeshView{v, plain_idx}, s);
    batch.end_query();
    for (const auto f : kFormats) {
        CAPTURE(static_cast<int>(f));
        auto ref = raster::DepthTarget::create(w, h, f).value();
        REQUIRE(ref.clear(0.5).ok());
        const auto want = raster::execute_reference(ref, batch, raster::ExecuteOptions{1, false});
        REQUIRE(want.ok());
        REQUIRE(want.value().size() == 2);
        CHECK(want.value()[1] > 1000);
        for (const int threads : {0, 1, 2, 3}) {  // 0: execute_reference with the dispatched kernel
            CAPTURE(threads);
            auto t = raster::DepthTarget::create(w, h, f).value();
            REQUIRE(t.clear(0.5).ok());
            const auto got = threads == 0 ? raster::execute_reference(t, batch, raster::ExecuteOptions{1, true})
                                          : raster::execute(t, batch, raster::ExecuteOptions{threads, true});
            REQUIRE(got.ok());
            CHECK(got.value() == want.value());
            const auto va = ref.values(), vb = t.values();
            CHECK(std::equal(va.begin(), va.end(), vb.begin(), vb.end()));
        }
    }
}

// The tiled executor sets up a triangle list once for draws of the same spans that differ only in
// face culling (R-CULLIDE's offset solids: the query culls front faces, the write back faces) and
// culls at binning (execute.cpp, share_setup). Random solids-like meshes (some crossing the near
// plane, so clipped fans cull triangle by triangle), each drawn with every culling, both front-face
// conventions and sub-spans, interleaved with queries: every bit equals the reference, which sets up
// each draw with its own culling.
TEST_CASE("draws that share geometry but not culling: tiled executor == reference, every bit") {
    raster_test::SplitMix64 rng(0xc011u);
    const int w = 150, h = 130;
    std::uint64_t culled_differently = 0;
    for (int rep = 0; rep < 12; ++rep) {
        std::vector<raster::Float4> v;
        std::vector<std::uint32_t> idx;
        const int n_tris = 1 + static_cast<int>(rng.below(60));
        for (int t = 0; t < n_tris; ++t) {
            const float cx = rng.uniform(-1.2f, 1.2f), cy = rng.uniform(-1.2f, 1.2f), r = rng.uniform(0.01f, 0.6f);
            for (int k = 0; k < 3; ++k) {
                idx.push_back(static_cast<std::uint32_t>(v.size()));
                const float z = rng.chance(10) ? rng.uniform(-1.6f, 1.6f) : rng.uniform(-0.9f, 0.9f);
                v.push_back({cx + rng.uniform(-r, r), cy + rng.uniform(-r, r), z, 1.0f});
            }
        }
        const std::span<const std::uint32_t> all(idx);
        const std::span<const std::uint32_t> half = all.first(idx.size() / 6 * 3);
        raster::CommandBatch batch(w, h);
        for (int k = 0; k < 10; ++k) {
            raster::DrawState s;
            const auto span = rng.chance(30) ? half : all;
            s.cull_face = static_cast<raster::CullFace>(rng.below(3));
            s.front_face = rng.chance(20) ? raster::FrontFace::CW : raster::FrontFace::CCW;
            s.depth_write = rng.chance(50);
            s.depth_func = s.depth_write ? DepthFunc::LEqual : DepthFunc::GEqual;
            if (s.cull_face != raster::CullFace::None) ++culled_differently;
            const bool query = !s.depth_write || rng.chance(30);
            if (query)
                batch.begin_query(rng.chance(50) ? raster::QueryKind::AnySamplesPassed : raster::QueryKind::SamplesPassed);
            batch.draw(raster::MeshView{v, span}, s);
            if (query) batch.end_query();
        }
        for (const auto f : kFormats) {
            auto ref = raster::DepthTarget::create(w, h, f).value();
            REQUIRE(ref.clear(0.75).ok());
            const auto want = raster::execute_reference(ref, batch, raster::ExecuteOptions{1, false});
            REQUIRE(want.ok());
            for (const int threads : {1, 2, 3}) {
                for (const bool simd : {false, true}) {
                    CAPTURE(rep);
                    CAPTURE(static_cast<int>(f));
                    CAPTURE(threads);
                    CAPTURE(simd);
                    auto t = raster::DepthTarget::create(w, h, f).value();
                    REQUIRE(t.clear(0.75).ok());
                    const auto got = raster::execute(t, batch, raster::ExecuteOptions{threads, simd});
                    REQUIRE(got.ok());
                    CHECK(got.value() == want.value());
                    const auto va = ref.values(), vb = t.values();
                    CHECK(std::equal(va.begin(), va.end(), vb.begin(), vb.end()));
                }
            }
        }
    }
    CHECK(culled_differently > 50);
}

// raster::execute_sequence: the front end is shared by every batch of the sequence (share_setup
// over all their draws). Random scenes; each sequence holds batches that draw the same spans (some
// with other culling, depth state or order, as CULLIDE's two passes do) and a clear between them;
// results and every bit equal execute() per batch with the same clear, for 1, 2 and 3 threads.
TEST_CASE("execute_sequence == execute per batch with the clear between, and an invalid batch runs nothing") {
    raster_test::SplitMix64 rng(0x5e9u);
    const int w = 140, h = 100;
    for (int rep = 0; rep < 8; ++rep) {
        std::vector<raster::Float4> v;
        std::vector<std::uint32_t> idx;
        for (int t = 0; t < 40; ++t) {
            const float cx = static_cast<float>(rng.uniform(-1.1, 1.1)), cy = static_cast<float>(rng.uniform(-1.1, 1.1));
            const float r = static_cast<float>(rng.uniform(0.02, 0.5));
            for (int k = 0; k < 3; ++k) {
                idx.push_back(static_cast<std::uint32_t>(v.size()));
                v.push_back({cx + static_cast<float>(rng.uniform(-r, r)), cy + static_cast<float>(rng.uniform(-r, r)),
                             static_cast<float>(rng.uniform(-1.3, 1.3)), 1.0f});
            }
        }
        // Items: runs of 6 indices (two triangles) of the one index list.
        std::vector<std::span<const std::uint32_t>> items;
        for (std::size_t k = 0; k + 6 <= idx.size(); k += 6) items.push_back(std::span<const std::uint32_t>(idx).subspan(k, 6));
        std::vector<raster::CommandBatch> batches;
        for (int b = 0; b < 3; ++b) {
            raster::CommandBatch batch(w, h);
            const bool backward = b == 1;
            for (std::size_t n = 0; n < items.size(); ++n) {
                const auto& item = items[backward ? items.size() - 1 - n : n];
                raster::DrawState q;
                q.depth_func = DepthFunc::GEqual;
                q.depth_write = false;
                q.cull_face = b == 2 ? raster::CullFace::Front : raster::CullFace::None;
                batch.begin_query(raster::QueryKind::AnySamplesPassed);
                batch.draw(raster::MeshView{v, item}, q);
                batch.end_query();
                raster::DrawState wr;
                wr.cull_face = b == 2 ? raster::CullFace::Back : raster::CullFace::None;
                batch.draw(raster::MeshView{v, item}, wr);
            }
            batches.push_back(std::move(batch));
        }
        std::vector<const raster::CommandBatch*> ptrs;
        for (const auto& b : batches) ptrs.push_back(&b);
        for (const auto f : kFormats) {
            // Want: execute per batch, the target cleared to 1 before each.
            auto want_t = raster::DepthTarget::create(w, h, f).value();
            std::vector<raster::QueryResults> want;
            std::vector<std::vector<std::uint32_t>> want_depth;
            for (const auto& b : batches) {
                REQUIRE(want_t.clear(1.0).ok());
                auto r = raster::execute(want_t, b, raster::ExecuteOptions{1, false});
                REQUIRE(r.ok());
                want.push_back(r.value());
                want_depth.emplace_back(want_t.values().begin(), want_t.values().end());
            }
            for (const int threads : {1, 2, 3}) {
                CAPTURE(rep);
                CAPTURE(static_cast<int>(f));
                CAPTURE(threads);
                auto t = raster::DepthTarget::create(w, h, f).value();
                std::vector<std::vector<std::uint32_t>> depth_before_clear;
                std::size_t calls = 0;
                const auto got = raster::execute_sequence(t, ptrs, raster::ExecuteOptions{threads, true}, [&](std::size_t k) {
                    CHECK(k == calls + 1);
                    ++calls;
                    depth_before_clear.emplace_back(t.values().begin(), t.values().end());
                    REQUIRE(t.clear(1.0).ok());
                });
                REQUIRE(got.ok());
                CHECK(calls == 2);
                CHECK(got.value() == want);
                depth_before_clear.emplace_back(t.values().begin(), t.values().end());
                CHECK(depth_before_clear == want_depth);
            }
        }
    }
    // An invalid later batch: nothing runs, the error names it.
    std::vector<raster::Float4> v = {{-0.5f, -0.5f, 0.0f, 1.0f}, {0.5f, -0.5f, 0.0f, 1.0f}, {0.0f, 0.5f, 0.0f, 1.0f}};
    const std::vector<std::uint32_t> good = {0, 1, 2}, bad = {0, 1, 5};
    raster::CommandBatch a(32, 32), b(32, 32);
    a.draw(raster::MeshView{v, good}, {});
    b.draw(raster::MeshView{v, bad}, {});
    auto t = raster::DepthTarget::create(32, 32, DepthFormat::D24).value();
    const std::vector<std::uint32_t> before(t.values().begin(), t.values().end());
    const raster::CommandBatch* const seq[2] = {&a, &b};
    const auto r = raster::execute_sequence(t, seq, {}, [](std::size_t) { FAIL("between() must not run"); });
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("batch 1: command 0: index 5") != std::string::npos);
    CHECK(std::equal(before.begin(), before.end(), t.values().begin(), t.values().end()));
    // A nested call from between() is refused (it would reuse the running sequence's buffers),
    // and the outer sequence still gives execute()'s answers.
    const raster::CommandBatch* const twice[2] = {&a, &a};
    auto other = raster::DepthTarget::create(32, 32, DepthFormat::D24).value();
    bool refused = false;
    const auto outer = raster::execute_sequence(t, twice, {}, [&](std::size_t) {
        const auto inner = raster::execute(other, a);
        refused = !inner.ok() && inner.error().message.find("between() callback") != std::string::npos;
    });
    REQUIRE(outer.ok());
    CHECK(refused);
    auto want_t = raster::DepthTarget::create(32, 32, DepthFormat::D24).value();
    const auto want = raster::execute(want_t, a);
    REQUIRE(want.ok());
    REQUIRE(outer.value().size() == 2);
    CHECK(outer.value()[1] == want.value());
}

// The sequence with queries_only on 1, 2 and 3 threads against `want`, full execution's results
// (its final target `want_t`): `calls` calls on one fresh target each, with clear_depth = 1 when
// `cleared` and then written_blocks kept across the calls when `tiles`, as the emulator device runs
// view after view. Counts the runs and those whose final depth differs from full execution's.
namespace {
void check_queries_only(const std::vector<const raster::CommandBatch*>& ptrs, DepthFormat f, bool cleared, bool tiles,
                        int calls, const std::vector<raster::QueryResults>& want, const raster::DepthTarget& want_t,
                        int& runs, int& differs) {
    for (const int threads : {1, 2, 3}) {
        CAPTURE(threads);
        auto t = raster::DepthTarget::create(want_t.width(), want_t.height(), f).value();
        std::vector<std::uint64_t> written;
        raster::ExecuteOptions o{threads, true};
        o.queries_only = true;
        if (cleared) o.clear_depth = 1.0;
        if (tiles) o.written_blocks = &written;
        for (int call = 0; call < calls; ++call) {
            const auto got = raster::execute_sequence(t, ptrs, o);
            REQUIRE(got.ok());
            CHECK(got.value() == want);
        }
        ++runs;
        if (!std::equal(t.values().begin(), t.values().end(), want_t.values().begin(), want_t.values().end())) ++differs;
    }
}
}  // namespace

// ExecuteOptions::queries_only (execute.cpp, observed_draws): draws that no query can observe are
// skipped, with the same query results. Random sequences of CULLIDE-like passes over clusters of
// items in separate places (so that most draws are unobserved) and some overlapping, plus draws of
// every kind the rules must keep: queries with the mask on, NEVER / LESS / GREATER / EQUAL /
// ALWAYS queries, samples-passed counts, items at the far plane (z = 1: GEQUAL passes on the clear
// value) and beyond it (clipped there), w != 1, outside the target, viewports, exact-bounds
// double input, Vulkan's rules; with clear_depth = 1 (both rules) and without (writes only), with
// written_blocks kept across calls as the emulator device keeps them; 1, 2 and 3 threads.
TEST_CASE("queries_only skips unobserved draws with the same query results") {
    raster_test::SplitMix64 rng(0x9a11u);
    int differs = 0, runs = 0;
    for (int rep = 0; rep < 24; ++rep) {
        const int w = rep % 3 == 0 ? 64 : rep % 3 == 1 ? 130 : 300, h = rep % 2 == 0 ? 64 : 90;
        const raster::RasterRules rules = rep % 4 == 3 ? raster::RasterRules::Vulkan : raster::RasterRules::GlLlvmpipe;
        std::vector<raster::Float4> v;
        std::vector<raster::Double4> vd;
        std::vector<std::uint32_t> idx;
        std::vector<std::size_t> item_start;  // items: 2 triangles each
        const int clusters = 3 + static_cast<int>(rng.below(6));
        for (int c = 0; c < clusters; ++c) {
            const float cx = rng.uniform(-0.9f, 0.9f), cy = rng.uniform(-0.9f, 0.9f), cz = rng.uniform(-0.8f, 0.8f);
            const int items = 1 + static_cast<int>(rng.below(12));
            for (int it = 0; it < items; ++it) {
                item_start.push_back(idx.size());
                const int kind = static_cast<int>(rng.below(10));
                for (int t = 0; t < 2; ++t) {
                    for (int k = 0; k < 3; ++k) {
                        raster::Float4 p{cx + rng.uniform(-0.12f, 0.12f), cy + rng.uniform(-0.12f, 0.12f),
                                         cz + rng.uniform(-0.1f, 0.1f), 1.0f};
                        if (kind == 0) p.z = 1.0f;                      // at the far plane
                        if (kind == 1 && k == 0) p.z = 1.3f;            // beyond it: clipped at z = 1
                        if (kind == 2) p.w = 1.5f, p.x *= 1.5f, p.y *= 1.5f;  // w != 1
                        if (kind == 3) p.x += 2.5f;                     // outside the target
                        if (kind == 4) p.x = cx + rng.uniform(-1.0f, 1.0f);  // wide
                        idx.push_back(static_cast<std::uint32_t>(v.size()));
                        v.push_back(p);
                        vd.push_back({p.x, p.y, p.z, p.w});
                    }
                }
            }
        }
        for (auto& d : vd) d.w = 1.0;  // (exact bounds take w = 1 only)
        const std::size_t n_items = item_start.size();
        const auto item = [&](std::size_t i) { return std::span<const std::uint32_t>(idx).subspan(item_start[i], 6); };
        std::vector<raster::CommandBatch> batches;
        for (int b = 0; b < 2; ++b) {  // the two passes: forward, backward
            raster::CommandBatch batch(w, h, rules);
            for (std::size_t n = 0; n < n_items; ++n) {
                const std::size_t i = b == 0 ? n : n_items - 1 - n;
                raster::DrawState q;
                q.depth_func = DepthFunc::GEqual;
                q.depth_write = false;
                const std::uint32_t extra = rng.below(20);
                if (extra == 0) q.depth_func = DepthFunc::Never;
                if (extra == 1) q.depth_func = DepthFunc::Less;
                if (extra == 2) q.depth_func = DepthFunc::Greater;
                if (extra == 3) q.depth_func = DepthFunc::Equal;
                if (extra == 4) q.depth_func = DepthFunc::Always;
                if (extra == 5) q.depth_write = true;  // a query that writes
                if (extra == 6) q.viewport = raster::Viewport{w / 4, h / 4, w / 2, h / 2};
                batch.begin_query(extra == 7 ? raster::QueryKind::SamplesPassed : raster::QueryKind::AnySamplesPassed);
                if (extra == 8) {
                    raster::DrawState e = q;
                    e.mode = raster::RasterMode::ExactBounds;
                    batch.draw(raster::MeshViewD{vd, item(i)}, e);
                } else {
                    batch.draw(raster::MeshView{v, item(i)}, q);
                }
                batch.end_query();
                raster::DrawState wr;
                wr.depth_func = extra == 9 ? DepthFunc::Always : DepthFunc::LEqual;
                if (extra != 10) batch.draw(raster::MeshView{v, item(i)}, wr);  // (10: never written)
                if (extra == 11) {  // a draw that neither writes nor counts
                    raster::DrawState none = q;
                    none.depth_write = false;
                    batch.draw(raster::MeshView{v, item(i)}, none);
                }
            }
            batches.push_back(std::move(batch));
        }
        std::vector<const raster::CommandBatch*> ptrs;
        for (const auto& b : batches) ptrs.push_back(&b);
        for (const auto f : kFormats) {
            for (const bool cleared : {true, false}) {
                auto want_t = raster::DepthTarget::create(w, h, f).value();
                raster::ExecuteOptions full{1, true};
                if (cleared) full.clear_depth = 1.0;
                const auto want = raster::execute_sequence(want_t, ptrs, full);
                REQUIRE(want.ok());
                CAPTURE(rep);
                CAPTURE(static_cast<int>(f));
                CAPTURE(cleared);
                // Cleared: twice on one target with written_blocks (the target's content after a call
                // is unspecified, so without clear_depth a second call would start from it).
                check_queries_only(ptrs, f, cleared, cleared, cleared ? 2 : 1, want.value(), want_t, runs, differs);
            }
        }
    }
    // Draws were skipped (the final depth is not full execution's) in most runs.
    CHECK(differs > runs / 2);
}

TEST_CASE("queries_only: the pieces of a big draw far from every other draw are skipped") {
    // A cloth-like grid of 2 x 60 x 40 = 4,800 triangles (more than 3 x kObservePiece: observed in
    // pieces of 1,024) drawn whole, as CULLIDE's object stage draws an object, with a few small
    // objects over parts of it; both passes (query then write per object, forward then backward).
    // The results equal full execution for every format and thread count, and the target's final
    // content differs (pieces were skipped).
    raster_test::SplitMix64 rng(0xc107u);
    int differs = 0, runs = 0;
    for (int rep = 0; rep < 6; ++rep) {
        std::vector<raster::Float4> v;
        std::vector<std::uint32_t> grid, small;
        const float gz = rng.uniform(-0.5f, 0.5f);
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 60; ++x) {
                const float x0 = -0.95f + 1.9f * static_cast<float>(x) / 60.0f, x1 = x0 + 1.9f / 60.0f;
                const float y0 = -0.95f + 1.9f * static_cast<float>(y) / 40.0f, y1 = y0 + 1.9f / 40.0f;
                const auto b = static_cast<std::uint32_t>(v.size());
                v.push_back({x0, y0, gz + rng.uniform(-0.05f, 0.05f), 1.0f});
                v.push_back({x1, y0, gz + rng.uniform(-0.05f, 0.05f), 1.0f});
                v.push_back({x1, y1, gz + rng.uniform(-0.05f, 0.05f), 1.0f});
                v.push_back({x0, y1, gz + rng.uniform(-0.05f, 0.05f), 1.0f});
                grid.insert(grid.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
            }
        std::vector<std::span<const std::uint32_t>> objects = {grid};
        const int n_small = 1 + static_cast<int>(rng.below(3));
        small.reserve(static_cast<std::size_t>(n_small) * 6);
        for (int o = 0; o < n_small; ++o) {
            const float cx = rng.uniform(-0.8f, 0.8f), cy = rng.uniform(-0.8f, 0.8f), r = rng.uniform(0.05f, 0.2f);
            const auto b = static_cast<std::uint32_t>(v.size());
            v.push_back({cx - r, cy - r, gz - 0.3f, 1.0f});
            v.push_back({cx + r, cy - r, gz + 0.3f, 1.0f});
            v.push_back({cx, cy + r, gz, 1.0f});
            v.push_back({cx - r, cy + r, gz + 0.2f, 1.0f});
            small.insert(small.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
        }
        for (int o = 0; o < n_small; ++o) objects.push_back(std::span<const std::uint32_t>(small).subspan(static_cast<std::size_t>(o) * 6, 6));
        std::vector<raster::CommandBatch> batches;
        for (int b = 0; b < 2; ++b) {
            raster::CommandBatch batch(256, 160);
            for (std::size_t n = 0; n < objects.size(); ++n) {
                const auto& obj = objects[b == 0 ? n : objects.size() - 1 - n];
                raster::DrawState q;
                q.depth_func = DepthFunc::GEqual;
                q.depth_write = false;
                batch.begin_query(rep % 2 == 0 ? raster::QueryKind::SamplesPassed : raster::QueryKind::AnySamplesPassed);
                batch.draw(raster::MeshView{v, obj}, q);
                batch.end_query();
                batch.draw(raster::MeshView{v, obj}, raster::DrawState{});
            }
            batches.push_back(std::move(batch));
        }
        std::vector<const raster::CommandBatch*> ptrs;
        for (const auto& b : batches) ptrs.push_back(&b);
        for (const auto f : kFormats) {
            auto want_t = raster::DepthTarget::create(256, 160, f).value();
            raster::ExecuteOptions full{1, true};
            full.clear_depth = 1.0;
            const auto want = raster::execute_sequence(want_t, ptrs, full);
            REQUIRE(want.ok());
            CAPTURE(rep);
            check_queries_only(ptrs, f, true, false, 1, want.value(), want_t, runs, differs);
        }
    }
    CHECK(differs == runs);
}

TEST_CASE("queries_only: a write that shares one pixel column with a later query is kept") {
    // On 64 x 64 (one pixel = 1/32 of clip space): W covers the pixel centres of columns 12..19,
    // Q (behind it, queried after it) those of columns 5..12. They share column 12 only, where Q's
    // GEQUAL query passes against W's depth; without W it would meet the clear value and fail. A
    // reach box 4 pixels too tight on either side (past both boxes' pixel of slack) skips W and
    // answers 0 (checked by mutation).
    const auto X = [](double px) { return static_cast<float>(px / 32.0 - 1.0); };  // window X -> clip x
    const std::vector<raster::Float4> v = {{X(12.2), X(30), -0.5f, 1}, {X(20), X(30), -0.5f, 1}, {X(12.2), X(34), -0.5f, 1},
                                           {X(5), X(30), 0.5f, 1},     {X(12.8), X(30), 0.5f, 1}, {X(12.8), X(34), 0.5f, 1}};
    const std::vector<std::uint32_t> wi = {0, 1, 2}, qi = {3, 4, 5};
    for (const auto f : kFormats) {
        raster::CommandBatch batch(64, 64);
        batch.draw(raster::MeshView{v, wi}, raster::DrawState{});  // LESS, mask on
        raster::DrawState q;
        q.depth_func = DepthFunc::GEqual;
        q.depth_write = false;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw(raster::MeshView{v, qi}, q);
        batch.end_query();
        auto t = raster::DepthTarget::create(64, 64, f).value();
        raster::ExecuteOptions o{1, true};
        o.clear_depth = 1.0;
        const auto want = raster::execute(t, batch, o);
        REQUIRE(want.ok());
        REQUIRE(want.value()[0] > 0);  // column 12's pixels under both
        o.queries_only = true;
        const auto got = raster::execute(t, batch, o);
        REQUIRE(got.ok());
        CHECK(got.value() == want.value());
    }
}

TEST_CASE("setup_range (each vertex transformed once, 8 triangles at a time) == setup_triangle per triangle, both rule sets and cullings") {
    // Random vertex lists of every flavour scene_gen makes (off-screen, near/far crossing, w < 0, the
    // 1/256 grid), indexed both ways: many triangles over a short list (the per-vertex path) and few
    // over a long one (per corner), with a NaN vertex nobody indexes. Every SetupTri field must match.
    // With AVX2, setup_range runs 8 vertices and 8 triangles at a time (setup_avx2.cpp), clipped
    // triangles among them through the scalar front end, and setup_triangle runs the scalar code.
    // Every third round has a viewport that is not the target (offset, up to 3 times as large), so
    // that boxes are cut to the target and large triangles fail fits32.
    raster_test::SplitMix64 rng(97531);
    std::size_t compared = 0, cut = 0, wide = 0;
    for (int round = 0; round < 300; ++round) {
        const int w = 40 + static_cast<int>(rng.below(90)), h = 40 + static_cast<int>(rng.below(90));
        // mode 0: many triangles over a short list; 1: one or two over a long one; 2: 8 to 40 over a
        // longer one (per corner, in groups of 8 triangles when the AVX2 setup runs: setup_avx2.cpp).
        const int mode = round % 3;
        std::vector<raster::Float4> v(mode == 2 ? 130 + rng.below(30) : 3 + rng.below(30));
        for (auto& p : v) p = raster_test::random_vertex(rng, w, h, static_cast<int>(rng.below(6)));
        v.push_back({std::nanf(""), 0.0f, 0.0f, 1.0f});  // unused
        const std::size_t used = v.size() - 1;
        const std::size_t n_tris = mode == 0 ? used * 2 : mode == 1 ? 1 + rng.below(2) : 8 + rng.below(33);
        std::vector<std::uint32_t> idx;
        for (std::size_t t = 0; t < 3 * n_tris; ++t) idx.push_back(rng.below(static_cast<std::uint32_t>(used)));
        detail::FrontEndParams p = whole_target(w, h);
        if (round % 3 == 2) {
            p.viewport.width = w / 2 + static_cast<int>(rng.below(static_cast<std::uint32_t>(5 * w / 2)));
            p.viewport.height = h / 2 + static_cast<int>(rng.below(static_cast<std::uint32_t>(5 * h / 2)));
            p.viewport.x = static_cast<int>(rng.below(static_cast<std::uint32_t>(w))) - w / 2;
            p.viewport.y = static_cast<int>(rng.below(static_cast<std::uint32_t>(h))) - h / 2;
        }
        p.rules = round % 5 < 2 ? raster::RasterRules::Vulkan : raster::RasterRules::GlLlvmpipe;
        p.cull_face = static_cast<raster::CullFace>(rng.below(3));
        p.front_face = rng.chance(50) ? raster::FrontFace::CCW : raster::FrontFace::CW;
        std::vector<detail::SetupTri> per_tri, ranged;
        for (std::size_t k = 0; k < idx.size(); k += 3)
            detail::setup_triangle(p, v[idx[k]], v[idx[k + 1]], v[idx[k + 2]], 7, per_tri);
        detail::setup_range(p, v, idx, 7, ranged);
        REQUIRE(per_tri.size() == ranged.size());
        for (std::size_t i = 0; i < per_tri.size(); ++i) {
            const auto& a = per_tri[i];
            const auto& b = ranged[i];
            // Field by field, floats by their bits (setup writes every field, not the padding).
            const auto fbits = [](float f) { return std::bit_cast<std::uint32_t>(f); };
            bool same = a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1 && fbits(a.z0) == fbits(b.z0) &&
                        fbits(a.dzdx) == fbits(b.dzdx) && fbits(a.dzdy) == fbits(b.dzdy) && a.draw == b.draw &&
                        a.fits32 == b.fits32 && a.front == b.front;
            for (int e = 0; e < 3; ++e) same = same && a.c[e] == b.c[e] && a.dcdx[e] == b.dcdx[e] && a.dcdy[e] == b.dcdy[e];
            CHECK(same);
            cut += a.x1 == w - 1 || a.y1 == h - 1 || a.x0 == 0 || a.y0 == 0 ? 1u : 0u;
            wide += a.fits32 ? 0u : 1u;
        }
        compared += per_tri.size();
    }
    CHECK(compared > 3000);
    // The cases the viewports are for happened.
    CHECK(cut > 100);
    CHECK(wide > 20);
}

TEST_CASE("setup_bounds_range (four triangles at a time with AVX2) == setup_bounds_triangle per triangle") {
    // Exact-bounds setup: every BoundsTri field and every pool value must be the scalar code's bits.
    // The vertices cover what decides the common front (setup_avx2.cpp, bounds_lanes4_avx2): tiny
    // triangles inside one pixel, corners on pixel edges and on half pixels (ceil / floor of exact
    // integers, single-pixel boxes), -0 coordinates, corners beyond the clip volume mixed into the
    // same group of four (they take the scalar path), triangles outside the target, degenerate ones,
    // large magnitudes up to kMaxExactBoundsCoordinate, viewports that are not the target, and counts
    // that are not multiples of four.
    raster_test::SplitMix64 rng(24681);
    std::size_t compared = 0, singles = 0, clipped_groups = 0, planes = 0;
    const auto coord = [&](int n, double lo, double hi) -> double {
        switch (rng.below(8)) {
            case 0: return -0.0;
            case 1: return 2.0 * static_cast<double>(std::floor(rng.uniform(0.0f, static_cast<float>(n)))) / n - 1.0;  // a pixel edge
            case 2: return (2.0 * static_cast<double>(std::floor(rng.uniform(0.0f, static_cast<float>(n)))) + 1.0) / n - 1.0;  // a centre
            case 3: return rng.chance(50) ? 1.0 : -1.0;
            default: return lo + (hi - lo) * static_cast<double>(rng.uniform(0.0f, 1.0f));
        }
    };
    for (int round = 0; round < 400; ++round) {
        const int w = 16 + static_cast<int>(rng.below(48)), h = 16 + static_cast<int>(rng.below(48));
        detail::FrontEndParams p = whole_target(w, h);
        if (round % 4 == 3) {
            p.viewport.width = w / 2 + static_cast<int>(rng.below(static_cast<std::uint32_t>(2 * w)));
            p.viewport.height = h / 2 + static_cast<int>(rng.below(static_cast<std::uint32_t>(2 * h)));
            p.viewport.x = static_cast<int>(rng.below(static_cast<std::uint32_t>(w))) - w / 2;
            p.viewport.y = static_cast<int>(rng.below(static_cast<std::uint32_t>(h))) - h / 2;
        }
        std::vector<raster::Double4> v;
        const std::size_t n_tris = 1 + rng.below(40);
        for (std::size_t t = 0; t < n_tris; ++t) {
            const std::uint32_t kind = rng.below(10);
            const double cx = coord(w, -1.1, 1.1), cy = coord(h, -1.1, 1.1), cz = coord(4, -1.0, 1.0);
            for (int k = 0; k < 3; ++k) {
                raster::Double4 c{cx, cy, cz, 1.0};
                if (kind < 4) {  // within a pixel or two
                    c.x += static_cast<double>(rng.uniform(-1.5f, 1.5f)) / w;
                    c.y += static_cast<double>(rng.uniform(-1.5f, 1.5f)) / h;
                } else if (kind < 6) {  // anywhere (some beyond the clip volume)
                    c = {coord(w, -1.3, 1.3), coord(h, -1.3, 1.3), coord(2, -1.2, 1.2), 1.0};
                } else if (kind == 6) {  // huge
                    c.x = (rng.chance(50) ? 1.0 : -1.0) * raster::kMaxExactBoundsCoordinate * static_cast<double>(rng.uniform(0.0f, 1.0f));
                } else if (kind == 7) {  // degenerate: every corner the same point
                } else {  // a few pixels
                    c.x += static_cast<double>(rng.uniform(-6.0f, 6.0f)) / w;
                    c.y += static_cast<double>(rng.uniform(-6.0f, 6.0f)) / h;
                    c.z += static_cast<double>(rng.uniform(-0.1f, 0.1f));
                }
                v.push_back(c);
            }
        }
        std::vector<std::uint32_t> idx(v.size());
        for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
        if (rng.chance(30)) std::reverse(idx.begin(), idx.end());  // indexed out of order
        std::vector<detail::BoundsTri> want, got;
        std::vector<detail::BoundsVertex> want_pool, got_pool;
        for (std::size_t k = 0; k < idx.size(); k += 3)
            detail::setup_bounds_triangle(p, v[idx[k]], v[idx[k + 1]], v[idx[k + 2]], 5, want, want_pool);
        detail::setup_bounds_range(p, v, idx, 5, got, got_pool);
        for (std::size_t g = 0; g + 4 <= n_tris; g += 4) {
            bool any = false;
            for (std::size_t k = 3 * g; k < 3 * g + 12; ++k)
                any = any || std::max({std::fabs(v[idx[k]].x), std::fabs(v[idx[k]].y), std::fabs(v[idx[k]].z)}) > 1.0;
            clipped_groups += any ? 1u : 0u;
        }
        REQUIRE(want.size() == got.size());
        REQUIRE(want_pool.size() == got_pool.size());
        const auto dbits = [](double d) { return std::bit_cast<std::uint64_t>(d); };
        for (std::size_t i = 0; i < want.size(); ++i) {
            const auto& a = want[i];
            const auto& b = got[i];
            CHECK((a.first == b.first && a.n == b.n && dbits(a.margin_xy) == dbits(b.margin_xy) &&
                   dbits(a.margin_z) == dbits(b.margin_z) && a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 &&
                   a.y1 == b.y1 && a.draw == b.draw && a.single == b.single && a.zq_lo == b.zq_lo &&
                   a.zq_hi == b.zq_hi && a.kind == b.kind));
            singles += a.single ? 1u : 0u;
            planes += a.kind == detail::BoundsTri::Kind::Plane ? 1u : 0u;
        }
        for (std::size_t i = 0; i < want_pool.size(); ++i)
            CHECK((dbits(want_pool[i].x) == dbits(got_pool[i].x) && dbits(want_pool[i].y) == dbits(got_pool[i].y) &&
                   dbits(want_pool[i].z) == dbits(got_pool[i].z)));
        compared += want.size();
        // Scalar only (allow_simd off) is the same list too.
        std::vector<detail::BoundsTri> scalar;
        std::vector<detail::BoundsVertex> scalar_pool;
        detail::setup_bounds_range(p, v, idx, 5, scalar, scalar_pool, false);
        CHECK(scalar.size() == want.size());
        CHECK(scalar_pool.size() == want_pool.size());
    }
    MESSAGE("AVX2 exact-bounds setup: " << std::string(detail::kernel_avx2_available() ? "on" : "off (scalar both sides)"));
    CHECK(compared > 3000);
    // The cases the inputs are for happened.
    CHECK(singles > 300);
    CHECK(planes > 100);
    CHECK(clipped_groups > 100);
}
