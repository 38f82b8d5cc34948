// The chapter's sizing constants, settled by property tests in 3-D (docs/spatialhash.md, "Sizing"):
//   - phantom cells from the bounding sphere scaled by sqrt(2): scale 1 loses pairs, sqrt(2) loses none;
//   - cell edge vs object size: at 1.0 x the scaled diameter the duplicate-avoidance rule loses
//     pairs; the library's 1.25 (and the chapter's 1.5) lose none.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "scene_gen.h"
#include "spatialhash/detail/grid_stages.h"

using namespace sh_test;
namespace d = spatialhash::detail;

namespace {

std::vector<Pair> grid_pairs(const std::vector<Sphere>& s, double cell, const d::PlanKnobs& knobs) {
    d::Executor ex(1);
    const auto bs = d::bounding_spheres(std::span<const Sphere>(s), ex);
    const d::Objects objects{{}, s};
    auto r = d::grid_find_pairs(objects, bs, cell, ex, knobs);
    REQUIRE(r.ok());
    return r.value().pairs;
}

// Missing pairs of the grid against the reference (the grid never invents pairs: it tests them).
std::size_t misses(const std::vector<Sphere>& s, double cell, const d::PlanKnobs& knobs) {
    const std::vector<Pair> got = grid_pairs(s, cell, knobs);
    const std::vector<Pair> want = reference_pairs(s);
    CHECK(std::includes(want.begin(), want.end(), got.begin(), got.end(),
                        [](const Pair& x, const Pair& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }));
    return want.size() - got.size();
}

// Dense scenes of near-maximal equal spheres for a cell of edge 1, anchored at the origin so that
// cell boundaries sit at integers.
std::vector<Sphere> dense_scene(Rng& rng, double r_max) {
    std::vector<Sphere> s = {Sphere{{0, 0, 0}, 0.0}};
    for (int i = 0; i < 40; ++i) {
        s.push_back(Sphere{{rng.range(0.5, 3.0), rng.range(0.5, 3.0), rng.range(0.5, 3.0)}, r_max * rng.range(0.9, 1.0)});
    }
    return s;
}

}  // namespace

TEST_CASE("phantom cells from the unscaled sphere lose a diagonal pair that the sqrt(2) scaling keeps") {
    // A fails to reach B's home cell on x, B fails to reach A's home on y; they overlap across the
    // corner, in a cell that is home to neither (docs/spatialhash.md, "Why sqrt(2)").
    const std::vector<Sphere> s = {Sphere{{0, 0, 0}, 0.0}, Sphere{{0.692, 1.028, 0.5}, 0.28},
                                   Sphere{{1.028, 0.692, 0.5}, 0.28}};
    REQUIRE(reference_pairs(s) == std::vector<Pair>{{1, 2}});
    d::PlanKnobs unscaled;
    unscaled.coverage_scale = 1.0;
    CHECK(grid_pairs(s, 1.0, unscaled).empty());
    CHECK(grid_pairs(s, 1.0, d::PlanKnobs{}) == std::vector<Pair>{{1, 2}});
}

TEST_CASE("in 3-D random scenes scale 1 loses pairs and sqrt(2) loses none") {
    Rng rng(2024);
    std::size_t lost_unscaled = 0;
    std::size_t lost_sqrt2 = 0;
    std::size_t pairs = 0;
    const double r_max = 1.0 / (1.25 * 2.0 * std::sqrt(2.0)) * 0.999;
    d::PlanKnobs unscaled;
    unscaled.coverage_scale = 1.0;
    for (int scene = 0; scene < 1500; ++scene) {
        const std::vector<Sphere> s = dense_scene(rng, r_max);
        pairs += reference_pairs(s).size();
        lost_unscaled += misses(s, 1.0, unscaled);
        lost_sqrt2 += misses(s, 1.0, d::PlanKnobs{});
    }
    MESSAGE("reference pairs " << pairs << ", lost with scale 1: " << lost_unscaled << ", with sqrt(2): " << lost_sqrt2);
    CHECK(lost_unscaled > 0);
    CHECK(lost_sqrt2 == 0);
}

TEST_CASE("a cell of only 1.0 x the scaled diameter lets the duplicate rule drop a pair") {
    // x's home is cell 0 (type 0) and it reaches cell 1; y's home is cell 1 (type 1) and it reaches
    // cell 2 (type 0). In pass 1 at cell 1 the rule assumes the pair met in pass 0, but the two type-0
    // cells are different ones (docs/spatialhash.md, "Why the cell must exceed (2 + sqrt 2) r").
    const std::vector<Sphere> s = {Sphere{{0, 0, 0}, 0.0}, Sphere{{0.9, 0.5, 0.5}, 0.35}, Sphere{{1.55, 0.5, 0.5}, 0.35}};
    REQUIRE(reference_pairs(s) == std::vector<Pair>{{1, 2}});
    d::PlanKnobs tight;
    tight.min_cell_factor = 1.0;
    CHECK(grid_pairs(s, 1.0, tight).empty());
    // The library's factor 1.25 sends these objects to the huge list instead: nothing lost.
    CHECK(grid_pairs(s, 1.0, d::PlanKnobs{}) == std::vector<Pair>{{1, 2}});
}

TEST_CASE("in 3-D random scenes a cell of 1.0 x the scaled diameter loses pairs and 1.25 x loses none") {
    Rng rng(4048);
    std::size_t lost_tight = 0;
    std::size_t lost_default = 0;
    d::PlanKnobs tight;
    tight.min_cell_factor = 1.0;
    const double r_tight = 1.0 / (1.0 * 2.0 * std::sqrt(2.0)) * 0.999;
    const double r_default = 1.0 / (1.25 * 2.0 * std::sqrt(2.0)) * 0.999;
    for (int scene = 0; scene < 1500; ++scene) {
        lost_tight += misses(dense_scene(rng, r_tight), 1.0, tight);
        lost_default += misses(dense_scene(rng, r_default), 1.0, d::PlanKnobs{});
    }
    MESSAGE("lost with cell = 1.0 x scaled diameter: " << lost_tight << ", with 1.25 x: " << lost_default);
    CHECK(lost_tight > 0);
    CHECK(lost_default == 0);
}

TEST_CASE("boxes: the bounding sphere of the box, scaled by sqrt(2), keeps every box pair") {
    // (find_pairs grids boxes through bounding cubes now; this checks the sphere route directly.)
    // The per-axis box extents alone do not work (a thin box beside a wide one can overlap in a
    // cell home to neither); the circumscribed sphere does. Dense near-maximal boxes, cell 1.
    Rng rng(99);
    const double h_max = 1.0 / (1.25 * 2.0 * std::sqrt(2.0) * std::sqrt(3.0)) * 0.999;
    std::size_t pairs = 0;
    for (int scene = 0; scene < 1000; ++scene) {
        std::vector<Box> s = {Box{{0, 0, 0}, {0, 0, 0}}};
        for (int i = 0; i < 40; ++i) {
            s.push_back(box_at(rng.range(0.5, 3.0), rng.range(0.5, 3.0), rng.range(0.5, 3.0), h_max * rng.range(0.0, 1.0),
                               h_max * rng.range(0.0, 1.0), h_max * rng.range(0.0, 1.0)));
        }
        d::Executor ex(1);
        const auto bs = d::bounding_spheres(std::span<const Box>(s), ex);
        auto r = d::grid_find_pairs(d::Objects{s, {}}, bs, 1.0, ex, d::PlanKnobs{});
        REQUIRE(r.ok());
        CHECK(r.value().stats.huge_objects == 0);
        const std::vector<Pair> want = reference_pairs(s);
        pairs += want.size();
        CHECK(r.value().pairs == want);
    }
    CHECK(pairs > 1000);
}

namespace {

std::vector<Pair> cube_grid_pairs(const std::vector<Box>& s, double cell, const d::PlanKnobs& knobs, std::uint32_t* huge) {
    d::Executor ex(1);
    const auto bc = d::bounding_cubes(std::span<const Box>(s), ex);
    auto r = d::grid_find_pairs(d::Objects{s, {}}, bc, cell, ex, knobs);
    REQUIRE(r.ok());
    *huge = r.value().stats.huge_objects;
    return r.value().pairs;
}

// Dense near-maximal boxes for a cell of edge 1 under the cube rule (half the longest edge up to
// 1/4): equal cubes, thin slabs and needles, centres anchored so that cell boundaries are integers.
std::vector<Box> dense_boxes(Rng& rng) {
    const double h_max = 0.25 * 0.999;
    std::vector<Box> s = {Box{{0, 0, 0}, {0, 0, 0}}};
    for (int i = 0; i < 40; ++i) {
        double h[3];
        const auto kind = rng.below(3);
        for (double& x : h) x = kind == 0 ? h_max * rng.range(0.9, 1.0) : h_max * rng.range(0.0, 1.0);
        if (kind == 2) h[rng.below(3)] = h_max;  // at least one full-length edge
        s.push_back(box_at(rng.range(0.5, 3.0), rng.range(0.5, 3.0), rng.range(0.5, 3.0), h[0], h[1], h[2]));
    }
    return s;
}

}  // namespace

TEST_CASE("boxes through bounding cubes: coverage scale 2 and a cell of 1.0 x the scaled diameter keep every pair") {
    // The cube rule (docs/spatialhash.md, "Sizing: boxes"): of two overlapping boxes, the one with the
    // larger bounding cube covers the other's home cell when its cube is scaled by 2, and cell >= 4
    // rho_max keeps the duplicate-avoidance rule right. A scale of 1.5 loses pairs in the same scenes.
    Rng rng(7070);
    std::size_t pairs = 0, lost_cube = 0, lost_small_scale = 0;
    d::PlanKnobs small_scale = d::kCubeKnobs;
    small_scale.coverage_scale = 1.5;
    for (int scene = 0; scene < 1500; ++scene) {
        const std::vector<Box> s = dense_boxes(rng);
        const std::vector<Pair> want = reference_pairs(s);
        pairs += want.size();
        std::uint32_t huge = 0;
        const std::vector<Pair> got = cube_grid_pairs(s, 1.0, d::kCubeKnobs, &huge);
        CHECK(huge == 0);
        CHECK(std::includes(want.begin(), want.end(), got.begin(), got.end(),
                            [](const Pair& x, const Pair& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }));
        lost_cube += want.size() - got.size();
        const std::vector<Pair> got_small = cube_grid_pairs(s, 1.0, small_scale, &huge);
        CHECK(huge == 0);
        lost_small_scale += want.size() - got_small.size();
    }
    MESSAGE("reference pairs " << pairs << ", lost with cube scale 2: " << lost_cube << ", with 1.5: " << lost_small_scale);
    CHECK(pairs > 10000);
    CHECK(lost_cube == 0);
    CHECK(lost_small_scale > 0);
}

TEST_CASE("boxes through bounding cubes: a cube just over the cell goes to the huge list, nothing lost") {
    // Two equal cubes, half-edge 0.2501 (scaled diameter 1.0004 > cell 1): both are tested apart.
    const std::vector<Box> s = {Box{{0, 0, 0}, {0, 0, 0}}, box_at(0.9, 0.5, 0.5, 0.2501, 0.2501, 0.2501),
                                box_at(1.4, 0.5, 0.5, 0.2501, 0.2501, 0.2501)};
    REQUIRE(reference_pairs(s) == std::vector<Pair>{{1, 2}});
    std::uint32_t huge = 0;
    CHECK(cube_grid_pairs(s, 1.0, d::kCubeKnobs, &huge) == std::vector<Pair>{{1, 2}});
    CHECK(huge == 2);
    // Automatic: the cell is kCubeAutoCellFactor x 4 x the largest half-edge (padded).
    spatialhash::Options o;
    auto r = spatialhash::find_pairs(std::span<const Box>(s), o);
    REQUIRE(r.ok());
    CHECK(r.value().pairs == std::vector<Pair>{{1, 2}});
    CHECK(r.value().stats.cell_size == doctest::Approx(d::kCubeAutoCellFactor * 4.0 * 0.2501));
}
