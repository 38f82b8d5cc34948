// visibility_test.cpp: raster::VisibilityPass (the fused exact-bounds visibility pass) against the
// two recorded passes it replaces (raster/visibility.h): on random scenes of objects made of items
// (including degenerate, flat, edge-on, out-of-volume and sub-pixel triangles, and objects covering
// the same pixels at the same depth), for every depth format, several target sizes (one tile and
// several, edges not on tile borders) and 1, 2, 3 and 8 threads (and 2 and 3 on the spread
// schedule, thread_runs.h), the per-item answer equals "one of the item's two queries passed a
// sample" from raster::execute and raster::execute_reference.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <string>
#include <vector>

#include "raster/raster.h"
#include "raster/visibility.h"
#include "recorded_visibility.h"
#include "test_rng.h"
#include "thread_runs.h"

namespace {

using raster::DepthFormat;
using raster::Double4;

struct Scene {
    std::vector<Double4> vertices;
    std::vector<std::vector<std::uint32_t>> item_indices;
    std::vector<std::uint32_t> item_object;  // non-decreasing: items of one object are consecutive
    std::uint32_t objects = 0;
};

Double4 vertex_near(test::Rng& rng, const Double4& c, double r, bool flat) {
    return {c.x + rng.uniform(-r, r), c.y + rng.uniform(-r, r), flat ? c.z : c.z + rng.uniform(-r, r), 1.0};
}

Scene random_scene(test::Rng& rng, int objects, double scale = 1.0) {
    Scene s;
    s.objects = static_cast<std::uint32_t>(objects);
    // A shared depth for some flat triangles, so that different objects tie exactly.
    const double tie_z = rng.uniform(-0.5, 0.5);
    for (int o = 0; o < objects; ++o) {
        const int items = 1 + static_cast<int>(rng.below(3));
        const Double4 centre{rng.uniform(-0.9, 0.9), rng.uniform(-0.9, 0.9), rng.uniform(-0.9, 0.9), 1.0};
        for (int it = 0; it < items; ++it) {
            std::vector<std::uint32_t> idx;
            const int tris = 1 + static_cast<int>(rng.below(4));
            for (int t = 0; t < tris; ++t) {
                const auto base = static_cast<std::uint32_t>(s.vertices.size());
                const int kind = static_cast<int>(rng.below(6));
                const double r = scale * (kind == 0 ? 0.6 : kind == 1 ? 0.01 : 0.2);  // large, sub-pixel, medium
                Double4 a = vertex_near(rng, centre, r, false);
                if (kind == 2) a.z = tie_z;
                Double4 b = vertex_near(rng, a, r, kind == 2);
                Double4 c = vertex_near(rng, a, r, kind == 2);
                if (kind == 3) {  // edge-on: all three on one vertical line of the window
                    b.x = c.x = a.x;
                    b.y = a.y;
                    c.y = a.y;
                }
                if (kind == 4) {  // degenerate: a segment, or a point
                    c = rng.below(2) == 0 ? a : b;
                }
                if (kind == 5) {  // partly outside the clip volume
                    b.x += 1.5;
                    c.z -= 1.5;
                }
                s.vertices.push_back(a);
                s.vertices.push_back(b);
                s.vertices.push_back(c);
                idx.insert(idx.end(), {base, base + 1, base + 2});
            }
            s.item_indices.push_back(std::move(idx));
            s.item_object.push_back(static_cast<std::uint32_t>(o));
        }
    }
    return s;
}

// The two passes as cullide.cpp records them (recorded_visibility.h). Per item: a query passed.
std::vector<std::uint8_t> recorded(const Scene& s, int w, int h, DepthFormat f, int threads, bool reference) {
    std::string error;
    const auto r = test::recorded_visibility(s.vertices, s.item_indices, s.item_object, s.objects, w, h, f, threads,
                                             reference, &error);
    REQUIRE_MESSAGE(r.has_value(), error);
    return *r;
}

std::uint64_t crowded_triangles(const Scene& s) {
    std::uint64_t n = 0;
    for (const auto& idx : s.item_indices) n += idx.size() / 3;
    return n;
}

std::vector<raster::VisibilityItem> items_of(const Scene& s) {
    std::vector<raster::VisibilityItem> items;
    for (std::size_t i = 0; i < s.item_indices.size(); ++i)
        items.push_back({raster::MeshViewD{s.vertices, s.item_indices[i]}, s.item_object[i]});
    return items;
}

}  // namespace

TEST_CASE("The fused visibility pass gives the two recorded passes' answers, any format, size and thread count") {
    test::Rng rng(20261121);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{16, 16}, {37, 23}, {130, 70}};
    raster::VisibilityPass pass;  // reused across calls, as the pipeline does
    int visible = 0, hidden = 0;
    for (int rep = 0; rep < 120; ++rep) {
        const Scene s = random_scene(rng, 2 + static_cast<int>(rng.below(12)));
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, w, h, f, 1, true);
        CHECK(recorded(s, w, h, f, 3, false) == want);
        for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
            const int threads = run.threads;
            CAPTURE(threads);
            CAPTURE(run.spread);
            const raster::detail::SpreadScheduleScope schedule(run.spread);
            auto got = pass.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            CHECK(got.value() == want);
        }
        for (auto v : want) (v != 0 ? hidden : visible) += 1;
    }
    // Both answers occur, so the comparison can fail either way.
    CHECK(visible > 20);
    CHECK(hidden > 20);
}

TEST_CASE("The fused visibility pass split between threads (one tile, many small triangles) gives the recorded answers") {
    // R-CULLIDE's 32^2 sub-object views: one tile, thousands of triangles of a pixel or two. With
    // more than 256 triangles per thread the pass cuts the items into one run per thread, each with
    // its own minima, and merges them (visibility.cpp, split_pass). Hundreds of objects, so that the
    // runs' minima hold different objects at the same pixel and the merge decides which one wins;
    // flat triangles at one shared depth make ties between runs.
    test::Rng rng(20261126);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{32, 32}, {37, 23}, {64, 64}};
    raster::VisibilityPass pass;
    int visible = 0, hidden = 0;
    for (int rep = 0; rep < 12; ++rep) {
        const Scene s = random_scene(rng, 500 + static_cast<int>(rng.below(300)), 0.05);
        std::size_t triangles = 0;
        for (const auto& idx : s.item_indices) triangles += idx.size() / 3;
        REQUIRE(triangles >= 256 * 8);  // every thread count below splits
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, w, h, f, 1, true);
        for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
            const int threads = run.threads;
            CAPTURE(threads);
            CAPTURE(run.spread);
            const raster::detail::SpreadScheduleScope schedule(run.spread);
            auto got = pass.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            CHECK(got.value() == want);
        }
        for (auto v : want) (v != 0 ? hidden : visible) += 1;
    }
    CHECK(visible > 100);
    CHECK(hidden > 100);
}

TEST_CASE("The fused visibility pass with large triangles (tiles settled from depth bounds) gives the recorded answers") {
    // Triangles a few times larger than above: their boxes average more than kSettleMinArea pixels,
    // so the pass settles 16-pixel tiles from the triangles' depth bounds and skips items already
    // found (visibility.cpp), also on a 16 x 16 target that is a single tile.
    test::Rng rng(20261125);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{16, 16}, {37, 23}, {130, 70}};
    raster::VisibilityPass pass;
    int visible = 0, hidden = 0;
    for (int rep = 0; rep < 90; ++rep) {
        const Scene s = random_scene(rng, 2 + static_cast<int>(rng.below(8)), 2.0 + rng.uniform(0.0, 2.0));
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, w, h, f, 1, true);
        for (const int threads : {1, 2, 3}) {
            CAPTURE(threads);
            auto got = pass.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            CHECK(got.value() == want);
        }
        for (auto v : want) (v != 0 ? hidden : visible) += 1;
    }
    CHECK(visible > 10);
    CHECK(hidden > 10);
}

// Objects in separate places (a few overlapping), each item a small cluster of 4 triangles; some
// items reach the far plane (kind 0), leave the clip volume by up to 2x (1) or far beyond (2), lie
// wholly outside (3) or have their triangles scattered (4). far_alone counts the kind-0 items.
Scene spread_scene(test::Rng& rng, int& far_alone) {
    Scene s;
    const int objects = 4 + static_cast<int>(rng.below(40));
    s.objects = static_cast<std::uint32_t>(objects);
    for (int o = 0; o < objects; ++o) {
        const Double4 centre{rng.uniform(-0.95, 0.95), rng.uniform(-0.95, 0.95), rng.uniform(-0.9, 0.9), 1.0};
        const int items = 1 + static_cast<int>(rng.below(30));
        for (int it = 0; it < items; ++it) {
            std::vector<std::uint32_t> idx;
            const int kind = static_cast<int>(rng.below(12));
            const Double4 c{centre.x + rng.uniform(-0.08, 0.08), centre.y + rng.uniform(-0.08, 0.08),
                            kind == 0 ? 1.0 - rng.uniform(0.0, 1e-9) : centre.z + rng.uniform(-0.05, 0.05), 1.0};
            for (int t = 0; t < 4; ++t) {
                const auto base = static_cast<std::uint32_t>(s.vertices.size());
                // Scattered items (kind 4): each triangle elsewhere, so one box would be too big
                // and the pre-pass marks each triangle's own.
                const Double4 tc = kind == 4 ? Double4{centre.x + rng.uniform(-0.5, 0.5), centre.y + rng.uniform(-0.5, 0.5),
                                                       c.z, 1.0}
                                             : c;
                for (int k = 0; k < 3; ++k) {
                    Double4 v{tc.x + rng.uniform(-0.02, 0.02), tc.y + rng.uniform(-0.02, 0.02),
                              kind == 0 ? c.z : c.z + rng.uniform(-0.02, 0.02), 1.0};
                    if (kind == 1 && k == 0) v.x = rng.coin() ? 1.6 : -1.9;  // clipped, |v| <= 2
                    if (kind == 2 && k == 1) v.y = 3.5;                      // far beyond: whole target
                    if (kind == 3) v.x += 2.5;                               // wholly outside
                    s.vertices.push_back(v);
                }
                idx.insert(idx.end(), {base, base + 1, base + 2});
            }
            if (kind == 0) ++far_alone;
            s.item_indices.push_back(std::move(idx));
            s.item_object.push_back(static_cast<std::uint32_t>(o));
        }
    }
    return s;
}

TEST_CASE("The fused visibility pass: items alone in the view are skipped with the recorded answers") {
    // visibility.cpp, State::alone: an item whose pixels no other object's triangle comes near is
    // neither set up nor drawn; its answer is 0 unless a fragment may reach the clear value. Objects
    // in separate places (a few overlapping), each item a small cluster; some items reach the far
    // plane (their query passes against the clear value even alone), some leave the clip volume by
    // up to 2x (clipped: the box from the vertices needs its extra pixel) or far beyond (the whole
    // target), some lie wholly outside, some have their triangles scattered (spread_scene); 32^2
    // (one tile; split between threads), 37 x 23, and 300 x 200 (cells of 4 pixels).
    test::Rng rng(20261127);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{32, 32}, {37, 23}, {300, 200}};
    int visible = 0, hidden = 0, far_alone = 0;
    std::uint64_t spared_runs = 0;
    for (int rep = 0; rep < 18; ++rep) {
        const Scene s = spread_scene(rng, far_alone);
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, w, h, f, 1, true);
        for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
            const int threads = run.threads;
            CAPTURE(threads);
            CAPTURE(run.spread);
            const raster::detail::SpreadScheduleScope schedule(run.spread);
            raster::VisibilityPass pass;  // fresh: the pre-pass runs on a first call
            pass.set_presettle(false);    // (which would settle these items first on one tile)
            auto got = pass.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            CHECK(got.value() == want);
            if (pass.last_spared_triangles() > 0) ++spared_runs;
            raster::VisibilityPass settling;
            auto settled = settling.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(settled.ok(), (settled.ok() ? std::string() : settled.error().message));
            CHECK(settled.value() == want);
        }
        for (auto v : want) (v != 0 ? hidden : visible) += 1;
    }
    CHECK(visible > 100);
    CHECK(hidden > 100);
    CHECK(far_alone > 20);
    CHECK(spared_runs == 18 * std::size(raster_test::kThreadRuns));  // every run found items alone
}

TEST_CASE("The fused visibility pass: the pre-pass's history of one scene does not turn it off for another") {
    // visibility.cpp, AloneGuard: the pre-pass runs per shape of call while it pays. A pass object
    // first serves many calls of a crowded scene (150 overlapping objects: nothing alone, so the
    // pre-pass turns itself off for that shape), then a scene of 2 objects far apart with as many
    // items and triangles (300 items, 1,200 triangles): its object count makes it another shape, so
    // the pre-pass runs on its first call and spares every triangle.
    test::Rng rng(20261129);
    const auto make = [&](int objects, int items_per_object, double spread) {
        Scene s;
        s.objects = static_cast<std::uint32_t>(objects);
        for (int o = 0; o < objects; ++o) {
            const double cx = objects == 2 ? (o == 0 ? -0.6 : 0.6) : rng.uniform(-spread, spread);
            const double cy = objects == 2 ? 0.0 : rng.uniform(-spread, spread);
            for (int it = 0; it < items_per_object; ++it) {
                std::vector<std::uint32_t> idx;
                const Double4 c{cx + rng.uniform(-0.2, 0.2), cy + rng.uniform(-0.2, 0.2), rng.uniform(-0.5, 0.5), 1.0};
                for (int t = 0; t < 4; ++t) {
                    const auto base = static_cast<std::uint32_t>(s.vertices.size());
                    for (int k = 0; k < 3; ++k) s.vertices.push_back(vertex_near(rng, c, 0.01, false));
                    idx.insert(idx.end(), {base, base + 1, base + 2});
                }
                s.item_indices.push_back(std::move(idx));
                s.item_object.push_back(static_cast<std::uint32_t>(o));
            }
        }
        return s;
    };
    const Scene crowded = make(150, 2, 0.1), apart = make(2, 150, 0.0);
    for (const int threads : {1, 2}) {
        CAPTURE(threads);
        raster::VisibilityPass pass;
        pass.set_presettle(false);  // the alone pre-pass's history (the settling one has its own)
        for (int call = 0; call < 40; ++call) {
            auto r = pass.run(32, 32, DepthFormat::D24, items_of(crowded), threads);
            REQUIRE(r.ok());
        }
        auto r = pass.run(32, 32, DepthFormat::D24, items_of(apart), threads);
        REQUIRE(r.ok());
        CHECK(pass.last_spared_triangles() == 1200);
        CHECK(r.value() == recorded(apart, 32, 32, DepthFormat::D24, 1, true));
    }
}

TEST_CASE("The fused visibility pass: items that touch only at a pixel border are not alone") {
    // Exact bounds cover closed pixel squares, so two triangles meeting on the line between two
    // pixel columns (window X = 16 at clip x = 0 on 32 pixels) share pixels 15 and 16. The far one
    // (object 0) is not fully visible there; the pre-pass must see both reach those pixels (a box
    // one margin too tight would leave it alone, with the answer 0).
    for (const DepthFormat f : {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F}) {
        for (const double gap : {0.0, 1.0 / 16.0}) {  // 1/16 of clip space: one pixel column apart
            CAPTURE(gap);
            // Small triangles (boxes of 2 x 2 pixels: one box per item in the pre-pass).
            const std::vector<Double4> v = {{-0.05, -0.02, 0.5, 1},      {0.0, 0.0, 0.5, 1},
                                            {-0.05, 0.02, 0.5, 1},       {gap, -0.02, -0.5, 1},
                                            {gap + 0.05, 0.0, -0.5, 1}, {gap, 0.02, -0.5, 1}};
            const std::vector<std::uint32_t> a = {0, 1, 2}, b = {3, 4, 5};
            const std::vector<raster::VisibilityItem> items = {{raster::MeshViewD{v, a}, 0},
                                                               {raster::MeshViewD{v, b}, 1}};
            Scene s;
            s.vertices = v;
            s.item_indices = {a, b};
            s.item_object = {0, 1};
            s.objects = 2;
            const std::vector<std::uint8_t> want = recorded(s, 32, 32, f, 1, true);
            // Touching: the far triangle is hidden at the shared pixels; one pixel column apart,
            // the two still share the closed squares' border column, again hidden.
            CHECK(want[0] == 1);
            for (const int threads : {1, 2}) {
                for (const bool settling : {false, true}) {
                    raster::VisibilityPass pass;
                    pass.set_presettle(settling);
                    auto r = pass.run(32, 32, f, items, threads);
                    REQUIRE(r.ok());
                    CHECK(r.value() == want);
                    // The settling pre-pass must not take the far one for certainly not hit.
                    CHECK(pass.last_presettle().items_not_hit == (settling ? 1 : 0));
                }
            }
            // Moved two pixel columns further away, both are alone: the pre-pass spares both (and
            // the settling pre-pass settles both: nothing is drawn).
            std::vector<Double4> apart = v;
            for (int k = 3; k < 6; ++k) apart[static_cast<std::size_t>(k)].x += 4.0 / 32.0;
            const std::vector<raster::VisibilityItem> items_apart = {{raster::MeshViewD{apart, a}, 0},
                                                                     {raster::MeshViewD{apart, b}, 1}};
            raster::VisibilityPass pass;
            pass.set_presettle(false);
            auto r = pass.run(32, 32, f, items_apart, 1);
            REQUIRE(r.ok());
            CHECK(r.value() == std::vector<std::uint8_t>{0, 0});
            CHECK(pass.last_spared_triangles() == 2);
            pass.set_presettle(true);
            r = pass.run(32, 32, f, items_apart, 1);
            REQUIRE(r.ok());
            CHECK(r.value() == std::vector<std::uint8_t>{0, 0});
            CHECK(pass.last_presettle().items_not_hit == 2);
            CHECK(pass.last_presettle().triangles_left_out == 2);
        }
    }
}

TEST_CASE("The fused visibility pass: an item of scattered triangles reaches each triangle's pixels") {
    // Object 0: one item of two small triangles at opposite corners (one box would be most of the
    // target, so the pre-pass marks each triangle's box); object 1: a small item under the second
    // triangle and behind it (hidden), and one in the empty middle (alone, spared).
    for (const DepthFormat f : {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F}) {
        const std::vector<Double4> v = {{-0.9, -0.9, -0.5, 1}, {-0.85, -0.9, -0.5, 1}, {-0.9, -0.85, -0.5, 1},
                                        {0.8, 0.8, -0.5, 1},   {0.85, 0.8, -0.5, 1},   {0.8, 0.85, -0.5, 1},
                                        {0.81, 0.81, 0.5, 1},  {0.84, 0.81, 0.5, 1},   {0.81, 0.84, 0.5, 1},
                                        {0.0, 0.0, 0.5, 1},    {0.03, 0.0, 0.5, 1},    {0.0, 0.03, 0.5, 1}};
        const std::vector<std::uint32_t> a = {0, 1, 2, 3, 4, 5}, b = {6, 7, 8}, c = {9, 10, 11};
        Scene s;
        s.vertices = v;
        s.item_indices = {a, b, c};
        s.item_object = {0, 1, 1};
        s.objects = 2;
        const std::vector<std::uint8_t> want = recorded(s, 32, 32, f, 1, true);
        CHECK(want == std::vector<std::uint8_t>{0, 1, 0});
        for (const int threads : {1, 2}) {
            raster::VisibilityPass pass;
            pass.set_presettle(false);
            auto r = pass.run(32, 32, f, items_of(s), threads);
            REQUIRE(r.ok());
            CHECK(r.value() == want);
            CHECK(pass.last_spared_triangles() == 1);  // the middle one only
            // The settling pre-pass (a box per scattered triangle): the hidden item is certainly
            // hit (a vertex of the near triangle shares its pixel), the other two certainly not.
            pass.set_presettle(true);
            r = pass.run(32, 32, f, items_of(s), threads);
            REQUIRE(r.ok());
            CHECK(r.value() == want);
            CHECK(pass.last_presettle().items_hit == 1);
            CHECK(pass.last_presettle().items_not_hit == 2);
            CHECK(pass.last_presettle().triangles_left_out == 4);
        }
    }
}

// Objects that are meshes (grid patches whose quads share vertices), cut into items of 4
// triangles as R-CULLIDE's sub-objects: the settling pre-pass (visibility.cpp, State::presettle)
// maps each shared vertex once per run of one object. Patches overlap in the window and in depth;
// some are flat at one shared depth (ties between objects), some reach the far plane, some leave
// the clip volume (clipped: bounds_reach's boxes), some have their vertices on pixel borders
// (snap_x, snap_y: a pixel's width in clip units; 0: none), and some come in touching pairs: the
// second patch starts at the first one's far edge, at the same positions and depths (or up to a
// few quantization steps behind), and goes on behind (contact, where the pre-pass's bounds are
// tightest); all_pairs: every patch is such a pair. `size`: a patch's side in clip units (2 = the
// target).
Scene patch_scene(test::Rng& rng, int objects, double size, bool clipped = true, double snap_x = 0.0,
                  double snap_y = 0.0, bool all_pairs = false) {
    Scene s;
    s.objects = static_cast<std::uint32_t>(objects);
    const double tie_z = rng.uniform(-0.3, 0.3);
    const auto snap = [](double v, double step) { return step > 0.0 ? std::round((v + 1.0) / step) * step - 1.0 : v; };
    for (int o = 0; o < objects; ++o) {
        const int gx = 2 + static_cast<int>(rng.below(6)), gy = 1 + static_cast<int>(rng.below(4));
        const double cx = rng.uniform(-0.95, 0.95), cy = rng.uniform(-0.95, 0.95);
        const double sx = size * rng.uniform(0.3, 1.0), sy = size * rng.uniform(0.3, 1.0);
        const int kind = all_pairs ? 3 : static_cast<int>(rng.below(10));
        const bool pair = kind == 3 && o + 1 < objects;
        const bool snapped = kind == 4 || (pair && rng.coin());
        const double z0 = kind == 0 ? tie_z : kind == 1 ? 1.0 : rng.uniform(-0.9, 0.6);
        // (half the pairs level along their shared edge, so that one depth bounds a whole item there)
        const double ax = kind <= 1 || (pair && rng.coin()) ? 0.0 : rng.uniform(-0.5, 0.5);
        const double ay = kind <= 1 ? 0.0 : pair ? rng.uniform(0.05, 0.5) : rng.uniform(-0.5, 0.5);
        std::vector<Double4> grid;
        for (int j = 0; j <= gy; ++j)
            for (int i = 0; i <= gx; ++i) {
                const double u = static_cast<double>(i) / gx - 0.5, v = static_cast<double>(j) / gy - 0.5;
                Double4 p{cx + u * sx, cy + v * sy, z0 + ax * u * sx + ay * v * sy, 1.0};
                if (snapped) p.x = snap(p.x, snap_x), p.y = snap(p.y, snap_y);
                if (kind >= 2 && !pair) p.z += rng.uniform(-0.01, 0.01);
                if (clipped && kind == 2 && i == 0) p.x -= 1.5;  // leaves the clip volume: clipped
                p.z = std::clamp(p.z, -1.0, 1.0);
                grid.push_back(p);
            }
        const auto add = [&](const std::vector<Double4>& g, std::uint32_t object) {
            const auto base = static_cast<std::uint32_t>(s.vertices.size());
            s.vertices.insert(s.vertices.end(), g.begin(), g.end());
            std::vector<std::uint32_t> tris;
            const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (gx + 1) + i); };
            for (int j = 0; j < gy; ++j)
                for (int i = 0; i < gx; ++i) {
                    tris.insert(tris.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1)});
                    tris.insert(tris.end(), {at(i, j), at(i + 1, j + 1), at(i, j + 1)});
                }
            for (std::size_t k = 0; k < tris.size(); k += 12) {
                s.item_indices.emplace_back(tris.begin() + static_cast<std::ptrdiff_t>(k),
                                            tris.begin() + static_cast<std::ptrdiff_t>(std::min(tris.size(), k + 12)));
                s.item_object.push_back(object);
            }
        };
        add(grid, static_cast<std::uint32_t>(o));
        if (!pair) continue;
        // The partner: the patch reflected across its far (last) row, in y and in depth, so it
        // shares that row exactly and lies behind it everywhere else; half the partners start up to
        // three D16 or D24 steps (2 / 65535 or 2 / 16777215 in clip z) further back, so that the
        // two lie a few quantization steps apart or straddle one by a hair (where the pre-pass's
        // cheap encodings must still bound the exact ones).
        const double step = rng.coin() ? 2.0 / 65535.0 : 2.0 / 16777215.0;
        const double gap = rng.coin() ? 0.0 : rng.uniform(0.0, 3.0) * step;
        std::vector<Double4> mirror(grid.size());
        for (int j = 0; j <= gy; ++j)
            for (int i = 0; i <= gx; ++i) {
                const Double4& edge = grid[static_cast<std::size_t>(gy * (gx + 1) + i)];
                const Double4& p = grid[static_cast<std::size_t>((gy - j) * (gx + 1) + i)];
                mirror[static_cast<std::size_t>(j * (gx + 1) + i)] = {p.x, edge.y + (edge.y - p.y),
                                                                      std::min(1.0, edge.z + gap + (edge.z - p.z)), 1.0};
            }
        ++o;
        add(mirror, static_cast<std::uint32_t>(o));
    }
    return s;
}

TEST_CASE("The settling pre-pass gives the recorded answers, settling items and leaving triangles out") {
    // visibility.cpp, State::presettle: items certainly hit (a vertex at or behind another object's
    // vertex in one pixel), certainly not hit (in front of every other object's box), and open;
    // only the open items and those near them in depth are drawn. Fresh passes (the pre-pass runs
    // on a first call), one-tile targets of several sizes and shapes, every format, 1, 2, 3 and 8
    // threads; the same answers as the recorded passes and as the pass without it.
    test::Rng rng(20261128);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{32, 32}, {37, 23}, {64, 64}, {128, 96}};
    raster::PresettleStats sum;
    int ran = 0, runs = 0;
    for (int rep = 0; rep < 24; ++rep) {
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 4][0], h = sizes[(rep / 3) % 4][1];
        // Patches of 3 to 12 pixels: triangles of a pixel or two, as in R-CULLIDE's 32^2 views.
        const double px = 2.0 / std::max(w, h);
        const Scene s = patch_scene(rng, 10 + static_cast<int>(rng.below(100)), px * (3.0 + rng.uniform(0.0, 9.0)),
                                    rep % 4 == 0, 2.0 / w, 2.0 / h);
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, w, h, f, 1, true);
        for (const raster_test::ThreadRun run : raster_test::kThreadRuns) {
            const int threads = run.threads;
            CAPTURE(threads);
            CAPTURE(run.spread);
            const raster::detail::SpreadScheduleScope schedule(run.spread);
            raster::VisibilityPass off;
            off.set_presettle(false);
            auto plain = off.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(plain.ok(), (plain.ok() ? std::string() : plain.error().message));
            CHECK(plain.value() == want);
            raster::VisibilityPass pass;
            auto got = pass.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            CHECK(got.value() == want);
            const raster::PresettleStats st = pass.last_presettle();
            ++runs;
            if (!st.ran) continue;
            ++ran;
            CHECK(st.items_hit + st.items_not_hit + st.items_open == s.item_indices.size());
            sum.items_hit += st.items_hit;
            sum.items_not_hit += st.items_not_hit;
            sum.items_open += st.items_open;
            sum.triangles_left_out += st.triangles_left_out;
        }
    }
    // It ran on most calls, and every verdict occurred, so each rule was exercised against the
    // recorded answers.
    CHECK(ran > runs / 2);
    CHECK(sum.items_hit > 5000);
    CHECK(sum.items_not_hit > 3000);
    CHECK(sum.items_open > 2000);
    CHECK(sum.triangles_left_out > 20000);
}

TEST_CASE("The settling pre-pass: objects in contact, a few quantization steps apart, give the recorded answers") {
    // Pairs of patches alone in the view that touch along an edge (the second starts at the first
    // one's far edge, at the same depth or up to three D16 or D24 steps behind: patch_scene's
    // pairs). There the exact pass finds the front one hit or not by a quantization step or two,
    // and the pre-pass's cheap encodings (encode_below_down, encode_above_up, encode_near) must still
    // bound the exact ones: a bound two steps off settles an item the wrong way.
    test::Rng rng(20261131);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    int hit = 0, visible = 0;
    for (int rep = 0; rep < 300; ++rep) {
        const double snap = rep % 2 == 0 ? 2.0 / 32.0 : 0.0;
        const Scene s = patch_scene(rng, 2, 0.4, false, snap, snap, true);
        const DepthFormat f = formats[rep % 3];
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, 32, 32, f, 1, true);
        raster::VisibilityPass pass;
        auto got = pass.run(32, 32, f, items_of(s), 1);
        REQUIRE(got.ok());
        CHECK(got.value() == want);
        for (auto v : want) (v != 0 ? hit : visible) += 1;
    }
    CHECK(hit > 100);
    CHECK(visible > 100);
}

// Closed axis-aligned boxes seen along the view axis, as R-CULLIDE's box stage draws them (8
// corners, 12 triangles): the two faces across the view are flat, the four others edge-on. Box
// sides of a fraction of a pixel to ten pixels, half of them on pixel borders or a hair (1e-12 of
// clip space) to either side; depths tied with an earlier box's near or far face, or up to three
// D16 or D24 steps from it, or on a quantization boundary; some boxes flat (near = far), some
// without width (a line), some leaving the clip volume (then never flat-face records); and lone
// triangles, flat or sloped, of any shape.
Scene box_scene(test::Rng& rng, int objects, int w, int h) {
    // Faces: near (z0) 0-1-3, 0-3-2 and far (z1) 4-7-5, 4-6-7 (corner c: x bit 1, y bit 2, z bit 4),
    // or the other diagonal; then the sides.
    static constexpr std::uint32_t kFaces[2][12] = {{0, 1, 3, 0, 3, 2, 4, 7, 5, 4, 6, 7},
                                                    {1, 3, 2, 1, 2, 0, 5, 4, 6, 5, 6, 7}};
    static constexpr std::uint32_t kSides[24] = {0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5,
                                                 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3};
    Scene s;
    s.objects = static_cast<std::uint32_t>(objects);
    std::vector<double> depths = {0.0};
    const double pw = 2.0 / w, ph = 2.0 / h;
    const auto edge = [&](double v, double step) {
        switch (rng.below(4)) {
            case 0: return v;
            case 1: return std::round((v + 1.0) / step) * step - 1.0;
            case 2: return std::round((v + 1.0) / step) * step - 1.0 + 1e-12;
            default: return std::round((v + 1.0) / step) * step - 1.0 - 1e-12;
        }
    };
    for (int o = 0; o < objects; ++o) {
        const int items = 1 + static_cast<int>(rng.below(2));
        for (int it = 0; it < items; ++it) {
            const double cx = rng.uniform(-0.9, 0.9), cy = rng.uniform(-0.9, 0.9);
            const double sx = pw * rng.uniform(0.3, 10.0), sy = ph * rng.uniform(0.3, 10.0);
            double x0 = edge(cx - sx / 2, pw), x1 = edge(cx + sx / 2, pw);
            const double y0 = edge(cy - sy / 2, ph), y1 = edge(cy + sy / 2, ph);
            if (rng.below(20) == 0) x1 = x0;  // no width
            const double step = rng.coin() ? 2.0 / 65535.0 : 2.0 / 16777215.0;
            double z0 = rng.coin() ? depths[rng.below(depths.size())] + std::floor(rng.uniform(-3.0, 4.0)) * step
                                   : rng.uniform(-0.9, 0.6);
            double z1 = rng.below(10) == 0 ? z0 : z0 + rng.uniform(0.0, 0.4);
            if (rng.below(3) == 0) {  // the far face tied to an earlier face
                z1 = depths[rng.below(depths.size())];
                if (z1 < z0) std::swap(z0, z1);
            }
            if (rng.below(15) == 0) z1 += 1.5;  // leaves the clip volume
            z0 = std::clamp(z0, -1.0, 1.0);
            if (rng.below(4) == 0) {  // on a D16 or D24 quantization boundary
                const double n = rng.coin() ? 65535.0 : 16777215.0;
                z0 = std::round((z0 + 1.0) * 0.5 * n) / n * 2.0 - 1.0;
            }
            depths.push_back(z0);
            depths.push_back(std::min(z1, 1.0));
            const auto base = static_cast<std::uint32_t>(s.vertices.size());
            if (rng.below(4) == 0) {
                // A lone triangle inside the box's window rectangle: flat at z0 (any shape, so its
                // slanted edges decide which pixels it reaches) or sloped from z0 to z1.
                const bool flat = rng.coin();
                for (int c = 0; c < 3; ++c)
                    s.vertices.push_back({rng.uniform(x0, x1), rng.uniform(y0, y1), flat || c == 0 ? z0 : std::min(z1, 1.0), 1.0});
                s.item_indices.push_back({base, base + 1, base + 2});
                s.item_object.push_back(static_cast<std::uint32_t>(o));
                continue;
            }
            for (int c = 0; c < 8; ++c)
                s.vertices.push_back({(c & 1) ? x1 : x0, (c & 2) ? y1 : y0, (c & 4) ? z1 : z0, 1.0});
            std::vector<std::uint32_t> idx;
            for (const std::uint32_t k : kFaces[rng.below(2)]) idx.push_back(base + k);
            for (const std::uint32_t k : kSides) idx.push_back(base + k);
            s.item_indices.push_back(std::move(idx));
            s.item_object.push_back(static_cast<std::uint32_t>(o));
        }
    }
    return s;
}

TEST_CASE("The settling pre-pass: boxes seen along an axis are settled by their flat faces with the recorded answers") {
    // visibility.cpp, State::presettle with detail::flat_triangle_pixels: every pixel a flat face
    // certainly reaches holds a record at the face's depth, as a vertex's pixel does, so boxes that
    // overlap are shown hit inside their faces, not only at their corners. A record one pixel too
    // far out, or its depth bound a step the wrong way, answers some of these boxes wrongly (border
    // pixels and tied depths).
    test::Rng rng(20261129);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{32, 32}, {37, 23}, {64, 64}};
    raster::PresettleStats sum;
    int hit = 0, visible = 0;
    for (int rep = 0; rep < 90; ++rep) {
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        const Scene s = box_scene(rng, 2 + static_cast<int>(rng.below(60)), w, h);
        CAPTURE(rep);
        const std::vector<std::uint8_t> want = recorded(s, w, h, f, 1, true);
        for (auto v : want) (v != 0 ? hit : visible) += 1;
        for (const int threads : {1, 2, 3}) {
            CAPTURE(threads);
            raster::VisibilityPass off;
            off.set_presettle(false);
            auto plain = off.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(plain.ok(), (plain.ok() ? std::string() : plain.error().message));
            CHECK(plain.value() == want);
            raster::VisibilityPass pass;
            auto got = pass.run(w, h, f, items_of(s), threads);
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            CHECK(got.value() == want);
            const raster::PresettleStats st = pass.last_presettle();
            if (!st.ran) continue;
            CHECK(st.items_hit_by_face <= st.items_hit);
            sum.items_hit += st.items_hit;
            sum.items_hit_by_face += st.items_hit_by_face;
            sum.items_not_hit += st.items_not_hit;
            sum.items_open += st.items_open;
        }
    }
    MESSAGE("boxes hit ", hit, ", visible ", visible, "; pre-pass hit ", sum.items_hit, " (by a face ",
            sum.items_hit_by_face, "), not hit ", sum.items_not_hit, ", open ", sum.items_open);
    CHECK(hit > 1000);
    CHECK(visible > 300);
    // The faces showed many of the hits (in these crowded scenes a corner often lies in another
    // box too, and ties keep many items open, which the pass answers).
    CHECK(sum.items_hit_by_face > 400);
    CHECK(sum.items_not_hit > 300);
    CHECK(sum.items_open > 300);

    // Two boxes crossed like a plus sign, no corner of either inside the other: only a face shows
    // the far one hit, and then nothing is drawn.
    const std::vector<Double4> v = {{-0.5, -0.1, -0.5, 1}, {0.5, -0.1, -0.5, 1}, {-0.5, 0.1, -0.5, 1},
                                    {0.5, 0.1, -0.5, 1},   {-0.5, -0.1, -0.3, 1}, {0.5, -0.1, -0.3, 1},
                                    {-0.5, 0.1, -0.3, 1},  {0.5, 0.1, -0.3, 1},   {-0.1, -0.5, 0.2, 1},
                                    {0.1, -0.5, 0.2, 1},   {-0.1, 0.5, 0.2, 1},   {0.1, 0.5, 0.2, 1},
                                    {-0.1, -0.5, 0.4, 1},  {0.1, -0.5, 0.4, 1},   {-0.1, 0.5, 0.4, 1},
                                    {0.1, 0.5, 0.4, 1}};
    static constexpr std::uint32_t kBox[36] = {0, 1, 3, 0, 3, 2, 4, 7, 5, 4, 6, 7, 0, 4, 6, 0, 6, 2,
                                               1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3};
    Scene plus;
    plus.vertices = v;
    plus.item_indices.resize(2);
    for (const std::uint32_t k : kBox) {
        plus.item_indices[0].push_back(k);
        plus.item_indices[1].push_back(k + 8);
    }
    plus.item_object = {0, 1};
    plus.objects = 2;
    for (const DepthFormat f : formats) {
        const std::vector<std::uint8_t> want = recorded(plus, 32, 32, f, 1, true);
        CHECK(want == std::vector<std::uint8_t>{0, 1});
        raster::VisibilityPass pass;
        auto got = pass.run(32, 32, f, items_of(plus), 1);
        REQUIRE(got.ok());
        CHECK(got.value() == want);
        CHECK(pass.last_presettle().items_hit_by_face == 1);
        CHECK(pass.last_presettle().items_not_hit == 1);
        CHECK(pass.last_presettle().triangles_left_out == 24);
    }
}

TEST_CASE("The settling pre-pass runs while it pays, and its history of one scene does not turn it off for another") {
    // visibility.cpp, PayGuard with kSettleMinSpared: a call shape whose pre-pass left out less than
    // 75% of the triangles runs without it on the next calls (now and then with it again); another
    // shape still runs it. The answers never change.
    test::Rng rng(20261130);
    // Crowded: large patches all over each other, so most items stay open and much is drawn.
    const Scene crowded = patch_scene(rng, 200, 0.5);
    Scene apart = patch_scene(rng, 3, 0.1);  // three small patches: everything settled
    for (const int threads : {1, 2}) {
        CAPTURE(threads);
        raster::VisibilityPass pass;
        const std::vector<std::uint8_t> want = recorded(crowded, 32, 32, DepthFormat::D24, 1, true);
        int ran = 0;
        for (int call = 0; call < 40; ++call) {
            auto r = pass.run(32, 32, DepthFormat::D24, items_of(crowded), threads);
            REQUIRE(r.ok());
            CHECK(r.value() == want);
            if (pass.last_presettle().ran) {
                ++ran;
                CHECK(pass.last_presettle().triangles_left_out * 4 < 3 * crowded_triangles(crowded));
            }
        }
        CHECK(ran >= 2);   // the first call, and probes
        CHECK(ran <= 10);  // but not every call
        auto r = pass.run(32, 32, DepthFormat::D24, items_of(apart), threads);
        REQUIRE(r.ok());
        CHECK(pass.last_presettle().ran);
        CHECK(pass.last_presettle().triangles_left_out > 0);
        CHECK(r.value() == recorded(apart, 32, 32, DepthFormat::D24, 1, true));
    }
}

TEST_CASE("The fused visibility pass: an item exactly at another object's depth is not fully visible") {
    // Two objects, one flat triangle each at the same depth: GEQUAL passes on equal values, so
    // neither is fully visible; with the second moved back, the first (nearer) is, the second not.
    for (const DepthFormat f : {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F}) {
        CAPTURE(static_cast<int>(f));
        for (const double dz : {0.0, 0.25}) {
            const std::vector<Double4> v = {{-0.5, -0.5, 0.0, 1}, {0.5, -0.5, 0.0, 1}, {0.5, 0.5, 0.0, 1},
                                            {-0.5, -0.5, dz, 1},  {0.5, -0.5, dz, 1},  {0.5, 0.5, dz, 1}};
            const std::vector<std::uint32_t> a = {0, 1, 2}, b = {3, 4, 5};
            const std::vector<raster::VisibilityItem> items = {{raster::MeshViewD{v, a}, 0},
                                                               {raster::MeshViewD{v, b}, 1}};
            raster::VisibilityPass pass;
            auto r = pass.run(32, 32, f, items, 2);
            REQUIRE(r.ok());
            CHECK(r.value()[0] == (dz == 0.0 ? 1 : 0));
            CHECK(r.value()[1] == 1);
            // Items of one object never hide each other.
            const std::vector<raster::VisibilityItem> same = {{raster::MeshViewD{v, a}, 7},
                                                              {raster::MeshViewD{v, b}, 7}};
            auto r2 = pass.run(32, 32, f, same, 2);
            REQUIRE(r2.ok());
            CHECK(r2.value() == std::vector<std::uint8_t>{0, 0});
        }
    }
}

TEST_CASE("The fused visibility pass rejects bad input, naming the item and vertex") {
    const std::vector<Double4> v = {{0, 0, 0, 1}, {0.5, 0, 0, 1}, {0, 0.5, 0, 2}};
    const std::vector<std::uint32_t> bad_w = {0, 1, 2}, bad_index = {0, 1, 9}, bad_count = {0, 1};
    raster::VisibilityPass pass;
    auto r = pass.run(16, 16, DepthFormat::D24, std::vector<raster::VisibilityItem>{{{v, bad_w}, 0}}, 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("item 0: vertex 2 has w = 2") != std::string::npos);
    r = pass.run(16, 16, DepthFormat::D24, std::vector<raster::VisibilityItem>{{{v, bad_count}, 0}, {{v, bad_index}, 1}},
                 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("item 0: index count 2") != std::string::npos);
    r = pass.run(16, 16, DepthFormat::D24, std::vector<raster::VisibilityItem>{{{v, bad_index}, 1}}, 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("index 9 at position 2") != std::string::npos);
    // A NaN in y or z (std::max drops a NaN in its second argument, so a magnitude taken as the
    // max of |x|, |y|, |z| misses these; raster_visibility_fuzz found the y case), in an item alone
    // in the view and a point, or beside another object far away; one tile and several.
    for (const int side : {16, 123}) {
        for (int axis = 0; axis < 3; ++axis) {
            CAPTURE(side);
            CAPTURE(axis);
            std::vector<Double4> nan = {{0.86, 0.1, -1.0, 1}, {0.86, 0.1, -1.0, 1}, {0.86, 0.1, -1.0, 1},
                                        {-0.9, -0.9, 0.0, 1}, {-0.8, -0.9, 0.0, 1}, {-0.9, -0.8, 0.0, 1}};
            (axis == 0 ? nan[1].x : axis == 1 ? nan[1].y : nan[1].z) = std::nan("");
            const std::vector<std::uint32_t> point = {0, 1, 2}, other = {3, 4, 5};
            for (const bool alone : {true, false}) {
                std::vector<raster::VisibilityItem> items = {{{nan, point}, 0}};
                if (!alone) items.push_back({{nan, other}, 1});
                for (const bool settling : {true, false}) {
                    raster::VisibilityPass p;
                    p.set_presettle(settling);
                    r = p.run(side, side, DepthFormat::D24, items, 1);
                    REQUIRE(!r.ok());
                    CHECK(r.error().message.find("item 0: vertex 1 is not finite") != std::string::npos);
                }
            }
        }
    }
    r = pass.run(0, 16, DepthFormat::D24, {}, 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("target 0x16") != std::string::npos);
    r = pass.run(16, 16, DepthFormat::D24, {}, 1);
    REQUIRE(r.ok());
    CHECK(r.value().empty());
}

TEST_CASE("Object views are subsumed by sub-object views: an object is fully visible iff each of its items is") {
    // cullide.cpp skips R-CULLIDE's object stage (ObjectStage::Auto) on this argument: in the same
    // view, an object drawn as one item is fully visible exactly when every one of its items is
    // (its fragments are the union of theirs, tested against the same other-object depths). Checked
    // for the fused pass and for the recorded passes through the reference executor.
    test::Rng rng(77031);
    raster::VisibilityPass pass;
    int objects_visible = 0, objects_hidden = 0, mixed = 0;
    for (int rep = 0; rep < 60; ++rep) {
        const Scene s = random_scene(rng, 2 + static_cast<int>(rng.below(10)));
        Scene whole;  // one item per object: the concatenation of its items
        whole.vertices = s.vertices;
        whole.objects = s.objects;
        whole.item_indices.resize(s.objects);
        for (std::uint32_t o = 0; o < s.objects; ++o) whole.item_object.push_back(o);
        for (std::size_t i = 0; i < s.item_indices.size(); ++i) {
            auto& dst = whole.item_indices[s.item_object[i]];
            dst.insert(dst.end(), s.item_indices[i].begin(), s.item_indices[i].end());
        }
        const DepthFormat f = rep % 3 == 0 ? DepthFormat::D16 : rep % 3 == 1 ? DepthFormat::D24 : DepthFormat::D32F;
        const int w = rep % 2 == 0 ? 32 : 45, h = rep % 2 == 0 ? 32 : 29;
        CAPTURE(rep);
        auto sub = pass.run(w, h, f, items_of(s), 2);
        REQUIRE(sub.ok());
        auto obj = pass.run(w, h, f, items_of(whole), 2);
        REQUIRE(obj.ok());
        const std::vector<std::uint8_t> sub_rec = recorded(s, w, h, f, 1, true);
        const std::vector<std::uint8_t> obj_rec = recorded(whole, w, h, f, 1, true);
        for (std::uint32_t o = 0; o < s.objects; ++o) {
            std::uint8_t any = 0, all = 1;
            for (std::size_t i = 0; i < s.item_indices.size(); ++i) {
                if (s.item_object[i] != o) continue;
                any = static_cast<std::uint8_t>(any | sub.value()[i]);
                all = static_cast<std::uint8_t>(all & sub.value()[i]);
                CHECK(sub_rec[i] == sub.value()[i]);
            }
            CHECK(obj.value()[o] == any);
            CHECK(obj_rec[o] == obj.value()[o]);
            (any != 0 ? objects_hidden : objects_visible) += 1;
            mixed += any != 0 && all == 0 ? 1 : 0;
        }
    }
    // Both answers occur, and objects with some items pruned and some not (what the sub-object
    // stage gains over the object stage), so the checks above can fail either way.
    CHECK(objects_visible > 10);
    CHECK(objects_hidden > 10);
    CHECK(mixed > 5);
}

// ---- WindowedPasses (Quick-CULLIDE's passes, each item rasterized once) --------------------------

namespace {

// Random non-decreasing windows [lo, hi] over n items: an object's items (hi = its last item, lo =
// its first, as Quick-CULLIDE without self-collision), or a band of width w around each item (as
// with self-collision), or a mix of both shapes across the list.
void random_windows(test::Rng& rng, std::size_t n, std::vector<std::uint32_t>& lo, std::vector<std::uint32_t>& hi,
                    const std::vector<std::uint32_t>& object) {
    // (assign, not resize: GCC 12 at -O3 reports a null dereference in resize on an empty vector)
    lo.assign(n, 0);
    hi.assign(n, 0);
    const int shape = static_cast<int>(rng.below(3));
    const auto w = static_cast<std::uint32_t>(rng.below(4));
    for (std::size_t i = 0; i < n; ++i) {
        if (shape == 0 || (shape == 2 && object[i] % 2 == 0)) {
            std::size_t s = i, e = i;
            while (s > 0 && object[s - 1] == object[i]) --s;
            while (e + 1 < n && object[e + 1] == object[i]) ++e;
            lo[i] = static_cast<std::uint32_t>(s);
            hi[i] = static_cast<std::uint32_t>(e);
        } else {
            lo[i] = static_cast<std::uint32_t>(i >= w ? i - w : 0);
            hi[i] = static_cast<std::uint32_t>(std::min<std::size_t>(n - 1, i + w));
        }
    }
    for (std::size_t i = 1; i < n; ++i) {  // the mixed shape: make both bounds non-decreasing
        lo[i] = std::max(lo[i], lo[i - 1]);
        hi[i] = std::max(hi[i], hi[i - 1]);
        lo[i] = std::min(lo[i], hi[i]);
    }
}

// The recorded pass (raster/visibility.h): forward, for each k query item k, then write every item not
// yet written whose window ends at or before k (not after the last query); backward mirrored.
std::vector<std::uint8_t> recorded_windowed(const Scene& s, const std::vector<std::uint32_t>& lo,
                                            const std::vector<std::uint32_t>& hi, const std::vector<std::uint8_t>& query,
                                            const std::vector<std::uint8_t>& write, bool forward, int w, int h,
                                            DepthFormat f) {
    std::string error;
    const auto r = test::recorded_windowed(s.vertices, s.item_indices, lo, hi, query, write, forward, w, h, f, &error);
    REQUIRE_MESSAGE(r.has_value(), error);
    return *r;
}

// prepare() with `threads`, then both passes against recorded_windowed; counts the queried items'
// answers (passed, failed) when `count`.
void check_windowed(raster::WindowedPasses& passes, const Scene& s, const std::vector<raster::WindowedItem>& items,
                    const std::vector<std::uint32_t>& lo, const std::vector<std::uint32_t>& hi,
                    const std::vector<std::uint8_t>& query, const std::vector<std::uint8_t>& write, int w, int h,
                    DepthFormat f, int threads, bool count, int& passed, int& failed) {
    CAPTURE(threads);
    auto prepared = passes.prepare(w, h, f, items, threads);
    REQUIRE_MESSAGE(prepared.ok(), (prepared.ok() ? std::string() : prepared.error().message));
    for (const bool forward : {true, false}) {
        CAPTURE(forward);
        const std::vector<std::uint8_t> want = recorded_windowed(s, lo, hi, query, write, forward, w, h, f);
        auto got = passes.run(forward, query, write);
        REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
        CHECK(got.value() == want);
        if (count)
            for (std::size_t k = 0; k < want.size(); ++k)
                if (query[k]) (want[k] != 0 ? passed : failed) += 1;
    }
}

}  // namespace

TEST_CASE("WindowedPasses (each item rasterized once) give the recorded windowed passes' answers") {
    test::Rng rng(20261127);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{16, 16}, {37, 23}, {64, 64}};
    raster::WindowedPasses passes;  // reused across calls, as the device does
    int passed = 0, failed = 0;
    for (int rep = 0; rep < 90; ++rep) {
        // Small scenes, scenes of hundreds of objects (several chunks of triangles), and every fifth
        // with runs of up to 64 items merged into one (items whose triangles span chunks, as
        // Quick-CULLIDE's whole objects do).
        Scene s = random_scene(rng, 2 + static_cast<int>(rng.below(rep % 2 == 0 ? 12 : 800)), rep % 3 == 0 ? 1.0 : 0.2);
        if (rep % 5 == 4) {
            Scene merged;
            merged.vertices = s.vertices;
            merged.objects = s.objects;
            const std::size_t run = 1 + rng.below(64);
            for (std::size_t b = 0; b < s.item_indices.size(); b += run) {
                std::vector<std::uint32_t> idx;
                for (std::size_t i = b; i < std::min(s.item_indices.size(), b + run); ++i)
                    idx.insert(idx.end(), s.item_indices[i].begin(), s.item_indices[i].end());
                merged.item_indices.push_back(std::move(idx));
                merged.item_object.push_back(s.item_object[b]);
            }
            s = std::move(merged);
        }
        const std::size_t n = s.item_indices.size();
        std::vector<std::uint32_t> lo, hi;
        random_windows(rng, n, lo, hi, s.item_object);
        std::vector<raster::WindowedItem> items(n);
        for (std::size_t i = 0; i < n; ++i) items[i] = {raster::MeshViewD{s.vertices, s.item_indices[i]}, lo[i], hi[i]};
        std::vector<std::uint8_t> query(n), write(n);
        for (std::size_t i = 0; i < n; ++i) {
            query[i] = rng.below(5) != 0 ? 1 : 0;
            write[i] = rng.below(5) != 0 ? 1 : 0;
        }
        for (std::size_t i = 0; i < n; ++i) items[i].used = query[i] != 0 || write[i] != 0;
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        CAPTURE(rep);
        for (const int threads : {1, 2, 3, 8})
            check_windowed(passes, s, items, lo, hi, query, write, w, h, f, threads, threads == 1, passed, failed);
    }
    // Both answers occur, so the comparison can fail either way.
    CHECK(passed > 100);
    CHECK(failed > 100);
}

TEST_CASE("WindowedPasses on spread scenes give the recorded answers") {
    // The spread scenes of the fused pass's items-alone test (objects apart, items at the far plane,
    // clipped, far beyond, outside, scattered) with object windows (Quick-CULLIDE without
    // self-collision), bands (with it) and the mix; random query and write masks; 32^2, 37 x 23 and
    // 300 x 200.
    test::Rng rng(20261128);
    const DepthFormat formats[] = {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F};
    const int sizes[][2] = {{32, 32}, {37, 23}, {300, 200}};
    int far_alone = 0, passed = 0, failed = 0;
    for (int rep = 0; rep < 27; ++rep) {
        const Scene s = spread_scene(rng, far_alone);
        const std::size_t n = s.item_indices.size();
        std::vector<std::uint32_t> lo, hi;
        random_windows(rng, n, lo, hi, s.item_object);
        std::vector<raster::WindowedItem> items(n);
        std::vector<std::uint8_t> query(n), write(n);
        for (std::size_t i = 0; i < n; ++i) {
            query[i] = rng.below(5) != 0 ? 1 : 0;
            write[i] = rng.below(5) != 0 ? 1 : 0;
            items[i] = {raster::MeshViewD{s.vertices, s.item_indices[i]}, lo[i], hi[i], query[i] != 0 || write[i] != 0};
        }
        const DepthFormat f = formats[rep % 3];
        const int w = sizes[(rep / 3) % 3][0], h = sizes[(rep / 3) % 3][1];
        CAPTURE(rep);
        for (const int threads : {1, 3}) {
            raster::WindowedPasses passes;
            check_windowed(passes, s, items, lo, hi, query, write, w, h, f, threads, true, passed, failed);
        }
    }
    CHECK(passed > 100);
    CHECK(failed > 100);
}

TEST_CASE("WindowedPasses reject bad input and windows, naming the item") {
    const std::vector<Double4> v = {{0, 0, 0, 1}, {0.5, 0, 0, 1}, {0, 0.5, 0, 2}, {0, 0.5, 0, 1}};
    const std::vector<std::uint32_t> bad_w = {0, 1, 2}, good = {0, 1, 3}, bad_index = {0, 1, 9}, bad_count = {0, 1};
    raster::WindowedPasses passes;
    const std::vector<std::uint8_t> one = {1}, two = {1, 1};
    CHECK(!passes.run(true, one, one).ok());  // nothing prepared yet
    auto r = passes.prepare(16, 16, DepthFormat::D24, std::vector<raster::WindowedItem>{{{v, bad_w}, 0, 0}}, 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("windowed passes: item 0: vertex 2 has w = 2") != std::string::npos);
    CHECK(!passes.run(true, one, one).ok());  // a failed prepare leaves nothing to run
    r = passes.prepare(16, 16, DepthFormat::D24, std::vector<raster::WindowedItem>{{{v, good}, 0, 0}, {{v, bad_index}, 1, 1}}, 2);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("item 1: index 9 at position 2") != std::string::npos);
    r = passes.prepare(16, 16, DepthFormat::D24, std::vector<raster::WindowedItem>{{{v, bad_count}, 0, 0}}, 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("item 0: index count 2") != std::string::npos);
    r = passes.prepare(16, 16, DepthFormat::D24, std::vector<raster::WindowedItem>{{{v, good}, 0, 1}, {{v, good}, 0, 0}}, 1);
    REQUIRE(!r.ok());  // near_hi decreases
    CHECK(r.error().message.find("item 1: window [0, 0]") != std::string::npos);
    r = passes.prepare(16, 16, DepthFormat::D24, std::vector<raster::WindowedItem>{{{v, good}, 0, 2}, {{v, good}, 1, 2}}, 1);
    REQUIRE(!r.ok());  // beyond the item list
    CHECK(r.error().message.find("item 0: window [0, 2]") != std::string::npos);
    r = passes.prepare(1024, 1024, DepthFormat::D24, {}, 1);
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("target 1024x1024") != std::string::npos);
    r = passes.prepare(16, 16, DepthFormat::D24, std::vector<raster::WindowedItem>{{{v, good}, 0, 0}, {{v, good}, 1, 1}}, 1);
    REQUIRE(r.ok());
    CHECK(r.value() > 0);
    CHECK(!passes.run(true, one, two).ok());  // a mask of the wrong size
    auto ok = passes.run(true, two, two);
    REQUIRE(ok.ok());
    CHECK(ok.value() == std::vector<std::uint8_t>{0, 1});  // item 1 meets item 0's equal depth: passes
    // An item prepared as unused: masks that use it are refused; without it, item 1 meets the clear.
    r = passes.prepare(16, 16, DepthFormat::D24,
                       std::vector<raster::WindowedItem>{{{v, good}, 0, 0, false}, {{v, good}, 1, 1}}, 1);
    REQUIRE(r.ok());
    auto refused = passes.run(true, two, two);
    REQUIRE(!refused.ok());
    CHECK(refused.error().message.find("item 0 was prepared as unused") != std::string::npos);
    const std::vector<std::uint8_t> only1 = {0, 1};
    ok = passes.run(true, only1, only1);
    REQUIRE(ok.ok());
    CHECK(ok.value() == std::vector<std::uint8_t>{0, 0});
}
