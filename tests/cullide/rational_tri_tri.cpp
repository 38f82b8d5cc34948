// The rational reference: exact constructions in mpq_class (see rational_tri_tri.h).
#include "rational_tri_tri.h"

#include <gmpxx.h>

#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace cullide::test {
namespace {

using Q = mpq_class;

struct QV {
    Q x, y, z;
};

QV to_q(const Vec3& v) { return {Q(v.x), Q(v.y), Q(v.z)}; }
QV sub(const QV& a, const QV& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
QV add(const QV& a, const QV& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
QV mul(const Q& s, const QV& a) { return {s * a.x, s * a.y, s * a.z}; }
Q dot(const QV& a, const QV& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
QV cross(const QV& a, const QV& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
bool is_zero(const QV& a) { return sgn(a.x) == 0 && sgn(a.y) == 0 && sgn(a.z) == 0; }
bool equal(const QV& a, const QV& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

using Tri3 = std::array<QV, 3>;

// Closed half-space {x : m . (x - o) >= 0}.
struct HalfSpace {
    QV m, o;
};

// Sutherland-Hodgman: the convex polygon `poly` (vertices in order; possibly degenerate, i.e.
// collinear or repeated points) clipped by a closed half-space. The result is the exact
// intersection, as a vertex cycle (possibly with repeats); empty when they do not meet.
std::vector<QV> clip(const std::vector<QV>& poly, const HalfSpace& h) {
    std::vector<QV> out;
    const std::size_t n = poly.size();
    if (n == 0) return out;
    std::vector<Q> f(n);
    for (std::size_t i = 0; i < n; ++i) f[i] = dot(h.m, sub(poly[i], h.o));
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t j = (i + 1) % n;
        if (sgn(f[i]) >= 0) out.push_back(poly[i]);
        if ((sgn(f[i]) > 0 && sgn(f[j]) < 0) || (sgn(f[i]) < 0 && sgn(f[j]) > 0)) {
            const Q s = f[i] / (f[i] - f[j]);
            out.push_back(add(poly[i], mul(s, sub(poly[j], poly[i]))));
        }
    }
    return out;
}

// The five half-spaces whose intersection is the non-degenerate triangle t with normal n.
std::array<HalfSpace, 5> triangle_halfspaces(const Tri3& t, const QV& n) {
    std::array<HalfSpace, 5> h;
    h[0] = {n, t[0]};
    h[1] = {mul(Q(-1), n), t[0]};
    for (std::size_t i = 0; i < 3; ++i) {
        // n x (edge) points to the left of the edge seen from n: into a triangle counterclockwise
        // about its own normal.
        h[2 + i] = {cross(n, sub(t[(i + 1) % 3], t[i])), t[i]};
    }
    return h;
}

std::vector<QV> clip_by_triangle(std::vector<QV> poly, const Tri3& t, const QV& n) {
    for (const HalfSpace& h : triangle_halfspaces(t, n)) {
        poly = clip(poly, h);
        if (poly.empty()) break;
    }
    return poly;
}

// Twice the vector area of a planar polygon cycle: zero exactly when it has no area.
bool has_area(const std::vector<QV>& poly) {
    if (poly.size() < 3) return false;
    QV acc{Q(0), Q(0), Q(0)};
    for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
        acc = add(acc, cross(sub(poly[i], poly[0]), sub(poly[i + 1], poly[0])));
    }
    return !is_zero(acc);
}

// A zero-area triangle as a segment [p, q] between its two farthest-apart vertices (p == q: point).
std::pair<QV, QV> flat_extent(const Tri3& t) {
    std::size_t bi = 0, bj = 1;
    Q best = -1;
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = i + 1; j < 3; ++j) {
            const QV d = sub(t[j], t[i]);
            const Q len2 = dot(d, d);
            if (len2 > best) {
                best = len2;
                bi = i;
                bj = j;
            }
        }
    }
    return {t[bi], t[bj]};
}

bool point_on_segment(const QV& p, const QV& s, const QV& e) {
    const QV d = sub(e, s);
    const QV r = sub(p, s);
    if (!is_zero(cross(d, r))) return false;
    const Q t = dot(r, d);
    return sgn(t) >= 0 && t <= dot(d, d);
}

bool flats_meet(const std::pair<QV, QV>& a, const std::pair<QV, QV>& b) {
    const bool a_point = equal(a.first, a.second);
    const bool b_point = equal(b.first, b.second);
    if (a_point && b_point) return equal(a.first, b.first);
    if (a_point) return point_on_segment(a.first, b.first, b.second);
    if (b_point) return point_on_segment(b.first, a.first, a.second);
    const QV d1 = sub(a.second, a.first);
    const QV d2 = sub(b.second, b.first);
    const QV r = sub(b.first, a.first);
    const QV c = cross(d1, d2);
    if (!is_zero(c)) {
        if (sgn(dot(r, c)) != 0) return false;  // skew
        // a.first + s d1 = b.first + t d2; crossing with d2 and d1 isolates s and t.
        const Q cc = dot(c, c);
        const Q s = dot(cross(r, d2), c) / cc;
        const Q t = dot(cross(r, d1), c) / cc;
        return sgn(s) >= 0 && s <= 1 && sgn(t) >= 0 && t <= 1;
    }
    if (!is_zero(cross(r, d1))) return false;  // parallel, distinct lines
    const Q dd = dot(d1, d1);
    Q t0 = dot(r, d1) / dd;
    Q t1 = dot(sub(b.second, a.first), d1) / dd;
    if (t0 > t1) std::swap(t0, t1);
    return t0 <= 1 && sgn(t1) >= 0;
}

struct Interval {
    bool empty = true;
    Q lo, hi;
    void add(const Q& t) {
        if (empty) {
            lo = t;
            hi = t;
            empty = false;
        } else {
            if (t < lo) lo = t;
            if (t > hi) hi = t;
        }
    }
};

// Parameters along direction u of the points where triangle t (signed distances d to the other
// plane, not all zero, not all of one strict sign) meets that plane.
Interval cut_interval(const Tri3& t, const std::array<Q, 3>& d, const QV& u) {
    std::array<Q, 3> tu{dot(u, t[0]), dot(u, t[1]), dot(u, t[2])};
    Interval iv;
    for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t j = (i + 1) % 3;
        if (sgn(d[i]) == 0) iv.add(tu[i]);
        if ((sgn(d[i]) > 0 && sgn(d[j]) < 0) || (sgn(d[i]) < 0 && sgn(d[j]) > 0)) {
            const Q s = d[i] / (d[i] - d[j]);
            iv.add(tu[i] + s * (tu[j] - tu[i]));
        }
    }
    return iv;
}

bool one_strict_sign(const std::array<Q, 3>& d) {
    return (sgn(d[0]) > 0 && sgn(d[1]) > 0 && sgn(d[2]) > 0) || (sgn(d[0]) < 0 && sgn(d[1]) < 0 && sgn(d[2]) < 0);
}
bool straddles(const std::array<Q, 3>& d) {
    const bool pos = sgn(d[0]) > 0 || sgn(d[1]) > 0 || sgn(d[2]) > 0;
    const bool neg = sgn(d[0]) < 0 || sgn(d[1]) < 0 || sgn(d[2]) < 0;
    return pos && neg;
}

}  // namespace

TriRelation rational_tri_tri_relation(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                                      const Vec3& b1, const Vec3& b2) {
    // The relation does not change when all coordinates are multiplied by one power of two, so
    // scale them to integers first: integer rationals (denominator 1) make GMP skip most gcd work.
    const Vec3* in[6] = {&a0, &a1, &a2, &b0, &b1, &b2};
    int min_exp = 0;
    bool any = false;
    for (const Vec3* v : in) {
        for (int k = 0; k < 3; ++k) {
            const double x = (*v)[k];
            if (x == 0) continue;
            int e = 0;
            (void)std::frexp(x, &e);  // |x| = m 2^e, m in [0.5, 1): x is a multiple of 2^(e - 53)
            if (!any || e - 53 < min_exp) min_exp = e - 53;
            any = true;
        }
    }
    auto q = [&](const Vec3& v) {
        QV r = to_q(v);
        for (Q* c : {&r.x, &r.y, &r.z}) {
            if (min_exp < 0) {
                mpq_mul_2exp(c->get_mpq_t(), c->get_mpq_t(), static_cast<mp_bitcnt_t>(-min_exp));
            } else {
                mpq_div_2exp(c->get_mpq_t(), c->get_mpq_t(), static_cast<mp_bitcnt_t>(min_exp));
            }
        }
        return r;
    };
    const Tri3 a{q(a0), q(a1), q(a2)};
    const Tri3 b{q(b0), q(b1), q(b2)};
    const QV na = cross(sub(a[1], a[0]), sub(a[2], a[0]));
    const QV nb = cross(sub(b[1], b[0]), sub(b[2], b[0]));
    const bool a_flat = is_zero(na);
    const bool b_flat = is_zero(nb);
    if (a_flat && b_flat) return flats_meet(flat_extent(a), flat_extent(b)) ? TriRelation::Touching : TriRelation::Disjoint;
    if (a_flat || b_flat) {
        const Tri3& flat = a_flat ? a : b;
        const Tri3& full = a_flat ? b : a;
        const std::vector<QV> cut = clip_by_triangle({flat[0], flat[1], flat[2]}, full, a_flat ? nb : na);
        return cut.empty() ? TriRelation::Disjoint : TriRelation::Touching;
    }
    // Signed distances (times |n|) of each triangle's vertices to the other's plane.
    const std::array<Q, 3> da{dot(nb, sub(a[0], b[0])), dot(nb, sub(a[1], b[0])), dot(nb, sub(a[2], b[0]))};
    if (one_strict_sign(da)) return TriRelation::Disjoint;
    const std::array<Q, 3> db{dot(na, sub(b[0], a[0])), dot(na, sub(b[1], a[0])), dot(na, sub(b[2], a[0]))};
    if (one_strict_sign(db)) return TriRelation::Disjoint;
    if (sgn(da[0]) == 0 && sgn(da[1]) == 0 && sgn(da[2]) == 0) {
        const std::vector<QV> common = clip_by_triangle({a[0], a[1], a[2]}, b, nb);
        if (common.empty()) return TriRelation::Disjoint;
        return has_area(common) ? TriRelation::CoplanarOverlap : TriRelation::Touching;
    }
    // Distinct planes meeting in a line with direction u; each triangle cuts an interval of it.
    const QV u = cross(na, nb);
    const Interval ia = cut_interval(a, da, u);
    const Interval ib = cut_interval(b, db, u);
    const Q lo = ia.lo > ib.lo ? ia.lo : ib.lo;
    const Q hi = ia.hi < ib.hi ? ia.hi : ib.hi;
    if (lo > hi) return TriRelation::Disjoint;
    if (lo < hi && straddles(da) && straddles(db)) return TriRelation::Crossing;
    return TriRelation::Touching;
}

int rational_orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const Q d = (Q(bx) - Q(ax)) * (Q(cy) - Q(ay)) - (Q(by) - Q(ay)) * (Q(cx) - Q(ax));
    return sgn(d);
}

int rational_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const QV qa = to_q(a);
    return sgn(dot(cross(sub(to_q(b), qa), sub(to_q(c), qa)), sub(to_q(d), qa)));
}

}  // namespace cullide::test
