// transform.cpp: deterministic CPU-side matrices (double, fixed operation order).
#include "raster/transform.h"

#include <cmath>
#include <numbers>
#include <string>

namespace raster {

Mat4 Mat4::identity() {
    Mat4 r;
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0;
    return r;
}

Result<Mat4> ortho(double l, double r, double b, double t, double n, double f) {
    for (double v : {l, r, b, t, n, f})
        if (!std::isfinite(v)) return Error{"ortho: a parameter is not finite"};
    if (l == r || b == t || n == f) return Error{"ortho: left == right, bottom == top or near == far"};
    Mat4 m;
    m.m[0] = 2.0 / (r - l);
    m.m[5] = 2.0 / (t - b);
    m.m[10] = -2.0 / (f - n);
    m.m[12] = -(r + l) / (r - l);
    m.m[13] = -(t + b) / (t - b);
    m.m[14] = -(f + n) / (f - n);
    m.m[15] = 1.0;
    return m;
}

Result<Mat4> perspective(double fovy_degrees, double aspect, double n, double f) {
    for (double v : {fovy_degrees, aspect, n, f})
        if (!std::isfinite(v)) return Error{"perspective: a parameter is not finite"};
    if (!(fovy_degrees > 0.0 && fovy_degrees < 180.0)) return Error{"perspective: fovy must be in (0, 180) degrees"};
    if (!(aspect > 0.0)) return Error{"perspective: aspect must be > 0"};
    if (!(n > 0.0 && n < f)) return Error{"perspective: need 0 < near < far"};
    const double cot = 1.0 / std::tan(fovy_degrees * (std::numbers::pi / 360.0));
    Mat4 m;
    m.m[0] = cot / aspect;
    m.m[5] = cot;
    m.m[10] = (f + n) / (n - f);
    m.m[11] = -1.0;
    m.m[14] = (2.0 * f * n) / (n - f);
    return m;
}

Mat4 multiply(const Mat4& a, const Mat4& b) {
    Mat4 r;
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row) {
            double s = 0.0;
            for (int k = 0; k < 4; ++k) s = s + a.m[k * 4 + row] * b.m[col * 4 + k];
            r.m[col * 4 + row] = s;
        }
    return r;
}

Result<std::vector<Float4>> transform_to_clip(const Mat4& m, std::span<const Double3> points) {
    std::vector<Float4> out;
    out.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Double3& p = points[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return Error{"transform_to_clip: point " + std::to_string(i) + " is not finite"};
        double r[4];
        for (int row = 0; row < 4; ++row)
            r[row] = ((m.m[row] * p.x + m.m[4 + row] * p.y) + m.m[8 + row] * p.z) + m.m[12 + row];
        Float4 v{static_cast<float>(r[0]), static_cast<float>(r[1]), static_cast<float>(r[2]), static_cast<float>(r[3])};
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z) || !std::isfinite(v.w))
            return Error{"transform_to_clip: point " + std::to_string(i) + " overflows float in clip space"};
        out.push_back(v);
    }
    return out;
}

}  // namespace raster
