// Quick-CULLIDE (qcullide, qcullide-gl) against the exact ground truth, with and without
// self-collision: built-in scenes, hand-made adjacency cases, the real meshes of
// ../shared/data/meshes (skipped when absent), thread-count determinism, and (oracle build) the
// GL-exact variant on OSMesa against the emulator.
//
// This file is compiled three times (tests/cullide/CMakeLists.txt): the default unit build, the
// `slow` build (QUICK_CULLIDE_SLOW: the 100K-triangle dragon, the 20K cloth at full scale) and the
// `oracle` build (QUICK_CULLIDE_OSMESA: the OSMesa device).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh_io.h"
#include "cullide/pipeline.h"
#include "cullide/quick_cullide.h"
#include "cullide/scenes.h"
#include "test_rng.h"
#ifdef QUICK_CULLIDE_OSMESA
#include "osmesa_query_device.h"
#endif
#if !defined(QUICK_CULLIDE_SLOW) && !defined(QUICK_CULLIDE_OSMESA)
#include <sstream>

#include "cli.h"
#endif

namespace {

using cullide::Method;
using cullide::TrianglePair;

[[maybe_unused]] std::vector<TrianglePair> truth(const std::vector<cullide::Mesh>& objects, bool self) {
    cullide::ExactOptions eo;
    eo.self = self;
    eo.threads = 2;
    auto r = cullide::exact_pairs(objects, eo);
    REQUIRE(r.ok());
    return r.value();
}

cullide::FrameResult run(const std::vector<cullide::Mesh>& objects, Method m, bool self, int resolution = 256,
                         int threads = 2, int subobject = 4, cullide::QueryDevice* device = nullptr) {
    cullide::RunOptions o;
    o.method = m;
    o.self = self;
    o.resolution = resolution;
    o.threads = threads;
    o.subobject_triangles = subobject;
    o.device = device;
    auto r = cullide::process_frame(objects, o);
    if (!r) FAIL(r.error().message);
    return r.value();
}

cullide::Frame scene_frame(const std::string& name, double scale, int frame) {
    cullide::SceneOptions so;
    so.scale = scale;
    so.mesh_dir = "";
    auto s = cullide::make_scene(name, so);
    REQUIRE(s.ok());
    return s.value()->frame(frame);
}

// Pairs of `found` missing from `exact`; every found pair must be a true one.
[[maybe_unused]] std::size_t misses(const std::vector<TrianglePair>& found, const std::vector<TrianglePair>& exact) {
    CHECK(std::includes(exact.begin(), exact.end(), found.begin(), found.end()));
    return exact.size() - found.size();
}

[[maybe_unused]] std::vector<cullide::Mesh> real_mesh(const std::string& file) {
    const std::filesystem::path p = std::filesystem::path(CULLIDE_SHARED_MESH_DIR) / file;
    if (!std::filesystem::exists(p)) return {};
    auto m = cullide::read_mesh_file(p.string());
    REQUIRE(m.ok());
    return m.value();
}

}  // namespace

namespace {
// `count` random scenes from `seed`: qcullide must equal the ground truth, qcullide-gl a subset.
[[maybe_unused]] void random_meshes(std::uint64_t seed, int count) {
    // Shared vertex pools on a quarter grid make fans, shared edges, touching and coplanar overlaps
    // frequent; some vertices are duplicated (unwelded copies) so adjacency must come from welding.
    test::Rng rng(seed);
    std::size_t self_pairs = 0, cases = 0;
    for (int scene = 0; scene < count; ++scene) {
        std::vector<cullide::Mesh> objects(static_cast<std::size_t>(rng.range(1, 3)));
        for (std::size_t o = 0; o < objects.size(); ++o) {
            cullide::Mesh& m = objects[o];
            m.name = "random_" + std::to_string(o);
            const int nv = rng.range(4, 14);
            for (int v = 0; v < nv; ++v) {
                if (v > 0 && rng.below(6) == 0) {
                    m.positions.push_back(m.positions[rng.below(m.positions.size())]);
                } else {
                    m.positions.push_back({rng.grid(-1, 1, 4), rng.grid(-1, 1, 4), rng.grid(-1, 1, 4)});
                }
            }
            const int nt = rng.range(1, 16);
            for (int t = 0; t < nt; ++t) {
                std::uint32_t a = 0, b = 0, c = 0;
                do {
                    a = static_cast<std::uint32_t>(rng.below(m.positions.size()));
                    b = static_cast<std::uint32_t>(rng.below(m.positions.size()));
                    c = static_cast<std::uint32_t>(rng.below(m.positions.size()));
                } while (a == b || b == c || a == c);
                m.triangles.push_back({a, b, c});
            }
        }
        const bool self = rng.coin();
        if (!cullide::validate_scene(objects)) continue;
        const auto exact = truth(objects, self);
        for (const TrianglePair& p : exact) self_pairs += p.object_a == p.object_b ? 1 : 0;
        cullide::RunOptions o;
        o.self = self;
        o.threads = 2;
        o.resolution = std::array<int, 4>{16, 32, 64, 256}[rng.below(4)];
        o.subobject_triangles = rng.range(1, 5);
        o.max_rounds = rng.range(1, 3);
        o.depth_format = std::array<raster::DepthFormat, 3>{raster::DepthFormat::D16, raster::DepthFormat::D24,
                                                            raster::DepthFormat::D32F}[rng.below(3)];
        CAPTURE(scene);
        CAPTURE(self);
        CAPTURE(o.resolution);
        CAPTURE(o.subobject_triangles);
        o.method = Method::QCullide;
        auto q = cullide::process_frame(objects, o);
        REQUIRE(q.ok());
        CHECK(q.value().pairs == exact);
        o.method = Method::QCullideGL;
        auto g = cullide::process_frame(objects, o);
        REQUIRE(g.ok());
        (void)misses(g.value().pairs, exact);
        ++cases;
    }
    CHECK(cases > static_cast<std::size_t>(count) * 2 / 3);
    CHECK(self_pairs > static_cast<std::size_t>(count) / 10);  // the generator does produce non-adjacent crossings inside one mesh
}

}  // namespace

#if !defined(QUICK_CULLIDE_SLOW) && !defined(QUICK_CULLIDE_OSMESA)

TEST_CASE("qcullide reports exactly the true pairs on every built-in scene without self-collision") {
    for (const std::string& name : cullide::scene_names()) {
        for (int frame : {3}) {
            CAPTURE(name);
            CAPTURE(frame);
            const cullide::Frame objects = scene_frame(name, 0.05, frame);
            const auto exact = truth(objects, false);
            for (int sub : {1, 4}) {
                CAPTURE(sub);
                const auto q = run(objects, Method::QCullide, false, 128, 2, sub);
                CHECK(q.pairs == exact);
                const auto g = run(objects, Method::QCullideGL, false, 128, 2, sub);
                (void)misses(g.pairs, exact);
            }
        }
    }
}

TEST_CASE("qcullide --self reports exactly the true self pairs on the cloth, through the fold") {
    std::uint64_t self_pairs = 0;
    for (int frame : {0, 30, 54, 58, 60, 62, 66}) {
        CAPTURE(frame);
        const cullide::Frame objects = scene_frame("cloth", 0.05, frame);
        const auto exact = truth(objects, true);
        for (const TrianglePair& p : exact) self_pairs += p.object_a == p.object_b ? 1 : 0;
        for (int sub : {1, 4}) {
            CAPTURE(sub);
            const auto q = run(objects, Method::QCullide, true, 256, 2, sub);
            CHECK(q.pairs == exact);
            CHECK(q.stats.exact_tests >= exact.size());
        }
    }
    CHECK(self_pairs > 0);  // the fold really self-intersects at these frames
}

TEST_CASE("qcullide --self reports exactly the true pairs on the breaking scene") {
    for (int frame : {0, 5, 12}) {
        CAPTURE(frame);
        const cullide::Frame objects = scene_frame("breaking", 0.05, frame);
        const auto exact = truth(objects, true);
        const auto q = run(objects, Method::QCullide, true, 256);
        CHECK(q.pairs == exact);
    }
}

TEST_CASE("adjacency: a flat welded grid has no self pair and is proven apart by the visibility passes") {
    // 20 x 20 cells in the plane z = 0 plus a bump: every triangle touches its neighbours only.
    cullide::Mesh m;
    m.name = "grid";
    const int n = 20;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) m.positions.push_back({i * 0.1, j * 0.1, 0.01 * ((i * 7 + j * 3) % 5)});
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const auto v = static_cast<std::uint32_t>(j * (n + 1) + i);
            m.triangles.push_back({v, v + 1, v + n + 2});
            m.triangles.push_back({v, v + n + 2, v + n + 1});
        }
    }
    const std::vector<cullide::Mesh> objects{m};
    REQUIRE(truth(objects, true).empty());
    auto device = cullide::make_emulator_device(2);
    cullide::QuickOptions qo;
    qo.self = true;
    qo.resolution = 256;
    qo.subobject_triangles = 1;
    qo.threads = 2;
    cullide::QuickStats st;
    auto r = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{0}, qo, *device, &st);
    REQUIRE(r.ok());
    CHECK(r.value().empty());
    // Row-major order: neighbours are at most one row plus one cell apart (2n + 3 triangles).
    CHECK(st.window_max <= 2 * n + 3);
    CHECK(st.window_max >= 1);
    // Every triangle was proven apart from the far triangles in some view: nothing but near pairs
    // reaches the exact stage, and the adjacent ones among them are dropped before it.
    CHECK(st.near_item_pairs == st.item_pairs_kept);
    CHECK(st.adjacent_skipped > 0);
    CHECK(st.pcs_subobjects == 0);
}

TEST_CASE("adjacency: a crossing of two far-apart triangles of one mesh is found, welded neighbours are not") {
    // A strip of triangles folded so that its last triangle pierces its first; the fold's own
    // triangles share vertices (adjacent: never reported).
    cullide::Mesh m;
    m.name = "fold";
    m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0.1}, {3, 1, 0.5}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0.2}};
    m.triangles = {{0, 1, 2}, {1, 3, 2}, {1, 4, 3}, {3, 4, 7}, {5, 6, 7}};
    const std::vector<cullide::Mesh> objects{m};
    const auto exact = truth(objects, true);
    REQUIRE(exact.size() >= 1);
    CHECK(std::find(exact.begin(), exact.end(), TrianglePair{0, 0, 0, 4}) != exact.end());
    for (int sub : {1, 2, 4}) {
        CAPTURE(sub);
        for (int res : {16, 64, 1024}) {
            CAPTURE(res);
            CHECK(run(objects, Method::QCullide, true, res, 2, sub).pairs == exact);
        }
    }
    // Unwelded duplicates of a shared vertex still count as adjacent (docs/conventions.md).
    cullide::Mesh split = m;
    split.positions.push_back(split.positions[1]);
    split.triangles[1] = {8, 3, 2};
    CHECK(run({split}, Method::QCullide, true).pairs == truth({split}, true));
}

TEST_CASE("self: the visibility passes prove far pairs apart where the boxes cannot (folded cloth)") {
    const cullide::Frame objects = scene_frame("cloth", 0.05, 60);
    auto device = cullide::make_emulator_device(2);
    cullide::QuickOptions qo;
    qo.self = true;
    qo.resolution = 256;
    qo.threads = 2;
    cullide::QuickStats with, without;
    auto a = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{0, 1}, qo, *device, &with);
    qo.skip_visibility = true;
    auto b = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{0, 1}, qo, *device, &without);
    REQUIRE(a.ok());
    REQUIRE(b.ok());
    const auto exact = truth(objects, true);
    CHECK(a.value() == exact);
    CHECK(b.value() == exact);  // the box-prefiltered all-pairs twin
    // The flap lies over the base: items with far overlapping boxes exist, and the passes prove
    // most of them apart, so fewer pairs reach the exact test than without the passes.
    CHECK(with.pcs_boxes > 0);
    CHECK(!with.views.empty());
    CHECK(with.pcs_subobjects < with.pcs_boxes);
    CHECK(with.item_pairs_kept < without.item_pairs_kept);
    CHECK(with.exact_tests < without.exact_tests);
    CHECK(without.views.empty());
    MESSAGE("cloth 0.05 frame 60: exact tests " << with.exact_tests << " (near " << with.near_exact_tests
                                                << ") vs " << without.exact_tests << " without the passes; "
                                                << exact.size() << " true pairs");
}

TEST_CASE("random small meshes on a coarse grid: qcullide equals the ground truth, with and without --self") {
    random_meshes(20261121, 50);
}

TEST_CASE("qcullide-gl --self misses are counted (pixel-centre sampling) and it never reports a false pair") {
    std::size_t total = 0, missed = 0;
    for (int frame : {56, 60, 64}) {
        const cullide::Frame objects = scene_frame("cloth", 0.05, frame);
        const auto exact = truth(objects, true);
        for (int res : {32, 256}) {
            const auto g = run(objects, Method::QCullideGL, true, res);
            total += exact.size();
            missed += misses(g.pairs, exact);
        }
    }
    MESSAGE("qcullide-gl on cloth (scale 0.05, frames 56/60/64, res 32 and 256): missed " << missed << " of "
                                                                                          << total << " pairs");
    CHECK(total > 0);
    CHECK(missed <= total);
}

TEST_CASE("qcullide sends fewer triangle pairs to the exact stage than CULLIDE") {
    std::uint64_t q_tests = 0, c_tests = 0;
    for (const std::string& name : {std::string("cylinders"), std::string("breaking")}) {
        const cullide::Frame objects = scene_frame(name, 0.05, 3);
        const auto exact = truth(objects, false);
        const auto q = run(objects, Method::QCullide, false, 128);
        const auto c = run(objects, Method::RCullide, false, 128);
        CHECK(q.pairs == exact);
        CHECK(c.pairs == exact);
        q_tests += q.stats.exact_tests;
        c_tests += c.stats.exact_tests;
    }
    MESSAGE("exact tests: qcullide " << q_tests << ", rcullide " << c_tests);
    CHECK(q_tests <= c_tests);
}

TEST_CASE("qcullide and qcullide-gl give the same bits for 1, 2, 3 and 8 threads") {
    for (const char* name : {"cloth", "breaking"}) {
        const cullide::Frame objects = scene_frame(name, 0.05, 60);
        for (Method m : {Method::QCullide, Method::QCullideGL}) {
            CAPTURE(name);
            CAPTURE(cullide::to_string(m));
            const auto ref = run(objects, m, true, 128, 1);
            for (int t : {2, 3, 8}) {
                const auto r = run(objects, m, true, 128, t);
                CHECK(r.pairs == ref.pairs);
                CHECK(r.stats.exact_tests == ref.stats.exact_tests);
                CHECK(r.stats.queries == ref.stats.queries);
                CHECK(r.stats.triangles_rasterized == ref.stats.triangles_rasterized);
                CHECK(r.stats.pcs_subobjects == ref.stats.pcs_subobjects);
                CHECK(r.stats.views.size() == ref.stats.views.size());
            }
        }
    }
}

TEST_CASE("bad options are refused with a message naming them") {
    const cullide::Frame objects = scene_frame("cloth", 0.05, 0);
    auto device = cullide::make_emulator_device(1);
    cullide::QuickOptions qo;
    qo.mode = cullide::VisibilityMode::Offset;
    auto r = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{0, 1}, qo, *device);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("offset") != std::string::npos);
    qo = {};
    qo.subobject_triangles = 0;
    r = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{0, 1}, qo, *device);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("sub-object size") != std::string::npos);
    qo = {};
    r = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{1, 0}, qo, *device);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("strictly increasing") != std::string::npos);
    r = cullide::quick_cullide_pairs(objects, std::vector<std::uint32_t>{5}, qo, *device);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("beyond the object list") != std::string::npos);
    cullide::RunOptions o;
    o.method = Method::RCullide;
    o.self = true;
    auto f = cullide::process_frame(objects, o);
    REQUIRE_FALSE(f.ok());
    CHECK(f.error().message.find("use method 'qcullide'") != std::string::npos);
}

TEST_CASE("CLI: --self defaults to auto, the new methods run, and CULLIDE methods refuse --self") {
    auto cli = [](std::vector<std::string> args, std::string& out, std::string& err) {
        std::ostringstream o, e;
        const int status = cullide::cli::run(args, o, e);
        out = o.str();
        err = e.str();
        return status;
    };
    const std::vector<std::string> base{"run", "cloth", "--scale", "0.05", "--frames", "1", "--resolution", "64"};
    std::string out, err;
    auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> a = base;
        a.insert(a.end(), extra.begin(), extra.end());
        return cli(a, out, err);
    };
    REQUIRE(with({"--self"}) == 0);
    CHECK(out.find("method auto, self-collision on") != std::string::npos);
    CHECK(out.find("auto: straight to the exact stage") != std::string::npos);
    REQUIRE(with({"--self", "--method", "qcullide-gl", "--json"}) == 0);
    CHECK(out.find("\"method\": \"qcullide-gl\", \"self\": true") != std::string::npos);
    REQUIRE(with({"--method", "qcullide", "--subobject", "1", "--broadphase", "sap"}) == 0);
    CHECK(out.find("method qcullide,") != std::string::npos);
    REQUIRE(with({"--self", "--method", "exact"}) == 0);
    CHECK(out.find("method exact, self-collision on") != std::string::npos);
    for (const char* m : {"cullide", "rcullide", "rcullide-offset"}) {
        CAPTURE(m);
        CHECK(with({"--self", "--method", m}) == 1);
        CHECK(err.find(std::string("self-collision is not supported by method '") + m + "'") != std::string::npos);
        CHECK(err.find("use method 'qcullide'") != std::string::npos);
    }
    CHECK(with({"--method", "qcullide-GL"}) == 2);
    CHECK(err.find("unknown method 'qcullide-GL'") != std::string::npos);
    CHECK(with({"--self", "--method", "qcullide", "--subobject", "0"}) == 2);
    CHECK(err.find("--subobject must be an integer in 1..65536") != std::string::npos);
    CHECK(cli({"help"}, out, err) == 0);
    CHECK(out.find("qcullide-gl (Quick-CULLIDE, GL-exact)") != std::string::npos);
}

TEST_CASE("real meshes with genuine self-intersections: teapot and cow") {
    for (const std::string file : {"teapot.obj", "cow.obj"}) {
        CAPTURE(file);
        const std::vector<cullide::Mesh> objects = real_mesh(file);
        if (objects.empty()) {
            MESSAGE("skipped: " << file << " not found in " << CULLIDE_SHARED_MESH_DIR);
            continue;
        }
        const auto exact = truth(objects, true);
        const auto q = run(objects, Method::QCullide, true, 512);
        CHECK(q.pairs == exact);
        MESSAGE(file << ": " << exact.size() << " self pairs; qcullide exact tests " << q.stats.exact_tests);
    }
}


// The emulator's native quick_view (raster::WindowedPasses, each item rasterized once per view)
// against the recorded passes (QuickOptions::fused_visibility = false): the same tags after every
// view, so the same PCS, statistics and pairs, on every built-in scene (self-collision on the cloth
// and the breaking pieces too), for 1 and 3 threads, at 32 px (the method's default) and 128 px.
TEST_CASE("qcullide: the native windowed passes give the recorded passes' PCS after every view, every scene") {
    struct Case {
        const char* scene;
        double scale;
        int frame;
        bool self;
    };
    const Case cases[] = {{"cylinders", 0.25, 30, false}, {"tori", 0.03, 30, false}, {"bunny-dragon", 0.05, 30, false},
                          {"breaking", 0.1, 30, false},   {"leaves", 0.25, 30, false}, {"cloth", 0.25, 55, false},
                          {"cloth", 0.25, 55, true},      {"breaking", 0.1, 30, true}};
    std::uint64_t views = 0, tags_gained = 0;
    for (const Case& c : cases) {
        const cullide::Frame objects = scene_frame(c.scene, c.scale, c.frame);
        std::vector<std::uint32_t> active(objects.size());
        for (std::size_t i = 0; i < active.size(); ++i) active[i] = static_cast<std::uint32_t>(i);
        for (const int res : {32, 128}) {
            CAPTURE(c.scene);
            CAPTURE(c.self);
            CAPTURE(res);
            cullide::QuickOptions o;
            o.self = c.self;
            o.resolution = res;
            o.threads = 2;
            o.fused_visibility = false;
            auto device = cullide::make_emulator_device(2);
            cullide::QuickStats want_stats;
            auto want = cullide::quick_cullide_pairs(objects, active, o, *device, &want_stats);
            REQUIRE_MESSAGE(want.ok(), (want.ok() ? std::string() : want.error().message));
            for (const int threads : {1, 3}) {
                CAPTURE(threads);
                o.fused_visibility = true;
                o.threads = threads;
                auto native = cullide::make_emulator_device(threads);
                cullide::QuickStats got_stats;
                auto got = cullide::quick_cullide_pairs(objects, active, o, *native, &got_stats);
                REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
                CHECK(got.value() == want.value());
                CHECK(got_stats.pcs_boxes == want_stats.pcs_boxes);
                CHECK(got_stats.pcs_objects == want_stats.pcs_objects);
                CHECK(got_stats.pcs_subobjects == want_stats.pcs_subobjects);
                CHECK(got_stats.pcs_triangles == want_stats.pcs_triangles);
                CHECK(got_stats.queries == want_stats.queries);
                CHECK(got_stats.triangles_rasterized == want_stats.triangles_rasterized);
                CHECK(got_stats.item_pairs_kept == want_stats.item_pairs_kept);
                REQUIRE(got_stats.views.size() == want_stats.views.size());
                for (std::size_t v = 0; v < want_stats.views.size(); ++v) {
                    CAPTURE(v);
                    CHECK(got_stats.views[v].items_before == want_stats.views[v].items_before);
                    CHECK(got_stats.views[v].items_after == want_stats.views[v].items_after);
                    CHECK(got_stats.views[v].queries == want_stats.views[v].queries);
                    CHECK(got_stats.views[v].triangles_rasterized == want_stats.views[v].triangles_rasterized);
                }
            }
            views += want_stats.views.size();
            for (const auto& v : want_stats.views) tags_gained += v.items_before - v.items_after;
        }
    }
    // The comparison means something: many views ran and proved items apart.
    CHECK(views > 50);
    CHECK(tags_gained > 1000);
}

#endif

#ifdef QUICK_CULLIDE_SLOW

TEST_CASE("slow: 600 random small meshes, qcullide equals the ground truth") { random_meshes(7, 600); }

TEST_CASE("slow: the dragon's self-intersections, exactly") {
    const std::vector<cullide::Mesh> objects = real_mesh("dragon.obj");
    if (objects.empty()) {
        MESSAGE("skipped: dragon.obj not found");
        return;
    }
    const auto exact = truth(objects, true);
    CHECK(run(objects, Method::QCullide, true, 1024).pairs == exact);
    const auto g = run(objects, Method::QCullideGL, true, 1024);
    MESSAGE("dragon: " << exact.size() << " self pairs, qcullide-gl missed " << misses(g.pairs, exact));
}

TEST_CASE("slow: the 20K cloth and the breaking scene at scale 1 with --self, exactly") {
    for (int frame : {0, 58, 62}) {
        CAPTURE(frame);
        const cullide::Frame objects = scene_frame("cloth", 1.0, frame);
        CHECK(run(objects, Method::QCullide, true, 1024).pairs == truth(objects, true));
    }
    const cullide::Frame objects = scene_frame("breaking", 1.0, 6);
    CHECK(run(objects, Method::QCullide, true, 1024).pairs == truth(objects, true));
}

#endif

#ifdef QUICK_CULLIDE_OSMESA

TEST_CASE("qcullide-gl runs the same passes on OSMesa as on the emulator") {
    auto device = cullide_oracle::make_osmesa_query_device();
    REQUIRE(device.ok());
    {
        // The exact-bounds mode exists only in the emulator: a clear error, not a wrong answer.
        const cullide::Frame objects = scene_frame("cloth", 0.05, 60);
        cullide::RunOptions o;
        o.method = Method::QCullide;
        o.self = true;
        o.resolution = 64;
        o.device = device.value().get();
        auto r = cullide::process_frame(objects, o);
        REQUIRE_FALSE(r.ok());
        CHECK(r.error().message.find("exact-bounds") != std::string::npos);
    }
    for (const char* name : {"cloth", "breaking", "cylinders"}) {
        for (bool self : {false, true}) {
            CAPTURE(name);
            CAPTURE(self);
            const cullide::Frame objects = scene_frame(name, 0.05, 60);
            const auto emu = run(objects, Method::QCullideGL, self, 128);
            const auto gl = run(objects, Method::QCullideGL, self, 128, 2, 4, device.value().get());
            CHECK(gl.pairs == emu.pairs);
            (void)misses(gl.pairs, truth(objects, self));  // a subset of the true pairs
            CHECK(gl.stats.queries == emu.stats.queries);
            CHECK(gl.stats.triangles_rasterized == emu.stats.triangles_rasterized);
            CHECK(gl.stats.exact_tests == emu.stats.exact_tests);
            REQUIRE(gl.stats.views.size() == emu.stats.views.size());
            for (std::size_t v = 0; v < gl.stats.views.size(); ++v) {
                CAPTURE(v);
                CHECK(gl.stats.views[v].items_after == emu.stats.views[v].items_after);
            }
        }
    }
}

#endif
