// unit_test.cpp: the raster API without an oracle: bad input is rejected before anything is drawn
// (target unchanged), the GL conventions hold on hand-checkable cases (expected values derived by
// hand from the rules in raster/raster.h, not by running the code), and the transform helpers.
#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "float_step.h"
#include "raster/raster.h"
#include "scene_gen.h"

namespace {

using raster::DepthFormat;
using raster::DepthFunc;
using raster::Float4;

// Window (pixel) coordinates -> clip space for a viewport at 0 of size n, w = 1.
Float4 px(float x, float y, float z_window, int w, int h) {
    return {x * (2.0f / static_cast<float>(w)) - 1.0f, y * (2.0f / static_cast<float>(h)) - 1.0f,
            z_window * 2.0f - 1.0f, 1.0f};
}

std::vector<std::uint32_t> snapshot(const raster::DepthTarget& t) { return {t.values().begin(), t.values().end()}; }

}  // namespace

TEST_CASE("Depth targets of zero, negative or oversized size are refused with the limit named") {
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{0, 5}, {5, 0}, {-1, 4}, {16385, 1}, {1, 100000}}) {
        CAPTURE(w);
        CAPTURE(h);
        auto t = raster::DepthTarget::create(w, h, DepthFormat::D24);
        REQUIRE_FALSE(t.ok());
        CHECK(t.error().message.find("16384") != std::string::npos);
    }
    auto ok = raster::DepthTarget::create(16384, 1, DepthFormat::D16);
    CHECK(ok.ok());
}

TEST_CASE("Clear stores GL's encodings of 0, 1/2 and 1 and refuses a non-finite depth") {
    auto t = raster::DepthTarget::create(3, 2, DepthFormat::D24).value();
    CHECK(t.value(0, 0) == 0xffffffu);  // created cleared to 1.0
    REQUIRE(t.clear(0.5).ok());
    CHECK(t.value(2, 1) == 8388608u);  // round(0.5 * (2^24 - 1)) = 8388607.5 -> 8388608 (half to even)
    REQUIRE(t.clear(0.0).ok());
    CHECK(t.value(1, 1) == 0u);
    const auto before = snapshot(t);
    CHECK_FALSE(t.clear(std::numeric_limits<double>::quiet_NaN()).ok());
    CHECK(snapshot(t) == before);
    auto f = raster::DepthTarget::create(2, 2, DepthFormat::D32F).value();
    REQUIRE(f.clear(0.25).ok());
    CHECK(f.depth(1, 1) == 0.25);
    auto s = raster::DepthTarget::create(2, 2, DepthFormat::D16).value();
    REQUIRE(s.clear(2.0).ok());  // clamped to 1
    CHECK(s.value(0, 0) == 0xffffu);
}

TEST_CASE("CommandBatch::reset empties the batch and takes the new size and rules: it runs as a new batch") {
    const std::vector<raster::Float4> v = {{-0.9f, -0.8f, 0.1f, 1}, {0.7f, -0.6f, 0.2f, 1}, {0.1f, 0.9f, -0.3f, 1}};
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    raster::CommandBatch reused(40, 30, raster::RasterRules::Vulkan);
    reused.begin_query(raster::QueryKind::AnySamplesPassed);
    reused.draw(raster::MeshView{v, idx}, raster::DrawState{});
    reused.end_query();
    reused.reset(24, 20, raster::RasterRules::GlLlvmpipe);
    CHECK(reused.commands().empty());
    CHECK(reused.query_kinds().empty());
    CHECK(reused.target_width() == 24);
    CHECK(reused.target_height() == 20);
    CHECK(reused.rules() == raster::RasterRules::GlLlvmpipe);
    raster::CommandBatch fresh(24, 20);
    for (raster::CommandBatch* b : {&reused, &fresh}) {
        b->begin_query(raster::QueryKind::SamplesPassed);
        b->draw(raster::MeshView{v, idx}, raster::DrawState{});
        b->end_query();
    }
    auto ta = raster::DepthTarget::create(24, 20, DepthFormat::D24).value();
    auto tb = raster::DepthTarget::create(24, 20, DepthFormat::D24).value();
    const auto ra = raster::execute(ta, reused);
    const auto rb = raster::execute(tb, fresh);
    REQUIRE(ra.ok());
    REQUIRE(rb.ok());
    CHECK(ra.value() == rb.value());
    CHECK(ra.value().at(0) > 0);  // the query saw the triangle
    CHECK(snapshot(ta) == snapshot(tb));
}

TEST_CASE("Bad batches are rejected before anything is drawn and name the element") {
    const int W = 16, H = 16;
    auto target = raster::DepthTarget::create(W, H, DepthFormat::D24).value();
    REQUIRE(target.clear(1.0).ok());
    const std::vector<Float4> good = {px(1, 1, 0.5f, W, H), px(15, 1, 0.5f, W, H), px(1, 15, 0.5f, W, H)};
    const std::vector<std::uint32_t> tri = {0, 1, 2};
    const auto before = snapshot(target);

    auto expect_error = [&](raster::CommandBatch& b, const std::string& needle) {
        CAPTURE(needle);
        auto r = raster::execute(target, b);
        REQUIRE_FALSE(r.ok());
        CHECK(r.error().message.find(needle) != std::string::npos);
        auto r2 = raster::execute_reference(target, b);
        REQUIRE_FALSE(r2.ok());
        CHECK(snapshot(target) == before);
    };

    {  // a valid draw first, then an out-of-range index: nothing may be drawn
        raster::CommandBatch b(W, H);
        b.draw({good, tri}, {});
        const std::vector<std::uint32_t> bad = {0, 1, 7};
        b.draw({good, bad}, {});
        expect_error(b, "index 7 at position 2 is beyond the vertex list (size 3)");
    }
    {
        raster::CommandBatch b(W, H);
        const std::vector<std::uint32_t> two = {0, 1};
        b.draw({good, two}, {});
        expect_error(b, "not a multiple of 3");
    }
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        raster::CommandBatch b(W, H);
        std::vector<Float4> v = good;
        v[1].y = bad;
        b.draw({v, tri}, {});
        expect_error(b, "vertex 1 is not finite");
    }
    {
        raster::CommandBatch b(W, H);
        std::vector<Float4> v = good;
        v[2] = {0.0f, 0.0f, 0.0f, 0.0f};
        b.draw({v, tri}, {});
        expect_error(b, "vertex 2 is (0, 0, 0, 0)");
    }
    {
        raster::CommandBatch b(W + 1, H);
        b.draw({good, tri}, {});
        expect_error(b, "built for a 17x16 target but the target is 16x16");
    }
    {
        raster::CommandBatch b(W, H);
        raster::DrawState s;
        s.viewport = raster::Viewport{0, 0, 0, 4};
        b.draw({good, tri}, s);
        expect_error(b, "viewport");
        raster::CommandBatch b2(W, H);
        s.viewport = raster::Viewport{0, 0, 20000, 4};
        b2.draw({good, tri}, s);
        expect_error(b2, "viewport");
    }
    {
        raster::CommandBatch b(W, H);
        b.begin_query(raster::QueryKind::SamplesPassed);
        b.begin_query(raster::QueryKind::SamplesPassed);
        expect_error(b, "queries do not nest");
        raster::CommandBatch b2(W, H);
        b2.end_query();
        expect_error(b2, "without an active query");
        raster::CommandBatch b3(W, H);
        b3.begin_query(raster::QueryKind::SamplesPassed);
        b3.draw({good, tri}, {});
        expect_error(b3, "still active");
    }
}

TEST_CASE("Shared vertex lists: validation names a used bad vertex whatever earlier draws checked, and ignores unused ones") {
    // command_batch.cpp checks a whole vertex list once per batch when it can (ListMemo) and falls
    // back to the per-index loop; the answers must be the per-index rules' in every order.
    const int W = 16, H = 16;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<Float4> v = {px(1, 1, 0.5f, W, H), px(15, 1, 0.5f, W, H), px(1, 15, 0.5f, W, H), {nan, 0.0f, 0.0f, 1.0f}};
    const std::vector<std::uint32_t> tri = {0, 1, 2}, uses_bad = {0, 1, 3};
    const std::span<const Float4> all(v), first3 = std::span<const Float4>(v).first(3);
    auto run = [&](const raster::CommandBatch& b, const raster::ExecuteOptions& o, bool reference) {
        auto t = raster::DepthTarget::create(W, H, DepthFormat::D24).value();
        REQUIRE(t.clear(1.0).ok());
        auto r = reference ? raster::execute_reference(t, b, o) : raster::execute(t, b, o);
        return std::make_pair(r.ok() ? std::string{} : r.error().message, snapshot(t));
    };
    for (const auto mode : {raster::RasterMode::GLExact, raster::RasterMode::ExactBounds}) {
        CAPTURE(static_cast<int>(mode));
        raster::DrawState s;
        s.mode = mode;
        s.depth_func = raster::DepthFunc::Always;
        // Unused bad vertex: accepted, and the same depths as the list without it.
        raster::CommandBatch with_bad(W, H), without(W, H);
        for (int k = 0; k < 5; ++k) {
            with_bad.draw({all, tri}, s);
            without.draw({first3, tri}, s);
        }
        for (const bool reference : {false, true}) {
            const auto a = run(with_bad, {}, reference), b = run(without, {}, reference);
            CHECK(a.first.empty());
            CHECK(b.first.empty());
            CHECK(a.second == b.second);
        }
        // The bad vertex used after many draws of the list (whole-list check failed) and after
        // draws of its first three vertices (the list known valid, but shorter): named either way.
        for (const bool prefix : {false, true}) {
            raster::CommandBatch b(W, H);
            for (int k = 0; k < 20; ++k) b.draw({prefix ? first3 : all, tri}, s);
            b.draw({all, uses_bad}, s);
            for (const bool reference : {false, true}) {
                const auto r = run(b, {}, reference);
                CAPTURE(r.first);
                CHECK(r.first.find("command 20: vertex 3 ") != std::string::npos);
            }
        }
        // An index beyond the list after the list was found valid.
        raster::CommandBatch b(W, H);
        for (int k = 0; k < 20; ++k) b.draw({first3, tri}, s);
        const std::vector<std::uint32_t> beyond = {0, 1, 3};
        b.draw({first3, beyond}, s);
        CHECK(run(b, {}, false).first.find("command 20: index 3 at position 2 is beyond the vertex list (size 3)") !=
              std::string::npos);
    }
    // Double input (exact bounds): w != 1 on a used vertex is named after the list was checked.
    std::vector<raster::Double4> d = {{-0.5, -0.5, 0.5, 1.0}, {0.5, -0.5, 0.5, 1.0}, {0.0, 0.5, 0.5, 1.0}, {0.0, 0.0, 0.0, 2.0}};
    raster::DrawState s;
    s.mode = raster::RasterMode::ExactBounds;
    raster::CommandBatch ok_batch(W, H), bad_batch(W, H);
    for (int k = 0; k < 8; ++k) {
        ok_batch.draw(raster::MeshViewD{d, tri}, s);
        bad_batch.draw(raster::MeshViewD{d, tri}, s);
    }
    bad_batch.draw(raster::MeshViewD{d, uses_bad}, s);
    CHECK(run(ok_batch, {}, false).first.empty());
    CHECK(run(bad_batch, {}, false).first.find("command 8: vertex 3 has w = 2") != std::string::npos);
}

TEST_CASE("Sequences: every bad vertex rule is named after the list's whole-list check, and the first problem in order") {
    // The whole-list check (command_batch.cpp's gl_list_valid, run once a list's allowance allows)
    // must refuse each rule's offence, or the memo would accept the list and a later draw of the
    // bad vertex would run; lists found valid are kept across a sequence's batches.
    const int W = 16, H = 16;
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const std::vector<Float4> bad_vertices = {{nan, 0, 0, 1}, {0, nan, 0, 1},  {0, 0, nan, 1},  {0, 0, 0, nan},
                                              {inf, 0, 0, 1}, {0, -inf, 0, 1}, {0, 0, inf, 1},  {0, 0, 0, inf},
                                              {0, 0, 0, 0},   {-0.0f, 0, -0.0f, -0.0f}};
    const std::vector<std::uint32_t> tri = {0, 1, 2}, uses_bad = {0, 1, 3};
    raster::DrawState s;
    s.depth_func = DepthFunc::Always;
    auto run = [&](std::span<const raster::CommandBatch* const> batches) {
        auto t = raster::DepthTarget::create(W, H, DepthFormat::D24).value();
        auto r = raster::execute_sequence(t, batches, raster::ExecuteOptions{1, true});
        return r.ok() ? std::string{} : r.error().message;
    };
    for (std::size_t b = 0; b < bad_vertices.size(); ++b) {
        CAPTURE(b);
        const std::vector<Float4> v = {px(1, 1, 0.5f, W, H), px(15, 1, 0.5f, W, H), px(1, 15, 0.5f, W, H),
                                       bad_vertices[b]};
        // Batch 0 draws the good vertices often enough for the whole list to be checked; batch 1
        // then draws the bad one.
        raster::CommandBatch first(W, H), second(W, H);
        for (int k = 0; k < 20; ++k) first.draw({v, tri}, s);
        second.draw({v, uses_bad}, s);
        const raster::CommandBatch* const both[2] = {&first, &second};
        const std::string e = run(both);
        CAPTURE(e);
        CHECK(e.find("execute_sequence: batch 1: command 0: vertex 3 ") != std::string::npos);
        CHECK(run(std::span<const raster::CommandBatch* const>(both, 1)).empty());
    }
    // Nine lists drawn in turn (more than the memo keeps), the last one's bad vertex used last.
    std::vector<std::vector<Float4>> lists(9, {px(1, 1, 0.5f, W, H), px(15, 1, 0.5f, W, H), px(1, 15, 0.5f, W, H),
                                               Float4{0, 0, 0, 0}});
    raster::CommandBatch many(W, H);
    for (int round = 0; round < 12; ++round)
        for (const auto& l : lists) many.draw({l, tri}, s);
    many.draw({lists.back(), uses_bad}, s);
    const raster::CommandBatch* const one[1] = {&many};
    CHECK(run(one).find("command 108: vertex 3 is (0, 0, 0, 0)") != std::string::npos);
    // The first problem in order: a bad batch before a null one, a null one before a bad one.
    const std::vector<Float4> good = {px(1, 1, 0.5f, W, H), px(15, 1, 0.5f, W, H), px(1, 15, 0.5f, W, H)};
    raster::CommandBatch ok_batch(W, H), bad_batch(W, H);
    ok_batch.draw({good, tri}, s);
    bad_batch.draw({good, uses_bad}, s);
    const raster::CommandBatch* const bad_then_null[3] = {&ok_batch, &bad_batch, nullptr};
    CHECK(run(bad_then_null).find("execute_sequence: batch 1: command 0: index 3 at position 2") != std::string::npos);
    const raster::CommandBatch* const null_then_bad[3] = {&ok_batch, nullptr, &bad_batch};
    CHECK(run(null_then_bad) == "execute_sequence: batch 1 is null");
}

TEST_CASE("next_down / next_up (float_step.h) equal std::nextafter on every exponent, zeros, subnormals and the extremes") {
    raster_test::SplitMix64 rng(0x57e9u);
    std::vector<float> values = {0.0f, -0.0f, std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min(),
                                 -std::numeric_limits<float>::min(), std::numeric_limits<float>::max(),
                                 -std::numeric_limits<float>::max(), 1.0f, -1.0f};
    for (std::uint32_t exponent = 0; exponent < 255; ++exponent) {  // every finite exponent, both signs
        for (int k = 0; k < 2000; ++k) {
            std::uint32_t mantissa = static_cast<std::uint32_t>(rng.next()) & 0x7fffffu;
            if (k == 0) mantissa = 0;
            if (k == 1) mantissa = 0x7fffffu;
            const std::uint32_t bits = (exponent << 23) | mantissa | (k % 2 == 0 ? 0u : 0x80000000u);
            values.push_back(std::bit_cast<float>(bits));
        }
    }
    std::size_t differ = 0;
    float first_bad = 0.0f;
    for (const float f : values) {
        const float down = raster::detail::next_down(f), up = raster::detail::next_up(f);
        const float want_down = std::nextafter(f, -HUGE_VALF), want_up = std::nextafter(f, HUGE_VALF);
        if (std::bit_cast<std::uint32_t>(down) != std::bit_cast<std::uint32_t>(want_down) ||
            std::bit_cast<std::uint32_t>(up) != std::bit_cast<std::uint32_t>(want_up)) {
            if (differ == 0) first_bad = f;
            ++differ;
        }
    }
    CHECK(values.size() > 500000);
    CAPTURE(first_bad);
    CHECK(differ == 0);
}

TEST_CASE("lrint32 (float_step.h) equals std::lrint below 2^31, ties and the default rounding mode included") {
    raster_test::SplitMix64 rng(0x1a1bu);
    std::vector<float> values = {0.0f, -0.0f, 0.5f, -0.5f, 1.5f, -1.5f, 2.5f, -2.5f, 0.49999997f, -0.49999997f,
                                 0x1p30f, -0x1p30f, 2147483520.0f, -2147483648.0f,
                                 std::numeric_limits<float>::denorm_min()};
    // Every exponent below 2^31, random mantissas, and the halfway points of the exponents where
    // floats still have a fraction (the ties of round half to even).
    for (std::uint32_t exponent = 0; exponent < 127 + 31; ++exponent) {
        for (int k = 0; k < 2000; ++k) {
            const std::uint32_t mantissa = static_cast<std::uint32_t>(rng.next()) & 0x7fffffu;
            values.push_back(std::bit_cast<float>((exponent << 23) | mantissa | (k % 2 == 0 ? 0u : 0x80000000u)));
        }
    }
    for (int i = -5000; i <= 5000; ++i) values.push_back(static_cast<float>(i) + 0.5f);
    std::size_t differ = 0;
    float first_bad = 0.0f;
    for (const float f : values) {
        if (raster::detail::lrint32(f) != std::lrint(f)) {
            if (differ == 0) first_bad = f;
            ++differ;
        }
    }
    CHECK(values.size() > 300000);
    CHECK(raster::detail::lrint32(2.5f) == 2);   // half to even, not away from zero
    CHECK(raster::detail::lrint32(-3.5f) == -4);
    CAPTURE(first_bad);
    CHECK(differ == 0);
}

TEST_CASE("Two triangles sharing a diagonal cover a pixel-aligned square exactly once") {
    // Square [2, 10] x [3, 11] in pixels: centres x + 0.5 for x = 2..9, y = 3..10: 64 pixels.
    // The diagonal passes through pixel centres; the fill rule must give each to one triangle.
    const int W = 16, H = 16;
    for (const auto fmt : {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F}) {
        auto t = raster::DepthTarget::create(W, H, fmt).value();
        const std::vector<Float4> v = {px(2, 3, 0.5f, W, H), px(10, 3, 0.5f, W, H), px(10, 11, 0.5f, W, H),
                                       px(2, 11, 0.5f, W, H)};
        const std::vector<std::uint32_t> a = {0, 1, 2}, b = {0, 2, 3};
        raster::CommandBatch batch(W, H);
        raster::DrawState s;
        s.depth_func = DepthFunc::Always;
        s.depth_write = false;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({v, a}, s);
        batch.end_query();
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({v, b}, s);
        batch.end_query();
        auto r = raster::execute(t, batch);
        REQUIRE(r.ok());
        CHECK(r.value()[0] + r.value()[1] == 64);
        // Lower-right triangle: pixels with centre on or below the diagonal y - 3 = x - 2... the
        // diagonal (2,3)-(10,11) holds 8 centres; they go to exactly one of the two triangles.
        CHECK((r.value()[0] == 28 || r.value()[0] == 36));
    }
}

TEST_CASE("Left and bottom edges through pixel centres are covered, right and top edges are not") {
    // Axis-aligned square with corners on pixel centres: [2.5, 6.5] x [3.5, 7.5]. Centres on the left
    // edge (x = 2.5) and the bottom edge (y = 3.5) count; right (x = 6.5) and top (y = 7.5) do not:
    // 4 x 4 = 16 pixels, x = 2..5, y = 3..6.
    const int W = 16, H = 16;
    auto t = raster::DepthTarget::create(W, H, DepthFormat::D24).value();
    const std::vector<Float4> v = {px(2.5f, 3.5f, 0.25f, W, H), px(6.5f, 3.5f, 0.25f, W, H),
                                   px(6.5f, 7.5f, 0.25f, W, H), px(2.5f, 7.5f, 0.25f, W, H)};
    const std::vector<std::uint32_t> idx = {0, 1, 2, 0, 2, 3};
    raster::CommandBatch batch(W, H);
    batch.begin_query(raster::QueryKind::SamplesPassed);
    batch.draw({v, idx}, {});
    batch.end_query();
    auto r = raster::execute_reference(t, batch);
    REQUIRE(r.ok());
    CHECK(r.value()[0] == 16);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const bool inside = x >= 2 && x <= 5 && y >= 3 && y <= 6;
            CAPTURE(x);
            CAPTURE(y);
            // z_window 0.25 in D24: round(0.25 * 16777215) = round(4194303.75) = 4194304.
            CHECK(t.value(x, y) == (inside ? 4194304u : 0xffffffu));
        }
}

TEST_CASE("Depth functions compare incoming with stored, and the write mask is honoured") {
    const int W = 8, H = 8;
    const std::vector<Float4> full = {{-1, -1, 0.0f, 1}, {3, -1, 0.0f, 1}, {-1, 3, 0.0f, 1}};  // covers all
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    struct Case {
        DepthFunc f;
        double clear;
        std::uint64_t want;
    };
    // Incoming depth is z_window = 0.5; stored clear values around it.
    const Case cases[] = {{DepthFunc::Never, 1.0, 0},   {DepthFunc::Always, 0.0, 64}, {DepthFunc::Less, 1.0, 64},
                          {DepthFunc::Less, 0.5, 0},    {DepthFunc::LEqual, 0.5, 64}, {DepthFunc::Equal, 0.5, 64},
                          {DepthFunc::Equal, 1.0, 0},   {DepthFunc::Greater, 0.5, 0}, {DepthFunc::GEqual, 0.5, 64},
                          {DepthFunc::NotEqual, 0.5, 0}, {DepthFunc::NotEqual, 0.0, 64}, {DepthFunc::Greater, 0.0, 64}};
    for (const auto fmt : {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F}) {
        for (const auto& c : cases) {
            CAPTURE(static_cast<int>(fmt));
            CAPTURE(static_cast<int>(c.f));
            CAPTURE(c.clear);
            for (const bool write : {false, true}) {
                auto t = raster::DepthTarget::create(W, H, fmt).value();
                REQUIRE(t.clear(c.clear).ok());
                raster::CommandBatch batch(W, H);
                raster::DrawState s;
                s.depth_func = c.f;
                s.depth_write = write;
                const auto q = batch.begin_query(raster::QueryKind::SamplesPassed);
                batch.draw({full, idx}, s);
                batch.end_query();
                const auto any = batch.begin_query(raster::QueryKind::AnySamplesPassed);
                batch.draw({full, idx}, s);
                batch.end_query();
                auto r = raster::execute(t, batch);
                REQUIRE(r.ok());
                CHECK(r.value()[q] == c.want);
                const bool changed = write && c.want > 0 && c.clear != 0.5;
                CHECK(t.depth(3, 3) == doctest::Approx(changed ? 0.5 : c.clear).epsilon(1e-4));
                if (!write) CHECK(r.value()[any] == (c.want > 0 ? 1u : 0u));
            }
        }
    }
}

TEST_CASE("Triangles behind the eye or beyond the far plane draw nothing: crossing ones are clipped") {
    const int W = 32, H = 32;
    auto t = raster::DepthTarget::create(W, H, DepthFormat::D32F).value();
    const std::vector<Float4> behind = {{-1, -1, -2, -1}, {1, -1, -2, -1}, {0, 1, -2, -1}};  // w < 0
    const std::vector<Float4> far = {{-1, -1, 2, 1}, {1, -1, 2, 1}, {0, 1, 2, 1}};          // z > w
    // Crossing the near plane (z = -w at x = 0): the left half is in front of it.
    const std::vector<Float4> crossing = {{-1, -1, 0.9f, 1}, {1, -1, -3.0f, 1}, {-1, 1, 0.9f, 1}};
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    raster::CommandBatch batch(W, H);
    raster::DrawState s;
    s.depth_func = DepthFunc::Always;
    for (const auto* m : {&behind, &far, &crossing}) {
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({*m, idx}, s);
        batch.end_query();
    }
    auto r = raster::execute(t, batch);
    REQUIRE(r.ok());
    CHECK(r.value()[0] == 0);
    CHECK(r.value()[1] == 0);
    // Unclipped the triangle would cover the lower-left half (496 of 1024 centres); clipped at the
    // near plane, only pixels with z_ndc >= -1 remain, and every written depth is inside [0, 1].
    CHECK(r.value()[2] > 0);
    CHECK(r.value()[2] < 496);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double d = t.depth(x, y);
            CHECK((d >= 0.0 && d <= 1.0));
        }
}

TEST_CASE("Back-face culling drops clockwise triangles by default and front-face culling the others") {
    const int W = 8, H = 8;
    const std::vector<Float4> ccw = {{-1, -1, 0, 1}, {3, -1, 0, 1}, {-1, 3, 0, 1}};
    const std::vector<Float4> cw = {{-1, -1, 0, 1}, {-1, 3, 0, 1}, {3, -1, 0, 1}};
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    auto t = raster::DepthTarget::create(W, H, DepthFormat::D24).value();
    raster::CommandBatch batch(W, H);
    for (const auto cull : {raster::CullFace::Back, raster::CullFace::Front}) {
        for (const auto* m : {&ccw, &cw}) {
            raster::DrawState s;
            s.depth_func = DepthFunc::Always;
            s.depth_write = false;
            s.cull_face = cull;
            batch.begin_query(raster::QueryKind::SamplesPassed);
            batch.draw({*m, idx}, s);
            batch.end_query();
        }
    }
    auto r = raster::execute(t, batch);
    REQUIRE(r.ok());
    CHECK(r.value() == raster::QueryResults{64, 0, 0, 64});
}

TEST_CASE("Orthographic and perspective helpers match the GL formulas and refuse bad parameters") {
    auto o = raster::ortho(-2, 2, -1, 1, 1, 3);
    REQUIRE(o.ok());
    const std::vector<raster::Double3> pts = {{2, 1, -1}, {-2, -1, -3}, {0, 0, -2}};
    auto c = raster::transform_to_clip(o.value(), pts);
    REQUIRE(c.ok());
    CHECK(c.value()[0].x == 1.0f);
    CHECK(c.value()[0].y == 1.0f);
    CHECK(c.value()[0].z == -1.0f);  // the near plane maps to z_ndc = -1
    CHECK(c.value()[1].z == 1.0f);   // the far plane to +1
    CHECK(c.value()[2].z == 0.0f);
    CHECK(c.value()[2].w == 1.0f);
    auto p = raster::perspective(90.0, 1.0, 1.0, 10.0);
    REQUIRE(p.ok());
    const std::vector<raster::Double3> q = {{0, 0, -1}, {0, 0, -10}, {1, 1, -1}};
    auto pc = raster::transform_to_clip(p.value(), q);
    REQUIRE(pc.ok());
    CHECK(pc.value()[0].z / pc.value()[0].w == doctest::Approx(-1.0));
    CHECK(pc.value()[1].z / pc.value()[1].w == doctest::Approx(1.0));
    CHECK(pc.value()[2].x / pc.value()[2].w == doctest::Approx(1.0));  // 45 degrees half-angle
    CHECK_FALSE(raster::ortho(1, 1, 0, 1, 0, 1).ok());
    CHECK_FALSE(raster::perspective(180.0, 1.0, 1.0, 2.0).ok());
    CHECK_FALSE(raster::perspective(60.0, 1.0, 0.0, 2.0).ok());
    const std::vector<raster::Double3> bad = {{0, 0, 0}, {std::nan(""), 0, 0}};
    auto e = raster::transform_to_clip(raster::Mat4::identity(), bad);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message.find("point 1") != std::string::npos);
}

TEST_CASE("Vulkan rules: z in [0, w] maps to depth unscaled, z < 0 is clipped, CCW is the other winding") {
    // Hand-derived from the Vulkan rules at the top of raster/raster.h.
    const int W = 8, H = 8;
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    // A triangle covering the whole target at clip z = 0.25 (w = 1): window depth 0.25 exactly under
    // Vulkan (fma(0.25, 1, 0)); under GL the same z would be 0.625.
    const std::vector<Float4> flat = {{-1, -1, 0.25f, 1}, {3, -1, 0.25f, 1}, {-1, 3, 0.25f, 1}};
    // z = -0.5 everywhere: inside GL's volume (-w <= z), outside Vulkan's (z >= 0).
    const std::vector<Float4> behind_near = {{-1, -1, -0.5f, 1}, {3, -1, -0.5f, 1}, {-1, 3, -0.5f, 1}};
    for (const auto rules : {raster::RasterRules::Vulkan, raster::RasterRules::GlLlvmpipe}) {
        auto t = raster::DepthTarget::create(W, H, DepthFormat::D32F).value();
        raster::CommandBatch batch(W, H, rules);
        raster::DrawState s;
        s.depth_func = DepthFunc::Always;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({behind_near, idx}, s);
        batch.end_query();
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({flat, idx}, s);
        batch.end_query();
        auto r = raster::execute(t, batch);
        REQUIRE(r.ok());
        const bool vk = rules == raster::RasterRules::Vulkan;
        CHECK(r.value() == raster::QueryResults{vk ? 0u : 64u, 64});
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) CHECK(t.depth(x, y) == (vk ? 0.25 : 0.625));
    }
    // Crossing Vulkan's near plane at x = 0 (z = 0 there): only the left half (z >= 0) remains.
    {
        auto t = raster::DepthTarget::create(W, H, DepthFormat::D32F).value();
        const std::vector<Float4> crossing = {{-1, -1, 0.5f, 1}, {1, -1, -0.5f, 1}, {1, 1, -0.5f, 1},
                                              {-1, 1, 0.5f, 1}};
        const std::vector<std::uint32_t> quad = {0, 1, 2, 0, 2, 3};
        raster::CommandBatch batch(W, H, raster::RasterRules::Vulkan);
        raster::DrawState s;
        s.depth_func = DepthFunc::Always;
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({crossing, quad}, s);
        batch.end_query();
        auto r = raster::execute(t, batch);
        REQUIRE(r.ok());
        CHECK(r.value()[0] == 32);  // columns 0..3 of 8, every row
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) CHECK((x < 4) == (t.depth(x, y) < 1.0));
    }
    // Facing: GL's counter-clockwise triangle (y up) is clockwise on Vulkan's y-down framebuffer, so
    // FrontFace::CCW + back-face culling keeps the other one.
    {
        const std::vector<Float4> gl_ccw = {{-1, -1, 0, 1}, {3, -1, 0, 1}, {-1, 3, 0, 1}};
        const std::vector<Float4> gl_cw = {{-1, -1, 0, 1}, {-1, 3, 0, 1}, {3, -1, 0, 1}};
        auto t = raster::DepthTarget::create(W, H, DepthFormat::D24).value();
        raster::CommandBatch batch(W, H, raster::RasterRules::Vulkan);
        for (const auto* m : {&gl_ccw, &gl_cw}) {
            raster::DrawState s;
            s.depth_func = DepthFunc::Always;
            s.depth_write = false;
            s.cull_face = raster::CullFace::Back;
            batch.begin_query(raster::QueryKind::SamplesPassed);
            batch.draw({*m, idx}, s);
            batch.end_query();
        }
        auto r = raster::execute(t, batch);
        REQUIRE(r.ok());
        CHECK(r.value() == raster::QueryResults{0, 64});
    }
}
