// cullide/predicates.h: exact orientation predicates on double coordinates.
//
// Each predicate returns the exact sign (-1, 0, +1) of a determinant of the *given* doubles, as if
// evaluated in real arithmetic. A floating-point filter with a proven error bound decides almost all
// calls; when it cannot, the determinant is recomputed exactly with floating-point expansions
// (Dekker / Knuth two-sum and two-product, expansion sums after Shewchuk, "Adaptive precision
// floating-point arithmetic and fast robust geometric predicates", 1997). Results do not depend on
// evaluation order, thread count or platform (no FMA, no excess precision).
//
// Exactness range: every coordinate x must be finite and either 0 or 2^-300 <= |x| <= 2^300
// (about 5e-91 .. 2e90; see predicate_coordinate_ok). Why: with these bounds every two-product of
// the expansions is a multiple of 2^-1056 (no underflow loses bits; the smallest double is 2^-1074)
// and every intermediate stays below 2^910 (no overflow). Outside the range the result is still a
// sign, but it is no longer guaranteed; callers that take outside data check it first
// (tri_tri_relation_checked).
#pragma once

#include "cullide/mesh.h"

namespace cullide {

inline constexpr double kPredicateMaxAbs = 0x1p300;
inline constexpr double kPredicateMinAbs = 0x1p-300;

// True when x is inside the exactness range above (0 counts; NaN and infinities do not).
[[nodiscard]] constexpr bool predicate_coordinate_ok(double x) {
    const double m = x < 0 ? -x : x;
    return x == 0 || (m >= kPredicateMinAbs && m <= kPredicateMaxAbs);
}

// Sign of det[[bx - ax, by - ay], [cx - ax, cy - ay]]: +1 when a, b, c turn counterclockwise
// (y up), -1 clockwise, 0 collinear.
[[nodiscard]] int orient2d(double ax, double ay, double bx, double by, double cx, double cy);

// Sign of det[b - a, c - a, d - a] = ((b - a) x (c - a)) . (d - a): +1 when d lies on the side of
// plane (a, b, c) that its right-handed normal (b - a) x (c - a) points to, 0 when the four points
// are coplanar. (Note: the opposite sign of Shewchuk's orient3d.)
[[nodiscard]] int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// orient2d on the projection that drops coordinate `drop` (0 = x, 1 = y, 2 = z). The kept axes are
// taken in cyclic order (drop z: x, y; drop x: y, z; drop y: z, x), so the result is the sign of
// component `drop` of (b - a) x (c - a).
[[nodiscard]] int orient2d_drop(const Vec3& a, const Vec3& b, const Vec3& c, int drop);

// Counters of how often the exact fallback's expansion arithmetic ran (per thread; for tests and
// benchmarks only). orient3d's exact small-span stage (predicates.cpp), which settles coplanar points
// of coarse grids without it, is not counted.
struct PredicateStats {
    unsigned long long orient2d_exact = 0;
    unsigned long long orient3d_exact = 0;
};
[[nodiscard]] PredicateStats predicate_stats();

}  // namespace cullide
