// Exact triangle-triangle relation.
//
// Non-coplanar, non-degenerate pairs follow Guigue & Devillers, "Fast and robust triangle-triangle
// overlap test using orientation predicates" (JGT 2003, corrected version): signs of each triangle's
// vertices against the other's plane, a permutation into a canonical form, then two orientation
// signs decide whether the two segments the triangles cut on the common line overlap. Every sign is
// an exact predicate (predicates.h), so there is no epsilon anywhere. The canonical-form rules and
// the sign conventions below were re-derived for our orient3d (see comments); the code is ours.
//
// Coplanar pairs are decided in 2-D on the projection that drops an axis along which the normal has
// a non-zero component (chosen by an exact sign, so the projection is a bijection of the plane):
// two convex polygons have disjoint closed sets (resp. disjoint interiors) exactly when the
// supporting line of an edge of one of them has the other strictly (resp. weakly) on its outer side
// (their Minkowski difference is bounded by lines parallel to their edges).
//
// Degenerate triangles (collinear vertices) are their convex hulls: a segment between the two
// lexicographically extreme vertices, or a point. They are tested as such, exactly.
#include "cullide/tri_tri.h"

#include <array>
#include <cstdio>
#include <utility>

#include "cullide/predicates.h"
#include "orient_plane.h"

namespace cullide {
namespace {

bool lex_less(const Vec3& a, const Vec3& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

// The axis to drop for a 2-D view of triangle (a, b, c): one where its normal component is non-zero.
// Returns -1 when the vertices are collinear (all three components are exactly 0). `sign` receives
// the orientation of the triangle in that view.
int drop_axis(const Vec3& a, const Vec3& b, const Vec3& c, int& sign) {
    for (int axis : {2, 0, 1}) {
        sign = orient2d_drop(a, b, c, axis);
        if (sign != 0) return axis;
    }
    return -1;
}

// A zero-area triangle as the set it is: the segment between its lexicographically smallest and
// largest vertex (collinear points are ordered along their line by the lexicographic order), or a
// point when those coincide.
struct Flat {
    Vec3 lo, hi;
    [[nodiscard]] bool is_point() const { return lo == hi; }
};

Flat flatten(const Vec3& a, const Vec3& b, const Vec3& c) {
    Flat f{a, a};
    for (const Vec3* p : {&b, &c}) {
        if (lex_less(*p, f.lo)) f.lo = *p;
        if (lex_less(f.hi, *p)) f.hi = *p;
    }
    return f;
}

bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
    return orient2d_drop(a, b, c, 0) == 0 && orient2d_drop(a, b, c, 1) == 0 &&
           orient2d_drop(a, b, c, 2) == 0;
}

// p in closed segment [f.lo, f.hi] (f not a point).
bool point_on_segment(const Vec3& p, const Flat& f) {
    return collinear(f.lo, f.hi, p) && !lex_less(p, f.lo) && !lex_less(f.hi, p);
}

// A non-degenerate triangle seen in its 2-D view.
struct View {
    std::array<Vec3, 3> v;
    int axis = 2;
    int sign = 1;  // orientation of v in the view

    // > 0 strictly inside edge e's line, 0 on it, < 0 strictly outside.
    [[nodiscard]] int side(int e, const Vec3& p) const {
        return sign * orient2d_drop(v[static_cast<std::size_t>(e)], v[static_cast<std::size_t>((e + 1) % 3)], p,
                                    axis);
    }
    // p (known to lie in the plane) in the closed triangle.
    [[nodiscard]] bool contains(const Vec3& p) const { return side(0, p) >= 0 && side(1, p) >= 0 && side(2, p) >= 0; }
};

// Segment [s0, s1] (s0 != s1) and the non-degenerate triangle t, all in t's plane.
bool coplanar_segment_meets(const View& t, const Vec3& s0, const Vec3& s1) {
    for (int e = 0; e < 3; ++e) {
        if (t.side(e, s0) < 0 && t.side(e, s1) < 0) return false;
    }
    int pos = 0, neg = 0;
    for (const Vec3& p : t.v) {
        const int o = orient2d_drop(s0, s1, p, t.axis);
        pos += o > 0;
        neg += o < 0;
    }
    return pos != 3 && neg != 3;
}

// The non-degenerate triangle (t0, t1, t2) and the flat set f.
bool triangle_meets_flat(const Vec3& t0, const Vec3& t1, const Vec3& t2, const Flat& f) {
    View t{{t0, t1, t2}};
    t.axis = drop_axis(t0, t1, t2, t.sign);
    const int d0 = orient3d(t0, t1, t2, f.lo);
    if (f.is_point()) return d0 == 0 && t.contains(f.lo);
    const int d1 = orient3d(t0, t1, t2, f.hi);
    if (d0 * d1 > 0) return false;
    if (d0 == 0 && d1 == 0) return coplanar_segment_meets(t, f.lo, f.hi);
    if (d0 == 0) return t.contains(f.lo);
    if (d1 == 0) return t.contains(f.hi);
    // The segment crosses the plane at one point X. The three volumes below are X's barycentric
    // coordinates times one common non-zero factor: X is in the closed triangle iff no two of them
    // have strictly opposite signs.
    const int e0 = orient3d(f.lo, f.hi, t0, t1);
    const int e1 = orient3d(f.lo, f.hi, t1, t2);
    const int e2 = orient3d(f.lo, f.hi, t2, t0);
    const bool pos = e0 > 0 || e1 > 0 || e2 > 0;
    const bool neg = e0 < 0 || e1 < 0 || e2 < 0;
    return !(pos && neg);
}

bool flat_meets_flat(const Flat& a, const Flat& b) {
    if (a.is_point() && b.is_point()) return a.lo == b.lo;
    if (a.is_point()) return point_on_segment(a.lo, b);
    if (b.is_point()) return point_on_segment(b.lo, a);
    if (orient3d(a.lo, a.hi, b.lo, b.hi) != 0) return false;  // skew lines
    // Coplanar: find a view in which three of the points are not collinear; it is a bijection of
    // their common plane.
    for (int axis : {2, 0, 1}) {
        const int o1 = orient2d_drop(a.lo, a.hi, b.lo, axis);
        const int o2 = orient2d_drop(a.lo, a.hi, b.hi, axis);
        if (o1 == 0 && o2 == 0) continue;
        const int o3 = orient2d_drop(b.lo, b.hi, a.lo, axis);
        const int o4 = orient2d_drop(b.lo, b.hi, a.hi, axis);
        return o1 * o2 <= 0 && o3 * o4 <= 0;
    }
    // All four points on one line: closed intervals in the lexicographic order.
    return !lex_less(a.hi, b.lo) && !lex_less(b.hi, a.lo);
}

// Both triangles non-degenerate and in one plane.
TriRelation coplanar_relation(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
    View va{a};
    va.axis = drop_axis(a[0], a[1], a[2], va.sign);
    View vb{b};
    vb.axis = va.axis;
    vb.sign = orient2d_drop(b[0], b[1], b[2], vb.axis);  // non-zero: same plane, bijective view
    bool weakly_separated = false;
    for (int pass = 0; pass < 2; ++pass) {
        const View& edges = pass == 0 ? va : vb;
        const View& other = pass == 0 ? vb : va;
        for (int e = 0; e < 3; ++e) {
            const int s0 = edges.side(e, other.v[0]);
            const int s1 = edges.side(e, other.v[1]);
            const int s2 = edges.side(e, other.v[2]);
            if (s0 < 0 && s1 < 0 && s2 < 0) return TriRelation::Disjoint;
            if (s0 <= 0 && s1 <= 0 && s2 <= 0) weakly_separated = true;
        }
    }
    return weakly_separated ? TriRelation::Touching : TriRelation::CoplanarOverlap;
}

// Canonical form of Guigue-Devillers for one triangle with vertex signs s (against the other
// triangle's plane): a rotation k and a direction flip such that, with t = flip * s rotated by k,
// either t = (+, <=0, <=0) or t = (0, -, -). In that form the triangle meets the plane exactly in
// the segment between the points where its edges (p, q) and (p, r) meet the plane. Every sign
// pattern that is neither all zero nor all of one strict sign has such a form.
void canonical(const std::array<int, 3>& s, int& k, int& flip) {
    for (flip = 1; flip >= -1; flip -= 2) {
        for (k = 0; k < 3; ++k) {
            const int p = flip * s[static_cast<std::size_t>(k)];
            const int q = flip * s[static_cast<std::size_t>((k + 1) % 3)];
            const int r = flip * s[static_cast<std::size_t>((k + 2) % 3)];
            if ((p > 0 && q <= 0 && r <= 0) || (p == 0 && q < 0 && r < 0)) return;
        }
    }
    k = 0;  // unreachable for the patterns the caller passes
    flip = 1;
}

bool straddles(const std::array<int, 3>& s) {
    const bool pos = s[0] > 0 || s[1] > 0 || s[2] > 0;
    const bool neg = s[0] < 0 || s[1] < 0 || s[2] < 0;
    return pos && neg;
}

template <bool kRelation>
TriRelation relate(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                   const Vec3& b2) {
    // Signs of A's vertices against B's plane; all of one strict sign: separated by that plane.
    // (orient3d(b0, b1, b2, .), with the plane's minors once: detail::Orient3dPlane.)
    const detail::Orient3dPlane plane_b(b0, b1, b2);
    const std::array<int, 3> sa{plane_b(a0), plane_b(a1), plane_b(a2)};
    if ((sa[0] > 0 && sa[1] > 0 && sa[2] > 0) || (sa[0] < 0 && sa[1] < 0 && sa[2] < 0)) {
        return TriRelation::Disjoint;
    }
    const detail::Orient3dPlane plane_a(a0, a1, a2);
    const std::array<int, 3> sb{plane_a(b0), plane_a(b1), plane_a(b2)};
    if ((sb[0] > 0 && sb[1] > 0 && sb[2] > 0) || (sb[0] < 0 && sb[1] < 0 && sb[2] < 0)) {
        return TriRelation::Disjoint;
    }
    const bool a_zero = sa[0] == 0 && sa[1] == 0 && sa[2] == 0;
    const bool b_zero = sb[0] == 0 && sb[1] == 0 && sb[2] == 0;
    if (a_zero || b_zero) {
        // A degenerate triangle has all-zero signs against its own "plane", so this is where the
        // degenerate and the coplanar cases land; otherwise both triangles span planes.
        const bool a_flat = collinear(a0, a1, a2);
        const bool b_flat = collinear(b0, b1, b2);
        bool meet = false;
        if (a_flat && b_flat) {
            meet = flat_meets_flat(flatten(a0, a1, a2), flatten(b0, b1, b2));
        } else if (a_flat) {
            meet = triangle_meets_flat(b0, b1, b2, flatten(a0, a1, a2));
        } else if (b_flat) {
            meet = triangle_meets_flat(a0, a1, a2, flatten(b0, b1, b2));
        } else {
            return coplanar_relation({a0, a1, a2}, {b0, b1, b2});
        }
        return meet ? TriRelation::Touching : TriRelation::Disjoint;
    }

    // Both planes exist and differ, so they meet in a line L, and A∩B = (A∩plane B) ∩ (B∩plane A):
    // two closed segments of L. Canonical form (see canonical()): A = (p1, q1, r1) with p1 alone on
    // the non-negative side of B's plane; flipping A's signs means reversing B's orientation.
    int ka = 0, fa = 1;
    canonical(sa, ka, fa);
    const Vec3* av[3] = {&a0, &a1, &a2};
    const Vec3* bv[3] = {&b0, &b1, &b2};
    std::array<int, 3> sbo = sb;
    if (fa < 0) {
        std::swap(bv[1], bv[2]);
        std::swap(sbo[1], sbo[2]);
    }
    int kb = 0, fb = 1;
    canonical(sbo, kb, fb);
    const Vec3& p1 = *av[ka];
    const Vec3* q1 = av[(ka + 1) % 3];
    const Vec3* r1 = av[(ka + 2) % 3];
    if (fb < 0) std::swap(q1, r1);  // reverses A's plane; A's canonical form is symmetric in q1, r1
    const Vec3& p2 = *bv[kb];
    const Vec3& q2 = *bv[(kb + 1) % 3];
    const Vec3& r2 = *bv[(kb + 2) % 3];
    // With direction v = nB x nA on L, A cuts [i, j] (i on p1q1, j on p1r1) and B cuts [l, k] (k on
    // p2q2, l on p2r2). orient3d(p1, q1, p2, q2) has the sign of t(i) - t(k) (the lines p1q1 and
    // p2q2 are coplanar exactly when they meet L at one point), and orient3d(p1, r1, p2, r2) the
    // sign of t(j) - t(l). The segments overlap iff t(i) <= t(k) and t(l) <= t(j).
    const int o1 = orient3d(p1, *q1, p2, q2);
    if (o1 > 0) return TriRelation::Disjoint;
    const int o2 = orient3d(p1, *r1, p2, r2);
    if (o2 < 0) return TriRelation::Disjoint;
    if constexpr (!kRelation) return TriRelation::Touching;  // the caller only asks "do they meet?"
    // Crossing: both triangles straddle the other's plane (then both cut segments have positive
    // length) and the overlap is not a single point: both comparisons strict.
    if (o1 < 0 && o2 > 0 && straddles(sa) && straddles(sb)) return TriRelation::Crossing;
    return TriRelation::Touching;
}

}  // namespace

const char* to_string(TriRelation r) {
    switch (r) {
        case TriRelation::Disjoint: return "disjoint";
        case TriRelation::Touching: return "touching";
        case TriRelation::Crossing: return "crossing";
        case TriRelation::CoplanarOverlap: return "coplanar-overlap";
    }
    return "?";
}

TriRelation tri_tri_relation(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                             const Vec3& b2) {
    return relate<true>(a0, a1, a2, b0, b1, b2);
}

bool tri_tri_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                       const Vec3& b2) {
    return relate<false>(a0, a1, a2, b0, b1, b2) != TriRelation::Disjoint;
}

Result<TriRelation> tri_tri_relation_checked(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                                             const Vec3& b1, const Vec3& b2) {
    const Vec3* v[6] = {&a0, &a1, &a2, &b0, &b1, &b2};
    static constexpr const char* kNames[6] = {"a0", "a1", "a2", "b0", "b1", "b2"};
    static constexpr const char* kAxes[3] = {"x", "y", "z"};
    for (int i = 0; i < 6; ++i) {
        for (int k = 0; k < 3; ++k) {
            const double x = (*v[i])[k];
            if (!predicate_coordinate_ok(x)) {
                char buf[160];
                std::snprintf(buf, sizeof buf,
                              "tri_tri_relation: vertex %s.%s = %.17g is outside the exact range "
                              "(0 or 2^-300 <= |x| <= 2^300, finite)",
                              kNames[i], kAxes[k], x);
                return Error{buf};
            }
        }
    }
    return tri_tri_relation(a0, a1, a2, b0, b1, b2);
}

}  // namespace cullide
