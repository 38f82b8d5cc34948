// exact_bounds.cpp: the conservative exact-bounds mode. See exact_bounds.h and
// docs/reliable-raster.md (the error analysis behind every margin below).
#include "exact_bounds.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace raster::detail {
namespace {

// Sutherland-Hodgman against the closed half-space s * p[axis] <= bound (s = +1 or -1): keeps the
// points with d = bound - s * p[axis] >= 0. A point or a segment (degenerate input) goes through the
// same loop and stays a point or a segment. New points lie on the edge between the two points they
// came from (0 <= t <= 1 in floating point too), so their depth never leaves the edge's range.
//
// A convex polygon gains at most one vertex per plane (<= 13 in all), but rounding can make a
// computed polygon very slightly non-convex; should the output ever not fit kBoundsMaxVerts, the
// input is returned unclipped: a superset, so still conservative (the margins are sized from the
// input magnitude, so they hold for unclipped coordinates too).
}  // namespace

int bounds_clip_axis(const BoundsP3* in, int n, BoundsP3* out, int axis, double s, double bound) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const BoundsP3& cur = in[i];
        const BoundsP3& nxt = in[i + 1 == n ? 0 : i + 1];
        const double dc = bound - s * cur.v[axis];
        const double dn = bound - s * nxt.v[axis];
        if (m + 2 > kBoundsMaxVerts) {
            std::copy(in, in + n, out);
            return n;
        }
        if (dc >= 0.0) out[m++] = cur;
        if ((dc >= 0.0) != (dn >= 0.0)) {
            const double t = dc / (dc - dn);
            BoundsP3 p{};
            for (int k = 0; k < 3; ++k) p.v[k] = cur.v[k] + t * (nxt.v[k] - cur.v[k]);
            out[m++] = p;
        }
    }
    return m;
}

namespace {

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

// floor and ceil without a libm call on baseline x86-64 (equal to std::floor / std::ceil for every
// finite x, up to the sign of a zero result: |x| >= 2^52 is already an integer).
double exact_floor(double x) {
    if (!(std::fabs(x) < 0x1p52)) return x;
    const double t = static_cast<double>(static_cast<std::int64_t>(x));
    return t > x ? t - 1.0 : t;
}
double exact_ceil(double x) {
    if (!(std::fabs(x) < 0x1p52)) return x;
    const double t = static_cast<double>(static_cast<std::int64_t>(x));
    return t < x ? t + 1.0 : t;
}

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
    BoundsP3 buf_a[kBoundsMaxVerts];
    BoundsP3 buf_b[kBoundsMaxVerts];
    buf_a[0] = {{a.x, a.y, a.z}};
    buf_a[1] = {{b.x, b.y, b.z}};
    buf_a[2] = {{c.x, c.y, c.z}};
    int n = 3;
    BoundsP3* cur = buf_a;
    BoundsP3* nxt = buf_b;
    // Trivial accept: a clip that keeps every vertex returns the triangle unchanged (mag >= every
    // |coordinate|, so only lim's rounding could matter, and the test is the clip's own d >= 0).
    // (lim - v >= 0 iff v <= lim and lim + v >= 0 iff v >= -lim: the signs of the rounded
    // differences are the exact ones.)
    double cmax = cur[0].v[0], cmin = cmax;
    for (int i = 0; i < 3; ++i)
        for (int axis = 0; axis < 3; ++axis) {
            cmax = cur[i].v[axis] > cmax ? cur[i].v[axis] : cmax;
            cmin = cur[i].v[axis] < cmin ? cur[i].v[axis] : cmin;
        }
    const bool inside = cmax <= lim && cmin >= -lim;
    for (int axis = 0; axis < 3 && n > 0 && !inside; ++axis) {
        for (double s : {1.0, -1.0}) {
            n = bounds_clip_axis(cur, n, nxt, axis, s, lim);
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
    const double bx0 = exact_ceil(minx - t.margin_xy) - 1.0, bx1 = exact_floor(maxx + t.margin_xy);
    const double by0 = exact_ceil(miny - t.margin_xy) - 1.0, by1 = exact_floor(maxy + t.margin_xy);
    const double w1 = static_cast<double>(params.target_width - 1),
                 h1 = static_cast<double>(params.target_height - 1);
    if (bx1 < 0.0 || by1 < 0.0 || bx0 > w1 || by0 > h1) return;
    t.x0 = static_cast<int>(std::max(bx0, 0.0));
    t.y0 = static_cast<int>(std::max(by0, 0.0));
    t.x1 = static_cast<int>(std::min(bx1, w1));
    t.y1 = static_cast<int>(std::min(by1, h1));
    t.single = bx0 == bx1 && by0 == by1;
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

}  // namespace

std::uint64_t bounds_rect(const BoundsTri& tri, const BoundsVertex* pool, DepthFormat format, DepthFunc func,
                          bool write, std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1) {
    std::uint64_t passed = 0;
    const bool d32f = format == DepthFormat::D32F;
    double last = std::numeric_limits<double>::quiet_NaN();  // quantize once per distinct depth
    std::uint32_t incoming = 0;
    bounds_pixels(tri, pool, rx0, ry0, rx1, ry1, [&](int px, int py, double zlo, double zhi) {
        const double z = write ? zlo : zhi;
        if (!(z == last)) {
            last = z;
            incoming = write ? quantize_down(zlo - tri.margin_z, format) : quantize_up(zhi + tri.margin_z, format);
        }
        std::uint32_t& stored = depth[static_cast<std::size_t>(py) * static_cast<std::size_t>(stride) +
                                      static_cast<std::size_t>(px)];
        const bool pass = d32f ? depth_pass(func, std::bit_cast<float>(incoming), std::bit_cast<float>(stored))
                               : depth_pass(func, incoming, stored);
        if (pass) {
            ++passed;
            if (write) stored = incoming;
        }
    });
    return passed;
}

}  // namespace raster::detail
