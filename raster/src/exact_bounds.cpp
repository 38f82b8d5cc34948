// exact_bounds.cpp: the conservative exact-bounds mode. See exact_bounds.h and
// docs/reliable-raster.md (the error analysis behind every margin below).
#include "exact_bounds.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace raster::detail {
namespace {

struct P3 {
    double v[3];
};

// Sutherland-Hodgman against the closed half-space s * p[axis] <= bound (s = +1 or -1): keeps the
// points with d = bound - s * p[axis] >= 0. A point or a segment (degenerate input) goes through the
// same loop and stays a point or a segment. New points lie on the edge between the two points they
// came from (0 <= t <= 1 in floating point too), so their depth never leaves the edge's range.
//
// A convex polygon gains at most one vertex per plane (<= 13 in all), but rounding can make a
// computed polygon very slightly non-convex; should the output ever not fit kBoundsMaxVerts, the
// input is returned unclipped: a superset, so still conservative (the margins are sized from the
// input magnitude, so they hold for unclipped coordinates too).
int clip_axis(const P3* in, int n, P3* out, int axis, double s, double bound) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const P3& cur = in[i];
        const P3& nxt = in[(i + 1) % n];
        const double dc = bound - s * cur.v[axis];
        const double dn = bound - s * nxt.v[axis];
        if (m + 2 > kBoundsMaxVerts) {
            std::copy(in, in + n, out);
            return n;
        }
        if (dc >= 0.0) out[m++] = cur;
        if ((dc >= 0.0) != (dn >= 0.0)) {
            const double t = dc / (dc - dn);
            P3 p{};
            for (int k = 0; k < 3; ++k) p.v[k] = cur.v[k] + t * (nxt.v[k] - cur.v[k]);
            out[m++] = p;
        }
    }
    return m;
}

// 2^-k as a constant.
constexpr double pow2m(int k) {
    double r = 1.0;
    for (int i = 0; i < k; ++i) r *= 0.5;
    return r;
}

// Margins (docs/reliable-raster.md): each is at least 2^8 times the rounding error it covers.
constexpr double kClipMarginRel = pow2m(40);  // clip units per unit of the triangle's magnitude M
constexpr double kPixelMargin = pow2m(20);    // pixels, for the window-space steps (|X| < 2^16)
constexpr double kDepthMargin = pow2m(40);    // window depth, for the window-space steps

constexpr double kFracGuard = pow2m(27);  // > 2^-29, the rounding error of z * n for n < 2^24

std::uint32_t unorm_max(DepthFormat f) { return f == DepthFormat::D16 ? 0xffffu : 0xffffffu; }

}  // namespace

std::uint32_t quantize_down(double z, DepthFormat format) {
    z = z > 0.0 ? z : 0.0;
    z = z < 1.0 ? z : 1.0;
    if (format == DepthFormat::D32F) {
        float f = static_cast<float>(z);
        if (static_cast<double>(f) > z) f = std::nextafter(f, -1.0f);
        return std::bit_cast<std::uint32_t>(f);
    }
    const double n = static_cast<double>(unorm_max(format));
    const double q = z * n;
    // 0 <= q < 2^24: truncation is the floor (and avoids a libm call on baseline x86-64).
    double v = static_cast<double>(static_cast<std::int64_t>(q));
    // q errs by <= 2^-29 (half an ulp below 2^24), so unless q is that close to an integer its floor
    // is the exact one (q - v is exact). Otherwise correct exactly: the sign of fma(z, n, -v) is
    // the sign of z * n - v.
    const double frac = q - v;
    if (frac >= kFracGuard && frac <= 1.0 - kFracGuard) return static_cast<std::uint32_t>(v);
    if (std::fma(z, n, -v) < 0.0) v -= 1.0;
    if (std::fma(z, n, -(v + 1.0)) >= 0.0) v += 1.0;
    v = std::clamp(v, 0.0, n);
    return static_cast<std::uint32_t>(v);
}

std::uint32_t quantize_up(double z, DepthFormat format) {
    z = z > 0.0 ? z : 0.0;
    z = z < 1.0 ? z : 1.0;
    if (format == DepthFormat::D32F) {
        float f = static_cast<float>(z);
        if (static_cast<double>(f) < z) f = std::nextafter(f, 2.0f);
        return std::bit_cast<std::uint32_t>(f);
    }
    const double n = static_cast<double>(unorm_max(format));
    const double q = z * n;
    double v = static_cast<double>(static_cast<std::int64_t>(q));
    if (v < q) v += 1.0;        // the ceiling
    const double frac = v - q;  // exact, as above
    if (frac >= kFracGuard && frac <= 1.0 - kFracGuard) return static_cast<std::uint32_t>(v);
    if (std::fma(z, n, -v) > 0.0) v += 1.0;
    if (std::fma(z, n, -(v - 1.0)) <= 0.0) v -= 1.0;
    v = std::clamp(v, 0.0, n);
    return static_cast<std::uint32_t>(v);
}

void setup_bounds_triangle(const FrontEndParams& params, const Double4& a, const Double4& b, const Double4& c,
                           std::uint32_t draw, std::vector<BoundsTri>& out, std::vector<BoundsVertex>& pool) {
    // M: the magnitude that scales every clip-space rounding error of this triangle.
    double mag = 1.0;
    for (const Double4* v : {&a, &b, &c})
        mag = std::max({mag, std::fabs(v->x), std::fabs(v->y), std::fabs(v->z)});
    const double mc = mag * kClipMarginRel;
    const double lim = 1.0 + mc;

    // Clip against the clip volume grown by mc (closed), in clip space: afterwards every coordinate
    // is within [-lim, lim] up to rounding, whatever the input magnitude.
    P3 buf_a[kBoundsMaxVerts];
    P3 buf_b[kBoundsMaxVerts];
    buf_a[0] = {{a.x, a.y, a.z}};
    buf_a[1] = {{b.x, b.y, b.z}};
    buf_a[2] = {{c.x, c.y, c.z}};
    int n = 3;
    P3* cur = buf_a;
    P3* nxt = buf_b;
    for (int axis = 0; axis < 3 && n > 0; ++axis) {
        for (double s : {1.0, -1.0}) {
            n = clip_axis(cur, n, nxt, axis, s, lim);
            std::swap(cur, nxt);
            if (n == 0) break;
        }
    }
    if (n == 0) return;

    // GL's viewport map in double: X = x * (w / 2) + (x0 + w / 2), Z = z * 0.5 + 0.5.
    const Viewport& vp = params.viewport;
    const double hw = static_cast<double>(vp.width) * 0.5;
    const double hh = static_cast<double>(vp.height) * 0.5;
    const double tx = static_cast<double>(vp.x) + hw;
    const double ty = static_cast<double>(vp.y) + hh;
    BoundsTri t;
    t.n = n;
    BoundsVertex win[kBoundsMaxVerts];
    double minx = std::numeric_limits<double>::infinity(), maxx = -minx, miny = minx, maxy = -minx;
    for (int i = 0; i < n; ++i) {
        win[i] = {cur[i].v[0] * hw + tx, cur[i].v[1] * hh + ty, cur[i].v[2] * 0.5 + 0.5};
        minx = std::min(minx, win[i].x);
        maxx = std::max(maxx, win[i].x);
        miny = std::min(miny, win[i].y);
        maxy = std::max(maxy, win[i].y);
    }
    // Clip-space errors (<= 2^-44 M per coordinate) reach window space scaled by the viewport.
    t.margin_xy = kPixelMargin + mc * std::max(hw, hh);
    t.margin_z = kDepthMargin + mc;
    t.draw = draw;

    // Closed square [px, px + 1] meets [lo, hi] iff ceil(lo) - 1 <= px <= floor(hi).
    const double bx0 = std::ceil(minx - t.margin_xy) - 1.0, bx1 = std::floor(maxx + t.margin_xy);
    const double by0 = std::ceil(miny - t.margin_xy) - 1.0, by1 = std::floor(maxy + t.margin_xy);
    const double w1 = static_cast<double>(params.target_width - 1),
                 h1 = static_cast<double>(params.target_height - 1);
    if (bx1 < 0.0 || by1 < 0.0 || bx0 > w1 || by0 > h1) return;
    t.x0 = static_cast<int>(std::max(bx0, 0.0));
    t.y0 = static_cast<int>(std::max(by0, 0.0));
    t.x1 = static_cast<int>(std::min(bx1, w1));
    t.y1 = static_cast<int>(std::min(by1, h1));
    t.first = static_cast<std::uint32_t>(pool.size());
    pool.insert(pool.end(), win, win + n);
    out.push_back(t);
}

namespace {

template <class T>
bool depth_pass(DepthFunc f, T incoming, T stored) {
    switch (f) {
        case DepthFunc::Never:
            return false;
        case DepthFunc::Less:
            return incoming < stored;
        case DepthFunc::Equal:
            return incoming == stored;
        case DepthFunc::LEqual:
            return incoming <= stored;
        case DepthFunc::Greater:
            return incoming > stored;
        case DepthFunc::NotEqual:
            return incoming != stored;
        case DepthFunc::GEqual:
            return incoming >= stored;
        case DepthFunc::Always:
            return true;
    }
    return false;
}

// One edge of a row polygon, prepared once per row: its ends and dz/dX (0 when vertical).
struct RowEdge {
    double xp, xq, zp, zq, slope, zmin, zmax;
};

int prepare_row(const P3* poly, int n, RowEdge* edges) {
    for (int i = 0; i < n; ++i) {
        const P3& p = poly[i];
        const P3& q = poly[(i + 1) % n];
        RowEdge& e = edges[i];
        e.xp = p.v[0];
        e.xq = q.v[0];
        e.zp = p.v[2];
        e.zq = q.v[2];
        e.slope = e.xq != e.xp ? (e.zq - e.zp) / (e.xq - e.xp) : 0.0;
        e.zmin = std::min(e.zp, e.zq);
        e.zmax = std::max(e.zp, e.zq);
    }
    return n;
}

// The depth range of a convex polygon (possibly a segment or a point) over the slab xl <= X <= xr:
// a linear function's extremes over polygon-and-slab lie on the polygon's boundary, so it is the
// range over each edge's part inside the slab, whose ends are the edge's vertices inside the slab
// and its crossings of the slab's sides. Which edges meet the slab is decided by exact comparisons.
// A crossing's depth zp + (bound - xp) * slope errs by <= 3 ulp of |zq - zp| <= 2^-50 (the bound
// lies between xp and xq) and is clamped to the edge's depth range: inside margin_z.
// Returns false when the polygon misses the slab.
bool column_range(const RowEdge* edges, int n, double xl, double xr, double& zlo, double& zhi) {
    bool any = false;
    zlo = std::numeric_limits<double>::infinity();
    zhi = -zlo;
    auto take = [&](double z) {
        zlo = std::min(zlo, z);
        zhi = std::max(zhi, z);
        any = true;
    };
    for (int i = 0; i < n; ++i) {
        const RowEdge& e = edges[i];
        if ((e.xp < xl && e.xq < xl) || (e.xp > xr && e.xq > xr)) continue;
        if (e.xp >= xl && e.xp <= xr) take(e.zp);
        if (e.xq >= xl && e.xq <= xr) take(e.zq);
        for (const double bound : {xl, xr}) {
            if ((e.xp < bound && e.xq > bound) || (e.xp > bound && e.xq < bound))
                take(std::clamp(e.zp + (bound - e.xp) * e.slope, e.zmin, e.zmax));
        }
    }
    return any;
}

}  // namespace

std::uint64_t bounds_rect(const BoundsTri& tri, const BoundsVertex* pool, DepthFormat format, DepthFunc func,
                          bool write, std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1) {
    const double m = tri.margin_xy;
    P3 poly[kBoundsMaxVerts];
    for (int i = 0; i < tri.n; ++i) {
        const BoundsVertex& v = pool[tri.first + static_cast<std::uint32_t>(i)];
        poly[i] = {{v.x, v.y, v.z}};
    }
    std::uint64_t passed = 0;
    P3 row_a[kBoundsMaxVerts];
    P3 row_b[kBoundsMaxVerts];
    RowEdge edges[kBoundsMaxVerts];
    for (int py = ry0; py <= ry1; ++py) {
        // The row's slab first (depends on py only), then each pixel's column.
        const double fy = static_cast<double>(py);
        int rn = clip_axis(poly, tri.n, row_a, 1, -1.0, -(fy - m));  // Y >= py - m
        if (rn == 0) continue;
        rn = clip_axis(row_a, rn, row_b, 1, 1.0, fy + 1.0 + m);  // Y <= py + 1 + m
        if (rn == 0) continue;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (int i = 0; i < rn; ++i) {
            lo = std::min(lo, row_b[i].v[0]);
            hi = std::max(hi, row_b[i].v[0]);
        }
        const int xs = std::max(rx0, static_cast<int>(std::max(std::ceil(lo - m) - 1.0, -1.0)));
        const int xe =
            std::min(rx1, static_cast<int>(std::min(std::floor(hi + m), static_cast<double>(rx1))));
        std::uint32_t* row = depth + static_cast<std::size_t>(py) * static_cast<std::size_t>(stride);
        const int ne = prepare_row(row_b, rn, edges);
        for (int px = xs; px <= xe; ++px) {
            const double fx = static_cast<double>(px);
            double zlo = 0.0, zhi = 0.0;
            if (!column_range(edges, ne, fx - m, fx + 1.0 + m, zlo, zhi)) continue;
            const std::uint32_t incoming =
                write ? quantize_down(zlo - tri.margin_z, format) : quantize_up(zhi + tri.margin_z, format);
            std::uint32_t& stored = row[px];
            const bool pass = format == DepthFormat::D32F ? depth_pass(func, std::bit_cast<float>(incoming),
                                                                       std::bit_cast<float>(stored))
                                                          : depth_pass(func, incoming, stored);
            if (pass) {
                ++passed;
                if (write) stored = incoming;
            }
        }
    }
    return passed;
}

}  // namespace raster::detail
