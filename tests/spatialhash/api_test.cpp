// find_pairs as a caller sees it: errors name the element, degenerate sizes, determinism across
// thread counts, and the outlier handling.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "scene_gen.h"
#include "spatialhash/broad_phase.h"

#if defined(CULLIDE_HAVE_TBB)
#include <tbb/global_control.h>
#endif

using namespace sh_test;
using spatialhash::Method;
using spatialhash::Options;

namespace {
constexpr Method kMethods[] = {Method::SpatialHash, Method::SweepAndPrune, Method::BruteForce};

Options with(Method m, unsigned threads = 1) {
    Options o;
    o.method = m;
    o.threads = threads;
    return o;
}
}  // namespace

TEST_CASE("a non-finite box coordinate is an error naming the box and the coordinate") {
    std::vector<Box> s(3, box_at(0, 0, 0, 1, 1, 1));
    s[2].lo[1] = std::numeric_limits<double>::quiet_NaN();
    for (Method m : kMethods) {
        auto r = spatialhash::find_pairs(std::span<const Box>(s), with(m));
        REQUIRE_FALSE(r.ok());
        CHECK(r.error().message == "box 2: lo[1] = nan is not finite");
    }
    s[2] = box_at(0, 0, 0, 1, 1, 1);
    s[1].hi[0] = std::numeric_limits<double>::infinity();
    auto r = spatialhash::find_pairs(std::span<const Box>(s));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "box 1: hi[0] = inf is not finite");
}

TEST_CASE("a box with lo above hi is an error naming the box and both values") {
    std::vector<Box> s(2, box_at(0, 0, 0, 1, 1, 1));
    s[1].lo[2] = 2.0;
    auto r = spatialhash::find_pairs(std::span<const Box>(s));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "box 1: lo[2] = 2 > hi[2] = 1");
}

TEST_CASE("bad spheres and a bad cell size are errors naming what is wrong") {
    std::vector<Sphere> s(2, Sphere{{0, 0, 0}, 1.0});
    s[1].radius = -0.5;
    auto r = spatialhash::find_pairs(std::span<const Sphere>(s));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "sphere 1: radius = -0.5 is negative");
    s[1] = Sphere{{0, 1e200, 0}, 1.0};
    r = spatialhash::find_pairs(std::span<const Sphere>(s));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "sphere 1: centre[1] = 1e+200 exceeds the limit 1e+150 in magnitude");
    s[1] = Sphere{{0, 0, 0}, 1.0};
    Options o;
    o.cell_size = -1.0;
    r = spatialhash::find_pairs(std::span<const Sphere>(s), o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "Options::cell_size = -1 must be 0 (automatic) or finite and positive");
    o.cell_size = std::numeric_limits<double>::infinity();
    CHECK_FALSE(spatialhash::find_pairs(std::span<const Sphere>(s), o).ok());
}

TEST_CASE("far-flung coordinates never overflow the key and every method agrees") {
    // Objects up to 1e300 apart, with automatic and with given cell sizes: the padding of bounding
    // spheres makes far objects large enough that cell coordinates stay below the key limit
    // (docs/spatialhash.md, "Keys and limits"); far outliers are tested apart.
    Rng rng(41);
    for (int round = 0; round < 50; ++round) {
        std::vector<Box> s;
        for (int i = 0; i < 40; ++i) {
            const double c = std::pow(10.0, rng.range(-3, 300)) * (rng.below(2) == 0 ? -1.0 : 1.0);
            const double h = std::pow(10.0, rng.range(-3, 2));
            s.push_back(box_at(c, c * 0.5, 1.0, h, h, h));
        }
        s.push_back(s[3]);  // an exact duplicate overlaps however far it is
        const std::vector<Pair> want = reference_pairs(s);
        for (double cell : {0.0, 1e-3, 1.0, 1e6}) {
            Options o;
            o.cell_size = cell;
            CAPTURE(round);
            CAPTURE(cell);
            auto r = spatialhash::find_pairs(std::span<const Box>(s), o);
            REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
            CHECK(r.value().pairs == want);
        }
        auto sap = spatialhash::find_pairs(std::span<const Box>(s), with(Method::SweepAndPrune));
        REQUIRE(sap.ok());
        CHECK(sap.value().pairs == want);
    }
}

TEST_CASE("zero, one and two objects give the obvious answers") {
    for (Method m : kMethods) {
        CAPTURE(static_cast<int>(m));
        const std::vector<Box> none;
        auto r0 = spatialhash::find_pairs(std::span<const Box>(none), with(m));
        REQUIRE(r0.ok());
        CHECK(r0.value().pairs.empty());
        const std::vector<Box> one = {box_at(1, 2, 3, 1, 1, 1)};
        auto r1 = spatialhash::find_pairs(std::span<const Box>(one), with(m));
        REQUIRE(r1.ok());
        CHECK(r1.value().pairs.empty());
        const std::vector<Box> two = {box_at(0, 0, 0, 1, 1, 1), box_at(2, 0, 0, 1, 1, 1)};  // touching at x = 1
        auto r2 = spatialhash::find_pairs(std::span<const Box>(two), with(m));
        REQUIRE(r2.ok());
        CHECK(r2.value().pairs == std::vector<Pair>{{0, 1}});
        const std::vector<Box> apart = {box_at(0, 0, 0, 1, 1, 1), box_at(2.000001, 0, 0, 1, 1, 1)};
        auto r3 = spatialhash::find_pairs(std::span<const Box>(apart), with(m));
        REQUIRE(r3.ok());
        CHECK(r3.value().pairs.empty());
    }
}

TEST_CASE("results are identical for 1, 2, 3 and 8 threads (and on the spread schedule) and equal the reference") {
#if defined(CULLIDE_HAVE_TBB)
    // Let TBB run 8 workers even on a 2-core machine, so that 3 and 8 threads really happen.
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
#endif
    Rng rng(8);
    std::vector<Box> boxes;
    for (int i = 0; i < 6000; ++i) {
        // Clustered and uniform halves, with a few giants among them.
        const double c = i % 2 == 0 ? rng.range(0, 60) : 30 + rng.range(-3, 3);
        boxes.push_back(box_at(c, rng.range(0, 60), rng.range(0, 60), rng.range(0.05, 0.6), rng.range(0.05, 0.6),
                               rng.range(0.05, 0.6)));
    }
    boxes[100] = box_at(30, 30, 30, 25, 1, 1);
    boxes[5000] = box_at(30, 30, 30, 1, 25, 1);
    const std::vector<Pair> want = reference_pairs(boxes);
    MESSAGE("reference pairs: " << want.size() << ", digest " << digest(want));
    for (Method m : kMethods) {
        for (const ThreadRun run : kThreadRuns) {
            const unsigned threads = run.threads;
            const SpreadScope spread(run.spread);
            CAPTURE(static_cast<int>(m));
            CAPTURE(threads);
            CAPTURE(run.spread);
            auto r = spatialhash::find_pairs(std::span<const Box>(boxes), with(m, threads));
            REQUIRE(r.ok());
            CHECK(r.value().pairs.size() == want.size());
            CHECK(digest(r.value().pairs) == digest(want));
            CHECK(r.value().pairs == want);
        }
    }
}

TEST_CASE("a few giants among many small objects are tested apart and the cell stays small") {
    Rng rng(12);
    std::vector<Box> boxes;
    for (int i = 0; i < 5000; ++i) {
        boxes.push_back(box_at(rng.range(0, 100), rng.range(0, 100), rng.range(0, 100), 0.3, 0.3, 0.3));
    }
    for (int g = 0; g < 5; ++g) boxes[static_cast<std::size_t>(g) * 997] = box_at(50, 50, 50, 40, 40, 40);
    auto r = spatialhash::find_pairs(std::span<const Box>(boxes));
    REQUIRE(r.ok());
    CHECK(r.value().stats.huge_objects == 5);
    // 1.5 x 2 sqrt2 x 0.3 sqrt3 = 2.2: the small objects decide the cell.
    CHECK(r.value().stats.cell_size < 2.3);
    CHECK(r.value().pairs == reference_pairs(boxes));
}

TEST_CASE("every method fills the statistics it owns") {
    Rng rng(13);
    double cell = 0;
    const std::vector<Box> boxes = box_scene(Family::Uniform, 500, rng, &cell);
    auto g = spatialhash::find_pairs(std::span<const Box>(boxes));
    auto s = spatialhash::find_pairs(std::span<const Box>(boxes), with(Method::SweepAndPrune));
    auto b = spatialhash::find_pairs(std::span<const Box>(boxes), with(Method::BruteForce));
    REQUIRE((g.ok() && s.ok() && b.ok()));
    CHECK(g.value().stats.cell_size > 0);
    CHECK(g.value().stats.cell_entries >= boxes.size());
    CHECK(g.value().stats.collision_cells > 0);
    // The grid's cells propose every reported pair; the float tests decide most of them, so the
    // exact tests are at most the proposals.
    CHECK(g.value().stats.cell_pairs >= g.value().pairs.size());
    CHECK(g.value().stats.candidate_tests <= g.value().stats.cell_pairs);
    CHECK(s.value().stats.sweep_axis >= 0);
    CHECK(b.value().stats.candidate_tests == 500ULL * 499 / 2);
    // Both fast methods consider far fewer pairs than brute force.
    CHECK(g.value().stats.cell_pairs < b.value().stats.candidate_tests / 4);
    CHECK(s.value().stats.candidate_tests < b.value().stats.candidate_tests / 4);
    // Spheres: no float test can accept a pair, so every reported pair had its exact test.
    std::vector<Sphere> spheres;
    for (const Box& x : boxes) {
        spheres.push_back(Sphere{{0.5 * x.lo[0] + 0.5 * x.hi[0], 0.5 * x.lo[1] + 0.5 * x.hi[1], 0.5 * x.lo[2] + 0.5 * x.hi[2]},
                                 0.5 * (x.hi[0] - x.lo[0])});
    }
    auto gs = spatialhash::find_pairs(std::span<const Sphere>(spheres));
    REQUIRE(gs.ok());
    CHECK(!gs.value().pairs.empty());
    CHECK(gs.value().stats.candidate_tests >= gs.value().pairs.size());
}

TEST_CASE("boxes and spheres near 1e-300 keep their size (fuzzer finding: squared edges underflowed)") {
    // Identical boxes [1e-300, 2e-300]^3 once got a zero bounding radius; with a box elsewhere the
    // grid then lost pairs.
    std::vector<Box> boxes(16, Box{{1e-300, 1e-300, 1e-300}, {2e-300, 2e-300, 2e-300}});
    boxes.push_back(Box{{-32, 1e-300, 1e-300}, {1e-300, 2e-300, 2e-300}});  // touches all 16
    boxes.push_back(Box{{2e-300, 0, 0}, {4e-300, 1e-300, 1e-300}});  // corner contact with all 16
    const std::vector<Pair> want = reference_pairs(boxes);
    CHECK(want.size() == 16 * 15 / 2 + 16 + 16);
    for (Method m : kMethods) {
        auto r = spatialhash::find_pairs(std::span<const Box>(boxes), with(m));
        REQUIRE(r.ok());
        CHECK(r.value().pairs == want);
    }
    // Points 1e-300 apart do not touch, though their squared distance underflows in a naive test.
    const std::vector<Sphere> spheres = {Sphere{{0, 0, 0}, 0.0}, Sphere{{1e-300, 0, 0}, 0.0}, Sphere{{1e-300, 0, 0}, 0.0},
                                         Sphere{{3e-300, 0, 0}, 2.5e-300}};
    CHECK_FALSE(spatialhash::overlaps(spheres[0], spheres[1]));
    CHECK(spatialhash::overlaps(spheres[1], spheres[2]));
    CHECK(spatialhash::overlaps(spheres[3], spheres[1]));
    for (Method m : kMethods) {
        auto r = spatialhash::find_pairs(std::span<const Sphere>(spheres), with(m));
        REQUIRE(r.ok());
        CHECK(r.value().pairs == reference_pairs(spheres));
        CHECK(r.value().pairs == std::vector<Pair>{{1, 2}, {1, 3}, {2, 3}});
    }
}

TEST_CASE("coordinates near the ends of the double range do not overflow the cell arithmetic (fuzzer finding)") {
    // Objects at -1.7e308 and +1.7e308: x - origin overflowed to inf and the grid refused input
    // that the other methods accept. An object whose coverage box reaches past -DBL_MAX cannot sit
    // in cells at all and is tested apart.
    constexpr double kMax = std::numeric_limits<double>::max();
    const std::vector<Box> boxes = {
        Box{{-1.7e308, 0, 0}, {-1.7e308 + 1e300, 1e300, 1e300}},
        Box{{1.7e308 - 1e300, 0, 0}, {1.7e308, 1e300, 1e300}},
        Box{{-1.7e308 + 5e299, 5e299, 5e299}, {-1.7e308 + 1.5e300, 1.5e300, 1.5e300}},
        Box{{-kMax, 0, 0}, {-1.7e308 + 1e299, 2e300, 2e300}},
        Box{{1.7e308 - 2e300, 5e299, 0}, {1.7e308 - 5e299, 6e299, 1e299}},
        Box{{0, 0, 0}, {1e300, 1e300, 1e300}},
    };
    const std::vector<Pair> want = reference_pairs(boxes);
    // (0, 2) and (1, 4) near the two ends, (0, 3) with the object that reaches -DBL_MAX.
    REQUIRE(want == std::vector<Pair>{{0, 2}, {0, 3}, {1, 4}});
    // 1e308: a cell large enough for every object, so only the coverage rule sets object 3 apart.
    for (double cell : {0.0, 1e301, 1e308}) {
        for (Method m : {Method::SpatialHash, Method::SweepAndPrune, Method::BruteForce}) {
            Options o = with(m);
            o.cell_size = cell;
            auto r = spatialhash::find_pairs(std::span<const Box>(boxes), o);
            CAPTURE(cell);
            CAPTURE(static_cast<int>(m));
            REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
            CHECK(r.value().pairs == want);
        }
    }
}
