// visibility_api_test.cpp: the pieces shared by every method (issue #15): the one exact stage
// (cullide/src/exact_stage.h), QueryDevice::visibility_pass and its recorded default, the view
// resolution checked once against one range with the mode's default, and the frame's parallel
// object boxes and input scan (cullide/src/cullide_detail.h).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "cullide/cullide.h"
#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/query_device.h"
#include "cullide/scenes.h"
#include "cullide_detail.h"
#include "exact_stage.h"
#include "test_rng.h"

namespace {

using cullide::detail::CandidateSet;
using cullide::detail::ExactObject;

// Three objects of small random triangles in one unit cube, so boxes overlap in every way. Shuffled
// triangle order inside each object makes sets of consecutive triangles loose.
std::vector<cullide::Mesh> soup(std::uint64_t seed, int triangles_per_object) {
    test::Rng rng(seed);
    std::vector<cullide::Mesh> objects(3);
    for (cullide::Mesh& m : objects) {
        m.name = "soup";
        for (int t = 0; t < triangles_per_object; ++t) {
            const cullide::Vec3 c{rng.grid(0, 1, 64), rng.grid(0, 1, 64), rng.grid(0, 1, 64)};
            const auto base = static_cast<std::uint32_t>(m.positions.size());
            for (int v = 0; v < 3; ++v)
                m.positions.push_back(c + 0.125 * cullide::Vec3{rng.sym(), rng.sym(), rng.sym()});
            m.triangles.push_back({base, base + 1, base + 2});
        }
    }
    return objects;
}

// The exact stage over sets of `group` consecutive triangles of every object.
cullide::detail::ExactStageResult exact_stage_in_groups(const std::vector<cullide::Mesh>& objects, std::uint32_t group,
                                                        std::vector<std::vector<cullide::Aabb>>& boxes, int threads) {
    std::vector<ExactObject> exact(objects.size());
    std::vector<CandidateSet> sets;
    boxes.assign(objects.size(), {});
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const cullide::Mesh& m = objects[i];
        for (std::size_t t = 0; t < m.triangles.size(); ++t) boxes[i].push_back(cullide::triangle_bounds(m, t));
        exact[i] = {&m, static_cast<std::uint32_t>(i), cullide::mesh_bounds(m), boxes[i], {}, {}};
        const auto n = static_cast<std::uint32_t>(m.triangles.size());
        for (std::uint32_t f = 0; f < n; f += group) {
            CandidateSet s{static_cast<std::uint32_t>(i), f, std::min(group, n - f), {}};
            s.box = boxes[i][f];
            for (std::uint32_t t = f; t < s.first + s.count; ++t) {
                for (int k = 0; k < 3; ++k) {
                    s.box.lo[k] = std::min(s.box.lo[k], boxes[i][t].lo[k]);
                    s.box.hi[k] = std::max(s.box.hi[k], boxes[i][t].hi[k]);
                }
            }
            sets.push_back(s);
        }
    }
    return cullide::detail::sweep_exact_stage(exact, sets, {false, true, threads});
}

// A device that runs only what any GL can: clear and execute (here the emulator's), so the
// visibility pass is the base class's recorded default.
class RecordingDevice final : public cullide::QueryDevice {
   public:
    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        return inner_->clear(width, height, format);
    }
    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        return inner_->execute(batch);
    }
    std::string name() const override { return "recording device"; }

   private:
    std::unique_ptr<cullide::QueryDevice> inner_ = cullide::make_emulator_device(2);
};

}  // namespace

TEST_CASE("the exact stage tests the same triangle pairs whether it sweeps triangles or groups of them") {
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
        CAPTURE(seed);
        const std::vector<cullide::Mesh> objects = soup(seed, 300);
        auto truth = cullide::exact_pairs(objects, cullide::ExactOptions{false, 2});
        REQUIRE(truth.ok());
        std::vector<std::vector<cullide::Aabb>> boxes;
        const auto single = exact_stage_in_groups(objects, 1, boxes, 1);
        CHECK(single.pairs == truth.value());
        CHECK(!single.pairs.empty());
        for (const std::uint32_t group : {2u, 4u, 16u, 300u}) {
            for (const int threads : {1, 3}) {
                CAPTURE(group);
                CAPTURE(threads);
                const auto grouped = exact_stage_in_groups(objects, group, boxes, threads);
                CHECK(grouped.pairs == truth.value());
                CHECK(grouped.stats.tests == single.stats.tests);
            }
        }
    }
}

TEST_CASE("a device with only clear and execute answers R-CULLIDE's views as the emulator's fused pass does") {
    cullide::SceneOptions so;
    so.scale = 0.05;
    so.mesh_dir = "";
    for (const std::string scene : {"cylinders", "tori", "breaking"}) {
        CAPTURE(scene);
        auto gen = cullide::make_scene(scene, so);
        REQUIRE(gen.ok());
        const cullide::Frame frame = gen.value()->frame(5);
        cullide::RunOptions o;
        o.method = cullide::Method::RCullide;
        o.threads = 2;
        auto fused = cullide::process_frame(frame, o);
        RecordingDevice device;
        o.device = &device;
        auto recorded = cullide::process_frame(frame, o);
        REQUIRE(fused.ok());
        REQUIRE(recorded.ok());
        CHECK(recorded.value().pairs == fused.value().pairs);
        CHECK(recorded.value().stats.pcs_subobjects == fused.value().stats.pcs_subobjects);
        CHECK(recorded.value().stats.queries == fused.value().stats.queries);
        REQUIRE(recorded.value().stats.views.size() == fused.value().stats.views.size());
        for (std::size_t v = 0; v < fused.value().stats.views.size(); ++v)
            CHECK(recorded.value().stats.views[v].items_after == fused.value().stats.views[v].items_after);
    }
}

TEST_CASE("the view resolution has one range, checked at the entry point, and the mode's default for 0") {
    using cullide::VisibilityMode;
    CHECK(cullide::view_size(0, VisibilityMode::ExactBounds).value().pixels() == 32);
    CHECK(cullide::view_size(0, VisibilityMode::GLExact).value().pixels() == 1024);
    CHECK(cullide::view_size(0, VisibilityMode::Offset).value().pixels() == 1024);
    CHECK(cullide::view_size(cullide::kMinViewResolution, VisibilityMode::GLExact).ok());
    CHECK(cullide::view_size(cullide::kMaxViewResolution, VisibilityMode::GLExact).ok());
    auto big = cullide::view_size(cullide::kMaxViewResolution + 1, VisibilityMode::GLExact);
    REQUIRE_FALSE(big.ok());
    CHECK(big.error().message == "resolution must be in 1..16384 (got 16385)");
    for (cullide::Method m : {cullide::Method::Cullide, cullide::Method::RCullide, cullide::Method::RCullideOffset,
                              cullide::Method::QCullide, cullide::Method::QCullideGL}) {
        CAPTURE(cullide::to_string(m));
        const VisibilityMode mode = m == cullide::Method::RCullide || m == cullide::Method::QCullide
                                        ? VisibilityMode::ExactBounds
                                        : VisibilityMode::GLExact;
        CHECK(cullide::default_resolution(m) == cullide::default_resolution(mode));
    }

    // The method entry points refuse what process_frame refuses, with the same words.
    cullide::SceneOptions so;
    so.scale = 0.05;
    so.mesh_dir = "";
    auto gen = cullide::make_scene("cylinders", so);
    REQUIRE(gen.ok());
    const cullide::Frame frame = gen.value()->frame(0);
    std::vector<std::uint32_t> active(frame.size());
    for (std::size_t i = 0; i < active.size(); ++i) active[i] = static_cast<std::uint32_t>(i);
    auto device = cullide::make_emulator_device(1);
    cullide::CullideOptions co;
    co.resolution = -3;
    auto r = cullide::cullide_pairs(frame, active, co, *device);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "resolution must be in 1..16384 (got -3)");
    // 0 is the mode's default: the same run as asking for it.
    co.mode = VisibilityMode::ExactBounds;
    co.resolution = 0;
    cullide::CullideStats implicit, explicit_stats;
    auto a = cullide::cullide_pairs(frame, active, co, *device, &implicit);
    co.resolution = cullide::kDefaultResolutionExactBounds;
    auto b = cullide::cullide_pairs(frame, active, co, *device, &explicit_stats);
    REQUIRE(a.ok());
    REQUIRE(b.ok());
    CHECK(a.value() == b.value());
    CHECK(implicit.queries == explicit_stats.queries);
    CHECK(implicit.triangles_rasterized == explicit_stats.triangles_rasterized);
}

namespace {

// Bitwise equality of two boxes (signed zeros and NaN payloads count).
bool same_bits(const cullide::Aabb& a, const cullide::Aabb& b) {
    const double x[6] = {a.lo.x, a.lo.y, a.lo.z, a.hi.x, a.hi.y, a.hi.z};
    const double y[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
    return std::memcmp(x, y, sizeof x) == 0;
}

}  // namespace

TEST_CASE("object_bounds gives mesh_bounds' bits, in jobs of triangles on any thread count") {
    // Objects of 1, kBoundsTriangles and 2.5 kBoundsTriangles + 7 triangles, on shared vertices, with
    // +0 and -0 both at the minimum of each axis in different jobs: which zero wins depends on the
    // order of the fold, so a fold out of mesh_bounds' order shows here.
    test::Rng rng(31);
    std::vector<cullide::Mesh> objects;
    for (const std::size_t n : {std::size_t{1}, cullide::detail::kBoundsTriangles,
                                cullide::detail::kBoundsTriangles * 5 / 2 + 7}) {
        cullide::Mesh m;
        m.name = "zeros";
        for (std::size_t v = 0; v < 64; ++v) m.positions.push_back({rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1)});
        m.positions.push_back({-0.0, -0.0, -0.0});  // 64
        m.positions.push_back({0.0, 0.0, 0.0});     // 65
        for (std::size_t t = 0; t < n; ++t) {
            auto pick = [&] { return static_cast<std::uint32_t>(rng.below(64)); };
            cullide::Tri tri{pick(), pick(), pick()};
            if (t == n - 1) tri[2] = 64;  // -0 in the last job
            if (t == n / 2) tri[0] = 65;  // +0 earlier (for n = 1: an earlier vertex of the same triangle)
            m.triangles.push_back(tri);
        }
        objects.push_back(std::move(m));
    }
    const std::vector<std::uint32_t> active = {0, 1, 2};
    for (const int threads : {1, 2}) {
        const std::vector<cullide::Aabb> boxes = cullide::detail::object_bounds(objects, active, threads);
        REQUIRE(boxes.size() == objects.size());
        for (std::size_t k = 0; k < objects.size(); ++k) {
            CAPTURE(k);
            CAPTURE(threads);
            CHECK(same_bits(boxes[k], cullide::mesh_bounds(objects[k])));
            CHECK(!std::signbit(boxes[k].lo.x));  // +0 came first in triangle order
        }
    }
    // Only the listed objects, in `active`'s order; an object without triangles has the empty box.
    objects.push_back(cullide::Mesh{});
    const std::vector<std::uint32_t> some = {2, 3};
    const std::vector<cullide::Aabb> two = cullide::detail::object_bounds(objects, some, 2);
    REQUIRE(two.size() == 2);
    CHECK(same_bits(two[0], cullide::mesh_bounds(objects[2])));
    CHECK(two[1].empty());
}

TEST_CASE("scene_clean is true exactly when the per-object checks find nothing, wherever the problem is") {
    // A clean scene of three objects, the big one spanning several check parts; then one problem at
    // a time in each object, in the first and in the last part.
    test::Rng rng(37);
    std::vector<cullide::Mesh> clean;
    for (const std::size_t n : {std::size_t{3}, cullide::detail::kCheckPart * 2 + 5, std::size_t{10}}) {
        cullide::Mesh m;
        m.name = "check";
        for (std::size_t v = 0; v < n + 2; ++v) m.positions.push_back({rng.uniform(1, 2), rng.uniform(1, 2), rng.uniform(1, 2)});
        for (std::size_t t = 0; t < n; ++t)
            m.triangles.push_back({static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(t + 1), static_cast<std::uint32_t>(t + 2)});
        clean.push_back(std::move(m));
    }
    const auto per_object_ok = [](const std::vector<cullide::Mesh>& objects) {
        for (std::size_t i = 0; i < objects.size(); ++i)
            if (!cullide::validate_mesh(objects[i]) || !cullide::detail::validate_exact_range_of(objects[i], i)) return false;
        return true;
    };
    for (const int threads : {1, 2}) {
        CAPTURE(threads);
        CHECK(cullide::detail::scene_clean(clean, threads));
        CHECK(per_object_ok(clean));
        const double bad_values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                     -std::numeric_limits<double>::infinity(), 1e-310 /* subnormal */, 0x1p-301, 0x1p301};
        for (std::size_t o = 0; o < clean.size(); ++o) {
            for (const bool last : {false, true}) {
                const std::size_t v = last ? clean[o].positions.size() - 1 : 0;
                for (const double bad : bad_values) {
                    for (int axis = 0; axis < 3; ++axis) {
                        std::vector<cullide::Mesh> s = clean;
                        (axis == 0 ? s[o].positions[v].x : axis == 1 ? s[o].positions[v].y : s[o].positions[v].z) = bad;
                        CAPTURE(o);
                        CAPTURE(v);
                        CAPTURE(bad);
                        CHECK(!per_object_ok(s));
                        CHECK(!cullide::detail::scene_clean(s, threads));
                    }
                }
                std::vector<cullide::Mesh> s = clean;
                const std::size_t t = last ? s[o].triangles.size() - 1 : 0;
                s[o].triangles[t][2] = static_cast<std::uint32_t>(s[o].positions.size());  // one beyond
                CHECK(!per_object_ok(s));
                CHECK(!cullide::detail::scene_clean(s, threads));
            }
            std::vector<cullide::Mesh> s = clean;
            s[o].triangles.clear();
            CHECK(!per_object_ok(s));
            CHECK(!cullide::detail::scene_clean(s, threads));
        }
        // Exact zero is inside the range.
        std::vector<cullide::Mesh> z = clean;
        z[1].positions.back() = {0.0, -0.0, 0.0};
        CHECK(per_object_ok(z));
        CHECK(cullide::detail::scene_clean(z, threads));
    }
}
