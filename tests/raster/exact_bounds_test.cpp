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

#include "exact_bounds.h"  // white box: which per-pixel path a triangle takes (raster/src)
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

namespace {

// One triangle through the exact-bounds write (ALWAYS, mask on) and a GEQUAL probe, against the
// exact reference: every exactly covered pixel holds a written value <= the exact zmin, the probe
// passes on exactly the exactly covered pixels (so zmax >= exact zmax and coverage is complete),
// and nothing is covered beyond the exact pixel box grown by one pixel (only when every |coordinate|
// is at most 2^20: the clip margin grows with the magnitude M, 2^-40 M, so huge inputs are looser
// by design). Returns the covered count.
int check_against_exact(const Tri& t, int w, int h, DepthFormat f) {
    bool moderate = true;
    for (const auto& v : t.v) moderate = moderate && std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}) <= 0x1p20;
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    const raster::MeshViewD mesh{t.v, idx};
    const raster_ref::ExactTriangle exact(raster::Viewport{0, 0, w, h}, t.v[0], t.v[1], t.v[2]);
    auto target = raster::DepthTarget::create(w, h, f);
    REQUIRE(target.ok());
    raster::CommandBatch write(w, h);
    raster::DrawState ws;
    ws.mode = raster::RasterMode::ExactBounds;
    ws.depth_func = raster::DepthFunc::Always;
    write.draw(mesh, ws);
    REQUIRE(raster::execute(target.value(), write, raster::ExecuteOptions{2}).ok());
    const std::uint32_t clear = raster::DepthTarget::encode_clear(1.0, f);
    auto probe = raster::DepthTarget::create(w, h, f);
    REQUIRE(probe.ok());
    const auto pv = probe.value().mutable_values();
    int covered = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            CAPTURE(x);
            CAPTURE(y);
            const raster_ref::PixelRange r = exact.pixel(x, y);
            const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
            const std::uint32_t written = target.value().value(x, y);
            if (!r.covered) {
                pv[i] = impossible_high(f);
                if (moderate && written != clear) {  // tight: within one pixel of the exact box
                    REQUIRE(!exact.empty());
                    CHECK(x >= exact.x0 - 1);
                    CHECK(x <= exact.x1 + 1);
                    CHECK(y >= exact.y0 - 1);
                    CHECK(y <= exact.y1 + 1);
                }
                continue;
            }
            ++covered;
            pv[i] = raster_ref::floor_value(r.zmax, f);
            CHECK(raster_ref::stored_depth(written, f) <= r.zmin);
        }
    }
    raster::CommandBatch query(w, h);
    raster::DrawState qs;
    qs.mode = raster::RasterMode::ExactBounds;
    qs.depth_func = raster::DepthFunc::GEqual;
    qs.depth_write = false;
    query.begin_query(raster::QueryKind::SamplesPassed);
    query.draw(mesh, qs);
    query.end_query();
    auto got = raster::execute(probe.value(), query, raster::ExecuteOptions{3});
    REQUIRE(got.ok());
    CHECK(got.value()[0] == static_cast<std::uint64_t>(covered));
    return covered;
}

// The per-pixel path the exact-bounds setup picks for a triangle (General when it is one pixel or
// culled: those never reach the new paths).
raster::detail::BoundsTri::Kind path_of(const Tri& t, int w, int h) {
    raster::detail::FrontEndParams p{};
    p.target_width = w;
    p.target_height = h;
    p.viewport = raster::Viewport{0, 0, w, h};
    p.cull_face = raster::CullFace::None;
    p.front_face = raster::FrontFace::CCW;
    std::vector<raster::detail::BoundsTri> out;
    std::vector<raster::detail::BoundsVertex> pool;
    raster::detail::setup_bounds_triangle(p, t.v[0], t.v[1], t.v[2], 0, out, pool);
    if (out.empty() || out[0].single) return raster::detail::BoundsTri::Kind::General;
    return out[0].kind;
}

// Triangles aimed at the plane (separating-axis) path, the edge-on row / column paths and their
// fallbacks, in clip space for a w x h viewport.
Tri targeted_triangle(test::Rng& rng, int kind, int w, int h) {
    const double px = 2.0 / w, py = 2.0 / h;  // one pixel in clip units
    auto z = [&] { return rng.uniform(-1.0, 1.0); };
    auto on_lattice = [&](double pixel, int n) {  // pixel corners and centres
        return -1.0 + pixel * 0.5 * static_cast<double>(rng.below(static_cast<std::uint64_t>(2 * n + 1)));
    };
    Tri t;
    switch (kind) {
        case 0: {  // sliver: a long edge and a third vertex 2^-k of its length off it
            const double x0 = rng.uniform(-1.1, 1.1), y0 = rng.uniform(-1.1, 1.1);
            const double ang = rng.uniform(0.0, 6.283185307179586);
            const double len = rng.uniform(0.2, 1.5);
            const double dx = std::cos(ang) * len, dy = std::sin(ang) * len;
            const double s = rng.uniform(0.05, 0.95), off = std::ldexp(rng.sym(), -static_cast<int>(rng.range(3, 30)));
            t.v[0] = {x0, y0, z(), 1};
            t.v[1] = {x0 + dx, y0 + dy, z(), 1};
            t.v[2] = {x0 + s * dx - off * dy, y0 + s * dy + off * dx, z(), 1};
            break;
        }
        case 1: {  // nearly collinear: orientation uncertain after rounding (offsets 2^-30 .. 2^-62)
            const double x0 = rng.uniform(-1, 1), y0 = rng.uniform(-1, 1);
            const double x1 = rng.uniform(-1, 1), y1 = rng.uniform(-1, 1);
            const double s = rng.unit(), off = std::ldexp(rng.sym(), -static_cast<int>(rng.range(30, 62)));
            t.v[0] = {x0, y0, z(), 1};
            t.v[1] = {x1, y1, z(), 1};
            t.v[2] = {x0 + s * (x1 - x0) - off * (y1 - y0), y0 + s * (y1 - y0) + off * (x1 - x0), z(), 1};
            break;
        }
        case 2: {  // axis-aligned edge-on: one common x (or y), often on a pixel boundary
            const bool by_x = rng.coin();
            const double c = rng.coin() ? on_lattice(by_x ? px : py, by_x ? w : h) : rng.uniform(-1.05, 1.05);
            for (auto& v : t.v) {
                const double o = rng.uniform(-1.2, 1.2);
                v = by_x ? Double4{c, o, z(), 1} : Double4{o, c, z(), 1};
            }
            break;
        }
        case 3: {  // oblique edge-on: three points of one line (up to the rounding of their coordinates)
            const double x0 = rng.uniform(-1, 1), y0 = rng.uniform(-1, 1);
            const double dx = rng.sym(), dy = rng.sym();
            for (auto& v : t.v) {
                const double s = rng.uniform(-0.7, 0.7);
                v = {x0 + s * dx, y0 + s * dy, z(), 1};
            }
            break;
        }
        case 4: {  // vertices on pixel corners and centres: edges along pixel boundaries
            for (auto& v : t.v) v = {on_lattice(px, w), on_lattice(py, h), rng.coin() ? 0.25 : z(), 1};
            break;
        }
        case 5: {  // steep: depth jumps across a pixel or less
            const double x0 = rng.uniform(-1, 1), y0 = rng.uniform(-1, 1);
            t.v[0] = {x0, y0, -1, 1};
            t.v[1] = {x0 + rng.uniform(-1.5, 1.5) * px, y0 + rng.uniform(-1.5, 1.5) * py, 1, 1};
            t.v[2] = {x0 + rng.uniform(-8, 8) * px, y0 + rng.uniform(-8, 8) * py, z(), 1};
            break;
        }
        case 6: {  // huge coordinates (clipped), tiny triangles (1e-12 of the view), beyond the depth range
            const int sub = static_cast<int>(rng.below(3));
            const double x0 = rng.uniform(-1, 1), y0 = rng.uniform(-1, 1);
            for (auto& v : t.v) {
                if (sub == 0)
                    v = {rng.sym() * std::ldexp(1.0, rng.range(10, 90)), rng.sym() * std::ldexp(1.0, rng.range(10, 90)),
                         rng.uniform(-3, 3), 1};
                else if (sub == 1)
                    v = {x0 + rng.sym() * 1e-12, y0 + rng.sym() * 1e-12, z(), 1};
                else
                    v = {rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-4, 4), 1};
            }
            break;
        }
        default: {  // constant depth, anywhere (screen-parallel faces)
            const double zc = z();
            for (auto& v : t.v) v = {rng.uniform(-1.2, 1.2), rng.uniform(-1.2, 1.2), zc, 1};
            break;
        }
    }
    return t;
}

}  // namespace

TEST_CASE("Exact-bounds fast paths (plane, edge-on rows and columns, fallbacks) contain the exact result") {
    // Slivers, nearly degenerate triangles of uncertain orientation, axis-aligned and oblique
    // edge-on triangles, lattice-aligned edges, steep planes, huge / tiny coordinates, clipped
    // triangles and constant depth: every check of check_against_exact, on the path each takes.
    test::Rng rng(777);
    const int sizes[][2] = {{24, 24}, {17, 31}, {40, 9}};
    int covered_total = 0;
    int paths[4] = {0, 0, 0, 0};
    for (int rep = 0; rep < 400; ++rep) {
        const int kind = rep % 8;
        const DepthFormat f = kFormats[(rep / 8) % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        const Tri t = targeted_triangle(rng, kind, w, h);
        CAPTURE(rep);
        CAPTURE(kind);
        CAPTURE(static_cast<int>(f));
        ++paths[static_cast<int>(path_of(t, w, h))];
        covered_total += check_against_exact(t, w, h, f);
    }
    CHECK(covered_total > 2000);
    // Every path is exercised (General includes the fallbacks of slivers and uncertain orientations).
    CHECK(paths[static_cast<int>(raster::detail::BoundsTri::Kind::General)] > 20);
    CHECK(paths[static_cast<int>(raster::detail::BoundsTri::Kind::Plane)] > 100);
    CHECK(paths[static_cast<int>(raster::detail::BoundsTri::Kind::Column)] > 10);
    CHECK(paths[static_cast<int>(raster::detail::BoundsTri::Kind::Row)] > 10);
}

TEST_CASE("Exact-bounds path choice: well-shaped triangles take the plane path, degenerate ones do not") {
    const int w = 32, h = 32;
    // A plain triangle several pixels wide.
    CHECK(path_of(Tri{{{-0.5, -0.5, 0.1, 1}, {0.5, -0.4, 0.3, 1}, {0.0, 0.6, -0.2, 1}}}, w, h) ==
          raster::detail::BoundsTri::Kind::Plane);
    // Edge-on along x and along y.
    CHECK(path_of(Tri{{{0.25, -0.5, 0.1, 1}, {0.25, 0.5, 0.3, 1}, {0.25, 0.0, -0.9, 1}}}, w, h) ==
          raster::detail::BoundsTri::Kind::Column);
    CHECK(path_of(Tri{{{-0.5, 0.25, 0.1, 1}, {0.5, 0.25, 0.3, 1}, {0.0, 0.25, -0.9, 1}}}, w, h) ==
          raster::detail::BoundsTri::Kind::Row);
    // Collinear up to 2^-60 (orientation not certain; zero area after rounding): the general path.
    CHECK(path_of(Tri{{{-0.5, -0.5, 0.1, 1}, {0.5, 0.5, 0.3, 1}, {0.0, 0x1p-60, -0.9, 1}}}, w, h) ==
          raster::detail::BoundsTri::Kind::General);
    // Crossing the clip volume (a clipped polygon): the general path.
    CHECK(path_of(Tri{{{-0.5, -0.5, 0.1, 1}, {3.0, -0.4, 0.3, 1}, {0.0, 0.6, -0.2, 1}}}, w, h) ==
          raster::detail::BoundsTri::Kind::General);
}

TEST_CASE("Exact-bounds plane path: the written depth of an interior pixel is within the documented bound") {
    // Tightness of the plane path (docs/reliable-raster.md, "The plane path"): for a pixel whose
    // square lies inside the triangle, the written zmin is below the exact minimum over the pixel by
    // at most g * m + 2^-36 + margin_z before the outward rounding, with g = |gx| + |gy| (which is
    // the exact range over a full square) and m = margin_xy ~ 2^-20: the same slack as the general
    // path's grown slabs. Checked as: written >= floor(exact zmin - g 2^-18 - 2^-30) less one step.
    test::Rng rng(4711);
    int interior = 0;
    for (int rep = 0; rep < 60; ++rep) {
        const DepthFormat f = kFormats[rep % 3];
        const int w = 24, h = 24;
        const Tri t{{{rng.uniform(-1, -0.5), rng.uniform(-1, -0.5), rng.uniform(-0.9, 0.9), 1},
                     {rng.uniform(0.5, 1), rng.uniform(-1, 0), rng.uniform(-0.9, 0.9), 1},
                     {rng.uniform(-0.5, 0.5), rng.uniform(0.5, 1), rng.uniform(-0.9, 0.9), 1}}};
        CAPTURE(rep);
        REQUIRE(path_of(t, w, h) == raster::detail::BoundsTri::Kind::Plane);
        const std::vector<std::uint32_t> idx = {0, 1, 2};
        auto target = raster::DepthTarget::create(w, h, f);
        REQUIRE(target.ok());
        raster::CommandBatch b(w, h);
        raster::DrawState s;
        s.mode = raster::RasterMode::ExactBounds;
        s.depth_func = raster::DepthFunc::Always;
        b.draw(raster::MeshViewD{t.v, idx}, s);
        REQUIRE(raster::execute(target.value(), b).ok());
        const raster_ref::ExactTriangle exact(raster::Viewport{0, 0, w, h}, t.v[0], t.v[1], t.v[2]);
        // Exact window vertices (viewport at the origin: X = x w/2 + w/2) and the sign of the area.
        mpq_class X[3], Y[3];
        for (int k = 0; k < 3; ++k) {
            X[k] = mpq_class(t.v[k].x) * w / 2 + mpq_class(w, 2);
            Y[k] = mpq_class(t.v[k].y) * h / 2 + mpq_class(h, 2);
        }
        const auto orient = [&](int i, int j, const mpq_class& x, const mpq_class& y) {
            const mpq_class v = (X[j] - X[i]) * (y - Y[i]) - (Y[j] - Y[i]) * (x - X[i]);
            return sgn(v);
        };
        const int area = orient(0, 1, X[2], Y[2]);
        REQUIRE(area != 0);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                bool inside = true;  // all four corners of the pixel square inside the triangle
                for (int c = 0; c < 4 && inside; ++c) {
                    const mpq_class cx(x + (c & 1)), cy(y + (c >> 1));
                    for (int i = 0; i < 3 && inside; ++i) inside = orient(i, (i + 1) % 3, cx, cy) * area >= 0;
                }
                if (!inside) continue;
                const raster_ref::PixelRange r = exact.pixel(x, y);
                REQUIRE(r.covered);
                ++interior;
                CAPTURE(x);
                CAPTURE(y);
                const std::uint32_t written = target.value().value(x, y);
                CHECK(raster_ref::stored_depth(written, f) <= r.zmin);
                const mpq_class slack = (r.zmax - r.zmin) / (1 << 18) + mpq_class(1, 1u << 30);
                const mpq_class lowest = r.zmin - slack < 0 ? mpq_class(0) : mpq_class(r.zmin - slack);
                const std::uint32_t fl = raster_ref::floor_value(lowest, f);
                if (f == DepthFormat::D32F) {
                    const float sf = std::bit_cast<float>(written), ff = std::bit_cast<float>(fl);
                    CHECK((sf >= ff || std::nextafter(sf, 2.0f) >= ff));
                } else {
                    CHECK(written + 1 >= fl);
                }
            }
    }
    CHECK(interior > 1000);
}

TEST_CASE("Exact-bounds: triangles clipped to three vertices with huge coordinates (large margins)") {
    // Two vertices far beyond the far plane (|z| up to 2^90) and one inside: the clip leaves a
    // triangle, but the margins grow with the magnitude M (2^-40 M clip units), so the plane path's
    // error bounds must cover squares grown by a large margin (or refuse the path).
    test::Rng rng(99991);
    int covered = 0;
    for (int rep = 0; rep < 60; ++rep) {
        const int e = 20 + static_cast<int>(rng.below(71));  // 2^20 .. 2^90
        const double far = std::ldexp(1.0, e) * (rng.coin() ? 1.0 : -1.0);
        const Tri t{{{rng.uniform(-0.8, 0.8), rng.uniform(-0.8, 0.8), rng.uniform(-0.5, 0.5), 1},
                     {rng.uniform(-0.8, 0.8), rng.uniform(-0.8, 0.8), far, 1},
                     {rng.uniform(-0.8, 0.8), rng.uniform(-0.8, 0.8), far * rng.uniform(0.5, 1.0), 1}}};
        CAPTURE(rep);
        CAPTURE(e);
        covered += check_against_exact(t, 24, 20, kFormats[rep % 3]);
    }
    CHECK(covered >= 50);  // the clipped part is a small triangle around the inside vertex
}
