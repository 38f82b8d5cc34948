// exact_bounds_reference.cpp: see exact_bounds_reference.h.
#include "exact_bounds_reference.h"

#include <bit>
#include <cmath>

namespace raster_ref {
namespace {

mpq_class& coord(QPoint& p, int axis) { return axis == 0 ? p.x : (axis == 1 ? p.y : p.z); }
const mpq_class& coord(const QPoint& p, int axis) { return axis == 0 ? p.x : (axis == 1 ? p.y : p.z); }

// Keeps s * p[axis] <= bound (closed), exactly.
std::vector<QPoint> clip(const std::vector<QPoint>& in, int axis, int s, const mpq_class& bound) {
    std::vector<QPoint> out;
    const std::size_t n = in.size();
    for (std::size_t i = 0; i < n; ++i) {
        const QPoint& cur = in[i];
        const QPoint& nxt = in[(i + 1) % n];
        const mpq_class dc = bound - s * coord(cur, axis);
        const mpq_class dn = bound - s * coord(nxt, axis);
        if (sgn(dc) >= 0) out.push_back(cur);
        if ((sgn(dc) >= 0) != (sgn(dn) >= 0)) {
            const mpq_class t = dc / (dc - dn);
            QPoint p;
            for (int k = 0; k < 3; ++k) coord(p, k) = coord(cur, k) + t * (coord(nxt, k) - coord(cur, k));
            out.push_back(p);
        }
    }
    return out;
}

mpq_class q(double v) { return mpq_class(v); }

int floor_int(const mpq_class& v) {
    mpz_class f;
    mpz_fdiv_q(f.get_mpz_t(), v.get_num_mpz_t(), v.get_den_mpz_t());
    return static_cast<int>(f.get_si());
}
int ceil_int(const mpq_class& v) {
    mpz_class f;
    mpz_cdiv_q(f.get_mpz_t(), v.get_num_mpz_t(), v.get_den_mpz_t());
    return static_cast<int>(f.get_si());
}

}  // namespace

ExactTriangle::ExactTriangle(const raster::Viewport& vp, const raster::Double4& a, const raster::Double4& b,
                             const raster::Double4& c) {
    std::vector<QPoint> p = {{q(a.x), q(a.y), q(a.z)}, {q(b.x), q(b.y), q(b.z)}, {q(c.x), q(c.y), q(c.z)}};
    for (int axis = 0; axis < 3 && !p.empty(); ++axis) {
        p = clip(p, axis, 1, mpq_class(1));
        if (!p.empty()) p = clip(p, axis, -1, mpq_class(1));
    }
    const mpq_class hw = mpq_class(vp.width, 2), hh = mpq_class(vp.height, 2);
    for (QPoint& v : p) {
        v.x = v.x * hw + (vp.x + hw);
        v.y = v.y * hh + (vp.y + hh);
        v.z = v.z / 2 + mpq_class(1, 2);
    }
    poly_ = std::move(p);
    if (poly_.empty()) return;
    mpq_class lx = poly_[0].x, hx = lx, ly = poly_[0].y, hy = ly;
    for (const QPoint& v : poly_) {
        if (v.x < lx) lx = v.x;
        if (v.x > hx) hx = v.x;
        if (v.y < ly) ly = v.y;
        if (v.y > hy) hy = v.y;
    }
    // Closed square [px, px + 1] meets [lo, hi] iff ceil(lo) - 1 <= px <= floor(hi).
    x0 = ceil_int(lx) - 1;
    x1 = floor_int(hx);
    y0 = ceil_int(ly) - 1;
    y1 = floor_int(hy);
}

PixelRange ExactTriangle::pixel(int px, int py) const {
    PixelRange r;
    if (poly_.empty() || px < x0 || px > x1 || py < y0 || py > y1) return r;
    std::vector<QPoint> p = clip(poly_, 0, -1, mpq_class(-px));
    if (!p.empty()) p = clip(p, 0, 1, mpq_class(px + 1));
    if (!p.empty()) p = clip(p, 1, -1, mpq_class(-py));
    if (!p.empty()) p = clip(p, 1, 1, mpq_class(py + 1));
    if (p.empty()) return r;
    r.covered = true;
    r.zmin = p[0].z;
    r.zmax = p[0].z;
    for (const QPoint& v : p) {
        if (v.z < r.zmin) r.zmin = v.z;
        if (v.z > r.zmax) r.zmax = v.z;
    }
    return r;
}

mpq_class stored_depth(std::uint32_t value, raster::DepthFormat format) {
    switch (format) {
        case raster::DepthFormat::D16:
            return mpq_class(value, 65535u);
        case raster::DepthFormat::D24:
            return mpq_class(value, 16777215u);
        case raster::DepthFormat::D32F:
            return mpq_class(static_cast<double>(std::bit_cast<float>(value)));
    }
    return mpq_class(0);
}

std::uint32_t floor_value(const mpq_class& z, raster::DepthFormat format) {
    if (format == raster::DepthFormat::D32F) {
        // Walk from the nearest float (z is in [0, 1]: a few steps at most).
        float f = static_cast<float>(z.get_d());
        while (mpq_class(static_cast<double>(f)) > z) f = std::nextafter(f, -1.0f);
        while (f < 1.0f && mpq_class(static_cast<double>(std::nextafter(f, 2.0f))) <= z)
            f = std::nextafter(f, 2.0f);
        return std::bit_cast<std::uint32_t>(f);
    }
    const unsigned n = format == raster::DepthFormat::D16 ? 65535u : 16777215u;
    return static_cast<std::uint32_t>(floor_int(z * n));
}

std::uint32_t ceil_value(const mpq_class& z, raster::DepthFormat format) {
    if (format == raster::DepthFormat::D32F) {
        float f = static_cast<float>(z.get_d());
        while (mpq_class(static_cast<double>(f)) < z) f = std::nextafter(f, 2.0f);
        while (f > 0.0f && mpq_class(static_cast<double>(std::nextafter(f, -1.0f))) >= z)
            f = std::nextafter(f, -1.0f);
        return std::bit_cast<std::uint32_t>(f);
    }
    const unsigned n = format == raster::DepthFormat::D16 ? 65535u : 16777215u;
    return static_cast<std::uint32_t>(ceil_int(z * n));
}

}  // namespace raster_ref
