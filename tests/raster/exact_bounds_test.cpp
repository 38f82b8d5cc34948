// exact_bounds_test.cpp: RasterMode::ExactBounds against the exact rational reference
// (exact_bounds_reference.h): every pixel the closed triangle meets is covered, the written depth is
// <= the exact minimum and the queried depth >= the exact maximum over the pixel; plus the
// GEQUAL-after-LEQUAL property, determinism over threads and the error paths.
#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "exact_bounds_reference.h"
#include "raster/raster.h"
#include "test_rng.h"

namespace {

using raster::DepthFormat;
using raster::Double4;

constexpr DepthFormat kFormats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};

// A clip-space vertex in one of several flavours that stress the conservative rules.
Double4 random_vertex(test::Rng& rng, int flavour, const Double4& anchor) {
    switch (flavour) {
        case 0:  // anywhere, slightly beyond the clip volume too
            return {rng.uniform(-1.2, 1.2), rng.uniform(-1.2, 1.2), rng.uniform(-1.1, 1.1), 1.0};
        case 1:  // within a pixel or so of the anchor (sub-pixel triangles)
            return {anchor.x + rng.uniform(-0.05, 0.05), anchor.y + rng.uniform(-0.05, 0.05),
                    anchor.z + rng.uniform(-0.3, 0.3), 1.0};
        case 2:  // the anchor's x and y, other depth: edge-on (vertical) triangles
            return {anchor.x + rng.uniform(-1e-12, 1e-12), anchor.y, rng.uniform(-1.0, 1.0), 1.0};
        case 3:  // far outside (huge offsets; the clipper must not lose the inside part)
            return {rng.uniform(-1e9, 1e9), rng.uniform(-1e9, 1e9), rng.uniform(-3.0, 3.0), 1.0};
        default:  // exactly the anchor (degenerate: segments and points)
            return anchor;
    }
}

struct Tri {
    Double4 v[3];
};

Tri random_triangle(test::Rng& rng) {
    Tri t;
    t.v[0] = random_vertex(rng, 0, {});
    const int flavour = static_cast<int>(rng.below(5));
    t.v[1] = random_vertex(rng, flavour, t.v[0]);
    t.v[2] = random_vertex(rng, rng.below(3) == 0 ? 0 : flavour, t.v[1]);
    return t;
}

std::uint32_t impossible_high(DepthFormat f) {
    // Larger than any incoming value, so GEQUAL never passes against it.
    switch (f) {
        case DepthFormat::D16:
            return 0x10000u;
        case DepthFormat::D24:
            return 0x1000000u;
        case DepthFormat::D32F:
            return std::bit_cast<std::uint32_t>(2.0f);
    }
    return 0;
}

}  // namespace

TEST_CASE("Exact-bounds pixels contain the exact coverage and depth range of random triangles") {
    test::Rng rng(20261121);
    const int sizes[][2] = {{13, 9}, {32, 32}, {7, 40}};
    int covered_total = 0;
    for (int rep = 0; rep < 240; ++rep) {
        const DepthFormat f = kFormats[rep % 3];
        const int w = sizes[rep % 3][0], h = sizes[(rep / 3) % 3][1];
        const Tri t = random_triangle(rng);
        CAPTURE(rep);
        CAPTURE(static_cast<int>(f));
        const std::vector<std::uint32_t> idx = {0, 1, 2};
        const raster::MeshViewD mesh{t.v, idx};
        const raster_ref::ExactTriangle exact(raster::Viewport{0, 0, w, h}, t.v[0], t.v[1], t.v[2]);

        // zmin: written with ALWAYS into a target cleared to 1; every exactly covered pixel must
        // hold a value <= the exact minimum (a missed pixel keeps 1.0, which fails unless zmin = 1).
        auto target = raster::DepthTarget::create(w, h, f);
        REQUIRE(target.ok());
        raster::CommandBatch write(w, h);
        raster::DrawState ws;
        ws.mode = raster::RasterMode::ExactBounds;
        ws.depth_func = raster::DepthFunc::Always;
        ws.depth_write = true;
        write.draw(mesh, ws);
        REQUIRE(raster::execute(target.value(), write).ok());

        // zmax and coverage: exactly covered pixels hold floor(exact zmax), others a value no
        // incoming depth reaches; a GEQUAL query must pass on exactly the covered pixels.
        auto probe = raster::DepthTarget::create(w, h, f);
        REQUIRE(probe.ok());
        const auto pv = probe.value().mutable_values();
        int covered = 0;
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const raster_ref::PixelRange r = exact.pixel(x, y);
                const std::size_t i =
                    static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
                if (!r.covered) {
                    pv[i] = impossible_high(f);
                    continue;
                }
                ++covered;
                pv[i] = raster_ref::floor_value(r.zmax, f);
                const mpq_class written = raster_ref::stored_depth(target.value().value(x, y), f);
                CAPTURE(x);
                CAPTURE(y);
                CHECK(written <= r.zmin);
            }
        }
        covered_total += covered;
        raster::CommandBatch query(w, h);
        raster::DrawState qs;
        qs.mode = raster::RasterMode::ExactBounds;
        qs.depth_func = raster::DepthFunc::GEqual;
        qs.depth_write = false;
        query.begin_query(raster::QueryKind::SamplesPassed);
        query.draw(mesh, qs);
        query.end_query();
        auto got = raster::execute_reference(probe.value(), query);
        REQUIRE(got.ok());
        CHECK(got.value()[0] == static_cast<std::uint64_t>(covered));
    }
    CHECK(covered_total > 1000);  // the sample is not trivially empty
}

TEST_CASE("Exact-bounds coverage is tight: nothing beyond the exact pixel box grown by one pixel") {
    test::Rng rng(99);
    for (int rep = 0; rep < 200; ++rep) {
        const int w = 24, h = 24;
        const Tri t = random_triangle(rng);
        CAPTURE(rep);
        const std::vector<std::uint32_t> idx = {0, 1, 2};
        const raster_ref::ExactTriangle exact(raster::Viewport{0, 0, w, h}, t.v[0], t.v[1], t.v[2]);
        auto target = raster::DepthTarget::create(w, h, DepthFormat::D24);
        REQUIRE(target.ok());
        raster::CommandBatch b(w, h);
        raster::DrawState s;
        s.mode = raster::RasterMode::ExactBounds;
        s.depth_func = raster::DepthFunc::Always;
        b.draw(raster::MeshViewD{t.v, idx}, s);
        REQUIRE(raster::execute(target.value(), b).ok());
        const std::uint32_t clear = raster::DepthTarget::encode_clear(1.0, DepthFormat::D24);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (target.value().value(x, y) == clear) continue;
                CAPTURE(x);
                CAPTURE(y);
                REQUIRE(!exact.empty());
                CHECK(x >= exact.x0 - 1);
                CHECK(x <= exact.x1 + 1);
                CHECK(y >= exact.y0 - 1);
                CHECK(y <= exact.y1 + 1);
            }
    }
}

TEST_CASE("A GEQUAL exact-bounds query after LEQUAL writes never misses an exact depth overlap") {
    // Sets A (written) and B (queried) of random triangles; whenever, in some pixel, B's exact
    // maximum depth is >= A's exact minimum there, the query must count at least one sample.
    test::Rng rng(4242);
    int overlaps = 0;
    for (int rep = 0; rep < 150; ++rep) {
        const DepthFormat f = kFormats[rep % 3];
        const int w = 16, h = 12;
        CAPTURE(rep);
        std::vector<Double4> a, b;
        for (int i = 0; i < 2; ++i) {
            const Tri t = random_triangle(rng);
            a.insert(a.end(), t.v, t.v + 3);
        }
        for (int i = 0; i < 2; ++i) {
            Tri t = random_triangle(rng);
            if (rng.below(2) == 0) {  // B nearly coplanar with A's first triangle, a hair behind or in front
                const double dz = (rng.unit() - 0.5) * std::ldexp(1.0, -static_cast<int>(rng.below(40)));
                for (int k = 0; k < 3; ++k)
                    t.v[k] = {a[static_cast<std::size_t>(k)].x, a[static_cast<std::size_t>(k)].y,
                              a[static_cast<std::size_t>(k)].z + dz, 1.0};
            }
            b.insert(b.end(), t.v, t.v + 3);
        }
        const std::vector<std::uint32_t> idx = {0, 1, 2, 3, 4, 5};
        bool exact_overlap = false;
        for (int y = 0; y < h && !exact_overlap; ++y)
            for (int x = 0; x < w && !exact_overlap; ++x) {
                bool have_a = false, have_b = false;
                mpq_class amin, bmax;
                for (std::size_t k = 0; k < 6; k += 3) {
                    const raster_ref::PixelRange ra =
                        raster_ref::ExactTriangle({0, 0, w, h}, a[k], a[k + 1], a[k + 2]).pixel(x, y);
                    if (ra.covered && (!have_a || ra.zmin < amin)) amin = ra.zmin, have_a = true;
                    const raster_ref::PixelRange rb =
                        raster_ref::ExactTriangle({0, 0, w, h}, b[k], b[k + 1], b[k + 2]).pixel(x, y);
                    if (rb.covered && (!have_b || rb.zmax > bmax)) bmax = rb.zmax, have_b = true;
                }
                exact_overlap = have_a && have_b && bmax >= amin;
            }
        auto target = raster::DepthTarget::create(w, h, f);
        REQUIRE(target.ok());
        raster::CommandBatch batch(w, h);
        raster::DrawState ws;
        ws.mode = raster::RasterMode::ExactBounds;
        ws.depth_func = raster::DepthFunc::LEqual;
        batch.draw(raster::MeshViewD{a, idx}, ws);
        raster::DrawState qs = ws;
        qs.depth_func = raster::DepthFunc::GEqual;
        qs.depth_write = false;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw(raster::MeshViewD{b, idx}, qs);
        batch.end_query();
        auto got = raster::execute(target.value(), batch, raster::ExecuteOptions{2});
        REQUIRE(got.ok());
        if (exact_overlap) {
            ++overlaps;
            CHECK(got.value()[0] > 0);
        }
    }
    CHECK(overlaps > 20);
}

TEST_CASE("Exact-bounds results are bit-identical for 1, 2, 3 and 8 threads, the reference and no SIMD") {
    test::Rng rng(31337);
    for (const DepthFormat f : kFormats) {
        const int w = 150, h = 97;
        std::vector<Double4> v;
        std::vector<std::vector<std::uint32_t>> idx;
        raster::CommandBatch batch(w, h);
        for (int o = 0; o < 60; ++o) {
            idx.emplace_back();
            for (int k = 0; k < 4; ++k) {
                const Tri t = random_triangle(rng);
                for (const auto& p : t.v) {
                    idx.back().push_back(static_cast<std::uint32_t>(v.size()));
                    v.push_back(p);
                }
            }
        }
        for (std::size_t o = 0; o < idx.size(); ++o) {
            raster::DrawState s;
            s.mode = raster::RasterMode::ExactBounds;
            s.depth_func = raster::DepthFunc::GEqual;
            s.depth_write = false;
            batch.begin_query(raster::QueryKind::SamplesPassed);
            batch.draw(raster::MeshViewD{v, idx[o]}, s);
            batch.end_query();
            s.depth_func = raster::DepthFunc::LEqual;
            s.depth_write = true;
            if (o % 7 == 3) s.viewport = raster::Viewport{10, -5, 90, 80};
            batch.draw(raster::MeshViewD{v, idx[o]}, s);
        }
        auto ref = raster::DepthTarget::create(w, h, f);
        REQUIRE(ref.ok());
        auto want = raster::execute_reference(ref.value(), batch, raster::ExecuteOptions{1, false});
        REQUIRE(want.ok());
        std::uint64_t total = 0;
        for (auto q : want.value()) total += q;
        CHECK(total > 0);
        for (const int threads : {1, 2, 3, 8}) {
            for (const bool simd : {true, false}) {
                CAPTURE(threads);
                CAPTURE(simd);
                auto t = raster::DepthTarget::create(w, h, f);
                REQUIRE(t.ok());
                auto got = raster::execute(t.value(), batch, raster::ExecuteOptions{threads, simd});
                REQUIRE(got.ok());
                CHECK(got.value() == want.value());
                CHECK(std::equal(t.value().values().begin(), t.value().values().end(),
                                 ref.value().values().begin()));
            }
        }
    }
}

TEST_CASE("Exact-bounds draws reject bad input before anything is drawn") {
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    const double nan = std::nan("");
    struct Case {
        std::vector<Double4> v;
        raster::RasterMode mode;
        raster::CullFace cull;
        const char* needle;
    };
    const Case cases[] = {
        {{{0, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, 2}},
         raster::RasterMode::ExactBounds,
         raster::CullFace::None,
         "w = 2"},
        {{{0, 0, 0, 1}, {nan, 0, 0, 1}, {0, 1, 0, 1}},
         raster::RasterMode::ExactBounds,
         raster::CullFace::None,
         "not finite"},
        {{{0, 0, 0, 1}, {1e31, 0, 0, 1}, {0, 1, 0, 1}},
         raster::RasterMode::ExactBounds,
         raster::CullFace::None,
         "2^100"},
        {{{0, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, 1}},
         raster::RasterMode::GLExact,
         raster::CullFace::None,
         "needs RasterMode::ExactBounds"},
        {{{0, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, 1}},
         raster::RasterMode::ExactBounds,
         raster::CullFace::Back,
         "CullFace::None"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.needle);
        auto t = raster::DepthTarget::create(8, 8, DepthFormat::D24);
        REQUIRE(t.ok());
        const std::vector<std::uint32_t> before(t.value().values().begin(), t.value().values().end());
        raster::CommandBatch b(8, 8);
        raster::DrawState good;
        good.mode = raster::RasterMode::ExactBounds;
        good.depth_func = raster::DepthFunc::Always;
        const std::vector<Double4> ok_v = {{-1, -1, 0, 1}, {1, -1, 0, 1}, {-1, 1, 0, 1}};
        b.draw(raster::MeshViewD{ok_v, idx}, good);  // would draw if anything ran
        raster::DrawState s = good;
        s.mode = c.mode;
        s.cull_face = c.cull;
        b.draw(raster::MeshViewD{c.v, idx}, s);
        for (const bool reference : {false, true}) {
            auto r = reference ? raster::execute_reference(t.value(), b) : raster::execute(t.value(), b);
            REQUIRE_FALSE(r.ok());
            CHECK(r.error().message.find("command 1") != std::string::npos);
            CHECK(r.error().message.find(c.needle) != std::string::npos);
            CHECK(std::equal(before.begin(), before.end(), t.value().values().begin()));
        }
    }
}

TEST_CASE("Exact-bounds writes round outward: a flat triangle's stored depth brackets its exact depth") {
    // Depths on and next to quantization boundaries of every format; the write rounds down, the
    // query rounds up, each to within a few quanta of the exact value (the mode's margin is 2^-40).
    test::Rng rng(5);
    for (const DepthFormat f : kFormats) {
        for (int rep = 0; rep < 60; ++rep) {
            const double n = f == DepthFormat::D16 ? 65535.0 : 16777215.0;
            double z = rep < 20 ? std::floor(rng.unit() * n) / n
                                : (rep < 40 ? rng.unit() : 0.5 + (rep - 40) * 0x1p-30);
            const double zc = 2.0 * z - 1.0;  // clip depth (exact for these values)
            CAPTURE(static_cast<int>(f));
            CAPTURE(z);
            const std::vector<Double4> v = {{-1, -1, zc, 1}, {3, -1, zc, 1}, {-1, 3, zc, 1}};
            const std::vector<std::uint32_t> idx = {0, 1, 2};
            auto t = raster::DepthTarget::create(4, 4, f);
            REQUIRE(t.ok());
            raster::CommandBatch b(4, 4);
            raster::DrawState s;
            s.mode = raster::RasterMode::ExactBounds;
            s.depth_func = raster::DepthFunc::Always;
            b.draw(raster::MeshViewD{v, idx}, s);
            REQUIRE(raster::execute(t.value(), b).ok());
            const mpq_class exact = mpq_class(zc) / 2 + mpq_class(1, 2);
            const std::uint32_t stored = t.value().value(2, 2);
            CHECK(raster_ref::stored_depth(stored, f) <= exact);
            // Tight: at most one representable step below floor(exact) (the 2^-40 margin).
            const std::uint32_t fl = raster_ref::floor_value(exact, f);
            if (f == DepthFormat::D32F) {
                const float sf = std::bit_cast<float>(stored), ff = std::bit_cast<float>(fl);
                CHECK((sf == ff || std::nextafter(sf, 2.0f) == ff));
            } else {
                CHECK(stored + 1 >= fl);
            }
        }
    }
}
