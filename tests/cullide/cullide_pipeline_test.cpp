// CULLIDE / R-CULLIDE pipeline against the exact ground truth (ground_truth.h): the reliable modes
// report exactly the ground-truth pairs, the GL-exact mode never reports a false pair and its misses
// are counted, results do not depend on the thread count, options and errors behave.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "cullide/cullide.h"
#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/quick_cullide.h"
#include "cullide/scenes.h"
#include "pipeline_test_util.h"
#include "raster/detail/parallel.h"
#include "test_rng.h"

namespace {

using cullide::Method;
using cullide::TrianglePair;

using test::misses;
using test::run;
using test::truth;

cullide::Mesh cube(cullide::Vec3 centre, double side, std::string name) {
    // A cube turned by fixed angles about z then x, so no face is parallel to a view axis (an
    // axis-aligned face is edge-on in two of the three views and GL-exact never samples it).
    const double a = 0.3, b = 0.5;
    const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b);
    cullide::Mesh m;
    m.name = std::move(name);
    for (int c = 0; c < 8; ++c) {
        double x = side * ((c & 1) - 0.5), y = side * (((c >> 1) & 1) - 0.5), z = side * (((c >> 2) & 1) - 0.5);
        const double x1 = x * ca - y * sa, y1 = x * sa + y * ca;
        const double y2 = y1 * cb - z * sb, z2 = y1 * sb + z * cb;
        m.positions.push_back({centre.x + x1, centre.y + y2, centre.z + z2});
    }
    m.triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                   {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
    return m;
}

cullide::Mesh triangle(cullide::Vec3 c, double s, cullide::Vec3 p, cullide::Vec3 q, cullide::Vec3 r,
                       std::string name) {
    cullide::Mesh m;
    m.name = std::move(name);
    m.positions = {c + s * p, c + s * q, c + s * r};
    m.triangles = {{0, 1, 2}};
    return m;
}

// Two pairs of crossing cubes at opposite corners of a room of side `room` keep the views wide;
// in the middle two crossing triangles of size ~1 are far smaller than a pixel at low resolution.
std::vector<cullide::Mesh> tiny_crossing_scene(double room) {
    const cullide::Vec3 mid{room / 2, room / 2, room / 2};
    return {cube({5, 5, 5}, 10, "a"),
            cube({10, 10, 10}, 10, "b"),
            cube({room - 5, room - 5, room - 5}, 10, "c"),
            cube({room - 10, room - 10, room - 10}, 10, "d"),
            triangle(mid, 0.5, {1, 0.1, 0.3}, {-0.5, 0.87, -0.2}, {-0.5, -0.87, 0.1}, "t1"),
            triangle(mid, 0.5, {0.3, 0.9, -0.1}, {-0.2, -0.3, 0.95}, {0.1, -0.4, -0.9}, "t2")};
}

bool has_object_pair(const std::vector<TrianglePair>& pairs, std::uint32_t a, std::uint32_t b) {
    return std::any_of(pairs.begin(), pairs.end(),
                       [&](const TrianglePair& p) { return p.object_a == a && p.object_b == b; });
}

}  // namespace

TEST_CASE("the reliable methods report exactly the ground-truth pairs on every built-in scene") {
    const double scale = std::getenv("CULLIDE_PIPELINE_SCALE") ? std::atof(std::getenv("CULLIDE_PIPELINE_SCALE")) : 0.05;
    std::uint64_t total_pairs = 0;
    for (const std::string& name : cullide::scene_names()) {
        cullide::SceneOptions so;
        so.scale = scale;
        so.mesh_dir = "";  // procedural stand-ins: the same scene everywhere
        auto scene = cullide::make_scene(name, so);
        REQUIRE(scene.ok());
        for (int frame : {0, 5}) {
            const cullide::Frame objects = scene.value()->frame(frame);
            const auto exact = truth(objects);
            total_pairs += exact.size();
            for (int resolution : {128}) {
                for (Method m : {Method::RCullide, Method::RCullideOffset, Method::Auto}) {
                    CAPTURE(name);
                    CAPTURE(frame);
                    CAPTURE(resolution);
                    CAPTURE(cullide::to_string(m));
                    const cullide::FrameResult r = run(objects, m, resolution);
                    CHECK(r.pairs == exact);
                    CHECK(r.stats.pcs_subobjects <= r.stats.subobjects);
                }
                CAPTURE(name);
                CAPTURE(frame);
                CAPTURE(resolution);
                const cullide::FrameResult c = run(objects, Method::Cullide, resolution);
                const std::size_t missed = misses(c.pairs, exact);
                MESSAGE(name << " frame " << frame << " resolution " << resolution << ": cullide missed " << missed
                             << " of " << exact.size() << " pairs");
            }
        }
    }
    CHECK(total_pairs > 1000);  // the scenes must collide, or the equality above proves little
}

TEST_CASE("cullide misses a collision smaller than a pixel and finds it when pixels are small enough") {
    const auto objects = tiny_crossing_scene(100.0);
    const auto exact = truth(objects);
    REQUIRE(has_object_pair(exact, 4, 5));  // the two tiny triangles do cross
    REQUIRE(has_object_pair(exact, 0, 1));
    REQUIRE(has_object_pair(exact, 2, 3));
    for (Method m : {Method::RCullide, Method::RCullideOffset}) {
        for (int resolution : {16, 64, 1024}) {
            CAPTURE(cullide::to_string(m));
            CAPTURE(resolution);
            CHECK(run(objects, m, resolution).pairs == exact);
        }
    }
    // Sampling error (algorithms.md section 4): at 64 pixels a pixel is 1.6 units, the triangles
    // cover no pixel centre, make no fragment, and so look fully visible.
    const cullide::FrameResult low = run(objects, Method::Cullide, 64);
    CHECK_FALSE(has_object_pair(low.pairs, 4, 5));
    CHECK(misses(low.pairs, exact) > 0);
    const cullide::FrameResult high = run(objects, Method::Cullide, 4096);
    CHECK(has_object_pair(high.pairs, 4, 5));
    CHECK(misses(high.pairs, exact) < misses(low.pairs, exact));
}

TEST_CASE("cullide misses faces that are edge-on in the views, whatever the resolution") {
    // Two axis-aligned cubes crossing: every face is parallel to two view axes, so each sub-object of
    // one face pair is edge-on (no fragments, hence fully visible) in some view and is pruned.
    auto aligned = [](cullide::Vec3 lo, std::string name) {
        cullide::Mesh m;
        m.name = std::move(name);
        for (int c = 0; c < 8; ++c)
            m.positions.push_back({lo.x + 10.0 * (c & 1), lo.y + 10.0 * ((c >> 1) & 1), lo.z + 10.0 * ((c >> 2) & 1)});
        m.triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                       {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
        return m;
    };
    const std::vector<cullide::Mesh> objects{aligned({0, 0, 0}, "a"), aligned({5, 5, 5}, "b")};
    const auto exact = truth(objects);
    REQUIRE_FALSE(exact.empty());
    for (int resolution : {64, 256}) {
        CAPTURE(resolution);
        CHECK(run(objects, Method::Cullide, resolution).pairs.empty());
        CHECK(run(objects, Method::RCullide, resolution).pairs == exact);
        CHECK(run(objects, Method::RCullideOffset, resolution).pairs == exact);
    }
}

TEST_CASE("pairs and every PCS figure are the same for 1, 2, 3 and 8 threads") {
    cullide::SceneOptions so;
    so.scale = 0.05;
    auto scene = cullide::make_scene("tori", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(2);
    for (Method m : {Method::Cullide, Method::RCullide, Method::RCullideOffset}) {
        const cullide::FrameResult one = run(objects, m, 128, 1);
        REQUIRE_FALSE(one.pairs.empty());
        for (int threads : {2, 3, 8}) {
            CAPTURE(cullide::to_string(m));
            CAPTURE(threads);
            const cullide::FrameResult r = run(objects, m, 128, threads);
            CHECK(r.pairs == one.pairs);
            CHECK(r.stats.queries == one.stats.queries);
            CHECK(r.stats.triangles_rasterized == one.stats.triangles_rasterized);
            CHECK(r.stats.exact_tests == one.stats.exact_tests);
            REQUIRE(r.stats.views.size() == one.stats.views.size());
            for (std::size_t v = 0; v < r.stats.views.size(); ++v) {
                CHECK(r.stats.views[v].items_after == one.stats.views[v].items_after);
                CHECK(r.stats.views[v].queries == one.stats.views[v].queries);
            }
        }
    }
}

// raster/detail/parallel.h's spread schedule: every parallel_for of raster and cullide hands items
// to threads of their own, in descending order, so a job that reads the calling thread's state (a
// thread_local named inside a job) shows here even where oneTBB would run every job on the caller.
TEST_CASE("on the spread schedule every method gives the pairs and figures of one thread, self-collision too") {
    cullide::SceneOptions so;
    so.scale = 0.05;
    struct Input {
        const char* scene;
        int frame;
        bool self;
    };
    for (const Input in : {Input{"tori", 2, false}, Input{"cloth", 55, true}}) {
        auto scene = cullide::make_scene(in.scene, so);
        REQUIRE(scene.ok());
        const cullide::Frame objects = scene.value()->frame(in.frame);
        for (Method m : {Method::Exact, Method::Auto, Method::Cullide, Method::RCullide,
                         Method::RCullideOffset, Method::QCullide, Method::QCullideGL}) {
            if (in.self && (m == Method::Cullide || m == Method::RCullide || m == Method::RCullideOffset))
                continue;
            CAPTURE(in.scene);
            CAPTURE(cullide::to_string(m));
            const cullide::FrameResult one = run(objects, m, 128, 1, cullide::BroadPhase::None, in.self);
            CHECK_FALSE(one.pairs.empty());
            const raster::detail::SpreadScheduleScope schedule;
            for (int threads : {2, 3}) {
                CAPTURE(threads);
                const cullide::FrameResult r = run(objects, m, 128, threads, cullide::BroadPhase::None, in.self);
                const cullide::FrameStats& a = r.stats;
                const cullide::FrameStats& b = one.stats;
                CHECK(r.pairs == one.pairs);
                CHECK(a.queries == b.queries);
                CHECK(a.triangles_rasterized == b.triangles_rasterized);
                CHECK(a.exact_tests == b.exact_tests);
                CHECK(a.candidate_triangles == b.candidate_triangles);
                CHECK(a.pcs_boxes == b.pcs_boxes);
                CHECK(a.pcs_subobjects == b.pcs_subobjects);
                REQUIRE(a.views.size() == b.views.size());
                for (std::size_t v = 0; v < a.views.size(); ++v) {
                    CAPTURE(v);
                    CHECK(a.views[v].items_after == b.views[v].items_after);
                    CHECK(a.views[v].queries == b.views[v].queries);
                }
            }
        }
    }
}

TEST_CASE("the statistics add up: views, queries and the PCS shrink monotonically") {
    cullide::SceneOptions so;
    so.scale = 0.1;
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);
    const cullide::FrameResult r = run(objects, Method::Cullide, 256);
    const cullide::FrameStats& s = r.stats;
    CHECK(s.objects == objects.size());
    CHECK(s.broadphase_objects == objects.size());
    CHECK(s.pcs_boxes <= s.broadphase_objects);
    CHECK(s.pcs_objects <= s.pcs_boxes);
    CHECK(s.pcs_subobjects <= s.subobjects);
    REQUIRE_FALSE(s.views.empty());
    std::uint64_t queries = 0, tris = 0;
    for (std::size_t v = 0; v < s.views.size(); ++v) {
        CAPTURE(v);
        const cullide::ViewStats& vs = s.views[v];
        CHECK(vs.items_after <= vs.items_before);
        CHECK(vs.queries == 2 * vs.items_before);  // one query per live item per pass
        queries += vs.queries;
        tris += vs.triangles_rasterized;
        if (v > 0 && s.views[v - 1].stage == vs.stage) CHECK(vs.items_before == s.views[v - 1].items_after);
    }
    CHECK(queries == s.queries);
    CHECK(tris == s.triangles_rasterized);
    // Within a stage the views cycle x, y, z from x.
    std::size_t first = 0;
    for (std::size_t v = 0; v < s.views.size(); ++v) {
        if (v > 0 && s.views[v].stage != s.views[v - 1].stage) first = v;
        CHECK(s.views[v].axis == static_cast<int>((v - first) % 3));
    }
    CHECK(s.candidate_triangles <= s.triangles);
    CHECK(r.pairs.size() <= s.exact_tests);
}

TEST_CASE("the broad phase keeps the ground truth and drops objects that overlap nothing") {
    auto objects = tiny_crossing_scene(100.0);
    objects.push_back(cube({50, 20, 80}, 3, "alone"));  // overlaps no other box
    const auto exact = truth(objects);
    for (cullide::BroadPhase bp : {cullide::BroadPhase::SpatialHash, cullide::BroadPhase::SweepAndPrune,
                                   cullide::BroadPhase::BruteForce}) {
        for (Method m : {Method::Exact, Method::RCullide, Method::RCullideOffset}) {
            CAPTURE(cullide::to_string(bp));
            CAPTURE(cullide::to_string(m));
            const cullide::FrameResult r = run(objects, m, 64, 2, bp);
            CHECK(r.pairs == exact);
            CHECK(r.stats.broadphase_objects == objects.size() - 1);
            CHECK(r.stats.broadphase_pairs == 3);
        }
    }
}

namespace {

// The objects whose closed box (over their triangles' vertices) overlaps another object's: what a
// broad phase keeps, found here by brute force.
std::vector<std::uint32_t> overlapping_objects(const cullide::Frame& objects) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<cullide::Aabb> box(objects.size(), cullide::Aabb{{inf, inf, inf}, {-inf, -inf, -inf}});
    for (std::size_t i = 0; i < objects.size(); ++i)
        for (const cullide::Tri& t : objects[i].triangles)
            for (std::uint32_t v : t) {
                const cullide::Vec3& p = objects[i].positions[v];
                box[i].lo = {std::min(box[i].lo.x, p.x), std::min(box[i].lo.y, p.y), std::min(box[i].lo.z, p.z)};
                box[i].hi = {std::max(box[i].hi.x, p.x), std::max(box[i].hi.y, p.y), std::max(box[i].hi.z, p.z)};
            }
    std::vector<std::uint32_t> kept;
    for (std::size_t i = 0; i < objects.size(); ++i)
        for (std::size_t j = 0; j < objects.size(); ++j)
            if (i != j && box[i].lo.x <= box[j].hi.x && box[j].lo.x <= box[i].hi.x && box[i].lo.y <= box[j].hi.y &&
                box[j].lo.y <= box[i].hi.y && box[i].lo.z <= box[j].hi.z && box[j].lo.z <= box[i].hi.z) {
                kept.push_back(static_cast<std::uint32_t>(i));
                break;
            }
    return kept;
}

// Whether every object's box overlaps another's with a common interior (not only a shared face,
// edge or corner).
bool every_box_open_overlaps(const cullide::Frame& objects) {
    std::vector<cullide::Aabb> box(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) box[i] = cullide::mesh_bounds(objects[i]);
    for (std::size_t i = 0; i < objects.size(); ++i) {
        bool any = false;
        for (std::size_t j = 0; j < objects.size() && !any; ++j)
            any = i != j && box[i].lo.x < box[j].hi.x && box[j].lo.x < box[i].hi.x && box[i].lo.y < box[j].hi.y &&
                  box[j].lo.y < box[i].hi.y && box[i].lo.z < box[j].hi.z && box[j].lo.z < box[i].hi.z;
        if (!any) return false;
    }
    return true;
}

// f(name, frame number, objects) for five built-in scenes at scale 0.3, frames 0, 17 and 40.
template <class F>
void each_scene_frame(F&& f) {
    for (const char* name : {"cylinders", "leaves", "breaking", "tori", "cloth"}) {
        cullide::SceneOptions so;
        so.scale = 0.3;
        auto scene = cullide::make_scene(name, so);
        REQUIRE(scene.ok());
        for (int frame : {0, 17, 40}) {
            CAPTURE(name);
            CAPTURE(frame);
            f(name, frame, scene.value()->frame(frame));
        }
    }
}

std::size_t box_views(const cullide::VisibilityStats& s) {
    return static_cast<std::size_t>(std::count_if(s.views.begin(), s.views.end(),
                                                  [](const cullide::ViewStats& v) { return v.stage == cullide::CullStage::Boxes; }));
}

}  // namespace

TEST_CASE("after a broad phase rcullide skips its box views, which would prune nothing: the same PCS and pairs") {
    auto device = cullide::make_emulator_device(2);
    REQUIRE(device);
    std::size_t frames_with_dropped = 0;
    each_scene_frame([&](const char*, int, const cullide::Frame& objects) {
        const cullide::FrameResult skipped = run(objects, Method::RCullide, 32, 2, cullide::BroadPhase::SweepAndPrune);
        const std::vector<std::uint32_t> active = overlapping_objects(objects);
        REQUIRE(skipped.stats.broadphase_objects == active.size());
        if (active.size() < objects.size()) ++frames_with_dropped;
        CHECK(box_views(skipped.stats) == 0);
        if (active.size() < 2) return;
        // The same objects with the box views run: they prune none of them, and everything after
        // them is the same.
        cullide::CullideOptions co;
        co.mode = cullide::VisibilityMode::ExactBounds;
        co.resolution = 32;
        co.threads = 2;
        REQUIRE(co.box_stage);
        co.settle_box_views = false;  // run them (settled, they would prune nothing by construction)
        cullide::CullideStats with;
        auto pairs = cullide::cullide_pairs(objects, active, co, *device, &with);
        REQUIRE_MESSAGE(pairs.ok(), (pairs.ok() ? std::string() : pairs.error().message));
        CHECK(box_views(with) > 0);
        CHECK(with.pcs_boxes == active.size());
        CHECK(pairs.value() == skipped.pairs);
        CHECK(with.pcs_objects == skipped.stats.pcs_objects);
        CHECK(with.subobjects == skipped.stats.subobjects);
        CHECK(with.pcs_subobjects == skipped.stats.pcs_subobjects);
        CHECK(with.subobject_pairs == skipped.stats.subobject_pairs);
        CHECK(with.candidate_triangles == skipped.stats.candidate_triangles);
        CHECK(with.exact_tests == skipped.stats.exact_tests);
        // The sub-object views, one for one.
        std::vector<cullide::ViewStats> later;
        for (const cullide::ViewStats& v : with.views)
            if (v.stage != cullide::CullStage::Boxes) later.push_back(v);
        REQUIRE(later.size() == skipped.stats.views.size());
        for (std::size_t v = 0; v < later.size(); ++v) {
            CHECK(later[v].items_before == skipped.stats.views[v].items_before);
            CHECK(later[v].items_after == skipped.stats.views[v].items_after);
            CHECK(later[v].queries == skipped.stats.views[v].queries);
        }
    });
    CHECK(frames_with_dropped > 0);  // the broad phase dropped objects somewhere, so the check above had room to differ
    // CULLIDE (GL-exact) keeps its box views after a broad phase: they may prune overlapping boxes.
    cullide::SceneOptions so;
    so.scale = 0.3;
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);
    CHECK(box_views(run(objects, Method::Cullide, 256, 2, cullide::BroadPhase::SweepAndPrune).stats) > 0);
    CHECK(box_views(run(objects, Method::RCullide, 32, 2).stats) > 0);  // and rcullide without a broad phase
}

// Both runs of cullide_pairs with exact bounds, box views settled and run: every figure but the
// settled count must be the same.
void check_settled_box_views(const cullide::Frame& objects, int resolution, raster::DepthFormat format,
                             cullide::QueryDevice& device, std::size_t& settled_runs, std::size_t& pruning_runs) {
    std::vector<std::uint32_t> all(objects.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
    cullide::CullideOptions co;
    co.mode = cullide::VisibilityMode::ExactBounds;
    co.resolution = resolution;
    co.depth_format = format;
    co.threads = 2;
    cullide::CullideStats settled, ran;
    auto a = cullide::cullide_pairs(objects, all, co, device, &settled);
    REQUIRE_MESSAGE(a.ok(), (a.ok() ? std::string() : a.error().message));
    co.settle_box_views = false;
    auto b = cullide::cullide_pairs(objects, all, co, device, &ran);
    REQUIRE_MESSAGE(b.ok(), (b.ok() ? std::string() : b.error().message));
    CHECK(ran.box_views_settled == 0);
    CHECK(a.value() == b.value());
    CHECK(settled.pcs_boxes == ran.pcs_boxes);
    CHECK(settled.pcs_subobjects == ran.pcs_subobjects);
    CHECK(settled.queries == ran.queries);
    CHECK(settled.triangles_rasterized == ran.triangles_rasterized);
    CHECK(settled.exact_tests == ran.exact_tests);
    REQUIRE(settled.views.size() == ran.views.size());
    for (std::size_t v = 0; v < ran.views.size(); ++v) {
        CAPTURE(v);
        CHECK(settled.views[v].stage == ran.views[v].stage);
        CHECK(settled.views[v].items_before == ran.views[v].items_before);
        CHECK(settled.views[v].items_after == ran.views[v].items_after);
        CHECK(settled.views[v].queries == ran.views[v].queries);
        CHECK(settled.views[v].triangles_rasterized == ran.views[v].triangles_rasterized);
    }
    if (settled.box_views_settled > 0) {
        ++settled_runs;
        CHECK(settled.box_views_settled == static_cast<std::uint64_t>(box_views(settled)));
        CHECK(settled.pcs_boxes == objects.size());
    }
    if (ran.pcs_boxes < objects.size()) ++pruning_runs;
}

TEST_CASE("rcullide settles its box views where every box overlaps another: the figures of running them") {
    auto device = cullide::make_emulator_device(2);
    REQUIRE(device);
    std::size_t settled_runs = 0, pruning_runs = 0;
    each_scene_frame([&](const char*, int, const cullide::Frame& objects) {
        check_settled_box_views(objects, 32, raster::DepthFormat::D24, *device, settled_runs, pruning_runs);
    });
    CHECK(settled_runs > 0);
    CHECK(pruning_runs > 0);
    // Boxes that only touch (a shared face, edge or corner on a coarse grid), flat and degenerate
    // objects: the closed-overlap rule must hold at the boundary, where the views' answers are
    // closest to pruning.
    test::Rng rng(23);
    const std::size_t settled_scenes = settled_runs;
    std::size_t touching_only = 0;  // settled scenes with an object whose box only touches the others'
    for (int scene = 0; scene < 300; ++scene) {
        CAPTURE(scene);
        cullide::Frame objects(static_cast<std::size_t>(rng.range(2, 6)));
        for (cullide::Mesh& m : objects) {
            const int tris = rng.range(1, 3);
            const double o[3] = {rng.grid(0, 1, 1), rng.grid(0, 1, 1), rng.grid(0, 1, 1)};
            for (int t = 0; t < tris; ++t) {
                for (int k = 0; k < 3; ++k) {
                    // On a coarse grid inside a unit cell from o: boxes of neighbouring cells touch.
                    const auto coord = [&](int axis) { return o[axis] + (rng.below(4) == 0 ? 0.5 : rng.coin() ? 1.0 : 0.0); };
                    m.positions.push_back({coord(0), coord(1), coord(2)});
                }
                const auto v = static_cast<std::uint32_t>(m.positions.size() - 3);
                m.triangles.push_back({v, v + 1, v + 2});
            }
        }
        const int resolution = std::array<int, 3>{16, 32, 33}[rng.below(3)];
        const raster::DepthFormat format =
            std::array<raster::DepthFormat, 3>{raster::DepthFormat::D16, raster::DepthFormat::D24,
                                               raster::DepthFormat::D32F}[rng.below(3)];
        const std::size_t before = settled_runs;
        check_settled_box_views(objects, resolution, format, *device, settled_runs, pruning_runs);
        if (settled_runs > before && !every_box_open_overlaps(objects)) ++touching_only;
    }
    CHECK(settled_runs - settled_scenes >= 60);  // the rule held on random scenes where it applied
    CHECK(touching_only >= 20);                  // ... and at its boundary
}

TEST_CASE("rcullide without its box stage still reports exactly the ground truth (the stage only prunes)") {
    auto device = cullide::make_emulator_device(2);
    REQUIRE(device);
    cullide::SceneOptions so;
    so.scale = 0.3;
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(5);
    std::vector<std::uint32_t> all(objects.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
    cullide::CullideOptions co;
    co.mode = cullide::VisibilityMode::ExactBounds;
    co.resolution = 32;
    co.threads = 2;
    cullide::CullideStats on, off;
    auto with = cullide::cullide_pairs(objects, all, co, *device, &on);
    co.box_stage = false;
    auto without = cullide::cullide_pairs(objects, all, co, *device, &off);
    REQUIRE(with.ok());
    REQUIRE(without.ok());
    CHECK(with.value() == truth(objects));
    CHECK(without.value() == with.value());
    CHECK(on.pcs_boxes < objects.size());  // here the box views prune: skipping them is a real change
    CHECK(off.pcs_boxes == objects.size());
    CHECK(box_views(off) == 0);
}

TEST_CASE("bad options and inputs are errors that name the problem") {
    const auto objects = tiny_crossing_scene(100.0);
    cullide::RunOptions o;
    o.method = Method::Cullide;
    o.self = true;
    auto r = cullide::process_frame(objects, o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("self-collision is not supported by method 'cullide'") != std::string::npos);

    o.self = false;
    o.subobject_triangles = 0;
    r = cullide::process_frame(objects, o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("sub-object size must be >= 1") != std::string::npos);

    o.subobject_triangles = 4;
    o.resolution = -1;
    r = cullide::process_frame(objects, o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("resolution must be in 1..16384 (got -1)") != std::string::npos);

    o.resolution = 64;
    auto bad = objects;
    bad[2].triangles[3][1] = 99;
    r = cullide::process_frame(bad, o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("object 2") != std::string::npos);

    auto device = cullide::make_emulator_device(1);
    const std::vector<std::uint32_t> unsorted{1, 0};
    auto p = cullide::cullide_pairs(objects, unsorted, {}, *device);
    REQUIRE_FALSE(p.ok());
    CHECK(p.error().message.find("strictly increasing (entry 1)") != std::string::npos);
    const std::vector<std::uint32_t> beyond{0, 9};
    p = cullide::cullide_pairs(objects, beyond, {}, *device);
    REQUIRE_FALSE(p.ok());
    CHECK(p.error().message.find("active object 1 = 9 is beyond the object list (size 6)") != std::string::npos);

    CHECK_FALSE(cullide::parse_method("rcullide-offsets").ok());
    CHECK(cullide::parse_method("rcullide-offset").value() == Method::RCullideOffset);
    CHECK(cullide::parse_depth_format("d32f").value() == raster::DepthFormat::D32F);
    CHECK(cullide::parse_depth_format("d8").error().message.find("valid: d16, d24, d32f") != std::string::npos);
    CHECK(cullide::parse_broadphase("sap").value() == cullide::BroadPhase::SweepAndPrune);
}

TEST_CASE("every sub-object size and depth format gives the ground truth in the reliable modes") {
    cullide::SceneOptions so;
    so.scale = 0.05;
    auto scene = cullide::make_scene("breaking", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(1);
    const auto exact = truth(objects);
    REQUIRE_FALSE(exact.empty());
    for (int group : {1, 3, 16}) {
        for (raster::DepthFormat f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
            if (group != 3 && f != raster::DepthFormat::D24) continue;  // every format once, every size once
            for (Method m : {Method::Cullide, Method::RCullide, Method::RCullideOffset}) {
                CAPTURE(group);
                CAPTURE(cullide::to_string(f));
                CAPTURE(cullide::to_string(m));
                cullide::RunOptions o;
                o.method = m;
                o.resolution = 128;
                o.subobject_triangles = group;
                o.depth_format = f;
                auto r = cullide::process_frame(objects, o);
                REQUIRE(r.ok());
                if (m == Method::Cullide)
                    misses(r.value().pairs, exact);
                else
                    CHECK(r.value().pairs == exact);
            }
        }
    }
}

TEST_CASE("every method refuses coordinates outside the exact range, as the ground truth does") {
    // Regression of fuzz/findings/pipeline: rcullide accepted a subnormal coordinate exact refused.
    std::vector<cullide::Mesh> objects(2);
    for (int o = 0; o < 2; ++o) {
        objects[static_cast<std::size_t>(o)].name = std::string("m").append(std::to_string(o));
        objects[static_cast<std::size_t>(o)].positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        objects[static_cast<std::size_t>(o)].triangles = {{0, 1, 2}};
    }
    // Far from object 0, so the broad phase drops it before any later stage could see it.
    objects[1].positions = {{10, 0, 0}, {11, 0, 0}, {10, 1, 0}};
    objects[1].positions[0].y = -0x1p-1073;  // subnormal
    const auto exact = cullide::exact_pairs(objects);
    REQUIRE_FALSE(exact.ok());
    for (Method m : {Method::Exact, Method::Cullide, Method::RCullide, Method::RCullideOffset}) {
        CAPTURE(cullide::to_string(m));
        cullide::RunOptions o;
        o.method = m;
        o.resolution = 64;
        o.broadphase = cullide::BroadPhase::SpatialHash;
        auto r = cullide::process_frame(objects, o);
        REQUIRE_FALSE(r.ok());
        CHECK(r.error().message == exact.error().message);
    }
}

namespace {
// Six overlapping cubes of 12 triangles, c0 .. c5: more than kSerialFrameTriangles (64) triangles, so
// the scene checks run in parallel jobs.
std::vector<cullide::Mesh> six_cubes() {
    std::vector<cullide::Mesh> objects;
    for (int o = 0; o < 6; ++o) objects.push_back(cube({0.4 * o, 0, 0}, 1.0, std::string("c").append(std::to_string(o))));
    return objects;
}
}  // namespace

TEST_CASE("every method names the first problem the serial scene checks name (exact and auto in exact_pairs' scan)") {
    // process_frame leaves the scene checks of a frame that goes straight to exact_pairs over every
    // object to exact_pairs' parallel scan: the message must be the one validate_scene, then
    // validate_exact_range, give, naming the first problem in that order.
    const auto scene = six_cubes;
    struct Case {
        const char* what;
        std::vector<cullide::Mesh> objects;
        const char* must_name;
    };
    std::vector<Case> cases;
    {
        auto s = scene();  // a range problem in object 1, an index problem in object 2: the index first
        s[1].positions[3].y = 0x1p-310;
        s[2].triangles[5][2] = 8;
        cases.push_back({"index after range", std::move(s), "object 2: mesh 'c2': triangle 5 vertex index 8"});
    }
    {
        auto s = scene();  // range problems in objects 1 and 3: object 1's
        s[3].positions[0].x = 0x1p301;
        s[1].positions[7].z = -0x1p-1070;
        cases.push_back({"two range problems", std::move(s), "object 1: mesh 'c1': vertex 7 coordinate z"});
    }
    {
        auto s = scene();  // a NaN in object 3, an empty object 2
        s[3].positions[2].x = std::nan("");
        s[2].triangles.clear();
        cases.push_back({"empty before non-finite", std::move(s), "object 2: mesh 'c2': has no triangles"});
    }
    {
        auto s = scene();
        s[0].positions[6].y = INFINITY;
        cases.push_back({"infinite", std::move(s), "object 0: mesh 'c0': vertex 6 has a non-finite coordinate"});
    }
    for (const Case& c : cases) {
        CAPTURE(c.what);
        cullide::Status serial = cullide::validate_scene(c.objects);
        if (serial) serial = cullide::validate_exact_range(c.objects);
        REQUIRE_FALSE(serial.ok());
        CHECK(serial.error().message.find(c.must_name) != std::string::npos);
        // exact and auto check in exact_pairs' scan; the visibility methods in process_frame's
        // parallel per-object checks (session 11): every one names the serial scans' first problem.
        for (Method m : {Method::Exact, Method::Auto, Method::RCullide, Method::Cullide, Method::QCullide})
            for (bool self : {false, true})
                for (int threads : {1, 2, 3}) {
                    if (self && (m == Method::RCullide || m == Method::Cullide)) continue;
                    CAPTURE(cullide::to_string(m));
                    CAPTURE(self);
                    CAPTURE(threads);
                    cullide::RunOptions o;
                    o.method = m;
                    o.self = self;
                    o.threads = threads;
                    auto r = cullide::process_frame(c.objects, o);
                    REQUIRE_FALSE(r.ok());
                    CHECK(r.error().message == serial.error().message);
                }
    }
}

TEST_CASE("cullide_pairs and quick_cullide_pairs name the first problem the serial scene checks name") {
    // Both check their own inputs (the public entry points), each object in its own parallel job
    // (session 12): validate_scene's first problem, then the active list's, then the exact range's,
    // in that order, whatever the thread count.
    const auto scene = six_cubes;
    struct Case {
        const char* what;
        std::vector<cullide::Mesh> objects;
        std::vector<std::uint32_t> active;
        const char* must_name;
    };
    const std::vector<std::uint32_t> all{0, 1, 2, 3, 4, 5};
    std::vector<Case> cases;
    {
        auto s = scene();  // a range problem in object 1, an index problem in object 2: the index first
        s[1].positions[3].y = 0x1p-310;
        s[2].triangles[5][2] = 8;
        cases.push_back({"index after range", std::move(s), all, "object 2: mesh 'c2': triangle 5 vertex index 8"});
    }
    {
        auto s = scene();  // range problems in objects 1 and 3: object 1's
        s[3].positions[0].x = 0x1p301;
        s[1].positions[7].z = -0x1p-1070;
        cases.push_back({"two range problems", std::move(s), all, "object 1: mesh 'c1': vertex 7 coordinate z"});
    }
    {
        auto s = scene();  // object 1 is not active: object 3's range problem
        s[3].positions[0].x = 0x1p301;
        s[1].positions[7].z = -0x1p-1070;
        cases.push_back({"inactive object's range", std::move(s), {0, 2, 3, 5}, "object 3: mesh 'c3': vertex 0 coordinate x"});
    }
    {
        auto s = scene();  // a range problem at entry 1, an unsorted active list from entry 2: the range first
        s[2].positions[1].x = 0x1p-1000;
        cases.push_back({"range before unsorted", std::move(s), {0, 2, 1}, "object 2: mesh 'c2': vertex 1 coordinate x"});
    }
    {
        auto s = scene();  // an unsorted list at entry 1, a range problem at entry 2: the list first
        s[3].positions[1].x = 0x1p-1000;
        cases.push_back({"unsorted before range", std::move(s), {2, 1, 3}, "strictly increasing (entry 1)"});
    }
    {
        auto s = scene();  // a NaN in object 4 (inactive) and a range problem in object 0: the NaN
        s[4].positions[2].x = std::nan("");
        s[0].positions[0].y = 0x1p-400;
        cases.push_back({"non-finite anywhere first", std::move(s), {0, 1}, "object 4: mesh 'c4': vertex 2 has a non-finite"});
    }
    for (const Case& c : cases) {
        CAPTURE(c.what);
        for (int threads : {1, 2, 3}) {
            CAPTURE(threads);
            auto device = cullide::make_emulator_device(threads);
            cullide::CullideOptions co;
            co.mode = cullide::VisibilityMode::ExactBounds;
            co.resolution = 32;
            co.threads = threads;
            auto p = cullide::cullide_pairs(c.objects, c.active, co, *device);
            REQUIRE_FALSE(p.ok());
            CHECK(p.error().message.find(c.must_name) != std::string::npos);
            cullide::QuickOptions qo;
            qo.resolution = 32;
            qo.threads = threads;
            auto q = cullide::quick_cullide_pairs(c.objects, c.active, qo, *device);
            REQUIRE_FALSE(q.ok());
            CHECK(q.error().message == p.error().message);
        }
    }
}

TEST_CASE("a view 2^-195 thin along one axis does not overflow the offset solids") {
    // Regression of a pipeline_fuzz finding: two objects whose bounds span 2^-195 along y gave a
    // view scale near 2^195, and rcullide-offset failed with "its box overflows float in clip
    // space" on a scene the ground truth accepts. The solids are now saturated in double first.
    std::vector<cullide::Mesh> objects(2);
    for (int o = 0; o < 2; ++o) objects[static_cast<std::size_t>(o)].name = std::string("m").append(std::to_string(o));
    objects[0].positions = {{0x1.5cp+1, -0x1.ac8f1032405ffp-195, 0x1.c8p+0}, {0, 0, 0}};
    objects[0].triangles = {{0, 0, 0}, {0, 1, 1}};
    objects[1].positions = {{0, 0, 0}, {1, 0, 0.5}};
    objects[1].triangles = {{0, 0, 0}, {0, 1, 0}};
    const auto exact = cullide::exact_pairs(objects);
    REQUIRE(exact.ok());
    for (Method m : {Method::RCullide, Method::RCullideOffset}) {
        for (int res : {16, 216, 1024}) {
            CAPTURE(cullide::to_string(m));
            CAPTURE(res);
            cullide::RunOptions o;
            o.method = m;
            o.resolution = res;
            auto r = cullide::process_frame(objects, o);
            REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
            CHECK(r.value().pairs == exact.value());
        }
    }
}

TEST_CASE("resolution 0 means each method's own default resolution") {
    // A library user who picks another method must not silently inherit rcullide's 32 px.
    cullide::SceneOptions so;
    so.scale = 0.25;
    so.mesh_dir = "";
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);
    for (Method m : {Method::Cullide, Method::RCullide, Method::QCullide, Method::QCullideGL}) {
        CAPTURE(cullide::to_string(m));
        cullide::RunOptions implicit;
        implicit.method = m;
        REQUIRE(implicit.resolution == 0);
        cullide::RunOptions explicit_res = implicit;
        explicit_res.resolution = cullide::default_resolution(m);
        auto a = cullide::process_frame(objects, implicit);
        auto b = cullide::process_frame(objects, explicit_res);
        REQUIRE(a.ok());
        REQUIRE(b.ok());
        CHECK(a.value().pairs == b.value().pairs);
        CHECK(a.value().stats.queries == b.value().stats.queries);
        CHECK(a.value().stats.pcs_subobjects == b.value().stats.pcs_subobjects);
        CHECK(a.value().stats.triangles_rasterized == b.value().stats.triangles_rasterized);
    }
    // And the defaults differ where they should (the exact-bounds methods low, the pixel-centre
    // methods high).
    CHECK(cullide::default_resolution(Method::RCullide) < cullide::default_resolution(Method::Cullide));
    CHECK(cullide::default_resolution(Method::QCullide) < cullide::default_resolution(Method::QCullideGL));
}

namespace {

// An axis-aligned box [lo, hi] as 12 triangles.
cullide::Mesh box_mesh(cullide::Vec3 lo, cullide::Vec3 hi, std::string name) {
    cullide::Mesh m;
    m.name = std::move(name);
    for (int c = 0; c < 8; ++c)
        m.positions.push_back({(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
    m.triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                   {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
    return m;
}

// A UV sphere of `rings` x `segments` quads (two triangles each, poles included as thin quads).
cullide::Mesh sphere(cullide::Vec3 c, double r, int rings, int segments, std::string name) {
    cullide::Mesh m;
    m.name = std::move(name);
    const double pi = std::acos(-1.0);
    for (int i = 0; i <= rings; ++i) {
        const double th = pi * (i + 0.5) / (rings + 1);
        for (int j = 0; j < segments; ++j) {
            const double ph = 2 * pi * j / segments + 0.1 * i;
            m.positions.push_back({c.x + r * std::sin(th) * std::cos(ph), c.y + r * std::sin(th) * std::sin(ph),
                                   c.z + r * std::cos(th)});
        }
    }
    const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(i * segments + (j % segments)); };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return m;
}

// A heap of spheres whose boxes all overlap each other: each triangle sits in many object-pair
// tasks of the exact stage, the case where auto runs R-CULLIDE's views.
std::vector<cullide::Mesh> sphere_heap() {
    std::vector<cullide::Mesh> heap;
    for (int k = 0; k < 20; ++k) {
        std::string name = "s";
        name.append(std::to_string(k));  // not "s" + std::string&&: GCC 12's false -Wrestrict at -O3 (bug 105329)
        heap.push_back(sphere({0.13 * (k % 3), 0.11 * (k % 4), 0.07 * k}, 1.0 + 0.031 * k, 16, 24, name));
    }
    return heap;
}

}  // namespace

TEST_CASE("auto: the plan counts the exact stage's task triangles from the object boxes") {
    // Two 12-triangle boxes overlapping over half of each along x: 6 + 6 task triangles.
    const std::vector<cullide::Mesh> two = {box_mesh({0, 0, 0}, {2, 2, 2}, "a"), box_mesh({1, 0, 0}, {3, 2, 2}, "b"),
                                            box_mesh({10, 10, 10}, {11, 11, 11}, "far")};
    const std::uint32_t all[] = {0, 1, 2};
    const cullide::AutoPlan p = cullide::plan_auto(two, all);
    CHECK(p.triangles == 36);
    CHECK(p.paired_triangles == 24);
    CHECK(p.object_pairs == 1);
    CHECK(p.task_triangles == doctest::Approx(12.0));
    CHECK_FALSE(p.views);  // far below kAutoMinViewTriangles
    // A flat object (zero extent along z) is covered along that axis by any box meeting it; the
    // other object's share along z is then the flat intersection's: none (an estimate).
    const std::vector<cullide::Mesh> flat = {box_mesh({0, 0, 0}, {4, 4, 0}, "f"), box_mesh({0, 0, -1}, {1, 4, 1}, "g")};
    const std::uint32_t both[] = {0, 1};
    CHECK(cullide::plan_auto(flat, both).task_triangles == doctest::Approx(12 * 0.25 + 12 * 0.0));
    // Only the listed objects count.
    const std::uint32_t one[] = {0};
    CHECK(cullide::plan_auto(two, one).object_pairs == 0);
}

TEST_CASE("auto: straight to the exact stage on small or loose scenes, views on a heap: always the ground truth") {
    // Small: two crossing triangles take the exact path (no view).
    const std::vector<cullide::Mesh> tiny = {
        triangle({0, 0, 0}, 1, {1, 0.1, 0.3}, {-0.5, 0.87, -0.2}, {-0.5, -0.87, 0.1}, "t1"),
        triangle({0, 0, 0}, 1, {0.3, 0.9, -0.1}, {-0.2, -0.3, 0.95}, {0.1, -0.4, -0.9}, "t2")};
    const cullide::FrameResult t = run(tiny, Method::Auto, 0);
    CHECK_FALSE(t.stats.auto_plan.views);
    CHECK(t.stats.views.empty());
    CHECK(t.pairs.size() == 1);
    CHECK(t.pairs == truth(tiny));

    // A heap: every box meets every other, views pay by the estimate and run.
    const std::vector<cullide::Mesh> heap = sphere_heap();
    const auto exact = truth(heap);
    REQUIRE(exact.size() > 100);  // the spheres cross each other
    const cullide::FrameResult h1 = run(heap, Method::Auto, 0, 1);
    const cullide::FrameResult h2 = run(heap, Method::Auto, 0, 2);
    CHECK(h1.stats.auto_plan.views);
    CHECK(h1.stats.auto_plan.object_pairs == 190);
    CHECK(h1.stats.auto_plan.task_triangles >= cullide::kAutoViewsPay * h1.stats.auto_plan.paired_triangles);
    CHECK_FALSE(h1.stats.views.empty());
    CHECK(h1.stats.pcs_subobjects < h1.stats.subobjects);  // the views pruned something
    CHECK(h1.pairs == exact);
    CHECK(h2.pairs == exact);
    CHECK(h1.stats.pcs_subobjects == h2.stats.pcs_subobjects);
    CHECK(h1.stats.exact_tests == h2.stats.exact_tests);
    // The same frame as rcullide gives the same PCS (auto's views are rcullide's).
    const cullide::FrameResult r = run(heap, Method::RCullide, 0, 1);
    CHECK(r.stats.pcs_subobjects == h1.stats.pcs_subobjects);
    CHECK(r.stats.triangles_rasterized == h1.stats.triangles_rasterized);

    // Self-collision runs as exact.
    cullide::RunOptions so;
    so.method = Method::Auto;
    so.self = true;
    auto self_auto = cullide::process_frame(tiny, so);
    REQUIRE(self_auto.ok());
    auto self_exact = cullide::exact_pairs(tiny, {true, 1});
    REQUIRE(self_exact.ok());
    CHECK(self_auto.value().pairs == self_exact.value());
    CHECK_FALSE(self_auto.value().stats.auto_plan.views);
}

TEST_CASE("auto is the default method") {
    CHECK(cullide::RunOptions{}.method == Method::Auto);
    CHECK(cullide::parse_method("auto").value() == Method::Auto);
    CHECK(cullide::default_resolution(Method::Auto) == cullide::default_resolution(Method::RCullide));
}
