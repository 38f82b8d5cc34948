// tri_tri_relation / tri_tri_intersect against the rational reference (rational_tri_tri.h), on
// named hand cases and on seeded random and adversarial families. Each family checks that it
// produced the mix of relations it exists for, so it cannot silently degenerate into "all
// disjoint". The case count can be lowered for sanitizer builds with CULLIDE_TRITRI_CASES (the
// default total is 1,000,000).
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "cullide/predicates.h"
#include "cullide/tri_tri.h"
#include "rational_tri_tri.h"
#include "test_rng.h"

using cullide::TriRelation;
using cullide::Vec3;

namespace {

// splitmix64 (Steele, Lea, Flood 2014): tests/test_rng.h, plus vector helpers.
struct Rng : test::Rng {
    using test::Rng::Rng;
    Vec3 sym3() { return {sym(), sym(), sym()}; }
    Vec3 int3(int lo, int hi) {
        return {static_cast<double>(range(lo, hi)), static_cast<double>(range(lo, hi)),
                static_cast<double>(range(lo, hi))};
    }
};

struct Case {
    std::array<Vec3, 6> v;  // a0 a1 a2 b0 b1 b2
};

Vec3 add(Vec3 a, Vec3 b) { return a + b; }
Vec3 scale(double s, Vec3 a) { return s * a; }

std::string describe(const Case& c) {
    std::string s;
    char buf[96];
    for (int i = 0; i < 6; ++i) {
        const Vec3& p = c.v[static_cast<std::size_t>(i)];
        std::snprintf(buf, sizeof buf, "%s(%a, %a, %a)", i == 0 ? "" : (i == 3 ? " | " : ", "), p.x, p.y, p.z);
        s += buf;
    }
    return s;
}

TriRelation fast(const Case& c, int perm = 0) {
    const auto& v = c.v;
    switch (perm) {
        case 1: return cullide::tri_tri_relation(v[3], v[4], v[5], v[0], v[1], v[2]);  // swapped
        case 2: return cullide::tri_tri_relation(v[1], v[2], v[0], v[5], v[3], v[4]);  // rotated
        case 3: return cullide::tri_tri_relation(v[0], v[2], v[1], v[3], v[5], v[4]);  // reversed
        default: return cullide::tri_tri_relation(v[0], v[1], v[2], v[3], v[4], v[5]);
    }
}

// Runs one family and checks every case against the reference.
struct Family {
    const char* name;
    long count = 0;
    std::array<long, 4> tally{};
    long mismatches = 0;

    void check(const Case& c) {
        const TriRelation got = fast(c);
        const TriRelation want =
            cullide::test::rational_tri_tri_relation(c.v[0], c.v[1], c.v[2], c.v[3], c.v[4], c.v[5]);
        const bool meet = cullide::tri_tri_intersect(c.v[0], c.v[1], c.v[2], c.v[3], c.v[4], c.v[5]);
        ++tally[static_cast<std::size_t>(want)];
        // Symmetry and vertex-order invariance are part of the contract; checked on every 4th case.
        const bool perms_ok = (count % 4 != 0) || (fast(c, 1) == got && fast(c, 2) == got && fast(c, 3) == got);
        ++count;
        if (got != want || meet != (want != TriRelation::Disjoint) || !perms_ok) {
            if (++mismatches <= 5) {
                const std::string what = std::string(name) + ": got " + cullide::to_string(got) + " (intersect " +
                           (meet ? "true" : "false") + ", permutations " + (perms_ok ? "agree" : "DISAGREE") +
                           "), reference " + cullide::to_string(want) + " for " + describe(c);
                FAIL_CHECK(what);
            }
        }
    }

    // The family must have produced each listed relation at least once (only meaningful at the
    // full default count; small sanitizer runs skip it).
    void expect(std::initializer_list<TriRelation> rels, long min_count) const {
        const std::string summary = std::string(name) + ": " + std::to_string(count) + " cases: disjoint " + std::to_string(tally[0]) +
                ", touching " + std::to_string(tally[1]) + ", crossing " + std::to_string(tally[2]) +
                ", coplanar-overlap " + std::to_string(tally[3]);
        MESSAGE(summary);
        CHECK(mismatches == 0);
        if (count < min_count) return;
        for (TriRelation r : rels) {
            const std::string relation = cullide::to_string(r);
            CAPTURE(relation);
            CHECK(tally[static_cast<std::size_t>(r)] > 0);
        }
    }
};

// Case counts: the default total is 1,000,000; CULLIDE_TRITRI_CASES scales every family.
long cases(long default_count) {
    static const double factor = [] {
        const char* env = std::getenv("CULLIDE_TRITRI_CASES");
        if (env == nullptr) return 1.0;
        const double want = std::atof(env);
        return want > 0 ? want / 1000000.0 : 1.0;
    }();
    const long n = static_cast<long>(static_cast<double>(default_count) * factor);
    return n < 50 ? 50 : n;
}
constexpr long kMixMin = 5000;  // below this a family does not insist on its relation mix

// ---- generators ------------------------------------------------------------------------------

// Two triangles in one plane, from integer grid coordinates (u, v) mapped through an integer
// basis: exactly coplanar, with frequent shared vertices, touching edges and overlaps.
Case coplanar_integer(Rng& rng) {
    Vec3 e1 = rng.int3(-3, 3), e2 = rng.int3(-3, 3);
    while (cross(e1, e2) == Vec3{0, 0, 0}) {  // a zero e1 would never pass: redraw both
        e1 = rng.int3(-3, 3);
        e2 = rng.int3(-3, 3);
    }
    const Vec3 o = rng.int3(-20, 20);
    Case c;
    for (auto& p : c.v) {
        const int u = rng.range(0, 6);
        const int v = rng.range(0, 6);
        p = add(o, add(scale(u, e1), scale(v, e2)));
    }
    return c;
}

// Coplanar on the dyadic plane z = alpha x + beta y + gamma, coordinates then permuted.
Case coplanar_dyadic(Rng& rng) {
    const double alpha = rng.range(-16, 16) / 8.0;
    const double beta = rng.range(-16, 16) / 8.0;
    const double gamma = rng.range(-64, 64) / 4.0;
    const int axis = rng.range(0, 2);
    Case c;
    for (auto& p : c.v) {
        const double x = rng.range(-64, 64) / 64.0;
        const double y = rng.range(-64, 64) / 64.0;
        const double z = alpha * x + beta * y + gamma;  // exact: few significant bits
        p = axis == 0 ? Vec3{x, y, z} : (axis == 1 ? Vec3{z, x, y} : Vec3{y, z, x});
    }
    return c;
}

// A point of integer triangle t with dyadic barycentric weights (w0, w1, w2) / 16: exact.
Vec3 on_triangle(Rng& rng, const Vec3& t0, const Vec3& t1, const Vec3& t2, bool edge_only) {
    int w0 = rng.range(0, 16), w1 = rng.range(0, 16 - w0);
    if (edge_only) w1 = 16 - w0;
    const int w2 = 16 - w0 - w1;
    return scale(1.0 / 16.0, add(add(scale(w0, t0), scale(w1, t1)), scale(w2, t2)));
}

// Touching configurations in integer/dyadic coordinates: a vertex of B on A's face, a vertex of B
// on an edge of A, an edge of B through a point of an edge of A; the other vertices of B on one
// side, on both sides, or in A's plane.
Case touching(Rng& rng) {
    Case c;
    c.v[0] = rng.int3(-8, 8);
    c.v[1] = rng.int3(-8, 8);
    c.v[2] = rng.int3(-8, 8);
    const int kind = rng.range(0, 2);
    const Vec3 x = on_triangle(rng, c.v[0], c.v[1], c.v[2], kind != 0);
    const Vec3 n = cross(c.v[1] - c.v[0], c.v[2] - c.v[0]);
    auto offset = [&](int side) {
        if (side == 0) {  // exactly in A's plane: an integer combination of A's edges
            const int k1 = rng.range(-2, 2);
            const int k2 = rng.range(-2, 2);
            return add(scale(k1, c.v[1] - c.v[0]), scale(k2, c.v[2] - c.v[0]));
        }
        Vec3 d = rng.int3(-6, 6);
        if ((dot(d, n) > 0) != (side > 0)) d = scale(-1, d);
        return d;
    };
    const int s1 = rng.range(-1, 1);
    const int s2 = rng.range(-1, 1);
    if (kind == 2) {
        const Vec3 d = scale(1.0 / 16.0, rng.int3(-32, 32));
        c.v[3] = x + d;
        c.v[4] = x - d;
        c.v[5] = x + offset(s2);
    } else {
        c.v[3] = x;
        c.v[4] = x + offset(s1);
        const Vec3 d2 = offset(s2);
        c.v[5] = x + d2;
    }
    return c;
}

// Triangles with all coordinates random in [-1, 1].
Case general(Rng& rng) {
    Case c;
    for (auto& p : c.v) p = rng.sym3();
    return c;
}

Case shared_vertex(Rng& rng) {
    Case c = general(rng);
    c.v[static_cast<std::size_t>(3 + rng.range(0, 2))] = c.v[static_cast<std::size_t>(rng.range(0, 2))];
    return c;
}

Case shared_edge(Rng& rng) {
    // Half in general position, half coplanar on an integer grid (overlap or fold-back).
    Case c = rng.coin() ? general(rng) : coplanar_integer(rng);
    const int i = rng.range(0, 2), j = (i + 1) % 3;
    const int k = rng.range(0, 2);
    const bool reversed = rng.coin();
    c.v[static_cast<std::size_t>(3 + k)] = c.v[static_cast<std::size_t>(reversed ? j : i)];
    c.v[static_cast<std::size_t>(3 + (k + 1) % 3)] = c.v[static_cast<std::size_t>(reversed ? i : j)];
    return c;
}

// Needle- and blade-shaped triangles: the third vertex a hair (2^-20 .. 2^-45) off the line of the
// first two, against a random or a touching partner.
Case sliver(Rng& rng) {
    Case c = rng.coin() ? general(rng) : touching(rng);
    auto hair = [&rng]() {
        const double m = rng.sym();
        const int e = rng.range(20, 45);
        return scale(std::ldexp(m, -e), rng.sym3());
    };
    const double t = rng.unit();
    c.v[2] = add(c.v[0] + scale(t, c.v[1] - c.v[0]), hair());
    if (rng.coin()) {  // a sliver B as well
        const double u = rng.unit();
        c.v[5] = add(c.v[3] + scale(u, c.v[4] - c.v[3]), hair());
    }
    return c;
}

// Collinear, repeated-vertex and point "triangles" on a small integer grid, against a triangle or
// another degenerate one.
Vec3 pick(const Case& c, Rng& rng) { return c.v[static_cast<std::size_t>(rng.range(0, 5))]; }
void make_flat(Case& c, int first, Rng& rng) {
    const Vec3 p = rng.int3(-4, 4);
    const Vec3 d = rng.int3(-2, 2);
    const int kind = rng.range(0, 2);
    auto at = [&](int k) { return p + scale(k, d); };
    std::array<Vec3, 3> t;
    if (kind == 0) {  // collinear (braced lists evaluate in order)
        t = {at(rng.range(-2, 2)), at(rng.range(-2, 2)), at(rng.range(-2, 2))};
    }
    if (kind == 1) t = {p, p, at(rng.range(-2, 2))};                                         // repeated
    if (kind == 2) t = {p, p, p};                                                            // a point
    for (int i = 0; i < 3; ++i) c.v[static_cast<std::size_t>(first + i)] = t[static_cast<std::size_t>((i + kind) % 3)];
}
Case degenerate(Rng& rng) {
    Case c;
    for (auto& p : c.v) p = rng.int3(-4, 4);
    const int which = rng.range(0, 2);  // A flat, B flat, both flat
    if (which != 1) make_flat(c, 0, rng);
    if (which != 0) make_flat(c, 3, rng);
    if (rng.range(0, 3) == 0) c.v[3] = pick(c, rng);  // force more contacts
    return c;
}

// Any of the generators above, for the scale and perturbation families.
Case any_base(Rng& rng) {
    switch (rng.range(0, 5)) {
        case 0: return general(rng);
        case 1: return coplanar_integer(rng);
        case 2: return touching(rng);
        case 3: return shared_edge(rng);
        case 4: return degenerate(rng);
        default: return coplanar_dyadic(rng);
    }
}

Case scaled(Rng& rng) {
    Case c = any_base(rng);
    // Exact power-of-two scaling keeps the geometry; then random mantissas on a quarter of them.
    const int e = rng.coin() ? -100 : 100;  // 2^-100 ~ 7.9e-31, 2^100 ~ 1.3e30
    for (auto& p : c.v) p = scale(std::ldexp(1.0, e), p);
    if (rng.range(0, 3) == 0) {
        for (auto& p : c.v) {
            const double r = std::ldexp(1.0, e - 2) * rng.unit();
            p = add(p, scale(r, rng.sym3()));
        }
    }
    return c;
}

Case translated(Rng& rng) {
    Case c = any_base(rng);
    Vec3 offset;
    for (int k = 0; k < 3; ++k) {
        const double magnitude = std::pow(10.0, rng.range(6, 15));
        offset[k] = magnitude * (k == 0 ? (rng.coin() ? 1.0 : -1.0) : rng.sym());
    }
    // Feature size ~ 2^-4 .. 2^6: tiny next to the offset, so the sums round (to whatever they
    // round to: the reference sees the same doubles).
    const double feature = std::ldexp(1.0, rng.range(-4, 6));
    for (auto& p : c.v) p = add(offset, scale(feature, p));
    return c;
}

Case ulp_perturbed(Rng& rng) {
    Case c = rng.coin() ? coplanar_integer(rng) : (rng.coin() ? touching(rng) : shared_edge(rng));
    const int moves = rng.range(1, 3);
    for (int m = 0; m < moves; ++m) {
        Vec3& p = c.v[static_cast<std::size_t>(rng.range(0, 5))];
        double& x = p[rng.range(0, 2)];
        const bool up = rng.coin();
        if (x == 0) {
            // One ulp of 0 is a subnormal, outside the exact range (predicates.h): use the smallest
            // magnitude inside it instead.
            x = up ? cullide::kPredicateMinAbs : -cullide::kPredicateMinAbs;
        } else {
            x = std::nextafter(x, up ? std::numeric_limits<double>::infinity()
                                     : -std::numeric_limits<double>::infinity());
        }
    }
    return c;
}

template <class Gen>
Family run(const char* name, std::uint64_t seed, long default_count, Gen gen) {
    Family f{name};
    Rng rng{seed};
    const long n = cases(default_count);
    for (long i = 0; i < n; ++i) f.check(gen(rng));
    return f;
}

TriRelation rel(Vec3 a0, Vec3 a1, Vec3 a2, Vec3 b0, Vec3 b1, Vec3 b2) {
    const TriRelation r = cullide::tri_tri_relation(a0, a1, a2, b0, b1, b2);
    // Every hand case is also checked against the reference.
    CHECK(r == cullide::test::rational_tri_tri_relation(a0, a1, a2, b0, b1, b2));
    return r;
}

}  // namespace

TEST_CASE("named hand cases have the relation written next to them") {
    const Vec3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0};
    // Far apart along z.
    CHECK(rel(o, x, y, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}) == TriRelation::Disjoint);
    // A vertical triangle piercing the unit right triangle: crossing.
    CHECK(rel(o, x, y, {0.25, 0.25, -1}, {0.25, 0.25, 1}, {2, 2, 0.5}) == TriRelation::Crossing);
    // The same triangle again: coplanar overlap.
    CHECK(rel(o, x, y, o, x, y) == TriRelation::CoplanarOverlap);
    // Coplanar, sharing only the edge from x to y, folded back: touching.
    CHECK(rel(o, x, y, x, y, {1, 1, 0}) == TriRelation::Touching);
    // Coplanar, one corner meeting another: touching.
    CHECK(rel(o, x, y, x, {2, 0, 0}, {2, 1, 0}) == TriRelation::Touching);
    // Coplanar, separated by a gap of 2^-52 along x: disjoint.
    CHECK(rel(o, x, y, {1 + 0x1p-52, 0, 0}, {2, 0, 0}, {2, 1, 0}) == TriRelation::Disjoint);
    // A vertex of B resting on the face of A, the rest above: touching.
    CHECK(rel(o, x, y, {0.25, 0.25, 0}, {0, 0, 1}, {1, 1, 1}) == TriRelation::Touching);
    // B's edge lying in A's plane across A, the rest above: touching (B does not straddle A).
    CHECK(rel(o, x, y, {-1, 0.25, 0}, {2, 0.25, 0}, {0, 0, 1}) == TriRelation::Touching);
    // Hinge: shared edge, B standing up: touching.
    CHECK(rel(o, x, y, o, x, {0, 0, 1}) == TriRelation::Touching);
    // B's vertex on A's plane through A's interior, B straddles: crossing.
    CHECK(rel(o, x, y, {0.25, 0.25, 0}, {0.25, 0.25, 1}, {0.5, -1, -1}) == TriRelation::Crossing);
    // Skew edges crossing at exactly one point (edge x-y of A and a vertical edge of B): touching.
    CHECK(rel(o, x, y, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0}) == TriRelation::Touching);
    // Degenerate: a point on A's face touches, a point 2^-60 above it does not.
    CHECK(rel(o, x, y, {0.25, 0.25, 0}, {0.25, 0.25, 0}, {0.25, 0.25, 0}) == TriRelation::Touching);
    CHECK(rel(o, x, y, {0.25, 0.25, 0x1p-60}, {0.25, 0.25, 0x1p-60}, {0.25, 0.25, 0x1p-60}) ==
          TriRelation::Disjoint);
    // Degenerate: a segment piercing A, and a collinear "triangle" crossing one on the x axis.
    CHECK(rel(o, x, y, {0.1, 0.1, -1}, {0.1, 0.1, 1}, {0.1, 0.1, 0.5}) == TriRelation::Touching);
    CHECK(rel({-1, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 1, 0}) == TriRelation::Touching);
    CHECK(rel({-1, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, -1, 1}, {0, 1, 1}, {0, 1, 1}) == TriRelation::Disjoint);
    // Two identical points; two different points.
    CHECK(rel(x, x, x, x, x, x) == TriRelation::Touching);
    CHECK(rel(x, x, x, y, y, y) == TriRelation::Disjoint);
    // tri_tri_intersect agrees.
    CHECK(cullide::tri_tri_intersect(o, x, y, o, x, {0, 0, 1}));
    CHECK_FALSE(cullide::tri_tri_intersect(o, x, y, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}));
}

TEST_CASE("the checked entry point names the coordinate outside the exact range") {
    const Vec3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0};
    const auto ok = cullide::tri_tri_relation_checked(o, x, y, o, x, y);
    REQUIRE(ok.ok());
    CHECK(ok.value() == TriRelation::CoplanarOverlap);
    const auto inf = cullide::tri_tri_relation_checked(o, x, y, o, {1, 0, std::numeric_limits<double>::infinity()}, y);
    REQUIRE_FALSE(inf.ok());
    CHECK(inf.error().message.find("b1.z") != std::string::npos);
    const auto tiny = cullide::tri_tri_relation_checked({0x1p-400, 0, 0}, x, y, o, x, y);
    REQUIRE_FALSE(tiny.ok());
    CHECK(tiny.error().message.find("a0.x") != std::string::npos);
    const auto nan = cullide::tri_tri_relation_checked(o, x, y, o, x, {0, std::nan(""), 0});
    REQUIRE_FALSE(nan.ok());
    CHECK(nan.error().message.find("b2.y") != std::string::npos);
}

TEST_CASE("general random triangles agree with the rational reference") {
    run("general", 1, 170000, general).expect({TriRelation::Disjoint, TriRelation::Crossing}, kMixMin);
}

TEST_CASE("exactly coplanar triangles agree with the rational reference") {
    run("coplanar-integer", 2, 90000, coplanar_integer)
        .expect({TriRelation::Disjoint, TriRelation::Touching, TriRelation::CoplanarOverlap}, kMixMin);
    run("coplanar-dyadic-plane", 3, 40000, coplanar_dyadic)
        .expect({TriRelation::Disjoint, TriRelation::Touching, TriRelation::CoplanarOverlap}, kMixMin);
}

TEST_CASE("triangles sharing a vertex or an edge agree with the rational reference") {
    run("shared-vertex", 4, 90000, shared_vertex).expect({TriRelation::Touching, TriRelation::Crossing}, kMixMin);
    run("shared-edge", 5, 90000, shared_edge).expect({TriRelation::Touching, TriRelation::CoplanarOverlap}, kMixMin);
}

TEST_CASE("triangles touching at a vertex, an edge point or crossing edges agree with the reference") {
    // B always contains a point of A here, so never disjoint.
    run("touching", 6, 130000, touching)
        .expect({TriRelation::Touching, TriRelation::Crossing, TriRelation::CoplanarOverlap},
                kMixMin);
}

TEST_CASE("slivers and degenerate triangles agree with the rational reference") {
    run("sliver", 7, 50000, sliver).expect({TriRelation::Disjoint, TriRelation::Touching, TriRelation::Crossing}, kMixMin);
    run("degenerate", 8, 90000, degenerate).expect({TriRelation::Disjoint, TriRelation::Touching}, kMixMin);
}

TEST_CASE("coordinates near 1e-30 and 1e+30 and large translations agree with the reference") {
    run("scaled-1e-30-1e30", 9, 90000, scaled)
        .expect({TriRelation::Disjoint, TriRelation::Touching, TriRelation::Crossing, TriRelation::CoplanarOverlap},
                kMixMin);
    run("translated-1e6-1e15", 10, 80000, translated)
        .expect({TriRelation::Disjoint, TriRelation::Touching, TriRelation::Crossing, TriRelation::CoplanarOverlap},
                kMixMin);
}

TEST_CASE("near-coplanar and near-touching cases moved by one ulp agree with the reference") {
    run("ulp-perturbed", 11, 80000, ulp_perturbed)
        .expect({TriRelation::Disjoint, TriRelation::Touching, TriRelation::Crossing, TriRelation::CoplanarOverlap},
                kMixMin);
}
