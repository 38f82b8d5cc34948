// FrameContext (cullide/pipeline.h): a context reused across frames gives the same bits as a fresh
// call, whatever ran through it before (methods, resolutions, depth formats, scene sizes, thread
// counts, failed frames), and it is movable; Quick-CULLIDE's self order kept in it is used only for
// the topology it came from. The emulator device's partial clear (it restores only
// the tiles where raster::execute ran writing draws) leaves the whole target at depth 1.0, as a
// full clear does.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/quick_cullide.h"
#include "cullide/scenes.h"
#include "cullide_detail.h"
#include "emulator_device.h"
#include "test_rng.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

using cullide::FrameResult;
using cullide::Mesh;
using cullide::Method;

std::vector<Mesh> scene_frame(const std::string& name, double scale, int frame) {
    cullide::SceneOptions so;
    so.mesh_dir = "";
    so.scale = scale;
    auto g = cullide::make_scene(name, so);
    REQUIRE(g.ok());
    return g.value()->frame(frame);
}

std::vector<Mesh> two_triangles() {
    Mesh a;
    a.positions = {{0, 0, 0}, {1, 0, 0.3}, {0, 1, 0.6}};
    a.triangles = {{0, 1, 2}};
    Mesh b;
    b.positions = {{0.25, 0.25, -0.5}, {0.3, 0.2, 0.5}, {0.75, 0.1, 0.25}};
    b.triangles = {{0, 1, 2}};
    return {a, b};
}

// Everything but the times.
void check_same(const FrameResult& got, const FrameResult& want) {
    CHECK(got.pairs == want.pairs);
    CHECK(got.object_pairs == want.object_pairs);
    const cullide::FrameStats& a = got.stats;
    const cullide::FrameStats& b = want.stats;
    CHECK(a.objects == b.objects);
    CHECK(a.triangles == b.triangles);
    CHECK(a.broadphase_objects == b.broadphase_objects);
    CHECK(a.broadphase_pairs == b.broadphase_pairs);
    CHECK(a.subobject_pairs == b.subobject_pairs);
    CHECK(a.objects_in == b.objects_in);
    CHECK(a.pcs_boxes == b.pcs_boxes);
    CHECK(a.pcs_objects == b.pcs_objects);
    CHECK(a.subobjects == b.subobjects);
    CHECK(a.pcs_subobjects == b.pcs_subobjects);
    CHECK(a.candidate_triangles == b.candidate_triangles);
    CHECK(a.exact_tests == b.exact_tests);
    CHECK(a.adjacent_skipped == b.adjacent_skipped);
    CHECK(a.queries == b.queries);
    CHECK(a.triangles_rasterized == b.triangles_rasterized);
    REQUIRE(a.views.size() == b.views.size());
    for (std::size_t v = 0; v < a.views.size(); ++v) {
        CAPTURE(v);
        CHECK(a.views[v].stage == b.views[v].stage);
        CHECK(a.views[v].axis == b.views[v].axis);
        CHECK(a.views[v].items_before == b.views[v].items_before);
        CHECK(a.views[v].items_after == b.views[v].items_after);
        CHECK(a.views[v].queries == b.views[v].queries);
        CHECK(a.views[v].triangles_rasterized == b.views[v].triangles_rasterized);
    }
}

struct Step {
    std::vector<Mesh> objects;
    Method method;
    int resolution;  // 0: the method's default
    raster::DepthFormat format;
    int threads;
    bool self;
};

}  // namespace

TEST_CASE("A reused FrameContext gives every frame of a mixed sequence the bits of a fresh call") {
    const std::vector<Mesh> tiny = two_triangles();
    const std::vector<Mesh> cylinders = scene_frame("cylinders", 0.05, 3);
    const std::vector<Mesh> tori = scene_frame("tori", 0.1, 7);
    const std::vector<Mesh> cloth = scene_frame("cloth", 0.05, 12);
    const std::vector<Mesh> leaves = scene_frame("leaves", 0.05, 40);
    using F = raster::DepthFormat;
    // Large views after small ones and back, formats switching, big frames after tiny ones: a
    // written span, a depth target or a serial run left over from one frame must not show in the next.
    const std::vector<Step> steps = {
        {tiny, Method::Cullide, 0, F::D24, 0, false},
        {cylinders, Method::Cullide, 0, F::D24, 2, false},
        {tiny, Method::RCullide, 0, F::D24, 0, false},
        {tori, Method::RCullideOffset, 512, F::D16, 3, false},
        {tiny, Method::RCullideOffset, 0, F::D24, 1, false},
        {cloth, Method::QCullide, 64, F::D32F, 2, true},
        {cylinders, Method::QCullideGL, 300, F::D32F, 8, false},
        {tiny, Method::QCullideGL, 0, F::D24, 0, false},
        {leaves, Method::Exact, 0, F::D24, 2, false},
        {tori, Method::Cullide, 700, F::D24, 1, false},
        {cloth, Method::QCullideGL, 0, F::D16, 0, true},
        {leaves, Method::RCullide, 128, F::D16, 3, false},
        {tiny, Method::Cullide, 0, F::D24, 2, false},
        {cylinders, Method::RCullide, 0, F::D24, 1, false},
    };
    cullide::FrameContext context;
    for (std::size_t i = 0; i < steps.size(); ++i) {
        const Step& s = steps[i];
        CAPTURE(i);
        CAPTURE(cullide::to_string(s.method));
        cullide::RunOptions o;
        o.method = s.method;
        o.resolution = s.resolution;
        o.depth_format = s.format;
        o.threads = s.threads;
        o.self = s.self;
        auto fresh = cullide::process_frame(s.objects, o);
        REQUIRE_MESSAGE(fresh.ok(), (fresh.ok() ? std::string() : fresh.error().message));
        auto reused = cullide::process_frame(s.objects, o, context);
        REQUIRE_MESSAGE(reused.ok(), (reused.ok() ? std::string() : reused.error().message));
        check_same(reused.value(), fresh.value());
        // Another thread count through the same context: the same bits again.
        o.threads = s.threads == 1 ? 2 : 1;
        auto other = cullide::process_frame(s.objects, o, context);
        REQUIRE_MESSAGE(other.ok(), (other.ok() ? std::string() : other.error().message));
        check_same(other.value(), fresh.value());
    }
}

namespace {

struct QuickRun {
    std::vector<cullide::TrianglePair> pairs;
    cullide::QuickStats stats;
};

QuickRun quick_self(const std::vector<Mesh>& objects, int group, cullide::detail::QuickSelfCache* cache) {
    std::vector<std::uint32_t> active(objects.size());
    for (std::size_t i = 0; i < active.size(); ++i) active[i] = static_cast<std::uint32_t>(i);
    cullide::QuickOptions o;
    o.self = true;
    o.subobject_triangles = group;
    o.threads = 2;
    cullide::detail::EmulatorDevice device(2);
    QuickRun r;
    auto got = cullide::detail::quick_cullide_pairs(objects, active, o, device, &r.stats, false, cache);
    REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
    r.pairs = std::move(got).value();
    return r;
}

// The fields of two runs that differ, by name (pairs, statistics, and per view its axis and the
// items left after it); empty when the runs agree.
std::string quick_differences(const QuickRun& a, const QuickRun& b) {
    std::string d;
    const auto field = [&](const char* name, bool same) {
        if (!same) d += std::string(d.empty() ? "" : ", ") + name;
    };
    field("pairs", a.pairs == b.pairs);
    field("window_max", a.stats.window_max == b.stats.window_max);
    field("item_pairs", a.stats.item_pairs == b.stats.item_pairs);
    field("item_pairs_kept", a.stats.item_pairs_kept == b.stats.item_pairs_kept);
    field("near_item_pairs", a.stats.near_item_pairs == b.stats.near_item_pairs);
    field("near_exact_tests", a.stats.near_exact_tests == b.stats.near_exact_tests);
    field("exact_tests", a.stats.exact_tests == b.stats.exact_tests);
    field("pcs_subobjects", a.stats.pcs_subobjects == b.stats.pcs_subobjects);
    field("queries", a.stats.queries == b.stats.queries);
    field("views", a.stats.views.size() == b.stats.views.size());
    for (std::size_t v = 0; v < std::min(a.stats.views.size(), b.stats.views.size()); ++v) {
        field(("view " + std::to_string(v) + " axis").c_str(), a.stats.views[v].axis == b.stats.views[v].axis);
        field(("view " + std::to_string(v) + " items_after").c_str(),
              a.stats.views[v].items_after == b.stats.views[v].items_after);
    }
    return d;
}

}  // namespace

TEST_CASE("Quick-CULLIDE's self order kept between frames is used only for the topology it came from") {
    // The folded sheet (views run and pairs are found) and three changes of what the order is a
    // function of: the welded ids (two corners of the sheet moved onto one point, so that the
    // first and last triangles become neighbours), the triangle list (shuffled) and the group size.
    const std::vector<Mesh> base = {scene_frame("cloth", 0.1, 55)[0]};  // the sheet alone
    std::vector<Mesh> welded = base;
    welded[0].positions.back() = welded[0].positions.front();
    std::vector<Mesh> shuffled = base;  // the same triangles in another list order
    {
        test::Rng rng(20261128);
        auto& t = shuffled[0].triangles;
        for (std::size_t i = t.size() - 1; i > 0; --i) std::swap(t[i], t[rng.below(i + 1)]);
    }
    const QuickRun fresh_base = quick_self(base, 4, nullptr);
    const QuickRun fresh_welded = quick_self(welded, 4, nullptr);
    const QuickRun fresh_shuffled = quick_self(shuffled, 4, nullptr);
    const QuickRun fresh_group2 = quick_self(base, 2, nullptr);
    REQUIRE_FALSE(fresh_base.pairs.empty());
    REQUIRE(fresh_base.stats.queries > 0);

    cullide::detail::QuickSelfCache cache;
    const struct {
        const std::vector<Mesh>* objects;
        int group;
        const QuickRun* want;
    } steps[] = {{&base, 4, &fresh_base},     {&base, 4, &fresh_base},         {&welded, 4, &fresh_welded},
                 {&base, 4, &fresh_base},     {&shuffled, 4, &fresh_shuffled}, {&base, 2, &fresh_group2},
                 {&base, 4, &fresh_base},     {&welded, 4, &fresh_welded},     {&welded, 4, &fresh_welded}};
    for (std::size_t i = 0; i < std::size(steps); ++i) {
        CAPTURE(i);
        const std::string differ = quick_differences(quick_self(*steps[i].objects, steps[i].group, &cache), *steps[i].want);
        CHECK(differ == "");
    }

    // The checks above would see an entry used for the wrong topology, and the entry is read when
    // its topology matches: the base frame's order filed under the welded frame's ids (as an entry
    // keyed on the triangles alone would use it) changes the welded frame's answer, and filed under
    // the shuffled frame's triangles (as one keyed on the ids alone would) the shuffled frame's.
    cullide::detail::QuickSelfCache planted;
    (void)quick_self(base, 4, &planted);
    REQUIRE(planted.entries.size() == 1);
    REQUIRE(planted.entries[0].valid);
    const std::vector<std::uint32_t> welded_ids = cullide::weld_vertices(welded[0]);
    REQUIRE(welded_ids != planted.entries[0].weld);
    planted.entries[0].weld = welded_ids;
    CHECK_FALSE(quick_differences(quick_self(welded, 4, &planted), fresh_welded).empty());
    // And under the shuffled frame's triangles.
    (void)quick_self(base, 4, &planted);
    planted.entries[0].triangles = shuffled[0].triangles;
    CHECK_FALSE(quick_differences(quick_self(shuffled, 4, &planted), fresh_shuffled).empty());
}

// Whether a sanitizer's allocator stands in for the C library's (it takes no glibc settings).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define CULLIDE_TEST_SANITIZER_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define CULLIDE_TEST_SANITIZER_ALLOCATOR 1
#endif
#endif

TEST_CASE("retain_freed_memory keeps a freed block of megabytes in the heap (glibc)") {
#if defined(CULLIDE_TEST_SANITIZER_ALLOCATOR)
    CHECK_FALSE(cullide::retain_freed_memory());  // mallopt is the sanitizer's, which refuses it
#elif defined(__GLIBC__)
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.") != nullptr) {
        CHECK_FALSE(cullide::retain_freed_memory());  // the user's own settings are left alone
        return;
    }
    REQUIRE(cullide::retain_freed_memory());
    // The heap's figures are glibc's own allocator's: valgrind preloads its own (which accepts
    // mallopt and ignores it), so there only the call is checked.
    const char* preload = std::getenv("LD_PRELOAD");
    if (preload != nullptr && std::strstr(preload, "vgpreload") != nullptr) return;
#if __GLIBC_PREREQ(2, 33)
    const struct mallinfo2 before = mallinfo2();
    struct mallinfo2 during {};
    {
        std::vector<char> block(std::size_t{8} << 20, 1);  // 8 MB: below the 32 MB mmap threshold
        during = mallinfo2();
        CHECK(block[12345] == 1);
    }
    const struct mallinfo2 after = mallinfo2();
    CHECK(during.hblkhd == before.hblkhd);  // from the heap, not a mapping of its own
    CHECK(during.arena >= before.arena);
    CHECK(after.arena == during.arena);     // freed, and the heap kept it (trim threshold 256 MB)
    CHECK(after.fordblks >= (std::size_t{8} << 20));
#endif
#else
    CHECK_FALSE(cullide::retain_freed_memory());  // another C library
#endif
}

TEST_CASE("A FrameContext stays usable after a failed frame and after a move") {
    const std::vector<Mesh> tiny = two_triangles();
    cullide::RunOptions o;
    o.method = Method::Cullide;
    auto want = cullide::process_frame(tiny, o);
    REQUIRE(want.ok());
    REQUIRE(want.value().pairs.size() == 1);

    cullide::FrameContext context;
    REQUIRE(cullide::process_frame(tiny, o, context).ok());
    std::vector<Mesh> bad = tiny;
    bad[1].triangles[0][2] = 7;  // beyond the 3 vertices
    auto failed = cullide::process_frame(bad, o, context);
    REQUIRE_FALSE(failed.ok());
    CHECK(failed.error().message.find("7") != std::string::npos);
    cullide::RunOptions too_big = o;
    too_big.resolution = cullide::kMaxViewResolution + 1;
    CHECK_FALSE(cullide::process_frame(tiny, too_big, context).ok());

    auto again = cullide::process_frame(tiny, o, context);
    REQUIRE(again.ok());
    check_same(again.value(), want.value());

    cullide::FrameContext moved = std::move(context);
    auto after_move = cullide::process_frame(tiny, o, moved);
    REQUIRE(after_move.ok());
    check_same(after_move.value(), want.value());
    // The moved-from context is still a valid (empty) one.
    auto from_moved = cullide::process_frame(tiny, o, context);  // NOLINT(bugprone-use-after-move)
    REQUIRE(from_moved.ok());
    check_same(from_moved.value(), want.value());
}

TEST_CASE("The emulator's partial clear leaves every pixel at depth 1.0 after random written triangles") {
    // Sizes of whole and partial 64 x 64 tiles, not square, in every format; triangles
    // inside, across and far outside the clip volume, thin ones, both raster modes, full and
    // partial viewports.
    test::Rng rng(0x7A11F7A3E5ULL);
    cullide::detail::EmulatorDevice device(1);
    const int sizes[][2] = {{256, 256}, {1024, 1024}, {300, 700}, {1000, 257}};
    for (int round = 0; round < 24; ++round) {
        const int w = sizes[round % 4][0];
        const int h = sizes[round % 4][1];
        const auto format = static_cast<raster::DepthFormat>(round % 3);
        CAPTURE(round);
        REQUIRE(device.clear(w, h, format).ok());
        std::vector<raster::Float4> verts;
        std::vector<raster::Double4> verts_d;
        for (int v = 0; v < 60; ++v) {
            const double spread = v % 7 == 0 ? 40.0 : 1.3;
            const double x = (rng.unit() * 2 - 1) * spread;
            const double y = (rng.unit() * 2 - 1) * spread;
            const double z = rng.unit() * 1.8 - 0.9;
            verts.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), 1.0f});
            verts_d.push_back({x, y, z, 1.0});
        }
        // A sliver: two vertices one float step apart.
        verts[1] = {std::nextafter(verts[0].x, 2.0f), verts[0].y, verts[0].z, 1.0f};
        std::vector<std::uint32_t> indices;
        for (std::uint32_t t = 0; t < 20; ++t)
            for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(rng.below(60)));
        raster::CommandBatch batch(w, h);
        raster::DrawState gl;
        gl.depth_func = raster::DepthFunc::Always;
        if (round % 5 == 4) gl.viewport = raster::Viewport{w / 4, h / 3, w / 2, h / 2};
        raster::DrawState eb = gl;
        eb.mode = raster::RasterMode::ExactBounds;
        eb.viewport.reset();
        batch.draw(raster::MeshView{verts, indices}, gl);
        batch.draw(raster::MeshViewD{verts_d, indices}, eb);
        REQUIRE(device.execute(batch).ok());
        const raster::DepthTarget* target = device.target();
        REQUIRE(target != nullptr);
        const std::uint32_t one = raster::DepthTarget::encode_clear(1.0, format);
        std::size_t written = 0;
        for (const std::uint32_t v : target->values()) written += v != one ? 1 : 0;
        CHECK(written > 0);  // the check below means something
        REQUIRE(device.clear(w, h, format).ok());
        std::size_t left = 0;
        for (const std::uint32_t v : target->values()) left += v != one ? 1 : 0;
        CHECK(left == 0);
    }
}
