// The ground-truth method against a brute-force twin (every triangle pair, no prefilter, naive
// O(V^2) welding), and its welding and determinism contracts.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <limits>
#include <thread>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh_io.h"
#include "cullide/tri_tri.h"
#include "brute_force_pairs.h"
#include "exact_stage.h"
#include "kept.h"
#include "parallel.h"
#include "test_rng.h"

using cullide::Mesh;
using cullide::TrianglePair;
using cullide::Vec3;

namespace {

// A soup of small random triangles in a box, some objects overlapping; coordinates on a coarse
// dyadic grid so that touching and coplanar contacts really happen.
std::vector<Mesh> random_scene(std::uint64_t seed, int objects, int triangles_per_object, bool shared_vertices) {
    test::Rng rng(seed);
    std::vector<Mesh> scene;
    for (int o = 0; o < objects; ++o) {
        Mesh m;
        m.name = "obj" + std::to_string(o);
        const Vec3 centre{rng.grid(0, 8, 8), rng.grid(0, 8, 8), rng.grid(0, 8, 8)};
        for (int t = 0; t < triangles_per_object; ++t) {
            const std::uint32_t base = static_cast<std::uint32_t>(m.positions.size());
            for (int k = 0; k < 3; ++k) {
                m.positions.push_back(centre + Vec3{rng.grid(-2, 2, 4), rng.grid(-2, 2, 4), rng.grid(-2, 2, 4)});
            }
            if (shared_vertices && t > 0) {
                // Reuse a vertex of the previous triangle (adjacency), or duplicate its position (a seam).
                if (rng.below(2) == 0) {
                    m.triangles.push_back({base - 1, base, base + 1});
                } else {
                    m.positions[base] = m.positions[base - 2];
                    m.triangles.push_back({base, base + 1, base + 2});
                }
            } else {
                m.triangles.push_back({base, base + 1, base + 2});
            }
        }
        scene.push_back(std::move(m));
    }
    return scene;
}

}  // namespace

TEST_CASE("ground truth equals the brute-force twin on 300 random scenes, with and without self pairs") {
    std::uint64_t total_pairs = 0, total_self_pairs = 0;
    for (std::uint64_t seed = 1; seed <= 300; ++seed) {
        CAPTURE(seed);
        const bool self = seed % 2 == 0;
        std::vector<Mesh> scene = random_scene(seed, 2 + static_cast<int>(seed % 5), 6 + static_cast<int>(seed % 13), self);
        auto pairs = cullide::exact_pairs(scene, {self, 1});
        REQUIRE(pairs.ok());
        const auto expected = test::brute_force_pairs(scene, self);
        CHECK(pairs.value() == expected);
        total_pairs += expected.size();
        for (const auto& p : expected) total_self_pairs += p.object_a == p.object_b;
    }
    // The families must really exercise both kinds of pairs, or the comparison proves little.
    CHECK(total_pairs > 1000);
    CHECK(total_self_pairs > 100);
}

TEST_CASE("self pairs skip triangles sharing a vertex or a welded (equal-coordinate) vertex") {
    Mesh m;
    m.name = "fan";
    // Two triangles sharing vertex 0, folded so that they also cross each other elsewhere.
    m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 1, -1}, {1, -1, 1}};
    m.triangles = {{0, 1, 2}, {0, 3, 4}};
    auto r = cullide::exact_pairs(std::vector<Mesh>{m}, {true, 1});
    REQUIRE(r.ok());
    CHECK(r.value().empty());

    // The same with vertex 0 duplicated (an unwelded seam): still adjacent.
    m.positions.push_back({0, 0, 0});
    m.triangles[1] = {5, 3, 4};
    r = cullide::exact_pairs(std::vector<Mesh>{m}, {true, 1});
    REQUIRE(r.ok());
    CHECK(r.value().empty());

    // Moved off the shared point, the crossing is a collision.
    m.positions[5] = {0.25, 0.25, 0.5};
    r = cullide::exact_pairs(std::vector<Mesh>{m}, {true, 1});
    REQUIRE(r.ok());
    REQUIRE(r.value().size() == 1);
    CHECK(r.value()[0] == TrianglePair{0, 0, 0, 1});
    // Without --self, one object has no pairs at all.
    r = cullide::exact_pairs(std::vector<Mesh>{m}, {false, 1});
    REQUIRE(r.ok());
    CHECK(r.value().empty());
}

TEST_CASE("welding treats -0.0 and 0.0 as one vertex and numbers ids by first appearance") {
    Mesh m;
    m.positions = {{1, 2, 3}, {0.0, 0, 0}, {1, 2, 3}, {-0.0, 0, 0}, {5, 5, 5}};
    const auto id = cullide::weld_vertices(m);
    CHECK(id == std::vector<std::uint32_t>{0, 1, 0, 1, 2});
}

TEST_CASE("welding equals its definition on random meshes full of repeats, signed zeros and NaN") {
    // The twin: a vertex's id is the id of the first earlier vertex whose position compares equal,
    // else the next one (quadratic, obviously right).
    const auto naive = [](const Mesh& m) {
        std::vector<std::uint32_t> id(m.positions.size());
        std::uint32_t next = 0;
        for (std::size_t v = 0; v < m.positions.size(); ++v) {
            std::size_t u = 0;
            while (u < v && !(m.positions[u] == m.positions[v])) ++u;
            id[v] = u < v ? id[u] : next++;
        }
        return id;
    };
    test::Rng rng(4242);
    std::size_t welded = 0;
    for (int round = 0; round < 60; ++round) {
        Mesh m;
        const std::size_t n = 1 + rng.below(round < 50 ? 400 : 3000);
        const double values[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, -1e300, 3.0};
        for (std::size_t v = 0; v < n; ++v) {
            if (v > 0 && rng.below(3) == 0) {  // a repeat of an earlier position, with a signed zero swapped
                Vec3 q = m.positions[rng.below(static_cast<std::uint32_t>(v))];
                if (q.y == 0.0 && rng.below(2) == 0) q.y = -q.y;
                m.positions.push_back(q);
            } else {
                m.positions.push_back({values[rng.below(8)], values[rng.below(8)], rng.uniform(-2, 2) * (rng.below(4) == 0 ? 0 : 1)});
            }
            if (round % 7 == 0 && rng.below(50) == 0) m.positions.back().z = std::numeric_limits<double>::quiet_NaN();
        }
        const auto got = cullide::weld_vertices(m);
        const auto want = naive(m);
        CAPTURE(round);
        CHECK(got == want);
        welded += n - (want.empty() ? 0 : *std::max_element(want.begin(), want.end()) + 1);
    }
    CHECK(welded > 1000);  // many vertices did weld
}

TEST_CASE("touching objects collide: a shared vertex between two objects is a pair") {
    Mesh a, b;
    a.name = "a";
    b.name = "b";
    a.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    a.triangles = {{0, 1, 2}};
    b.positions = {{1, 0, 0}, {2, 0, 1}, {2, 1, 0}};
    b.triangles = {{0, 1, 2}};
    auto r = cullide::exact_pairs(std::vector<Mesh>{a, b}, {});
    REQUIRE(r.ok());
    CHECK(r.value() == std::vector<TrianglePair>{{0, 0, 1, 0}});
    CHECK(cullide::object_pairs(r.value()) == std::vector<cullide::ObjectPair>{{0, 1}});
}

namespace {

// The exact stage's general set sweep with one set per triangle: the ground truth's path before
// sweep_exact_triangles, an independent prefilter on double boxes only.
cullide::detail::ExactStageResult set_sweep(const std::vector<Mesh>& scene, bool self,
                                            std::vector<std::vector<std::uint32_t>>& welded) {
    std::vector<cullide::detail::ExactObject> exact(scene.size());
    std::vector<cullide::detail::CandidateSet> sets;
    welded.assign(scene.size(), {});
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const auto object = static_cast<std::uint32_t>(i);
        for (std::size_t t = 0; t < scene[i].triangles.size(); ++t)
            sets.push_back({object, static_cast<std::uint32_t>(t), 1, cullide::triangle_bounds(scene[i], t)});
        if (self) welded[i] = cullide::weld_vertices(scene[i]);
        exact[i] = {&scene[i], object, cullide::mesh_bounds(scene[i]), {}, {}, welded[i]};
    }
    return cullide::detail::sweep_exact_stage(exact, sets, {self, false, 1});
}

// exact_pairs on `threads` threads against both twins: the set sweep (the pairs and every count)
// and brute force (the pairs). Returns the set sweep's result.
cullide::detail::ExactStageResult check_twins(const std::vector<Mesh>& scene, bool self, int threads) {
    cullide::ExactStats st;
    auto got = cullide::exact_pairs(scene, {self, threads}, &st);
    REQUIRE(got.ok());
    std::vector<std::vector<std::uint32_t>> welded;
    cullide::detail::ExactStageResult want = set_sweep(scene, self, welded);
    CHECK(got.value() == want.pairs);
    CHECK(got.value() == test::brute_force_pairs(scene, self));
    CHECK(st.candidate_triangles == want.stats.task_triangles);
    CHECK(st.box_pairs == want.stats.tests);
    CHECK(st.adjacent_skipped == want.stats.adjacent_skipped);
    return want;
}

}  // namespace

TEST_CASE("float_down and float_up give the nearest floats below and above, infinities beyond the range") {
    using cullide::detail::float_down;
    using cullide::detail::float_up;
    const auto check = [](double x) {
        CAPTURE(x);
        const float d = float_down(x), u = float_up(x);
        REQUIRE(static_cast<double>(d) <= x);
        REQUIRE(static_cast<double>(u) >= x);
        // Nearest: the next float beyond each is on the other side of x (or d, u are infinite).
        constexpr float kInf = std::numeric_limits<float>::infinity();
        if (!std::isinf(d)) REQUIRE(static_cast<double>(std::nextafter(d, kInf)) > x);
        if (!std::isinf(u)) REQUIRE(static_cast<double>(std::nextafter(u, -kInf)) < x);
        if (static_cast<double>(static_cast<float>(x)) == x) REQUIRE((d == u && d == static_cast<float>(x)));
    };
    const auto flt_max = static_cast<double>(std::numeric_limits<float>::max());
    for (double x : {0.0, -0.0, 1.0, -1.0, 0.1, -0.1, 1e-300, -1e-300, 1e-45, -1e-45, 1e300, -1e300, flt_max,
                     -flt_max, std::nextafter(flt_max, 1e300), -std::nextafter(flt_max, 1e300), 0x1p-149, 0x1.8p-149})
        check(x);
    CHECK(float_up(1e300) == std::numeric_limits<float>::infinity());
    CHECK(float_down(1e300) == std::numeric_limits<float>::max());
    CHECK(float_down(-1e300) == -std::numeric_limits<float>::infinity());
    CHECK(float_down(-1e-300) == -std::numeric_limits<float>::denorm_min());
    CHECK(float_up(1e-300) == std::numeric_limits<float>::denorm_min());
    test::Rng rng(11);
    for (int i = 0; i < 200000; ++i) {
        double x = std::bit_cast<double>(rng.next());
        if (std::isfinite(x)) check(x);
        check(std::ldexp(rng.sym(), static_cast<int>(rng.below(320)) - 160));
    }
}

// A box bound for the float-box tests: one of `edges` (range edges, subnormals, signed zeros), raw
// finite bits, or a value scaled 2^-160..2^160, a third of the time each.
template <std::size_t N>
double box_bound(test::Rng& rng, const double (&edges)[N]) {
    switch (rng.below(3)) {
        case 0: return edges[rng.below(N)];
        case 1: {
            const double x = std::bit_cast<double>(rng.next());
            return std::isfinite(x) ? x : 1.5;
        }
        default: return std::ldexp(rng.sym(), static_cast<int>(rng.below(320)) - 160);
    }
}

TEST_CASE("float_box(lo, hi) rounds every bound as float_down and float_up do, to the bit") {
    // The scan's box rounding (four bounds per SSE2 step on x86-64) against the scalar functions,
    // lane by lane: each bound of a box lands in a different lane, so a lane mix-up fails here.
    using cullide::detail::float_down;
    using cullide::detail::float_up;
    test::Rng rng(12);
    const auto flt_max = static_cast<double>(std::numeric_limits<float>::max());
    const double edges[] = {0.0, -0.0, 1e-300, -1e-300, 0x1p-149, -0x1.8p-149, flt_max, -flt_max,
                            std::nextafter(flt_max, 1e300), -std::nextafter(flt_max, 1e300), 1e300, -1e300, 0.1, -0.1};
    const auto draw = [&] { return box_bound(rng, edges); };
    std::uint64_t differ = 0;
    for (int i = 0; i < 300000; ++i) {
        const Vec3 lo{draw(), draw(), draw()}, hi{draw(), draw(), draw()};
        const cullide::detail::FloatBox f = cullide::detail::float_box(lo, hi);
        for (int k = 0; k < 3; ++k) {
            const float want_lo = float_down(lo[k]), want_hi = float_up(hi[k]);
            differ += std::bit_cast<std::uint32_t>(f.lo[k]) != std::bit_cast<std::uint32_t>(want_lo) ? 1 : 0;
            differ += std::bit_cast<std::uint32_t>(f.hi[k]) != std::bit_cast<std::uint32_t>(want_hi) ? 1 : 0;
        }
    }
    CHECK(differ == 0);
}

#if defined(__SSE2__)
TEST_CASE("float_box_round_down under a RoundDownScope gives float_box's bits, and the scope restores MXCSR") {
    // The scan converts with MXCSR rounding toward -infinity instead of float_down's correction: the
    // same bits for every finite double (the range edges, subnormals, signed zeros, beyond the float
    // range), whatever flush-to-zero or denormals-are-zero mode the caller runs in.
    using cullide::detail::float_down;
    using cullide::detail::float_up;
    test::Rng rng(13);
    const auto flt_max = static_cast<double>(std::numeric_limits<float>::max());
    const double edges[] = {0.0, -0.0, 1e-300, -1e-300, 0x1p-149, -0x1.8p-149, 0x1p-150, -0x1p-150, 1e-320, -1e-320,
                            flt_max, -flt_max, std::nextafter(flt_max, 1e300), -std::nextafter(flt_max, 1e300), 1e300,
                            -1e300, 0.1, -0.1, 1.0, -1.0};
    const auto draw = [&] { return box_bound(rng, edges); };
    // The boxes and float_down's bits first, in the caller's mode.
    std::vector<std::array<double, 6>> boxes(100000);
    std::vector<std::array<float, 6>> want(boxes.size());
    for (std::size_t i = 0; i < boxes.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const auto lo = static_cast<std::size_t>(k), hi = lo + 3;
            boxes[i][lo] = draw();
            boxes[i][hi] = draw();
            want[i][lo] = float_down(boxes[i][lo]);
            want[i][hi] = float_up(boxes[i][hi]);
        }
    const unsigned before = _mm_getcsr();
    std::uint64_t differ = 0;
    for (const unsigned caller : {before, before | 0x8040u}) {  // as is; with flush-to-zero and DAZ set
        _mm_setcsr(caller);
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            const std::array<double, 6>& b = boxes[i];
            cullide::detail::FloatBox f;
            {
                const cullide::detail::RoundDownScope scope;
                f = cullide::detail::float_box_round_down(_mm_set_pd(b[1], b[0]), _mm_set_sd(b[2]), _mm_set_pd(b[4], b[3]),
                                                          _mm_set_sd(b[5]));
            }
            for (std::size_t k = 0; k < 3; ++k) {
                differ += std::bit_cast<std::uint32_t>(f.lo[k]) != std::bit_cast<std::uint32_t>(want[i][k]) ? 1 : 0;
                differ += std::bit_cast<std::uint32_t>(f.hi[k]) != std::bit_cast<std::uint32_t>(want[i][k + 3]) ? 1 : 0;
            }
        }
        const unsigned after = _mm_getcsr();
        _mm_setcsr(before);
        CHECK(after == caller);  // restored whole
    }
    CHECK(differ == 0);
}
#endif

TEST_CASE("the triangle sweep gives the set sweep's pairs and counts where floats cannot hold the boxes") {
    // Coordinates a tiny step (2^-30, far below a float's spacing near 8) off the dyadic grid, so
    // that boxes a float cannot tell apart are disjoint or touching in doubles; and whole scenes
    // scaled beyond the float range (2^200) and below it (2^-200), where the float boxes are
    // infinite or zero-sized. The double boxes must decide every count.
    std::uint64_t pairs = 0, tests = 0;
    for (std::uint64_t seed = 1; seed <= 120; ++seed) {
        CAPTURE(seed);
        const bool self = seed % 2 == 0;
        std::vector<Mesh> scene = random_scene(seed + 1000, 2 + static_cast<int>(seed % 4), 20, self);
        test::Rng rng(seed);
        for (Mesh& m : scene)
            for (Vec3& p : m.positions)
                for (int k = 0; k < 3; ++k) p[k] += static_cast<double>(static_cast<int>(rng.below(3)) - 1) * 0x1p-30;
        const double scale = seed % 3 == 0 ? 0x1p200 : seed % 3 == 1 ? 0x1p-200 : 1.0;
        for (Mesh& m : scene)
            for (Vec3& p : m.positions)
                for (int k = 0; k < 3; ++k) p[k] *= scale;
        const cullide::detail::ExactStageResult want = check_twins(scene, self, 1 + static_cast<int>(seed % 3));
        pairs += want.pairs.size();
        tests += want.stats.tests;
    }
    CHECK(pairs > 500);
    CHECK(tests > 2 * pairs);
}

TEST_CASE("a big object in many pair tasks (walked in spatial order) gives the set sweep's pairs and counts") {
    // One object of 3,000 small triangles over the whole scene box and 12 small objects inside it:
    // the big one is in 12 pair tasks, so its gathers walk it in Morton order (exact_stage.cpp,
    // kSpatialMin / kSpatialTasks); the triangles come in a scrambled order, so its mesh-order blocks
    // are loose (loose_blocks: about 0.9 of the object's size, the rule's threshold is 0.4).
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
        CAPTURE(seed);
        std::vector<Mesh> scene = random_scene(seed + 2000, 13, 20, false);
        test::Rng rng(seed);
        Mesh& big = scene[0];
        big.positions.clear();
        big.triangles.clear();
        for (std::uint32_t t = 0; t < 3000; ++t) {
            const Vec3 c{rng.grid(-1, 9, 8), rng.grid(-1, 9, 8), rng.grid(-1, 9, 8)};
            for (int k = 0; k < 3; ++k)
                big.positions.push_back(c + Vec3{rng.grid(-0.5, 0.5, 8), rng.grid(-0.5, 0.5, 8), rng.grid(-0.5, 0.5, 8)});
            big.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
        }
        const cullide::detail::ExactStageResult want = check_twins(scene, false, 2);
        std::uint64_t with_big = 0;
        for (const TrianglePair& p : want.pairs) with_big += p.object_a == 0 ? 1 : 0;
        CHECK(with_big > 20);  // the big object really meets the others
    }
}

TEST_CASE("dense cells sorted once per slab by radix give the set sweep's pairs and counts") {
    // Triangles a quarter of the scene across, so the sweep grid's cells hold hundreds of refs each
    // and the slab's refs are radix-sorted before binning (exact_stage.cpp, sorted_refs). The lows
    // span signs, -0.0 and 0.0, magnitudes from 2^-20 to 2^10 and many exact ties, so every byte of
    // the ordered float key and the sign flip matter; with self pairs too (adjacency first).
    std::uint64_t pairs = 0;
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
        CAPTURE(seed);
        const bool self = seed % 2 == 0;
        test::Rng rng(seed + 3000);
        std::vector<Mesh> scene(2);
        const double scale = seed % 3 == 0 ? 0x1p-20 : seed % 3 == 1 ? 1.0 : 0x1p10;
        for (Mesh& m : scene) {
            for (std::uint32_t t = 0; t < 700; ++t) {
                // Half on a coarse grid (ties, zero low bytes), half anywhere (every byte varies).
                const bool on_grid = rng.coin();
                const auto coord = [&](double lo, double hi) { return on_grid ? rng.grid(lo, hi, 8) : rng.uniform(lo, hi); };
                const Vec3 c{coord(-4, 4), coord(-4, 4), coord(-4, 4)};
                for (int k = 0; k < 3; ++k) {
                    Vec3 p = c + Vec3{coord(-1, 1), coord(-1, 1), coord(-1, 1)};
                    for (int a = 0; a < 3; ++a) p[a] = p[a] == 0.0 && rng.coin() ? -0.0 : p[a] * scale;
                    m.positions.push_back(p);
                }
                if (self && t > 0 && rng.below(2) == 0)
                    m.triangles.push_back({3 * t - 1, 3 * t, 3 * t + 1});  // shares a vertex with the previous
                else
                    m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
            }
        }
        const cullide::detail::ExactStageResult want = check_twins(scene, self, 2);
        pairs += want.pairs.size();
    }
    CHECK(pairs > 1000);
    // Slivers whose lows along x differ only in the float key's low bytes (x = 1 + k 2^-23, floats
    // apart, k < 512), all spanning the same y and z: the cells hold them all, and a wrong order
    // among nearly equal lows stops a scan before a box it should meet.
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
        CAPTURE(seed);
        const bool self = seed % 2 == 0;
        test::Rng rng(seed + 4000);
        std::vector<Mesh> scene(2);
        const auto x_at = [&] { return 1.0 + static_cast<double>(rng.below(512)) * 0x1p-23; };
        for (Mesh& m : scene) {
            for (std::uint32_t t = 0; t < 200; ++t) {
                m.positions.push_back({x_at(), 0.0, 0.0});
                m.positions.push_back({x_at(), 1.0, 0.0});
                m.positions.push_back({x_at(), 0.5, 1.0});
                m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
            }
            // Anchors at x = 0 and x = 2 make x the longest extent of the pair's common box, so the
            // sweep runs along x (plan_task).
            for (const double x : {0.0, 2.0}) {
                const auto b = static_cast<std::uint32_t>(m.positions.size());
                m.positions.push_back({x, 0.0, 0.0});
                m.positions.push_back({x, 1.0, 0.0});
                m.positions.push_back({x, 0.5, 1.0});
                m.triangles.push_back({b, b + 1, b + 2});
            }
        }
        (void)check_twins(scene, self, 2);
    }
}

TEST_CASE("one big pair task, made in chunks on several workers, gives the serial task's pairs and counts") {
    // Two soups of 12,000 small triangles each over one box, in sets of 4 scattered triangles (so
    // every set is loose and make_task sweeps its triangles): one pair task, fewer tasks than
    // workers, so make_task expands the 6,000 sets in chunks of kSetChunk and bin_task bins the
    // ~24,000 triangles in chunks of kBinChunk refs (session 12: the serial make_task was a fifth of
    // an R-CULLIDE bunny-dragon frame at 2 threads). Every thread count (and so chunk count) must
    // give the 1-thread pairs and counts, and the pairs must be the ground truth's (its own sweep).
    test::Rng rng(77);
    std::vector<Mesh> scene(2);
    std::vector<std::vector<cullide::Aabb>> boxes(2);
    for (std::uint32_t o = 0; o < 2; ++o) {
        Mesh& m = scene[o];
        m.name = "soup" + std::to_string(o);
        for (std::uint32_t t = 0; t < 12000; ++t) {
            const Vec3 c{rng.grid(0, 10, 64), rng.grid(0, 10, 64), rng.grid(0, 10, 64)};
            for (int k = 0; k < 3; ++k)
                m.positions.push_back(c + Vec3{rng.grid(-0.15, 0.15, 64), rng.grid(-0.15, 0.15, 64), rng.grid(-0.15, 0.15, 64)});
            m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
            boxes[o].push_back(cullide::triangle_bounds(m, t));
        }
    }
    std::vector<cullide::detail::ExactObject> exact(2);
    std::vector<cullide::detail::CandidateSet> sets;
    for (std::uint32_t o = 0; o < 2; ++o) {
        exact[o] = {&scene[o], o, cullide::mesh_bounds(scene[o]), boxes[o], {}, {}};
        for (std::uint32_t first = 0; first < 12000; first += 4) {
            cullide::Aabb b = boxes[o][first];
            for (std::uint32_t t = first + 1; t < first + 4; ++t)
                for (int k = 0; k < 3; ++k) {
                    b.lo[k] = std::min(b.lo[k], boxes[o][t].lo[k]);
                    b.hi[k] = std::max(b.hi[k], boxes[o][t].hi[k]);
                }
            sets.push_back({o, first, 4, b});
        }
    }
    const cullide::detail::ExactStageResult one = cullide::detail::sweep_exact_stage(exact, sets, {false, true, 1});
    CHECK(one.stats.task_triangles == 24000);  // every set meets the common box
    CHECK(one.stats.tests > 2000);
    CHECK(one.pairs.size() > 100);
    const auto truth = cullide::exact_pairs(scene, {false, 2});
    REQUIRE(truth.ok());
    CHECK(one.pairs == truth.value());
    for (int threads : {2, 3, 8}) {
        CAPTURE(threads);
        const cullide::detail::ExactStageResult r = cullide::detail::sweep_exact_stage(exact, sets, {false, true, threads});
        CHECK(r.pairs == one.pairs);
        CHECK(r.stats.tests == one.stats.tests);
        CHECK(r.stats.set_pairs == one.stats.set_pairs);
        CHECK(r.stats.task_triangles == one.stats.task_triangles);
        CHECK(r.stats.adjacent_skipped == one.stats.adjacent_skipped);
    }
}

namespace {

// The overlapping pairs of a brute-force double loop, sorted (what overlapping_sets must return).
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_overlaps(const std::vector<cullide::detail::SweepRef>& refs) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> want;
    for (std::size_t i = 0; i < refs.size(); ++i)
        for (std::size_t j = i + 1; j < refs.size(); ++j)
            if (cullide::overlaps(refs[i].box, refs[j].box))
                want.emplace_back(std::min(refs[i].set, refs[j].set), std::max(refs[i].set, refs[j].set));
    std::sort(want.begin(), want.end());
    return want;
}

// overlapping_sets on `refs` against `want` for 1 to 3 threads, without a filter and with one (the
// kept pairs in the same order, and the count of all overlaps).
void check_overlapping_sets(const std::vector<cullide::detail::SweepRef>& refs,
                            const std::vector<std::pair<std::uint32_t, std::uint32_t>>& want) {
    for (const int threads : {1, 2, 3}) {
        CAPTURE(threads);
        CHECK(cullide::detail::overlapping_sets(refs, threads) == want);
        std::uint64_t overlapping = 0;
        const auto odd = cullide::detail::overlapping_sets(
            refs, threads, [](std::uint32_t a, std::uint32_t b) { return (a + b) % 2 == 1; }, overlapping);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> want_odd;
        for (const auto& p : want)
            if ((p.first + p.second) % 2 == 1) want_odd.push_back(p);
        CHECK(odd == want_odd);
        CHECK(overlapping == want.size());
    }
}

}  // namespace

TEST_CASE("overlapping_sets gives the sorted multiset of overlapping set pairs of a brute-force double loop") {
    test::Rng rng(777);
    std::size_t total_pairs = 0;
    for (const std::size_t n : {std::size_t{1}, std::size_t{40}, std::size_t{3000}, std::size_t{9000}}) {  // 1 to 5 sweep chunks
        std::vector<cullide::detail::SweepRef> refs(n);
        for (std::size_t i = 0; i < n; ++i) {
            const double x = rng.uniform(0, 60), y = rng.uniform(0, 3), z = rng.uniform(0, 3);
            const double e = rng.uniform(0.05, 0.6);
            refs[i].box = {{x, y, z}, {x + e, y + e, z + e}};
            refs[i].object = static_cast<std::uint32_t>(rng.below(4));
            refs[i].set = static_cast<std::uint32_t>(rng.below(n / 2 + 1));  // sets of several parts: repeated pairs
            refs[i].part = static_cast<std::uint32_t>(i);
        }
        const auto want = brute_overlaps(refs);
        CAPTURE(n);
        check_overlapping_sets(refs, want);
        total_pairs += want.size();
    }
    CHECK(total_pairs > 10000);
}

TEST_CASE("overlapping_sets' grid gives the brute-force pairs on boxes spread in every axis") {
    // Above the grid's threshold (1,024 refs): thin boxes on a torus-like ring (the case the grid is
    // for), boxes on a lattice that touch face to face (a touching pair is an overlap: the low
    // corner of their common part lies on a cell border), flat boxes, repeated boxes, and a few
    // boxes over everything (many cells each: at enough of them the plain sweep takes over).
    test::Rng rng(4242);
    std::size_t total_pairs = 0;
    for (int shape = 0; shape < 5; ++shape) {
        std::vector<cullide::detail::SweepRef> refs;
        const auto add = [&](cullide::Vec3 lo, cullide::Vec3 hi) {
            cullide::detail::SweepRef r;
            r.box = {lo, hi};
            r.set = static_cast<std::uint32_t>(refs.size() % 1500);  // repeated sets: repeated pairs
            r.part = static_cast<std::uint32_t>(refs.size());
            refs.push_back(r);
        };
        if (shape == 0 || shape == 4) {  // a ring of thin boxes in the x-y plane
            for (int i = 0; i < 3000; ++i) {
                const double a = rng.uniform(0, 6.283185307179586), r = 10.0 + rng.uniform(-1, 1);
                const cullide::Vec3 c{r * std::cos(a), r * std::sin(a), rng.uniform(-1, 1)};
                const cullide::Vec3 e{rng.uniform(0, 0.3), rng.uniform(0, 0.3), rng.uniform(0, 0.3)};
                add(c, c + e);
            }
        } else if (shape == 1) {  // a lattice of unit boxes touching their neighbours
            for (int x = 0; x < 12; ++x)
                for (int y = 0; y < 12; ++y)
                    for (int z = 0; z < 12; ++z) add({double(x), double(y), double(z)}, {x + 1.0, y + 1.0, z + 1.0});
        } else if (shape == 2) {  // flat boxes (no extent along one or two axes) and repeated boxes
            for (int i = 0; i < 2000; ++i) {
                const cullide::Vec3 c{rng.grid(0, 8, 4), rng.grid(0, 8, 4), rng.grid(0, 8, 4)};
                const cullide::Vec3 e{rng.coin() ? 0.0 : 0.25, rng.coin() ? 0.0 : 0.25, 0.0};
                add(c, c + e);
                if (i % 7 == 0) add(c, c + e);
            }
        } else {  // shape 3: small boxes and a few that cover everything
            for (int i = 0; i < 2500; ++i) {
                const cullide::Vec3 c{rng.uniform(0, 20), rng.uniform(0, 20), rng.uniform(0, 20)};
                add(c, c + cullide::Vec3{0.2, 0.2, 0.2});
            }
            for (int i = 0; i < 3; ++i) add({-1, -1, -1}, {21, 21, 21});
        }
        if (shape == 4)  // enough boxes over everything for the plain sweep to take over
            for (int i = 0; i < 40; ++i) add({-12, -12, -2}, {12, 12, 2});
        const auto want = brute_overlaps(refs);
        CAPTURE(shape);
        check_overlapping_sets(refs, want);
        total_pairs += want.size();
    }
    CHECK(total_pairs > 20000);
}

namespace {

// `objects` soups of `triangles` small triangles each over one box (many overlapping, few pairs).
std::vector<Mesh> soups(std::uint64_t seed, std::uint32_t objects, std::uint32_t triangles) {
    test::Rng rng(seed);
    std::vector<Mesh> scene(objects);
    for (Mesh& m : scene) {
        for (std::uint32_t t = 0; t < triangles; ++t) {
            const Vec3 c{rng.grid(0, 10, 64), rng.grid(0, 10, 64), rng.grid(0, 10, 64)};
            for (int k = 0; k < 3; ++k)
                m.positions.push_back(c + Vec3{rng.grid(-0.15, 0.15, 64), rng.grid(-0.15, 0.15, 64), rng.grid(-0.15, 0.15, 64)});
            m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
        }
    }
    return scene;
}

}  // namespace

TEST_CASE("Kept storage: one user per thread and tag, a nested user gets its own, the capacity stays") {
    struct TagA;
    struct TagB;
    using cullide::detail::Kept;
    std::vector<int>* first = nullptr;
    {
        const Kept<std::vector<int>, TagA> a;
        first = &*a;
        a->assign(1000, 7);
        const Kept<std::vector<int>, TagA> nested;  // the same tag while `a` is held: its own
        CHECK(&*nested != first);
        CHECK(nested->empty());
        const Kept<std::vector<int>, TagB> other;  // another tag: its own slot
        CHECK(&*other != first);
    }
    const Kept<std::vector<int>, TagA> again;  // released: the slot again, its capacity kept
    CHECK(&*again == first);
    CHECK(again->capacity() >= 1000);
    std::vector<int>* on_other_thread = nullptr;
    std::thread([&] {
        const Kept<std::vector<int>, TagA> t;
        on_other_thread = &*t;
    }).join();
    CHECK(on_other_thread != first);

    cullide::detail::KeptBytes bytes;
    std::byte* p = bytes.reserve(100);
    REQUIRE(p != nullptr);
    CHECK(bytes.reserve(100) == p);  // no growth: the same buffer
    CHECK(bytes.reserve(10) == p);
    std::byte* q = bytes.reserve(101);  // grows by at least a quarter
    REQUIRE(q != nullptr);
    CHECK(bytes.reserve(125) == q);
    CHECK(reinterpret_cast<std::uintptr_t>(q) % alignof(std::max_align_t) == 0);
}

TEST_CASE("exact_pairs called from parallel tasks gives every call its serial answer") {
    // exact_pairs keeps its largest buffers per calling thread (kept.h): calls running at once on
    // two threads must each get their own. (A call nested inside another on one thread, which oneTBB
    // may do while a thread waits, is not forced here; the Kept test above covers that case.)
    // Scenes of different sizes, so that a shared buffer would be too small or hold another scene's
    // boxes; the two soups of 12,000 make a pair task big enough to be cut into slabs.
    std::vector<std::vector<Mesh>> scenes = {soups(5, 2, 12000), soups(6, 3, 2000), random_scene(7, 30, 40, true),
                                             soups(8, 1, 9000), random_scene(9, 6, 15, false)};
    std::vector<std::vector<TrianglePair>> serial;
    std::uint64_t total = 0;
    for (std::size_t k = 0; k < scenes.size(); ++k) {
        auto r = cullide::exact_pairs(scenes[k], {k % 2 == 0, 1});
        REQUIRE(r.ok());
        serial.push_back(r.value());
        total += r.value().size();
    }
    CHECK(total > 500);
    constexpr std::size_t kCalls = 20;
    std::vector<std::vector<TrianglePair>> got(kCalls);
    std::vector<char> ok(kCalls, 0);
    cullide::detail::parallel_chunks(2, kCalls, [&](std::size_t c) {
        const std::size_t k = (c * 3) % scenes.size();
        auto r = cullide::exact_pairs(scenes[k], {k % 2 == 0, 2});
        if (!r.ok()) return;
        ok[c] = 1;
        got[c] = r.value();
    });
    for (std::size_t c = 0; c < kCalls; ++c) {
        CAPTURE(c);
        REQUIRE(ok[c] == 1);
        CHECK(got[c] == serial[(c * 3) % scenes.size()]);
    }
}

TEST_CASE("the result is the same for 1, 2, 3 and 8 threads") {
    std::vector<Mesh> scene = random_scene(77, 40, 120, true);
    cullide::ExactStats s1;
    auto one = cullide::exact_pairs(scene, {true, 1}, &s1);
    REQUIRE(one.ok());
    CHECK(one.value().size() > 100);
    for (int threads : {2, 3, 8}) {
        CAPTURE(threads);
        cullide::ExactStats s;
        auto r = cullide::exact_pairs(scene, {true, threads}, &s);
        REQUIRE(r.ok());
        CHECK(r.value() == one.value());
        CHECK(s.box_pairs == s1.box_pairs);
        CHECK(s.adjacent_skipped == s1.adjacent_skipped);
    }
}

TEST_CASE("invalid meshes are refused with the object, element and limit named") {
    std::vector<Mesh> scene = random_scene(5, 2, 3, false);
    scene[1].triangles[2] = {0, 1, 99};
    auto r = cullide::exact_pairs(scene, {});
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "object 1: mesh 'obj1': triangle 2 vertex index 99 is beyond the vertex list (size 9)");
}

TEST_CASE("coordinates outside the exact predicates' range are refused, not guessed") {
    std::vector<Mesh> scene = random_scene(6, 2, 3, false);
    scene[0].positions[4].y = 1e-310;  // subnormal: products of three would lose bits
    auto r = cullide::exact_pairs(scene, {});
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message ==
          "object 0: mesh 'obj0': vertex 4 coordinate y = 9.9999999999999694e-311 is outside the exact range (0, or "
          "2^-300 <= |x| <= 2^300)");
    scene[0].positions[4].y = 0x1p301;
    CHECK_FALSE(cullide::exact_pairs(scene, {}).ok());
    scene[0].positions[4].y = 0x1p300;  // the limit itself is inside
    CHECK(cullide::exact_pairs(scene, {}).ok());
}

TEST_CASE("the teapot's self-intersections are found and none of its seam contacts") {
    const std::filesystem::path path = std::filesystem::path(CULLIDE_SHARED_MESH_DIR) / "teapot.obj";
    if (!std::filesystem::exists(path)) {
        MESSAGE("skipped: " << path.string() << " is absent");
        return;
    }
    auto meshes = cullide::read_mesh_file(path.string());
    REQUIRE(meshes.ok());
    REQUIRE(meshes.value().size() == 1);
    const Mesh& teapot = meshes.value()[0];
    std::vector<Mesh> scene{teapot};
    auto r = cullide::exact_pairs(scene, {true, 1});
    REQUIRE(r.ok());
    const auto& pairs = r.value();
    MESSAGE("teapot self pairs: " << pairs.size());
    CHECK(pairs.size() > 0);  // spout and handle pass into the body

    // No reported pair shares a position (checked naively, independently of weld_vertices).
    for (const auto& p : pairs) {
        const auto& ta = teapot.triangles[p.triangle_a];
        const auto& tb = teapot.triangles[p.triangle_b];
        for (auto u : ta)
            for (auto v : tb) REQUIRE_FALSE(teapot.positions[u] == teapot.positions[v]);
    }
    // Seams are real: pairs that share a position but no index touch there, and welding by index
    // alone would report each of them. Counted naively, independently of weld_vertices.
    std::uint64_t seam_contacts = 0;
    for (std::uint32_t i = 0; i < teapot.triangles.size(); ++i) {
        for (std::uint32_t j = i + 1; j < teapot.triangles.size(); ++j) {
            const auto& ta = teapot.triangles[i];
            const auto& tb = teapot.triangles[j];
            bool share_index = false, share_position = false;
            for (auto u : ta)
                for (auto v : tb) {
                    share_index = share_index || u == v;
                    share_position = share_position || teapot.positions[u] == teapot.positions[v];
                }
            seam_contacts += share_position && !share_index;
        }
    }
    MESSAGE("teapot triangle pairs touching at a seam (shared position, no shared index): " << seam_contacts);
    CHECK(seam_contacts > 100);

    for (int threads : {2, 3}) {
        auto again = cullide::exact_pairs(scene, {true, threads});
        REQUIRE(again.ok());
        CHECK(again.value() == pairs);
    }
}
