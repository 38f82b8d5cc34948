// orient_plane.h: orient3d against one plane for several points (internal; the library is built
// with -ffp-contract=off, which the filter below assumes, so this is not a public header).
#pragma once

#include <cmath>

#include "cullide/predicates.h"

namespace cullide::detail {

// The filter's constants (predicates.cpp, "filters", has the derivation).
inline constexpr double kOrient3dBound = 9.0 * 0x1p-53;  // C = 9u: |det_computed| > C * P_computed decides
inline constexpr double kFilterMinPermanent = 0x1p-600;  // below it the filter is not trusted

// orient3d(a, b, c, d) for one plane (a, b, c) and several points d. orient3d evaluates
// det = u . (v x w) with u = b - a, v = c - a, w = d - a; the triple product is cyclic, so det is also
// w . (u x v), and u x v depends on the plane only: its three minors (and their magnitudes for the
// permanent) are computed once, and each point costs three differences, a dot product and its
// permanent instead of the whole evaluation. Every monomial of the determinant is still rounded at
// most 8 times (the differences of its three factors, two products, the minor's subtraction, two
// additions) and the permanent is evaluated the same way from the same rounded differences, so
// orient3d's bound C = 9u holds unchanged (predicates.cpp). Where it does not decide, orient3d
// itself answers. So the sign is orient3d's, exactly, for every d. The plane keeps references to
// its corners: it lives while they do (a local of the test that holds them). Triangle-triangle
// tests ask three points against each triangle's plane (tri_tri.cpp): orient3d was 22% of a
// 1-thread tori frame of `exact` (perf, session 25).
class Orient3dPlane {
public:
    Orient3dPlane(const Vec3& a, const Vec3& b, const Vec3& c) : a_(a), b_(b), c_(c) {
        const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
        const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
        const double p1 = uy * vz, p2 = uz * vy;
        const double p3 = uz * vx, p4 = ux * vz;
        const double p5 = ux * vy, p6 = uy * vx;
        nx_ = p1 - p2;
        ny_ = p3 - p4;
        nz_ = p5 - p6;
        mx_ = std::fabs(p1) + std::fabs(p2);
        my_ = std::fabs(p3) + std::fabs(p4);
        mz_ = std::fabs(p5) + std::fabs(p6);
    }

    // == orient3d(a, b, c, d).
    [[nodiscard]] int operator()(const Vec3& d) const {
        const double wx = d.x - a_.x, wy = d.y - a_.y, wz = d.z - a_.z;
        const double det = wx * nx_ + wy * ny_ + wz * nz_;
        const double permanent = std::fabs(wx) * mx_ + std::fabs(wy) * my_ + std::fabs(wz) * mz_;
        if (permanent >= kFilterMinPermanent) {
            const double bound = kOrient3dBound * permanent;
            if (det > bound) return 1;
            if (-det > bound) return -1;
        }
        return orient3d(a_, b_, c_, d);
    }

private:
    const Vec3& a_;
    const Vec3& b_;
    const Vec3& c_;
    double nx_, ny_, nz_;  // u x v, rounded as above
    double mx_, my_, mz_;  // the magnitudes of its two products per component
};

}  // namespace cullide::detail
