// rational_tri_tri.h: the slow exact reference of the triangle-triangle test (tests only).
//
// Deliberately a different method from cullide/tri_tri.cpp: no orientation predicates and no
// Guigue-Devillers case analysis. Everything is *constructed* in GMP rationals (mpq_class), which
// represent every double exactly: plane equations, the points where each triangle's edges cross the
// other's plane, their parameters along the common line (Moller's interval method, made exact),
// polygon clipping (Sutherland-Hodgman) for coplanar and flat cases, and explicit line solving for
// segment pairs. It returns the same TriRelation, per the definitions of cullide/tri_tri.h.
#pragma once

#include "cullide/mesh.h"
#include "cullide/tri_tri.h"

namespace cullide::test {

[[nodiscard]] TriRelation rational_tri_tri_relation(const Vec3& a0, const Vec3& a1, const Vec3& a2,
                                                    const Vec3& b0, const Vec3& b1, const Vec3& b2);

// Exact signs of the determinants of cullide/predicates.h, evaluated in rationals.
[[nodiscard]] int rational_orient2d(double ax, double ay, double bx, double by, double cx, double cy);
[[nodiscard]] int rational_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace cullide::test
