// orient2d / orient3d against exact rational evaluation (GMP), on inputs where the floating-point
// filter must give up: points on a line or a plane moved by a few ulps, Shewchuk's (0.5 + x ulp)
// grid, large offsets, and coordinates at both ends of the exactness range.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "cullide/predicates.h"
#include "orient_plane.h"
#include "rational_tri_tri.h"
#include "test_rng.h"

using cullide::Vec3;

namespace {

// splitmix64 (Steele, Lea, Flood 2014): tests/test_rng.h, plus vector helpers.
struct Rng : test::Rng {
    using test::Rng::Rng;
    Vec3 sym3() {
        const double x = sym();
        const double y = sym();
        return {x, y, sym()};
    }
};

// x moved by k ulps (k may be negative); 0 stays 0 (its neighbours are subnormals, outside the
// exact range).
double ulps(double x, int k) {
    if (x == 0) return x;
    const double dir = k > 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
    for (int i = 0; i < (k > 0 ? k : -k); ++i) x = std::nextafter(x, dir);
    return x;
}

// A random double of magnitude 2^lo .. 2^hi with a full random mantissa, random sign.
double wide(Rng& rng, int lo, int hi) {
    const double m = 1.0 + rng.unit();
    const int e = rng.range(lo, hi);
    return std::ldexp(rng.next() & 1u ? m : -m, e);
}

}  // namespace

TEST_CASE("orient2d is exact on Shewchuk's grid of points near the line through (12,12) and (24,24)") {
    // a = (0.5 + i u, 0.5 + j u), u = 2^-53: the naive double formula gets many of these wrong.
    const auto before = cullide::predicate_stats().orient2d_exact;
    long naive_wrong = 0, wrong = 0, zeros = 0;
    for (int i = 0; i < 256; ++i) {
        for (int j = 0; j < 256; ++j) {
            CAPTURE(i);
            CAPTURE(j);
            const double ax = 0.5 + i * 0x1p-53, ay = 0.5 + j * 0x1p-53;
            const int want = cullide::test::rational_orient2d(ax, ay, 12, 12, 24, 24);
            const int got = cullide::orient2d(ax, ay, 12, 12, 24, 24);
            const double naive = (12 - ax) * (24 - ay) - (12 - ay) * (24 - ax);
            naive_wrong += (naive > 0 ? 1 : (naive < 0 ? -1 : 0)) != want;
            wrong += got != want;
            zeros += want == 0;
        }
    }
    CHECK(wrong == 0);
    CHECK(naive_wrong > 0);  // the inputs really are hard
    CHECK(zeros > 0);
    CHECK(cullide::predicate_stats().orient2d_exact > before);  // the exact path ran
}

TEST_CASE("orient2d is exact for points on a line moved by a few ulps, at several scales") {
    Rng rng{21};
    long wrong = 0, signs[3] = {0, 0, 0};
    for (int n = 0; n < 100000; ++n) {
        const int e = (n % 5 == 0) ? 0 : rng.range(-280, 280);
        const double s = std::ldexp(1.0, e);
        // Every 3rd case on small integers, where c is often exactly on the line.
        const bool ints = n % 3 == 0;
        auto coord = [&]() { return ints ? s * rng.range(-100, 100) : s * rng.sym(); };
        const double ax = coord(), ay = coord(), bx = coord(), by = coord();
        const double t = ints ? rng.range(-2, 3) : rng.unit() * 3 - 1;
        double cx = ax + t * (bx - ax), cy = ay + t * (by - ay);
        cx = ulps(cx, rng.range(-2, 2));
        cy = ulps(cy, rng.range(-2, 2));
        const int want = cullide::test::rational_orient2d(ax, ay, bx, by, cx, cy);
        const int got = cullide::orient2d(ax, ay, bx, by, cx, cy);
        wrong += got != want;
        ++signs[want + 1];
        if (got != want && wrong < 5) FAIL_CHECK("orient2d wrong at case " << n);
    }
    CHECK(wrong == 0);
    CHECK(signs[0] > 0);
    CHECK(signs[1] > 0);  // some exactly collinear after rounding
    CHECK(signs[2] > 0);
}

TEST_CASE("orient3d is exact for points on a plane moved by a few ulps, with offsets and tiny or huge scales") {
    Rng rng{22};
    const auto before = cullide::predicate_stats().orient3d_exact;
    long wrong = 0, signs[3] = {0, 0, 0};
    for (int n = 0; n < 100000; ++n) {
        const int kind = n % 4;
        const double s = kind == 1 ? 0x1p-100 : (kind == 2 ? 0x1p100 : 1.0);
        const Vec3 offset = kind == 3 ? Vec3{1e15 * rng.sym(), 1e12 * rng.sym(), 1e9 * rng.sym()} : Vec3{};
        const Vec3 a = offset + s * rng.sym3();
        const Vec3 b = offset + s * rng.sym3();
        const Vec3 c = offset + s * rng.sym3();
        const double u = rng.unit() * 2 - 0.5, v = rng.unit() * 2 - 0.5;
        Vec3 d = a + u * (b - a) + v * (c - a);
        for (int k = 0; k < 3; ++k) d[k] = ulps(d[k], rng.range(-1, 1));
        const int want = cullide::test::rational_orient3d(a, b, c, d);
        const int got = cullide::orient3d(a, b, c, d);
        wrong += got != want;
        ++signs[want + 1];
        if (got != want && wrong < 5) FAIL_CHECK("orient3d wrong at case " << n);
    }
    CHECK(wrong == 0);
    CHECK(signs[0] > 0);
    CHECK(signs[1] > 0);
    CHECK(signs[2] > 0);
    CHECK(cullide::predicate_stats().orient3d_exact > before);
}

TEST_CASE("orient3d is exact for exactly coplanar integer points and for repeated points") {
    Rng rng{23};
    long wrong = 0;
    for (int n = 0; n < 20000; ++n) {
        const Vec3 o{double(rng.range(-1000, 1000)), double(rng.range(-1000, 1000)), double(rng.range(-1000, 1000))};
        const Vec3 e1{double(rng.range(-9, 9)), double(rng.range(-9, 9)), double(rng.range(-9, 9))};
        const Vec3 e2{double(rng.range(-9, 9)), double(rng.range(-9, 9)), double(rng.range(-9, 9))};
        auto at = [&](int i, int j) { return o + double(i) * e1 + double(j) * e2; };
        const int i1 = rng.range(-5, 5), j1 = rng.range(-5, 5), i2 = rng.range(-5, 5), j2 = rng.range(-5, 5);
        const int i3 = rng.range(-5, 5), j3 = rng.range(-5, 5);
        const Vec3 a = at(0, 0), b = at(i1, j1), c = at(i2, j2), d = at(i3, j3);
        wrong += cullide::orient3d(a, b, c, d) != 0;
        wrong += cullide::orient3d(a, a, c, d) != 0;
        // orient2d_drop is the sign of one component of (b - a) x (c - a).
        const Vec3 n3 = cross(b - a, c - a);
        for (int axis = 0; axis < 3; ++axis) {
            const int want = n3[axis] > 0 ? 1 : (n3[axis] < 0 ? -1 : 0);
            wrong += cullide::orient2d_drop(a, b, c, axis) != want;
        }
    }
    CHECK(wrong == 0);
}

TEST_CASE("orient3d is exact on coarse grids, on both sides of the small-span stage's 16-bit limit") {
    // Integer points scaled by 2^e: a, b, c in [-2^(g-1), 2^(g-1)], d on their plane (integer
    // combination) or one grid unit off it. The nine differences span about g + 3 bits, so g = 10..22
    // puts them on both sides of the 16-bit limit under which orient3d's own evaluation is exact,
    // and far enough past it (products of three differences above 2^53 units) that a stage taken
    // past its limit gives wrong signs here (checked with a limit of 22 bits).
    Rng rng{24};
    long wrong = 0, zeros = 0, nonzeros = 0;
    for (int n = 0; n < 91000; ++n) {
        const int g = 10 + n % 13;
        const int lim = 1 << (g - 1);
        const double unit = std::ldexp(1.0, rng.range(-60, 60));
        std::int64_t p[3][3];
        for (auto& q : p)
            for (auto& x : q) x = rng.range(-lim, lim);
        const int i = rng.range(-3, 3), j = rng.range(-3, 3);
        std::int64_t q[3];
        for (int k = 0; k < 3; ++k) q[k] = p[0][k] + i * (p[1][k] - p[0][k]) + j * (p[2][k] - p[0][k]);
        if (n % 3 == 1) q[rng.range(0, 2)] += rng.coin() ? 1 : -1;  // one unit off the plane
        auto vec = [&](const std::int64_t* v) {
            return Vec3{double(v[0]) * unit, double(v[1]) * unit, double(v[2]) * unit};
        };
        const Vec3 a = vec(p[0]), b = vec(p[1]), c = vec(p[2]), d = vec(q);
        const auto exact_before = cullide::predicate_stats().orient3d_exact;
        const int got = cullide::orient3d(a, b, c, d);
        const int want = cullide::test::rational_orient3d(a, b, c, d);
        wrong += got != want;
        if (got != want && wrong < 5) FAIL_CHECK("orient3d wrong at case " << n << " (g = " << g << ")");
        (want == 0 ? zeros : nonzeros) += 1;
        // Spans of at most 13 bits (g = 10): a coplanar point never reaches the expansion arithmetic.
        if (g == 10 && want == 0) CHECK(cullide::predicate_stats().orient3d_exact == exact_before);
    }
    CHECK(wrong == 0);
    CHECK(zeros > 10000);
    CHECK(nonzeros > 10000);
}

TEST_CASE("both predicates are exact across the whole stated range, magnitudes 2^-300 to 2^300 mixed") {
    Rng rng{24};
    long wrong = 0;
    for (int n = 0; n < 50000; ++n) {
        // Coordinates drawn from a small pool so that equal coordinates (and with them cancellation
        // down to the tiniest terms) are frequent.
        double pool[4];
        for (double& p : pool) p = (rng.range(0, 5) == 0) ? 0.0 : wide(rng, -300, 298);
        auto pick = [&]() { return pool[rng.range(0, 3)]; };
        Vec3 q[4];
        for (Vec3& v : q) {
            const double x = pick();
            const double y = pick();
            v = {x, y, pick()};
        }
        for (const Vec3& v : q) {
            for (int k = 0; k < 3; ++k) REQUIRE(cullide::predicate_coordinate_ok(v[k]));
        }
        wrong += cullide::orient3d(q[0], q[1], q[2], q[3]) != cullide::test::rational_orient3d(q[0], q[1], q[2], q[3]);
        wrong += cullide::orient2d(q[0].x, q[0].y, q[1].x, q[1].y, q[2].x, q[2].y) !=
                 cullide::test::rational_orient2d(q[0].x, q[0].y, q[1].x, q[1].y, q[2].x, q[2].y);
    }
    CHECK(wrong == 0);
    // The range predicate itself.
    CHECK(cullide::predicate_coordinate_ok(0.0));
    CHECK(cullide::predicate_coordinate_ok(-0x1p300));
    CHECK(cullide::predicate_coordinate_ok(0x1p-300));
    CHECK_FALSE(cullide::predicate_coordinate_ok(0x1p301));
    CHECK_FALSE(cullide::predicate_coordinate_ok(0x1p-301));
    CHECK_FALSE(cullide::predicate_coordinate_ok(std::numeric_limits<double>::quiet_NaN()));
    CHECK_FALSE(cullide::predicate_coordinate_ok(std::numeric_limits<double>::infinity()));
}

TEST_CASE("Orient3dPlane gives orient3d's exact sign for every point: near the plane, on grids, across the range") {
    // cullide/src/orient_plane.h: the plane's minors once, orient3d's bound, orient3d where the
    // filter does not decide. Against the rational sign on the inputs where the filter is tested
    // hardest: points a few ulps off the plane (at tiny and huge scales and far from the origin),
    // exactly coplanar integer grids, degenerate planes (repeated or collinear corners: a zero
    // normal), and magnitudes across the whole range mixed.
    Rng rng{25};
    long wrong = 0, checked = 0, signs[3] = {0, 0, 0};
    const auto check = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3* ds, int count) {
        const cullide::detail::Orient3dPlane plane(a, b, c);
        for (int i = 0; i < count; ++i) {
            const int want = cullide::test::rational_orient3d(a, b, c, ds[i]);
            const int got = plane(ds[i]);
            wrong += got != want;
            ++signs[want + 1];
            ++checked;
            if (got != want && wrong < 5) FAIL_CHECK("Orient3dPlane wrong at check " << checked);
        }
    };
    for (int n = 0; n < 40000; ++n) {  // a few ulps off the plane
        const int kind = n % 4;
        const double s = kind == 1 ? 0x1p-100 : (kind == 2 ? 0x1p100 : 1.0);
        const Vec3 offset = kind == 3 ? Vec3{1e15 * rng.sym(), 1e12 * rng.sym(), 1e9 * rng.sym()} : Vec3{};
        const Vec3 a = offset + s * rng.sym3(), b = offset + s * rng.sym3(), c = offset + s * rng.sym3();
        Vec3 ds[3];
        for (Vec3& d : ds) {
            const double u = rng.unit() * 2 - 0.5, v = rng.unit() * 2 - 0.5;
            d = a + u * (b - a) + v * (c - a);
            for (int k = 0; k < 3; ++k) d[k] = ulps(d[k], rng.range(-1, 1));
        }
        check(a, b, c, ds, 3);
    }
    for (int n = 0; n < 20000; ++n) {  // integer grids: coplanar, repeated and collinear corners
        const Vec3 o{double(rng.range(-1000, 1000)), double(rng.range(-1000, 1000)), double(rng.range(-1000, 1000))};
        const Vec3 e1{double(rng.range(-9, 9)), double(rng.range(-9, 9)), double(rng.range(-9, 9))};
        const Vec3 e2{double(rng.range(-9, 9)), double(rng.range(-9, 9)), double(rng.range(-9, 9))};
        const auto at = [&](int i, int j) { return o + double(i) * e1 + double(j) * e2; };
        // n % 5 == 0: b repeated as c; == 1: three corners on one line; else a random grid plane.
        const Vec3 a = n % 5 == 1 ? at(1, 0) : at(0, 0);
        const Vec3 b = n % 5 == 1 ? at(3, 0) : at(rng.range(-5, 5), rng.range(-5, 5));
        const Vec3 c = n % 5 == 0 ? b : (n % 5 == 1 ? at(2, 0) : at(rng.range(-5, 5), rng.range(-5, 5)));
        const Vec3 ds[3] = {at(rng.range(-5, 5), rng.range(-5, 5)),
                            at(rng.range(-5, 5), rng.range(-5, 5)) + Vec3{0.0, 0.0, double(rng.range(-1, 1))},
                            a};
        check(a, b, c, ds, 3);
    }
    for (int n = 0; n < 20000; ++n) {  // magnitudes 2^-300 .. 2^300 from a small pool
        double pool[4];
        for (double& p : pool) p = (rng.range(0, 5) == 0) ? 0.0 : wide(rng, -300, 298);
        const auto pick = [&]() { return pool[rng.range(0, 3)]; };
        Vec3 q[6];
        for (Vec3& v : q) {
            const double x = pick();
            const double y = pick();
            v = {x, y, pick()};
        }
        check(q[0], q[1], q[2], q + 3, 3);
    }
    CHECK(wrong == 0);
    CHECK(checked == 240000);
    CHECK(signs[0] > 1000);
    CHECK(signs[1] > 1000);
    CHECK(signs[2] > 1000);
}
