// threads_test.cpp: the tiled executor equals the scalar reference bit for bit, for 1, 2, 3 and 8
// threads, on random scenes (no OSMesa needed: the reference is the independent twin); its clears
// (clear_depth, written_blocks, the target's fast clear) equal full clears.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "raster/raster.h"
#include "scene_gen.h"
#include "thread_runs.h"

namespace {

std::uint64_t fnv1a(std::uint64_t h, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
        h ^= (v >> (8 * i)) & 0xffu;
        h *= 0x100000001b3ull;
    }
    return h;
}

}  // namespace

TEST_CASE("The tiled executor matches the scalar reference for 1, 2, 3 and 8 threads, and on the spread schedule") {
    const raster::DepthFormat formats[] = {raster::DepthFormat::D16, raster::DepthFormat::D24,
                                           raster::DepthFormat::D32F};
    struct Size {
        int w, h;
    };
    const Size sizes[] = {{64, 64}, {200, 130}, {333, 77}};
    raster_test::SplitMix64 rng(77);
    for (const auto f : formats) {
        for (const auto& sz : sizes) {
            for (int rep = 0; rep < 6; ++rep) {
                CAPTURE(static_cast<int>(f));
                CAPTURE(sz.w);
                CAPTURE(rep);
                raster_test::Scene scene;
                raster_test::SceneOptions o;
                o.width = sz.w;
                o.height = sz.h;
                o.objects = 150;
                raster_test::build_scene(scene, rng, o);
                auto ref = raster::DepthTarget::create(sz.w, sz.h, f);
                REQUIRE(ref.ok());
                REQUIRE(ref.value().clear(scene.clear_depth).ok());
                auto want = raster::execute_reference(ref.value(), scene.batch);
                REQUIRE(want.ok());
                std::uint64_t covered = 0;
                for (auto v : want.value()) covered += v;
                for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
                    const int threads = run.threads;
                    const bool spread = run.spread;
                    CAPTURE(threads);
                    CAPTURE(spread);
                    const raster::detail::SpreadScheduleScope schedule(spread);
                    auto t = raster::DepthTarget::create(sz.w, sz.h, f);
                    REQUIRE(t.ok());
                    REQUIRE(t.value().clear(scene.clear_depth).ok());
                    auto got = raster::execute(t.value(), scene.batch, raster::ExecuteOptions{threads});
                    REQUIRE(got.ok());
                    CHECK(got.value() == want.value());
                    std::uint64_t h1 = 1469598103934665603ull, h2 = h1;
                    for (auto v : t.value().values()) h1 = fnv1a(h1, v);
                    for (auto v : ref.value().values()) h2 = fnv1a(h2, v);
                    CHECK(h1 == h2);
                }
                CHECK(covered > 0);  // the scenes are not trivially empty
            }
        }
    }
}

TEST_CASE("Repeated runs of the tiled executor give the same bits") {
    raster_test::SplitMix64 rng(99);
    raster_test::Scene scene;
    raster_test::SceneOptions o;
    o.width = 256;
    o.height = 256;
    o.objects = 300;
    raster_test::build_scene(scene, rng, o);
    std::uint64_t first_hash = 0;
    raster::QueryResults first;
    for (int run = 0; run < 4; ++run) {
        auto t = raster::DepthTarget::create(256, 256, raster::DepthFormat::D24);
        REQUIRE(t.ok());
        auto r = raster::execute(t.value(), scene.batch, raster::ExecuteOptions{1 + run * 2});
        REQUIRE(r.ok());
        std::uint64_t h = 1469598103934665603ull;
        for (auto v : t.value().values()) h = fnv1a(h, v);
        if (run == 0) {
            first_hash = h;
            first = r.value();
        } else {
            CHECK(h == first_hash);
            CHECK(r.value() == first);
        }
    }
}

TEST_CASE("The AVX2+FMA kernel and the portable kernel give the same bits") {
    raster_test::SplitMix64 rng(2024);
    for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
        for (int rep = 0; rep < 4; ++rep) {
            CAPTURE(static_cast<int>(f));
            CAPTURE(rep);
            raster_test::Scene scene;
            raster_test::SceneOptions o;
            o.width = 300;
            o.height = 200;
            o.objects = 200;
            raster_test::build_scene(scene, rng, o);
            auto a = raster::DepthTarget::create(300, 200, f).value();
            auto b = raster::DepthTarget::create(300, 200, f).value();
            auto ra = raster::execute_reference(a, scene.batch, raster::ExecuteOptions{1, false});
            auto rb = raster::execute(b, scene.batch, raster::ExecuteOptions{2, true});
            REQUIRE(ra.ok());
            REQUIRE(rb.ok());
            CHECK(ra.value() == rb.value());
            const auto va = a.values(), vb = b.values();
            CHECK(std::equal(va.begin(), va.end(), vb.begin(), vb.end()));
        }
    }
}

TEST_CASE("Draws of the same spans share their setup only when the front-end state is equal") {
    // One mesh drawn under several culling / facing / viewport states in one batch (the executor
    // shares a setup list between draws of the same spans and state): each query must equal the
    // reference's and the answer of a batch that draws separate copies of the mesh (no sharing).
    raster_test::SplitMix64 rng(4242);
    std::vector<raster::Float4> v;
    std::vector<std::uint32_t> idx;
    for (int t = 0; t < 60; ++t) {
        for (int k = 0; k < 3; ++k) {
            idx.push_back(static_cast<std::uint32_t>(v.size()));
            v.push_back({rng.uniform(-1.1f, 1.1f), rng.uniform(-1.1f, 1.1f), rng.uniform(-0.9f, 0.9f), 1});
        }
    }
    struct St {
        raster::CullFace cull;
        raster::FrontFace front;
        bool sub_viewport;
    };
    const St states[] = {{raster::CullFace::None, raster::FrontFace::CCW, false},
                         {raster::CullFace::Back, raster::FrontFace::CCW, false},
                         {raster::CullFace::Front, raster::FrontFace::CCW, false},
                         {raster::CullFace::Back, raster::FrontFace::CW, false},
                         {raster::CullFace::None, raster::FrontFace::CCW, true},
                         {raster::CullFace::None, raster::FrontFace::CCW, false}};
    std::vector<std::vector<raster::Float4>> copies(std::size(states), v);
    raster::CommandBatch shared(150, 100), separate(150, 100);
    for (std::size_t i = 0; i < std::size(states); ++i) {
        raster::DrawState s;
        s.depth_write = false;
        s.depth_func = raster::DepthFunc::Always;
        s.cull_face = states[i].cull;
        s.front_face = states[i].front;
        if (states[i].sub_viewport) s.viewport = raster::Viewport{10, 5, 90, 70};
        shared.begin_query(raster::QueryKind::SamplesPassed);
        shared.draw(raster::MeshView{v, idx}, s);
        shared.end_query();
        separate.begin_query(raster::QueryKind::SamplesPassed);
        separate.draw(raster::MeshView{copies[i], idx}, s);
        separate.end_query();
    }
    auto a = raster::DepthTarget::create(150, 100, raster::DepthFormat::D24).value();
    auto b = raster::DepthTarget::create(150, 100, raster::DepthFormat::D24).value();
    auto c = raster::DepthTarget::create(150, 100, raster::DepthFormat::D24).value();
    const auto want = raster::execute_reference(a, shared);
    const auto got = raster::execute(b, shared, raster::ExecuteOptions{2});
    const auto sep = raster::execute(c, separate, raster::ExecuteOptions{2});
    REQUIRE(want.ok());
    REQUIRE(got.ok());
    REQUIRE(sep.ok());
    CHECK(got.value() == want.value());
    CHECK(sep.value() == want.value());
    // The states really differ (culling and the viewport change the counts): not a vacuous check.
    CHECK(want.value()[0] != want.value()[1]);
    CHECK(want.value()[1] != want.value()[2]);
    CHECK(want.value()[0] != want.value()[4]);
    CHECK(want.value()[0] == want.value()[5]);
}

// The bit of pixel (x, y) in ExecuteOptions::written_blocks (tiles_x tiles per row).
namespace {
bool block_flagged(const std::vector<std::uint64_t>& flags, int tiles_x, int x, int y) {
    const std::uint64_t mask = flags[static_cast<std::size_t>(y / 64 * tiles_x + x / 64)];
    return ((mask >> ((y % 64) / 8 * 8 + (x % 64) / 8)) & 1u) != 0;
}
}  // namespace

TEST_CASE("written_blocks flags every block whose pixels a batch changed, and only blocks with passing writes") {
    raster_test::SplitMix64 rng(606);
    std::uint64_t changed_total = 0, unflagged_blocks = 0;
    for (int rep = 0; rep < 6; ++rep) {
        CAPTURE(rep);
        raster_test::Scene scene;
        raster_test::build_scene(scene, rng, {.width = 333, .height = 200, .objects = 80});
        auto t = raster::DepthTarget::create(333, 200, raster::DepthFormat::D24).value();
        const std::vector<std::uint32_t> before(t.values().begin(), t.values().end());
        std::vector<std::uint64_t> flags;
        raster::ExecuteOptions eo{1 + rep % 2};
        eo.written_blocks = &flags;
        REQUIRE(raster::execute(t, scene.batch, eo).ok());
        const int tiles_x = (333 + raster::kExecuteTileSize - 1) / raster::kExecuteTileSize;
        REQUIRE(flags.size() == static_cast<std::size_t>(tiles_x) * 4);
        for (int y = 0; y < 200; ++y)
            for (int x = 0; x < 333; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * 333 + static_cast<std::size_t>(x);
                if (x % 8 == 0 && y % 8 == 0 && !block_flagged(flags, tiles_x, x, y)) ++unflagged_blocks;
                if (t.values()[i] == before[i]) continue;
                ++changed_total;
                CHECK(block_flagged(flags, tiles_x, x, y));
            }
    }
    CHECK(changed_total > 1000);
    CHECK(unflagged_blocks > 0);  // not every block: the flags are finer than the tiles

    // One written triangle over the pixels [0, 19] x [0, 19] of the bottom-left tile, a query over the
    // whole target, and a writing draw that fails everywhere (NEVER): the blocks [0, 2] x [0, 2].
    std::vector<raster::Float4> small{{-1.0f, -1.0f, 0.0f, 1}, {-0.8f, -1.0f, 0.0f, 1}, {-1.0f, -0.8f, 0.0f, 1}};
    std::vector<raster::Float4> big{{-1, -1, 0.5f, 1}, {3, -1, 0.5f, 1}, {-1, 3, 0.5f, 1}};
    const std::vector<std::uint32_t> tri{0, 1, 2};
    raster::CommandBatch batch(200, 200);
    raster::DrawState w;
    batch.draw(raster::MeshView{small, tri}, w);
    raster::DrawState q;
    q.depth_write = false;
    batch.begin_query(raster::QueryKind::SamplesPassed);
    batch.draw(raster::MeshView{big, tri}, q);
    batch.end_query();
    raster::DrawState never;
    never.depth_func = raster::DepthFunc::Never;
    batch.draw(raster::MeshView{big, tri}, never);
    auto t = raster::DepthTarget::create(200, 200, raster::DepthFormat::D24).value();
    std::vector<std::uint64_t> flags(16, 0);
    raster::ExecuteOptions eo;
    eo.written_blocks = &flags;
    const auto r = raster::execute(t, batch, eo);
    REQUIRE(r.ok());
    CHECK(r.value()[0] > 30000);  // the query did cover the target
    std::vector<std::uint64_t> want(16, 0);
    want[0] = 0x070707;
    CHECK(flags == want);
}

// ExecuteOptions::clear_depth: each tile task fills its tile before drawing there. The reference is
// the plain DepthTarget::clear before each batch; the tiled runs start from a target holding
// unrelated values, so a tile left unfilled shows in the buffer and usually in the counts.
TEST_CASE("clear_depth gives the buffer and counts of DepthTarget::clear before each batch, with and without written_blocks") {
    const raster::DepthFormat formats[] = {raster::DepthFormat::D16, raster::DepthFormat::D24,
                                           raster::DepthFormat::D32F};
    raster_test::SplitMix64 rng(0xc1ea7);
    int scenes = 0;
    std::size_t blocks_skipped = 0;  // blocks the written_blocks runs did not fill (not flagged) ...
    std::size_t partial_tiles = 0;   // ... in tiles where others were filled
    for (int s = 0; s < 24; ++s) {
        raster_test::SceneOptions o;
        o.width = 40 + static_cast<int>(rng.next() % 200);  // 1 to 4 tiles per side, partial tiles
        o.height = 40 + static_cast<int>(rng.next() % 200);
        o.objects = 40;
        // Three batches, as CULLIDE's passes: each must start from the cleared target.
        raster_test::Scene batches[3];
        for (auto& b : batches) raster_test::build_scene(b, rng, o);
        const raster::DepthFormat format = formats[s % 3];
        const double clear_depth = (s % 4 == 0) ? 0.75 : 1.0;
        CAPTURE(s);
        CAPTURE(o.width);
        CAPTURE(o.height);
        // Reference: clear, execute_reference, per batch.
        auto ref = raster::DepthTarget::create(o.width, o.height, format);
        REQUIRE(ref.ok());
        std::vector<raster::QueryResults> want;
        for (auto& b : batches) {
            REQUIRE(ref.value().clear(clear_depth).ok());
            auto r = raster::execute_reference(ref.value(), b.batch);
            REQUIRE(r.ok());
            want.push_back(r.value());
        }
        const std::vector<std::uint32_t> want_depth(ref.value().values().begin(), ref.value().values().end());
        const raster::CommandBatch* seq[3] = {&batches[0].batch, &batches[1].batch, &batches[2].batch};
        // 3 threads run the batches as one sequence, the others one execute per batch.
        for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
            const int threads = run.threads;
            const bool spread = run.spread;
            if (threads == 8) continue;
            const raster::detail::SpreadScheduleScope schedule(spread);
            for (const bool with_written : {false, true}) {
                CAPTURE(threads);
                CAPTURE(spread);
                CAPTURE(with_written);
                auto t = raster::DepthTarget::create(o.width, o.height, format);
                REQUIRE(t.ok());
                for (auto& v : t.value().mutable_values()) v = static_cast<std::uint32_t>(rng.next()) & 0x3fffffffu;
                std::vector<std::uint64_t> written;  // empty: resized, every block flagged
                raster::ExecuteOptions eo{threads};
                eo.clear_depth = clear_depth;
                if (with_written) eo.written_blocks = &written;
                if (threads == 3) {
                    auto r = raster::execute_sequence(t.value(), seq, eo);
                    REQUIRE(r.ok());
                    CHECK(r.value() == want);
                } else {
                    for (std::size_t k = 0; k < 3; ++k) {
                        auto r = raster::execute(t.value(), *seq[k], eo);
                        REQUIRE(r.ok());
                        CHECK(r.value() == want[k]);
                        if (with_written && k < 2) {  // what the next call restores
                            const int tiles_x = (o.width + 63) / 64;
                            for (int y = 0; y < o.height; y += 8)
                                for (int x = 0; x < o.width; x += 8)
                                    blocks_skipped += block_flagged(written, tiles_x, x, y) ? 0 : 1;
                            for (const std::uint64_t m : written) partial_tiles += m != 0 && m != ~std::uint64_t{0} ? 1 : 0;
                        }
                    }
                }
                CHECK(std::equal(want_depth.begin(), want_depth.end(), t.value().values().begin(), t.value().values().end()));
            }
        }
        ++scenes;
    }
    CHECK(scenes == 24);
    CHECK(blocks_skipped > 0);  // the written_blocks runs did skip blocks that no draw wrote ...
    CHECK(partial_tiles > 0);   // ... beside blocks they filled in the same tile
}

TEST_CASE("A non-finite clear_depth is an error naming it, and changes nothing") {
    auto t = raster::DepthTarget::create(16, 16, raster::DepthFormat::D24);
    REQUIRE(t.ok());
    REQUIRE(t.value().clear(0.5).ok());
    const std::vector<raster::Float4> v = {{-1, -1, 0, 1}, {1, -1, 0, 1}, {0, 1, 0, 1}};
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    raster::CommandBatch batch(16, 16);
    batch.draw(raster::MeshView{v, idx}, raster::DrawState{});
    const std::vector<std::uint32_t> before(t.value().values().begin(), t.value().values().end());
    for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
        raster::ExecuteOptions eo{2};
        eo.clear_depth = bad;
        auto r = raster::execute(t.value(), batch, eo);
        REQUIRE_FALSE(r.ok());
        CHECK(r.error().message == "execute: clear_depth is not finite");
        auto rr = raster::execute_reference(t.value(), batch, eo);
        REQUIRE_FALSE(rr.ok());
        CHECK(rr.error().message.find("clear_depth") != std::string::npos);
        CHECK(std::vector<std::uint32_t>(t.value().values().begin(), t.value().values().end()) == before);
    }
}

// DepthTarget's fast clear (raster/depth_target.h): a clear, or an execute() with clear_depth,
// fills only the blocks that may differ from the value the target was last cleared to. Random
// sequences of every operation that touches a target (clears to the same and to other values,
// executes with and without clear_depth, sequences whose between() writes pixels, writes through
// mutable_values(), queries_only runs, the caller's own written_blocks) must give the counts and
// the buffer of a target that is filled in full at every clear and drawn by execute_reference.
TEST_CASE(
    "The fast clear: any sequence of clears, executes and writes gives the counts and buffer of full "
    "clears") {
    struct Size {
        int w, h;
    };
    const Size sizes[] = {{64, 64}, {200, 130}, {333, 77}, {70, 260}};
    const raster::DepthFormat formats[] = {raster::DepthFormat::D16, raster::DepthFormat::D24,
                                           raster::DepthFormat::D32F};
    const double clears[] = {1.0, 1.0, 1.0, 0.75, 0.0, 0.5};
    int compared = 0, value_changes = 0, writes = 0;
    for (std::size_t si = 0; si < std::size(sizes); ++si) {
        const Size sz = sizes[si];
        const raster::DepthFormat format = formats[si % 3];
        raster_test::SplitMix64 scene_rng(0xfa57c1ea + si);
        raster_test::SceneOptions so;
        so.width = sz.w;
        so.height = sz.h;
        so.objects = 30;
        raster_test::Scene pool[4];
        for (auto& sc : pool) raster_test::build_scene(sc, scene_rng, so);
        for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
            if (run.threads == 8) continue;
            const raster::detail::SpreadScheduleScope schedule(run.spread);
            CAPTURE(sz.w);
            CAPTURE(sz.h);
            CAPTURE(run.threads);
            CAPTURE(run.spread);
            raster_test::SplitMix64 rng(0x5eed + si);  // the same operations for every thread run
            auto made = raster::DepthTarget::create(sz.w, sz.h, format);
            auto made_ref = raster::DepthTarget::create(sz.w, sz.h, format);
            REQUIRE(made.ok());
            REQUIRE(made_ref.ok());
            raster::DepthTarget& t = made.value();
            raster::DepthTarget& ref = made_ref.value();  // filled by hand, drawn by execute_reference
            const auto fill_ref = [&](double depth) {
                const std::uint32_t v = raster::DepthTarget::encode_clear(depth, format);
                for (auto& x : ref.mutable_values()) x = v;
            };
            // A few pixels written behind the executor's back (valid values of the format).
            const auto write_pixels = [&](raster::DepthTarget& target, std::uint64_t seed) {
                raster_test::SplitMix64 w(seed);
                const std::span<std::uint32_t> a = target.mutable_values();
                for (int k = 0; k < 12; ++k) {
                    const std::size_t i = w.next() % a.size();
                    a[i] = static_cast<std::uint32_t>(w.next()) &
                           (format == raster::DepthFormat::D16 ? 0xffffu : 0x3f7fffffu);
                }
                ++writes;
            };
            bool defined = true;  // false after a queries_only run: the content is unspecified
            double last = 1.0;
            for (int step = 0; step < 30; ++step) {
                CAPTURE(step);
                int op = static_cast<int>(rng.below(7));
                if (!defined && op != 0 && op != 1 && op != 6) op = 1;  // only a clear makes it defined
                const double c = clears[rng.below(static_cast<std::uint32_t>(std::size(clears)))];
                value_changes += c != last && (op == 0 || op == 1 || op == 3 || op == 5 || op == 6) ? 1 : 0;
                const raster_test::Scene& sc = pool[rng.below(4)];
                CAPTURE(op);
                CAPTURE(c);
                raster::ExecuteOptions eo{run.threads};
                if (op == 0) {  // DepthTarget::clear
                    REQUIRE(t.clear(c).ok());
                    fill_ref(c);
                    last = c;
                    defined = true;
                } else if (op == 1 || op == 2 || op == 6) {  // execute: clearing (6: own list) or not
                    std::vector<std::uint64_t> own;          // empty: every block flagged
                    if (op != 2) eo.clear_depth = c;
                    if (op == 6) eo.written_blocks = &own;
                    auto r = raster::execute(t, sc.batch, eo);
                    if (op != 2) fill_ref(c), last = c;
                    auto want = raster::execute_reference(ref, sc.batch);
                    REQUIRE(r.ok());
                    REQUIRE(want.ok());
                    CHECK(r.value() == want.value());
                    defined = defined || op != 2;
                } else if (op == 3) {  // a sequence, clearing each batch or not, between() writing pixels
                    const bool clearing = rng.chance(70);
                    if (clearing) eo.clear_depth = c;
                    const std::uint64_t seed = rng.next();
                    const raster::CommandBatch* seq[3] = {
                        &pool[rng.below(4)].batch, &pool[rng.below(4)].batch, &pool[rng.below(4)].batch};
                    // between(k) also clears (to the value of bits 8-10 of the seed) when bit k + 4 is set.
                    const double between_clear = clears[(seed >> 8) % std::size(clears)];
                    auto r = raster::execute_sequence(t, seq, eo, [&](std::size_t k) {
                        if ((seed >> (k + 4)) & 1u) REQUIRE(t.clear(between_clear).ok());
                        if ((seed >> k) & 1u) write_pixels(t, seed + k);
                    });
                    REQUIRE(r.ok());
                    for (std::size_t k = 0; k < 3; ++k) {
                        if (k > 0 && ((seed >> (k + 4)) & 1u)) fill_ref(between_clear);
                        if (k > 0 && ((seed >> k) & 1u))
                            write_pixels(ref, seed + k);  // the same, at the same moment
                        if (clearing) fill_ref(c);
                        auto want = raster::execute_reference(ref, *seq[k]);
                        REQUIRE(want.ok());
                        CHECK(r.value()[k] == want.value());
                    }
                    if (clearing) last = c;
                } else if (op == 4) {  // writes through mutable_values()
                    const std::uint64_t seed = rng.next();
                    write_pixels(t, seed);
                    write_pixels(ref, seed);
                } else {  // op 5: queries_only (CULLIDE's recorded passes): counts only, content unspecified
                    eo.clear_depth = c;
                    eo.queries_only = true;
                    auto r = raster::execute(t, sc.batch, eo);
                    fill_ref(c);
                    last = c;
                    auto want = raster::execute_reference(ref, sc.batch);
                    REQUIRE(r.ok());
                    REQUIRE(want.ok());
                    CHECK(r.value() == want.value());
                    defined = false;
                }
                if (defined) {
                    CHECK(std::equal(t.values().begin(), t.values().end(), ref.values().begin(),
                                     ref.values().end()));
                    ++compared;
                }
            }
        }
    }
    CHECK(compared > 400);
    CHECK(value_changes > 40);
    CHECK(writes > 40);
}

// The fast clear skips the blocks it knows hold the clear value: a pixel changed through a span
// kept past the next execute() (which the span's contract does not allow) is left as it is by a
// clear to the same value, and filled by a clear to another value or after mutable_values().
TEST_CASE("The fast clear fills only blocks a draw wrote since the last clear to the same value") {
    auto made = raster::DepthTarget::create(128, 128, raster::DepthFormat::D24);
    REQUIRE(made.ok());
    raster::DepthTarget& t = made.value();
    // One triangle in the bottom-left tile, written at depth 0.
    raster::CommandBatch batch(128, 128);
    const std::vector<raster::Float4> v = {
        {-1.0f, -1.0f, -1.0f, 1.0f}, {-0.8f, -1.0f, -1.0f, 1.0f}, {-1.0f, -0.8f, -1.0f, 1.0f}};
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    raster::DrawState write;
    write.depth_func = raster::DepthFunc::Always;
    batch.draw({v, idx}, write);
    const std::span<std::uint32_t> stale = t.mutable_values();  // forgets: the next clear fills all
    raster::ExecuteOptions eo;
    eo.clear_depth = 1.0;
    REQUIRE(raster::execute(t, batch, eo).ok());
    const std::uint32_t one = raster::DepthTarget::encode_clear(1.0, raster::DepthFormat::D24);
    CHECK(t.value(1, 1) == 0u);  // drawn
    CHECK(t.value(100, 100) == one);
    stale[100 * 128 + 100] = 7;  // behind the target's back, in a block no draw wrote
    REQUIRE(t.clear(1.0).ok());
    CHECK(t.value(1, 1) == one);     // the written block is filled ...
    CHECK(t.value(100, 100) == 7u);  // ... the other one is known to hold 1 and left alone
    REQUIRE(raster::execute(t, batch, eo).ok());
    CHECK(t.value(100, 100) == 7u);  // (execute's own clear the same)
    REQUIRE(t.clear(0.5).ok());      // another value: every pixel
    CHECK(t.value(100, 100) == raster::DepthTarget::encode_clear(0.5, raster::DepthFormat::D24));
    t.mutable_values()[100 * 128 + 100] = 9;  // through mutable_values(): forgotten, filled again
    REQUIRE(t.clear(0.5).ok());
    CHECK(t.value(100, 100) == raster::DepthTarget::encode_clear(0.5, raster::DepthFormat::D24));
}
