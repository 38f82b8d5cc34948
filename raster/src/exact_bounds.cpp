// exact_bounds.cpp: the conservative exact-bounds mode. See exact_bounds.h and
// docs/reliable-raster.md (the error analysis behind every margin below).
#include "exact_bounds.h"
#include "setup_simd.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

namespace raster::detail {

namespace {

// 2^-k as a constant.
constexpr double pow2m(int k) {
    double r = 1.0;
    for (int i = 0; i < k; ++i) r *= 0.5;
    return r;
}

}  // namespace

namespace {

// Error-bound constants of the plane path (docs/reliable-raster.md, "The plane path"); each is at
// least 2^4 times the rounding error it covers.
constexpr double kPlaneEdgeErr = pow2m(44);   // edge function: relative to its magnitude bound
constexpr double kPlaneDepthErr = pow2m(44);  // plane value: relative to its magnitude bound
constexpr double kRoundUp = 1.0 + pow2m(48);  // > (1 + 2^-53)^2: a sum of two roundings, upward
constexpr int kPlaneMinBoxPixels = 4;  // pixel boxes up to this many pixels take the general path
// Tightness limits: beyond them the general path is taken (a looser bound would still be correct).
constexpr double kPlaneMaxSlackPx = pow2m(20);  // edge slack, in pixels
constexpr double kPlaneMaxDepthErr = pow2m(36); // depth widening beyond the square's own range

// Chooses the per-pixel path of a (non-single) polygon `win` of n vertices with pixel box
// [t.x0, t.x1] x [t.y0, t.y1]; fills t.kind and, for the plane path, `plane`.
// (minx .. maxy: the polygon's coordinate ranges, as setup_bounds_triangle computed them.)
void classify_bounds_triangle(BoundsTri& t, const BoundsVertex* win, int n, double minx, double maxx, double miny,
                              double maxy, BoundsPlane& plane) {
    // Column path: every vertex has the same X, or every column of the pixel box holds the whole
    // polygon's X range in its grown interval [px - m, px + 1 + m] (thin triangles one or two
    // columns wide). Then the part of the polygon above a pixel's grown square is its part over the
    // row slab, whose depth range the column path reads off the boundary. Row path: the same with
    // X and Y exchanged. (The bounds are computed as bounds_pixels computes them.)
    const double m = t.margin_xy;
    if (minx == maxx ||
        (static_cast<double>(t.x1) - m <= minx && maxx <= static_cast<double>(t.x0) + 1.0 + m)) {
        t.kind = BoundsTri::Kind::Column;
        return;
    }
    if (miny == maxy ||
        (static_cast<double>(t.y1) - m <= miny && maxy <= static_cast<double>(t.y0) + 1.0 + m)) {
        t.kind = BoundsTri::Kind::Row;
        return;
    }
    if (n != 3) return;  // clipped polygons (and segments) take the general path
    // Small boxes: the general path is about as fast there and exact on partly covered pixels.
    if ((t.x1 - t.x0 + 1) * (t.y1 - t.y0 + 1) <= kPlaneMinBoxPixels) return;
    // Local coordinates relative to the anchor pixel (x0, y0): each is one rounding (<= 2^-53 * 2^17
    // = 2^-36 pixels) away from the window vertex; the triangle T'' of these local vertices is what
    // the tests below bound (docs: that drift is far inside margin_xy).
    const double ax = static_cast<double>(t.x0), ay = static_cast<double>(t.y0);
    double lx[3], ly[3], lz[3];
    // P bounds |local coordinate| of the vertices and of every point of every grown pixel square
    // of the box: [-m, (x1 - x0) + 1 + m] (m is large only for huge inputs, M >= 2^30 or so, whose
    // clipped polygon may still have 3 vertices; the bounds below then refuse the path).
    double big = static_cast<double>(std::max(t.x1 - t.x0, t.y1 - t.y0)) + 2.0 + 2.0 * m;
    for (int i = 0; i < 3; ++i) {
        lx[i] = win[i].x - ax;
        ly[i] = win[i].y - ay;
        lz[i] = win[i].z;
        big = std::max({big, std::fabs(lx[i]), std::fabs(ly[i])});
    }
    const double dx1 = lx[1] - lx[0], dy1 = ly[1] - ly[0], dz1 = lz[1] - lz[0];
    const double dx2 = lx[2] - lx[0], dy2 = ly[2] - ly[0], dz2 = lz[2] - lz[0];
    const double area = dx1 * dy2 - dy1 * dx2;  // twice the signed area (rounded)
    if (!(std::fabs(area) > 0.0) || !std::isfinite(area)) return;
    const double sgn = area > 0.0 ? 1.0 : -1.0;
    BoundsPlane d;  // every field is set below before it is stored
    for (int i = 0; i < 3; ++i) {
        const int j = i == 2 ? 0 : i + 1;
        // E(x, y) = A x + B y + C, >= 0 on the inner side of edge (i, j) when the orientation is
        // right; the slack eta below makes the half-plane hold all three vertices regardless.
        const double a = sgn * (ly[i] - ly[j]);
        const double b = sgn * (lx[j] - lx[i]);
        const double c = -(a * lx[i] + b * ly[i]);
        // err bounds the rounding of every evaluation of E (vertices, corners) and of the corner
        // constant: fewer than 16 roundings, each <= 2^-53 of a magnitude <= this bound.
        const double err = kPlaneEdgeErr * ((std::fabs(a) + std::fabs(b)) * big + std::fabs(c));
        double eta = 0.0;  // -min over the vertices of E (computed), at least 0
        for (int k = 0; k < 3; ++k) eta = std::max(eta, -(a * lx[k] + b * ly[k] + c));
        eta = (eta + err) * kRoundUp;  // exact E at every vertex >= -eta
        if (!(eta <= kPlaneMaxSlackPx * (std::fabs(a) + std::fabs(b)))) return;  // orientation unsure / sliver
        // The maximum of E over the grown square [lx - m, lx + 1 + m] x [ly - m, ly + 1 + m] is
        // A lx + B ly + (C + max(A (1 + m), -A m) + max(B (1 + m), -B m)).
        const double ox = a > 0.0 ? a * (1.0 + m) : -a * m;
        const double oy = b > 0.0 ? b * (1.0 + m) : -b * m;
        d.ea[i] = a;
        d.inv_a[i] = a != 0.0 ? 1.0 / a : 0.0;
        d.eb[i] = b;
        d.ek[i] = c + ox + oy;
        // Dropped when the computed maximum < et: then the exact maximum < -eta <= E everywhere on
        // the triangle (computed + err < et + err <= -eta).
        d.et[i] = -((eta + err) * kRoundUp);
        if (!std::isfinite(d.ek[i]) || !std::isfinite(d.et[i])) return;
    }
    // Plane through the three local vertices: z = z0 + gx (x - x0) + gy (y - y0); stored as the
    // value at the centre of the anchor pixel, pz = z0 + gx (0.5 - x0) + gy (0.5 - y0). Whatever its
    // rounding, the vertex residuals below bound how far this plane P' is from the triangle's.
    const double gx = (dz1 * dy2 - dz2 * dy1) / area;
    const double gy = (dx1 * dz2 - dx2 * dz1) / area;
    const double pz = lz[0] + gx * (0.5 - lx[0]) + gy * (0.5 - ly[0]);
    if (!std::isfinite(gx) || !std::isfinite(gy) || !std::isfinite(pz)) return;
    const double g = std::fabs(gx) + std::fabs(gy);
    // Magnitude bound of every plane evaluation (vertices, pixel centres, the +- widening).
    const double zmag = 2.0 + std::fabs(pz) + g * (big + 1.0);
    const double zerr = kPlaneDepthErr * zmag;
    double res = 0.0;  // max |z_k - P'(vertex k)| (computed; its own rounding is inside zerr)
    for (int k = 0; k < 3; ++k)
        res = std::max(res, std::fabs(lz[k] - (pz + gx * (lx[k] - 0.5) + gy * (ly[k] - 0.5))));
    const double extra = (res + 2.0 * zerr) * kRoundUp;  // residual + evaluation errors
    if (!(extra <= kPlaneMaxDepthErr)) return;
    d.pz = pz;
    d.pgx = gx;
    d.pgy = gy;
    // P' over the grown square: centre value +- (|gx| + |gy|) (1/2 + m).
    d.pw = (g * (0.5 + m) + extra) * kRoundUp * kRoundUp;
    d.pzlo = std::min({lz[0], lz[1], lz[2]});
    d.pzhi = std::max({lz[0], lz[1], lz[2]});
    // A slab range's crossing z = zp + (s - tp) * slope, clamped to the edge's depth range, is
    // within 4 roundings of (|zp| + |dz|) <= 3 max|z| of the exact crossing of the (window) edge.
    d.sw = kPlaneDepthErr * (3.0 * std::max(std::fabs(d.pzlo), std::fabs(d.pzhi)) + 1.0);
    if (!std::isfinite(d.pw)) return;
    plane = d;
    t.kind = BoundsTri::Kind::Plane;
}

}  // namespace

namespace {

// The end of a polygon's setup, once its box, margins and single flag are set (and it is not
// outside the target): its per-pixel path, then the polygon (and plane) into the pool and the record
// into `out`.
void emit_bounds_polygon(BoundsTri& t, const BoundsVertex* win, double minx, double maxx, double miny, double maxy,
                         std::vector<BoundsTri>& out, std::vector<BoundsVertex>& pool) {
    BoundsPlane plane;
    if (!t.single) classify_bounds_triangle(t, win, t.n, minx, maxx, miny, maxy, plane);
    t.first = static_cast<std::uint32_t>(pool.size());
    for (int i = 0; i < t.n; ++i) pool.push_back(win[i]);
    if (t.kind == BoundsTri::Kind::Plane) {
        const std::size_t at = pool.size();
        pool.resize(at + kPlaneSlots);
        std::memcpy(static_cast<void*>(pool.data() + at), &plane, sizeof plane);
    }
    out.push_back(t);
}

}  // namespace

void setup_bounds_triangle(const FrontEndParams& params, const Double4& a, const Double4& b, const Double4& c,
                           std::uint32_t draw, std::vector<BoundsTri>& out, std::vector<BoundsVertex>& pool) {
    // M = max(1, every |coordinate|): the magnitude that scales every clip-space rounding error of
    // this triangle. (Straight-line code for the three vertices: the same maxima as a loop, which
    // the compiler does not unroll; no value is NaN.)
    const double absmax = std::max(std::max(std::max(std::max(std::fabs(a.x), std::fabs(a.y)), std::fabs(a.z)),
                                            std::max(std::max(std::fabs(b.x), std::fabs(b.y)), std::fabs(b.z))),
                                   std::max(std::max(std::fabs(c.x), std::fabs(c.y)), std::fabs(c.z)));
    const double mag = std::max(1.0, absmax);
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
    // Trivial accept: a clip that keeps every vertex returns the triangle unchanged, and it keeps
    // them all iff every coordinate v has lim - v >= 0 and lim + v >= 0 (the clip's own d >= 0; the
    // signs of those rounded differences are the exact ones), i.e. iff every |v| <= lim: one
    // compare of the largest |v|, which M needs anyway.
    const bool inside = absmax <= lim;
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
    if (inside) {  // the input triangle: the same arithmetic, unrolled
        win[0] = {a.x * hw + tx, a.y * hh + ty, a.z * 0.5 + 0.5};
        win[1] = {b.x * hw + tx, b.y * hh + ty, b.z * 0.5 + 0.5};
        win[2] = {c.x * hw + tx, c.y * hh + ty, c.z * 0.5 + 0.5};
        minx = std::min(std::min(win[0].x, win[1].x), win[2].x);
        maxx = std::max(std::max(win[0].x, win[1].x), win[2].x);
        miny = std::min(std::min(win[0].y, win[1].y), win[2].y);
        maxy = std::max(std::max(win[0].y, win[1].y), win[2].y);
    } else {
        for (int i = 0; i < n; ++i) {
            win[i] = {cur[i].v[0] * hw + tx, cur[i].v[1] * hh + ty, cur[i].v[2] * 0.5 + 0.5};
            minx = std::min(minx, win[i].x);
            maxx = std::max(maxx, win[i].x);
            miny = std::min(miny, win[i].y);
            maxy = std::max(maxy, win[i].y);
        }
    }
    // Clip-space errors (<= 2^-44 M per coordinate) reach window space scaled by the viewport.
    t.margin_xy = kPixelMargin + mc * std::max(hw, hh);
    t.margin_z = kDepthMargin + mc;
    t.draw = draw;

    // Closed square [px, px + 1] meets [lo, hi] iff ceil(lo) - 1 <= px <= floor(hi).
    const GrownBox box = grown_box(minx, maxx, miny, maxy, t.margin_xy);
    if (box.outside(params.target_width, params.target_height)) return;
    box.cut(params.target_width, params.target_height, t.x0, t.y0, t.x1, t.y1);
    t.single = box.bx0 == box.bx1 && box.by0 == box.by1;
    emit_bounds_polygon(t, win, minx, maxx, miny, maxy, out, pool);
}

void setup_bounds_range(const FrontEndParams& params, std::span<const Double4> vertices,
                        std::span<const std::uint32_t> indices, std::uint32_t draw, std::vector<BoundsTri>& out,
                        std::vector<BoundsVertex>& pool, bool allow_simd) {
    const std::size_t n_tris = indices.size() / 3;
    std::size_t k = 0;
    if (allow_simd && kernel_avx2_available()) {
        const Viewport& vp = params.viewport;
        BoundsViewport bv{};
        bv.hw = static_cast<double>(vp.width) * 0.5;
        bv.hh = static_cast<double>(vp.height) * 0.5;
        bv.tx = static_cast<double>(vp.x) + bv.hw;
        bv.ty = static_cast<double>(vp.y) + bv.hh;
        bv.hmax = std::max(bv.hw, bv.hh);
        bv.width = params.target_width;
        bv.height = params.target_height;
        BoundsLanes4 io;
        for (; k + 4 <= n_tris; k += 4) {
            for (int t = 0; t < 4; ++t)
                for (int c = 0; c < 3; ++c) {
                    const Double4& v = vertices[indices[3 * (k + static_cast<std::size_t>(t)) + static_cast<std::size_t>(c)]];
                    io.v[c][0][t] = v.x;
                    io.v[c][1][t] = v.y;
                    io.v[c][2][t] = v.z;
                }
            bounds_lanes4_avx2(io, bv);
            for (int t = 0; t < 4; ++t) {
                const std::size_t base = 3 * (k + static_cast<std::size_t>(t));
                if (!((io.inside >> t) & 1u)) {  // clipped: the scalar path
                    setup_bounds_triangle(params, vertices[indices[base]], vertices[indices[base + 1]],
                                          vertices[indices[base + 2]], draw, out, pool);
                    continue;
                }
                if ((io.outside >> t) & 1u) continue;
                BoundsTri tri;
                tri.n = 3;
                tri.margin_xy = io.margin_xy[t];
                tri.margin_z = io.margin_z[t];
                tri.draw = draw;
                tri.x0 = io.x0[t], tri.y0 = io.y0[t], tri.x1 = io.x1[t], tri.y1 = io.y1[t];
                tri.single = ((io.single >> t) & 1u) != 0;
                const BoundsVertex win[3] = {{io.win[0][0][t], io.win[0][1][t], io.win[0][2][t]},
                                             {io.win[1][0][t], io.win[1][1][t], io.win[1][2][t]},
                                             {io.win[2][0][t], io.win[2][1][t], io.win[2][2][t]}};
                emit_bounds_polygon(tri, win, io.minx[t], io.maxx[t], io.miny[t], io.maxy[t], out, pool);
            }
        }
    }
    for (; k < n_tris; ++k)
        setup_bounds_triangle(params, vertices[indices[3 * k]], vertices[indices[3 * k + 1]], vertices[indices[3 * k + 2]],
                              draw, out, pool);
}

namespace {

// bounds_rect for one depth function and format class (D32F compares floats, D16/D24 integers):
// the per-pixel callback is then a few instructions, inlined into the traversal.
template <DepthFunc F, bool D32F>
std::uint64_t bounds_rect_impl(const BoundsTri& tri, const BoundsVertex* pool, DepthFormat format, bool write,
                               DepthRows depth, PixelRect rect) {
    std::uint64_t passed = 0;
    const double mz = tri.margin_z;
    const auto pass_at = [](std::uint32_t in, std::uint32_t st) __attribute__((always_inline)) {
        if constexpr (D32F)
            return depth_pass<F>(std::bit_cast<float>(in), std::bit_cast<float>(st));
        else
            return depth_pass<F>(in, st);
    };
    // Constant depth (screen-parallel faces): the plane path gives every covered pixel exactly [z, z]
    // (the clamp to the vertex range [z, z]), so one quantized value for the triangle and a plain
    // loop over each row's span: the same values as the traversal below.
    const bool flat_plane = tri.kind == BoundsTri::Kind::Plane && pool[tri.first].z == pool[tri.first + 1].z &&
                            pool[tri.first].z == pool[tri.first + 2].z;
    if (flat_plane) {
        const BoundsPlane d = load_plane(tri, pool);
        const std::uint32_t in = write ? quantize_down(d.pzlo - mz, format) : quantize_up(d.pzhi + mz, format);
        const int ys = std::max(rect.y0, tri.y0), ye = std::min(rect.y1, tri.y1);
        const int xs = std::max(rect.x0, tri.x0), xe = std::min(rect.x1, tri.x1);
        for (int py = ys; py <= ye; ++py) {
            int lo = xs - tri.x0, hi = xe - tri.x0;
            plane_row_span(d, static_cast<double>(py - tri.y0), lo, hi);
            std::uint32_t* row = depth.row(py) + static_cast<std::size_t>(tri.x0);
            std::uint64_t n = 0;
            if (write) {
                for (int x = lo; x <= hi; ++x) {
                    const bool p = pass_at(in, row[x]);
                    n += p ? 1u : 0u;
                    row[x] = p ? in : row[x];
                }
            } else {
                for (int x = lo; x <= hi; ++x) n += pass_at(in, row[x]) ? 1u : 0u;
            }
            passed += n;
        }
        return passed;
    }
    double last = std::numeric_limits<double>::quiet_NaN();  // quantize once per distinct depth
    std::uint32_t incoming = 0;
    bounds_pixels(tri, pool, rect, [&](int px, int py, double zlo, double zhi) __attribute__((always_inline)) {
        const double z = write ? zlo : zhi;
        if (!(z == last)) {
            last = z;
            incoming = write ? quantize_down(zlo - mz, format) : quantize_up(zhi + mz, format);
        }
        std::uint32_t& stored = depth.row(py)[px];
        if (pass_at(incoming, stored)) {
            ++passed;
            if (write) stored = incoming;
        }
    });
    return passed;
}

}  // namespace

std::uint64_t bounds_rect(const BoundsTri& tri, const BoundsVertex* pool, const DepthState& state, DepthRows depth,
                          PixelRect rect) {
    // One traversal per depth function and format class (D32F compares floats, D16 and D24
    // unsigned integers); the format and the write stay run-time values inside it.
    return dispatch_depth(state, [&]<DepthFormat Fmt, DepthFunc F, bool Write>() -> std::uint64_t {
        if constexpr (F == DepthFunc::Never) {
            return 0;  // nothing passes, nothing is written
        } else {
            return bounds_rect_impl<F, Fmt == DepthFormat::D32F>(tri, pool, state.format, Write, depth, rect);
        }
    });
}

}  // namespace raster::detail
