// spatialhash::Workspace: one workspace reused across scenes of every family and size (growing and
// shrinking), boxes and spheres, all methods and 1, 2, 3, 8 threads, gives exactly the pairs and
// statistics of a fresh call; a frame of a scene no larger than an earlier one makes no large
// allocation; an error leaves the output empty and the workspace usable.
#include <doctest/doctest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include "scene_gen.h"

using namespace sh_test;
using spatialhash::Method;
using spatialhash::Options;
using spatialhash::Stats;

namespace {

// Allocations of at least kBig bytes through operator new, counted while `counting` is set.
constexpr std::size_t kBig = std::size_t{64} << 10;
std::atomic<bool> counting{false};
std::atomic<std::size_t> big_allocations{0};

void same_stats(const Stats& x, const Stats& y) {
    CHECK(x.cell_size == y.cell_size);
    CHECK(x.axis_bits == y.axis_bits);
    CHECK(x.huge_objects == y.huge_objects);
    CHECK(x.cell_entries == y.cell_entries);
    CHECK(x.collision_cells == y.collision_cells);
    CHECK(x.cell_pairs == y.cell_pairs);
    CHECK(x.candidate_tests == y.candidate_tests);
    CHECK(x.sweep_axis == y.sweep_axis);
}

}  // namespace

// A counting replacement of the global operator new/delete over malloc/free (GCC cannot see that
// the pair is consistent once both are replaced).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t size) {
    if (size >= kBig && counting.load(std::memory_order_relaxed)) big_allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

TEST_CASE("one workspace across box scenes of every family and size equals fresh calls") {
    Rng rng(31337);
    spatialhash::Workspace ws;
    std::vector<Pair> pairs;
    std::size_t checked = 0;
    for (int round = 0; round < 2; ++round) {
        for (int f = 0; f < static_cast<int>(Family::kCount); ++f) {
            // Sizes that grow and shrink, so that stale capacity and stale contents both occur.
            for (std::size_t n : {std::size_t{300}, std::size_t{3}, std::size_t{1200}, std::size_t{0}, std::size_t{40}}) {
                double cell = 0.0;
                const std::vector<Box> s = box_scene(static_cast<Family>(f), n, rng, &cell);
                const std::vector<Pair> want = reference_pairs(s);
                for (Method m : {Method::SpatialHash, Method::SweepAndPrune, Method::BruteForce}) {
                    // (1, 2, 3, 8 threads for the grid; the twins, which share little with it, at 2.)
                    const std::vector<unsigned> thread_counts =
                        m == Method::SpatialHash ? std::vector<unsigned>{1U, 2U, 3U, 8U} : std::vector<unsigned>{2U};
                    for (unsigned threads : thread_counts) {
                        Options o;
                        o.method = m;
                        o.threads = threads;
                        o.cell_size = m == Method::SpatialHash ? cell : 0.0;
                        auto fresh = spatialhash::find_pairs(std::span<const Box>(s), o);
                        REQUIRE(fresh.ok());
                        auto reused = spatialhash::find_pairs(std::span<const Box>(s), o, ws, pairs);
                        REQUIRE(reused.ok());
                        CHECK(pairs == want);
                        CHECK(fresh.value().pairs == want);
                        same_stats(reused.value(), fresh.value().stats);
                        ++checked;
                    }
                }
            }
        }
    }
    CHECK(checked == 2 * static_cast<std::size_t>(Family::kCount) * 5 * (4 + 1 + 1));
}

TEST_CASE("one workspace across sphere scenes, and between boxes and spheres, equals fresh calls") {
    Rng rng(4242);
    spatialhash::Workspace ws;
    std::vector<Pair> pairs;
    for (int round = 0; round < 8; ++round) {
        for (int kind = 0; kind < 4; ++kind) {
            const std::vector<Sphere> s = sphere_scene(kind, 50 + 150 * static_cast<std::size_t>(round % 3), rng);
            double cell = 0.0;
            const std::vector<Box> b = box_scene(Family::Clustered, 500, rng, &cell);
            for (unsigned threads : {1U, 3U}) {
                Options o;
                o.threads = threads;
                auto r = spatialhash::find_pairs(std::span<const Sphere>(s), o, ws, pairs);
                REQUIRE(r.ok());
                CHECK(pairs == reference_pairs(s));
                same_stats(r.value(), spatialhash::find_pairs(std::span<const Sphere>(s), o).value().stats);
                auto rb = spatialhash::find_pairs(std::span<const Box>(b), o, ws, pairs);
                REQUIRE(rb.ok());
                CHECK(pairs == reference_pairs(b));
            }
        }
    }
}

TEST_CASE("a moved workspace keeps working, and the moved-from one starts afresh") {
    Rng rng(5);
    double cell = 0.0;
    const std::vector<Box> s = box_scene(Family::Clustered, 400, rng, &cell);
    const std::vector<Pair> want = reference_pairs(s);
    spatialhash::Workspace a;
    std::vector<Pair> pairs;
    REQUIRE(spatialhash::find_pairs(std::span<const Box>(s), Options{}, a, pairs).ok());
    spatialhash::Workspace b = std::move(a);
    REQUIRE(spatialhash::find_pairs(std::span<const Box>(s), Options{}, b, pairs).ok());
    CHECK(pairs == want);
    REQUIRE(spatialhash::find_pairs(std::span<const Box>(s), Options{}, a, pairs).ok());  // NOLINT(bugprone-use-after-move)
    CHECK(pairs == want);
}

TEST_CASE("an error through a workspace leaves the pairs empty and the workspace usable") {
    spatialhash::Workspace ws;
    std::vector<Pair> pairs = {Pair{0, 1}};
    const std::vector<Box> bad = {box_at(0, 0, 0, 1, 1, 1), Box{{0, 0, 2}, {1, 1, 1}}};
    auto r = spatialhash::find_pairs(std::span<const Box>(bad), Options{}, ws, pairs);
    REQUIRE(!r.ok());
    CHECK(r.error().message == "box 1: lo[2] = 2 > hi[2] = 1");
    CHECK(pairs.empty());
    const std::vector<Box> good = {box_at(0, 0, 0, 1, 1, 1), box_at(1.5, 0, 0, 1, 1, 1), box_at(9, 9, 9, 1, 1, 1)};
    auto g = spatialhash::find_pairs(std::span<const Box>(good), Options{}, ws, pairs);
    REQUIRE(g.ok());
    CHECK(pairs == std::vector<Pair>{{0, 1}});
}

TEST_CASE("a warm workspace makes no large allocation for a scene no larger than an earlier one") {
    // 60,000 uniform boxes: every per-object and per-pair array is well above 64 KiB, so a fresh call
    // allocates many of them; through a warm workspace, frames of this scene and of a smaller one
    // allocate none.
    Rng rng(77);
    std::vector<Box> big, small;
    for (int i = 0; i < 60000; ++i) {
        big.push_back(box_at(rng.range(0, 90), rng.range(0, 90), rng.range(0, 90), rng.range(0.2, 0.6),
                             rng.range(0.2, 0.6), rng.range(0.2, 0.6)));
    }
    small.assign(big.begin(), big.begin() + 20000);
    Options o;
    o.threads = 1;
    spatialhash::Workspace ws;
    std::vector<Pair> pairs;
    REQUIRE(spatialhash::find_pairs(std::span<const Box>(big), o, ws, pairs).ok());
    const std::vector<Pair> want_big = pairs;
    CHECK(ws.capacity_bytes() > 60000 * 32);

    big_allocations = 0;
    counting = true;
    auto fresh = spatialhash::find_pairs(std::span<const Box>(big), o);
    counting = false;
    REQUIRE(fresh.ok());
    MESSAGE("large allocations of a fresh call: " << big_allocations.load());
    CHECK(big_allocations.load() >= 5);  // the counter works

    big_allocations = 0;
    counting = true;
    auto r1 = spatialhash::find_pairs(std::span<const Box>(big), o, ws, pairs);
    const std::vector<Pair> got_big = pairs;  // (copy made while counting: excluded below)
    const std::size_t after_copy = big_allocations.load();
    auto r2 = spatialhash::find_pairs(std::span<const Box>(small), o, ws, pairs);
    counting = false;
    REQUIRE(r1.ok());
    REQUIRE(r2.ok());
    CHECK(got_big == want_big);
    CHECK(got_big == fresh.value().pairs);
    CHECK(pairs == spatialhash::find_pairs(std::span<const Box>(small), o).value().pairs);
    CHECK(after_copy <= 1);  // only the test's own copy
    CHECK(big_allocations.load() == after_copy);
}
