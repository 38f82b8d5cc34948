// Each stage of the grid pipeline on its own, against a direct computation written here.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <set>
#include <thread>
#include <tuple>
#include <vector>

#include "scene_gen.h"
#include "spatialhash/detail/grid_stages.h"

using namespace sh_test;
namespace d = spatialhash::detail;

namespace {

std::vector<d::BoundingSphere> spheres_of(const std::vector<Sphere>& s) {
    d::Executor ex(1);
    return d::bounding_spheres(std::span<const Sphere>(s), ex);
}

}  // namespace

TEST_CASE("The executor's spread schedule runs every item once, lanes other than 0 on threads of their own") {
    const std::thread::id caller = std::this_thread::get_id();
    for (unsigned threads : {1U, 2U, 3U, 8U}) {
        for (std::size_t n :
             {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{9}, std::size_t{500}}) {
            CAPTURE(threads);
            CAPTURE(n);
            const SpreadScope spread(true);
            d::Executor ex(threads);
            std::vector<std::atomic<int>> calls(n);
            for (auto& c : calls) c.store(0);
            std::vector<std::thread::id> ran_on(n);
            ex.for_each(n, [&](std::size_t i) {
                calls[i].fetch_add(1);
                ran_on[i] = std::this_thread::get_id();
            });
            const std::size_t k = ex.concurrency() > 1 ? std::min<std::size_t>({ex.concurrency(), n, 4}) : 1;
            for (std::size_t i = 0; i < n; ++i) {
                CAPTURE(i);
                CHECK(calls[i].load() == 1);
                if (k <= 1 || i % k == 0) CHECK(ran_on[i] == caller);
                else CHECK(ran_on[i] != caller);
            }
        }
    }
}

TEST_CASE("radix sort is stable and equals std::stable_sort on the low key bits") {
    Rng rng(11);
    for (const ThreadRun run : kThreadRuns) {
        const unsigned threads = run.threads;
        const SpreadScope spread(run.spread);
        d::Executor ex(threads);
        for (int round = 0; round < 6; ++round) {
            const std::size_t n = round == 0 ? 0 : (round == 1 ? 1 : 1000 + rng.below(70000));
            const unsigned key_bits = 1 + rng.below(64);
            std::vector<std::uint64_t> keys(n);
            std::vector<std::uint32_t> values(n);
            for (std::size_t i = 0; i < n; ++i) {
                // Few distinct keys, so that stability matters; only the low key_bits bits set.
                const std::uint64_t mask = key_bits == 64 ? ~0ULL : ((1ULL << key_bits) - 1);
                keys[i] = (rng.next() % 97) * 0x9E3779B97F4A7C15ULL & mask;
                values[i] = static_cast<std::uint32_t>(i);
            }
            std::vector<std::size_t> idx(n);
            for (std::size_t i = 0; i < n; ++i) idx[i] = i;
            std::stable_sort(idx.begin(), idx.end(), [&](std::size_t x, std::size_t y) { return keys[x] < keys[y]; });
            std::vector<std::uint64_t> want_keys(n);
            std::vector<std::uint32_t> want_values(n);
            for (std::size_t i = 0; i < n; ++i) {
                want_keys[i] = keys[idx[i]];
                want_values[i] = values[idx[i]];
            }
            d::radix_sort(keys, values, key_bits, ex);
            CAPTURE(threads);
            CAPTURE(run.spread);
            CAPTURE(n);
            CAPTURE(key_bits);
            CHECK(keys == want_keys);
            CHECK(values == want_values);
        }
    }
}

TEST_CASE("cell-ID array: home in slot 0, phantoms next, sentinels last, control bits match the cells") {
    Rng rng(5);
    std::vector<Sphere> s;
    for (int i = 0; i < 400; ++i) s.push_back(Sphere{{rng.range(0, 6), rng.range(0, 6), rng.range(0, 6)}, rng.range(0, 0.2)});
    const auto bs = spheres_of(s);
    d::Executor ex(2);
    auto planned = d::plan_grid(bs, 1.0, ex);
    REQUIRE(planned.ok());
    const d::GridPlan& plan = planned.value();
    CHECK(plan.huge_ids.empty());
    const d::CellIdArray ids = d::build_cell_ids(bs, plan, ex);
    const std::size_t n = s.size();
    REQUIRE(ids.cell_ids.size() == 8 * n);
    for (std::size_t i = 0; i < n; ++i) {
        CAPTURE(i);
        // Direct computation: the cells that the scaled sphere's box touches, by brute enumeration
        // of the 3x3x3 block around the home cell.
        long home[3];
        for (int k = 0; k < 3; ++k) home[k] = static_cast<long>(std::floor((bs[i].centre[k] - plan.origin[k]) / plan.cell_size));
        const double rho = plan.coverage_scale * bs[i].radius;
        std::set<std::uint64_t> want;
        unsigned want_mask = 0;
        for (long dx = -1; dx <= 1; ++dx) {
            for (long dy = -1; dy <= 1; ++dy) {
                for (long dz = -1; dz <= 1; ++dz) {
                    const long c[3] = {home[0] + dx, home[1] + dy, home[2] + dz};
                    bool touches = true;
                    for (int k = 0; k < 3; ++k) {
                        const double clo = plan.origin[k] + static_cast<double>(c[k]) * plan.cell_size;
                        const double chi = plan.origin[k] + static_cast<double>(c[k] + 1) * plan.cell_size;
                        // The coverage interval [x - rho, x + rho] meets the half-open cell [clo, chi).
                        if (!(bs[i].centre[k] + rho >= clo && bs[i].centre[k] - rho < chi)) touches = false;
                    }
                    if (!touches) continue;
                    want.insert(d::cell_key(static_cast<std::uint64_t>(c[0]), static_cast<std::uint64_t>(c[1]),
                                            static_cast<std::uint64_t>(c[2]), plan.axis_bits));
                    want_mask |= 1U << ((c[0] & 1) | ((c[1] & 1) << 1) | ((c[2] & 1) << 2));
                }
            }
        }
        const std::uint64_t home_key = d::cell_key(static_cast<std::uint64_t>(home[0]), static_cast<std::uint64_t>(home[1]),
                                                   static_cast<std::uint64_t>(home[2]), plan.axis_bits);
        CHECK(ids.cell_ids[i] == home_key);
        CHECK_FALSE(d::entry_is_phantom(ids.objects[i]));
        CHECK(d::entry_object(ids.objects[i]) == i);
        std::set<std::uint64_t> got;
        bool sentinel_seen = false;
        for (int slot = 0; slot < 8; ++slot) {
            const std::uint64_t key = ids.cell_ids[static_cast<std::size_t>(slot) * n + i];
            CHECK(d::entry_object(ids.objects[static_cast<std::size_t>(slot) * n + i]) == i);
            CHECK(d::entry_is_phantom(ids.objects[static_cast<std::size_t>(slot) * n + i]) == (slot != 0));
            if (key == plan.sentinel) {
                sentinel_seen = true;
                continue;
            }
            CHECK_FALSE(sentinel_seen);  // sentinels only after the used slots
            got.insert(key);
        }
        CHECK(got == want);
        CHECK(d::home_type(ids.control[i]) == d::cell_type_of_key(home_key, plan.axis_bits));
        CHECK(d::type_mask(ids.control[i]) == want_mask);
    }
}

TEST_CASE("the collision cell list holds exactly the cells with a home occupant and two or more in all") {
    Rng rng(9);
    std::vector<Sphere> s;
    for (int i = 0; i < 3000; ++i) s.push_back(Sphere{{rng.range(0, 10), rng.range(0, 10), rng.range(0, 10)}, rng.range(0, 0.15)});
    const auto bs = spheres_of(s);
    d::Executor ex(3);
    auto planned = d::plan_grid(bs, 0.0, ex);
    REQUIRE(planned.ok());
    d::CellIdArray ids = d::build_cell_ids(bs, planned.value(), ex);
    // Reference grouping by a map over the unsorted arrays.
    std::map<std::uint64_t, std::pair<std::uint32_t, std::uint32_t>> occupancy;  // key -> (H, P)
    std::size_t entries = 0;
    for (std::size_t e = 0; e < ids.cell_ids.size(); ++e) {
        if (ids.cell_ids[e] == planned.value().sentinel) continue;
        ++entries;
        auto& o = occupancy[ids.cell_ids[e]];
        (d::entry_is_phantom(ids.objects[e]) ? o.second : o.first) += 1;
    }
    d::radix_sort(ids.cell_ids, ids.objects, planned.value().key_bits, ex);
    const d::CollisionCells cells = d::build_collision_cells(ids.cell_ids, ids.objects, planned.value(), ex);
    CHECK(cells.entries == entries);
    std::vector<std::tuple<std::uint64_t, std::uint32_t, std::uint32_t>> want, got;
    for (const auto& [key, hp] : occupancy) {
        if (hp.first >= 1 && hp.first + hp.second >= 2) want.emplace_back(key, hp.first, hp.second);
    }
    for (const d::CollisionCell& c : cells.cells) {
        got.emplace_back(ids.cell_ids[c.start], c.homes, c.phantoms);
        CHECK(c.type == d::cell_type_of_key(ids.cell_ids[c.start], planned.value().axis_bits));
        // H entries first, then P entries, all of this cell.
        for (std::uint32_t e = c.start; e < c.start + c.homes + c.phantoms; ++e) {
            CHECK(ids.cell_ids[e] == ids.cell_ids[c.start]);
            CHECK(d::entry_is_phantom(ids.objects[e]) == (e >= c.start + c.homes));
        }
    }
    CHECK(got == want);
    CHECK(want.size() > 100);
}

TEST_CASE("the duplicate-avoidance rule skips a pair only for an earlier home type both objects overlap") {
    const auto control = [](unsigned home, unsigned mask) { return static_cast<std::uint16_t>(home | (mask << 3)); };
    // a at home type 0 overlapping types {0,1}; b at home type 1 overlapping {1, 0}: in pass 1 the
    // pair was already tested in pass 0 at a's home.
    CHECK(d::tested_in_earlier_pass(control(0, 0b11), control(1, 0b11), 1));
    // ... but not in pass 0 itself.
    CHECK_FALSE(d::tested_in_earlier_pass(control(0, 0b11), control(1, 0b11), 0));
    // b does not overlap any cell of type 0: nothing was tested earlier.
    CHECK_FALSE(d::tested_in_earlier_pass(control(0, 0b11), control(1, 0b10), 1));
    // The rule applies to either object.
    CHECK(d::tested_in_earlier_pass(control(5, 0xFF), control(2, 0b100100), 5));
    CHECK_FALSE(d::tested_in_earlier_pass(control(5, 0xFF), control(6, 0b1100000), 5));
}

TEST_CASE("the passes report each overlapping pair once, before the final sort") {
    Rng rng(21);
    for (int round = 0; round < 20; ++round) {
        std::vector<Sphere> s;
        for (int i = 0; i < 500; ++i) s.push_back(Sphere{{rng.range(0, 4), rng.range(0, 4), rng.range(0, 4)}, rng.range(0.01, 0.3)});
        const auto bs = spheres_of(s);
        d::Executor ex(2);
        auto planned = d::plan_grid(bs, 0.0, ex);
        REQUIRE(planned.ok());
        d::CellIdArray ids = d::build_cell_ids(bs, planned.value(), ex);
        d::radix_sort(ids.cell_ids, ids.objects, planned.value().key_bits, ex);
        const d::CollisionCells cells = d::build_collision_cells(ids.cell_ids, ids.objects, planned.value(), ex);
        const d::Objects objects{{}, s};
        std::vector<Pair> raw = d::collide_cells(cells, ids.objects, ids.control, objects, d::filter_boxes(objects, bs, ex), ex);
        for (const Pair& p : raw) CHECK(p.a < p.b);
        std::vector<Pair> sorted = raw;
        d::sort_pairs(sorted, s.size(), ex);
        CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());  // no duplicate
        CHECK(sorted == reference_pairs(s));
    }
}

TEST_CASE("huge objects are tested apart against everything, each pair once") {
    Rng rng(31);
    std::vector<Box> s;
    for (int i = 0; i < 3000; ++i) s.push_back(box_at(rng.range(0, 50), rng.range(0, 50), rng.range(0, 50), 0.2, 0.2, 0.2));
    s[17] = box_at(25, 25, 25, 30, 2, 2);    // two giants that cross each other
    s[2500] = box_at(25, 25, 25, 2, 30, 2);
    d::Executor ex(2);
    const auto bs = d::bounding_spheres(std::span<const Box>(s), ex);
    auto planned = d::plan_grid(bs, 0.0, ex);
    REQUIRE(planned.ok());
    const d::GridPlan& plan = planned.value();
    CHECK(plan.huge_ids == std::vector<std::uint32_t>{17, 2500});
    // The cell follows the small objects (scaled diameter 2 sqrt2 x 0.2 sqrt3, x 1.5), not the giants.
    CHECK(plan.cell_size < 2.0);
    const d::Objects objects{s, {}};
    std::vector<Pair> got = d::collide_huge(plan.huge_ids, plan.huge, objects, ex);
    d::sort_pairs(got, s.size(), ex);
    std::vector<Pair> want;
    for (const Pair& p : reference_pairs(s)) {
        if (p.a == 17 || p.b == 17 || p.a == 2500 || p.b == 2500) want.push_back(p);
    }
    CHECK(got == want);
    CHECK(std::find(want.begin(), want.end(), Pair{17, 2500}) != want.end());
}

TEST_CASE("automatic cell size is 1.5 times the largest scaled diameter when there are no outliers") {
    std::vector<Sphere> s = {Sphere{{0, 0, 0}, 0.5}, Sphere{{3, 0, 0}, 1.0}, Sphere{{0, 7, 0}, 0.25}};
    const auto bs = spheres_of(s);
    d::Executor ex(1);
    auto planned = d::plan_grid(bs, 0.0, ex);
    REQUIRE(planned.ok());
    const double expected = 1.5 * 2.0 * std::sqrt(2.0) * 1.0;
    CHECK(planned.value().cell_size == doctest::Approx(expected).epsilon(1e-9));
    CHECK(planned.value().huge_ids.empty());
    // Origin = lowest coverage corner.
    CHECK(planned.value().origin[0] == doctest::Approx(-std::sqrt(2.0) * 0.5).epsilon(1e-9));
}

TEST_CASE("the key layout packs x, y, z with b bits each and puts the sentinel above every key") {
    CHECK(d::cell_key(1, 2, 3, 4) == ((1U << 8) | (2U << 4) | 3U));
    CHECK(d::cell_type_of_key(d::cell_key(1, 2, 3, 4), 4) == (1U | 0U | 4U));
    std::vector<Sphere> s;
    for (int i = 0; i < 10; ++i) s.push_back(Sphere{{static_cast<double>(i) * 100.0, 0, 0}, 0.5});
    const auto bs = spheres_of(s);
    d::Executor ex(1);
    auto planned = d::plan_grid(bs, 1.0 * 1.25 * 2 * std::sqrt(2.0) * 0.5 * 1.001, ex);
    REQUIRE(planned.ok());
    const d::GridPlan& plan = planned.value();
    // x spans about 900 / 1.77 = 509 cells: 9 bits; the sentinel is 2^27.
    CHECK(plan.axis_bits == 9);
    CHECK(plan.sentinel == (std::uint64_t{1} << 27));
    CHECK(plan.key_bits == 28);
}

TEST_CASE("coordinates beyond 2^21 cells wrap in the key and the result stays exact") {
    // Two groups 3 million cells apart: their x coordinates alias modulo 2^21 if the offset is a
    // multiple of 2^21; here it is exactly 2^21 cells, so both groups share keys.
    std::vector<Box> s;
    Rng rng(3);
    const double far = 2097152.0;  // 2^21 cells of edge 1
    for (int i = 0; i < 200; ++i) {
        const double x = rng.range(0, 4);
        const double y = rng.range(0, 4);
        s.push_back(box_at(x, y, 0.5, 0.1, 0.1, 0.1));
        s.push_back(box_at(x + far, y, 0.5, 0.1, 0.1, 0.1));
    }
    spatialhash::Options o;
    o.cell_size = 1.0;
    auto r = spatialhash::find_pairs(std::span<const Box>(s), o);
    REQUIRE(r.ok());
    CHECK(r.value().stats.axis_bits == 21);
    CHECK(r.value().pairs == reference_pairs(s));
}

TEST_CASE("the key-limit guard names the object when a cell coordinate would pass 2^50") {
    // Valid input cannot reach the guard (padding bounds the coordinates); hand-made unpadded
    // bounding spheres can.
    const std::vector<d::BoundingSphere> bs = {{{0, 0, 0}, 0.0}, {{0, 0x1.0p52, 0}, 0.0}};
    d::Executor ex(1);
    auto planned = d::plan_grid(bs, 1.0, ex);
    REQUIRE_FALSE(planned.ok());
    CHECK(planned.error().message ==
          "spatial hash: object 1 lies 4503599627370496 cells from the grid origin on axis 1, beyond the limit "
          "2^50 (cell size 1); pass a larger Options::cell_size or use Method::SweepAndPrune");
}

TEST_CASE("build_cell_entries equals build_cell_ids without its sentinels, for any thread count") {
    Rng rng(41);
    for (int round = 0; round < 12; ++round) {
        // Up to 40K objects (3 chunks), some large enough to be huge, so chunks and slots both vary.
        const std::size_t n = round == 0 ? 0 : (round == 1 ? 1 : 100 + rng.below(40000));
        std::vector<Sphere> s;
        for (std::size_t i = 0; i < n; ++i) {
            const double r = rng.below(500) == 0 ? 5.0 : rng.range(0.0, 0.3);
            s.push_back(Sphere{{rng.range(-20, 20), rng.range(-20, 20), rng.range(0, 9)}, r});
        }
        const auto bs = spheres_of(s);
        for (const ThreadRun run : kThreadRuns) {
            const unsigned threads = run.threads;
            if (threads == 8) continue;
            const SpreadScope spread(run.spread);
            d::Executor ex(threads);
            auto planned = d::plan_grid(bs, 0.0, ex);
            REQUIRE(planned.ok());
            d::CellIdArray want = d::build_cell_ids(bs, planned.value(), ex);
            d::drop_sentinels(want, planned.value(), ex);
            const d::CellIdArray got = d::build_cell_entries(bs, planned.value(), ex);
            CAPTURE(round);
            CAPTURE(threads);
            CAPTURE(run.spread);
            CHECK(got.cell_ids == want.cell_ids);
            CHECK(got.objects == want.objects);
            CHECK(got.control == want.control);
            // drop_sentinels itself: exactly the non-sentinel entries, in their order.
            const d::CellIdArray full = d::build_cell_ids(bs, planned.value(), ex);
            std::vector<std::uint64_t> kept;
            for (std::uint64_t key : full.cell_ids) {
                if (key != planned.value().sentinel) kept.push_back(key);
            }
            CHECK(want.cell_ids == kept);
        }
    }
}

TEST_CASE("float filter boxes: outer boxes never miss an overlapping pair, inner boxes never claim a false one") {
    // Coordinates that float cannot hold exactly, at every magnitude (subnormal to beyond FLT_MAX),
    // and partners placed one double ulp inside, on, or one ulp outside each other's faces.
    Rng rng(51);
    const double scales[] = {1e-310, 1e-300, 1e-40, 1e-6, 1.0, 3.3e7, 1e20, 3.4028234663852886e38, 1e39, 1e300};
    std::size_t outer_hits = 0, inner_hits = 0, overlapping = 0;
    for (double scale : scales) {
        std::vector<Box> boxes;
        for (int i = 0; i < 150; ++i) {
            Box b{};
            for (int k = 0; k < 3; ++k) {
                b.lo[k] = scale * rng.range(-1.0, 1.0);
                b.hi[k] = b.lo[k] + scale * rng.range(0.0, 0.3);
            }
            boxes.push_back(b);
            // A partner that meets b on axis 0 at b.hi[0], nudged by -1, 0 or +1 ulp.
            Box p = b;
            const int nudge = static_cast<int>(rng.below(3)) - 1;
            double face = b.hi[0];
            if (nudge < 0) face = std::nextafter(face, -INFINITY);
            if (nudge > 0) face = std::nextafter(face, INFINITY);
            p.lo[0] = face;
            p.hi[0] = face + scale * 0.1;
            boxes.push_back(p);
        }
        d::Executor ex(2);
        const d::Objects objects{boxes, {}};
        const auto bs = d::bounding_spheres(std::span<const Box>(boxes), ex);
        const std::vector<d::FilterBox> f = d::filter_boxes(objects, bs, ex);
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            for (std::size_t j = i + 1; j < boxes.size(); ++j) {
                const bool exact = ref_overlap(boxes[i], boxes[j]);
                CAPTURE(scale);
                CAPTURE(i);
                CAPTURE(j);
                if (exact) CHECK(d::outer_overlap(f[i], f[j]));
                if (d::inner_overlap(f[i], f[j])) CHECK(exact);
                // Where float cannot resolve the scale (below its normal range, beyond FLT_MAX)
                // the float boxes are useless but still safe; count the useful range only.
                if (scale < 1e-6 || scale > 1e20) continue;
                overlapping += exact ? 1 : 0;
                outer_hits += d::outer_overlap(f[i], f[j]) ? 1 : 0;
                inner_hits += d::inner_overlap(f[i], f[j]) ? 1 : 0;
            }
        }
    }
    // In float's range the tests decide most pairs: the outer test does not pass everything, and
    // the inner test accepts the pairs that overlap by more than float rounding (about half here:
    // the other half are the partners built to touch within one double ulp, left to the exact test).
    CHECK(overlapping > 300);
    CHECK(inner_hits > overlapping / 3);
    CHECK(outer_hits < 3 * overlapping);
}

TEST_CASE("float filter boxes of spheres contain every pair the sphere predicate accepts, and never decide one") {
    Rng rng(61);
    for (double scale : {1e-300, 1e-3, 1.0, 1e9, 1e140}) {
        std::vector<Sphere> s;
        for (int i = 0; i < 120; ++i) {
            const Sphere a{{scale * rng.range(-1, 1), scale * rng.range(-1, 1), scale * rng.range(-1, 1)}, scale * rng.range(0, 0.2)};
            s.push_back(a);
            // A tangent partner along a random axis: centres exactly r_a + r_b apart on it.
            Sphere b = a;
            b.radius = scale * rng.range(0, 0.2);
            b.centre[rng.below(3)] += a.radius + b.radius;
            s.push_back(b);
        }
        d::Executor ex(1);
        const d::Objects objects{{}, s};
        const auto bs = d::bounding_spheres(std::span<const Sphere>(s), ex);
        const std::vector<d::FilterBox> f = d::filter_boxes(objects, bs, ex);
        std::size_t overlapping = 0;
        for (std::size_t i = 0; i < s.size(); ++i) {
            for (std::size_t j = i + 1; j < s.size(); ++j) {
                CAPTURE(scale);
                CAPTURE(i);
                CAPTURE(j);
                if (ref_overlap(s[i], s[j])) {
                    ++overlapping;
                    CHECK(d::outer_overlap(f[i], f[j]));
                }
                CHECK_FALSE(d::inner_overlap(f[i], f[j]));
            }
        }
        CHECK(overlapping >= 100);
    }
}
