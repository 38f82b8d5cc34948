// transform.cpp: deterministic CPU-side matrices (double, fixed operation order).
#include "raster/transform.h"

#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>

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

namespace {

double& axis_ref(Double3& p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }
double axis_of(const Double3& p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }

}  // namespace

void view_axis_indices(Axis axis, int& u, int& v, int& d) {
    d = axis == Axis::X ? 0 : (axis == Axis::Y ? 1 : 2);
    u = (d + 1) % 3;
    v = (d + 2) % 3;
}

Result<OrthoView> make_ortho_view(Axis axis, Double3 box_min, Double3 box_max, int width, int height,
                                  DepthFormat format) {
    if (axis != Axis::X && axis != Axis::Y && axis != Axis::Z)
        return Error{"ortho view: axis " + std::to_string(static_cast<int>(axis)) + " is not X, Y or Z"};
    static const char* kNames[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
        const double lo = axis_of(box_min, k), hi = axis_of(box_max, k);
        if (!std::isfinite(lo) || !std::isfinite(hi))
            return Error{std::string("ortho view: box bound along ") + kNames[k] + " is not finite"};
        if (!(lo < hi))
            return Error{std::string("ortho view: box is empty along ") + kNames[k] + " (min " + std::to_string(lo) +
                         " >= max " + std::to_string(hi) + ")"};
        const double scale = 2.0 / (hi - lo);
        if (!std::isfinite(hi - lo) || !std::isfinite(scale) || scale == 0.0)
            return Error{std::string("ortho view: box extent along ") + kNames[k] + " is outside the double range"};
    }
    if (width < 1 || height < 1 || width > kMaxTargetSize || height > kMaxTargetSize)
        return Error{"ortho view: resolution " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxTargetSize) + " per side"};
    if (format != DepthFormat::D16 && format != DepthFormat::D24 && format != DepthFormat::D32F)
        return Error{"ortho view: depth format " + std::to_string(static_cast<int>(format)) + " is not D16, D24 or D32F"};
    OrthoView v;
    v.axis = axis;
    v.box_min = box_min;
    v.box_max = box_max;
    v.width = width;
    v.height = height;
    v.format = format;
    return v;
}

Double3 view_axes(const OrthoView& view, Double3 world) {
    int u = 0, v = 0, d = 0;
    view_axis_indices(view.axis, u, v, d);
    return Double3{axis_of(world, u), axis_of(world, v), axis_of(world, d)};
}

namespace {

// The view's box corner and scale along its (u, v, d) axes, and d: chosen once per call, not per
// point (view_axes per point was 3% of a leaves / rcullide frame, with the transform itself 5%,
// perf). Every ortho_view_to_clip uses them, so each gives a point the same values.
struct ClipParams {
    Double3 lo, scale;
    int d = 0;
};
ClipParams clip_params(const OrthoView& view) {
    ClipParams c;
    c.lo = view_axes(view, view.box_min);
    const Double3 hi = view_axes(view, view.box_max);
    for (int k = 0; k < 3; ++k) axis_ref(c.scale, k) = 2.0 / (axis_of(hi, k) - axis_of(c.lo, k));
    int u = 0, v = 0;
    view_axis_indices(view.axis, u, v, c.d);
    return c;
}

// One point's transform (the arithmetic of every ortho_view_to_clip); false when a result is not
// finite.
template <int U, int V, int D>
inline bool point_to_clip(const Double3& lo, const Double3& scale, const Double3& p, Double4& c) {
    const auto at = [](const Double3& q, auto k) { return k == 0 ? q.x : (k == 1 ? q.y : q.z); };
    c.x = (at(p, std::integral_constant<int, U>{}) - lo.x) * scale.x - 1.0;
    c.y = (at(p, std::integral_constant<int, V>{}) - lo.y) * scale.y - 1.0;
    c.z = (at(p, std::integral_constant<int, D>{}) - lo.z) * scale.z - 1.0;
    c.w = 1.0;
    return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
}
// The transform of the points at(0) .. at(count - 1) (indices into points and out) with the view's
// axes (u, v, d: view_axis_indices) as constants. Returns the first k whose point's clip
// coordinates are not all finite, or count. A point with a coordinate that is not finite is one of
// those: (inf - lo) * scale is an infinity or NaN, and NaN stays NaN.
template <class At>
std::size_t to_clip(const ClipParams& c, std::span<const Double3> points, std::size_t count, At at, Double4* out) {
    const auto run = [&](auto u, auto v, auto d) {
        for (std::size_t k = 0; k < count; ++k) {
            const std::size_t i = at(k);
            if (!point_to_clip<decltype(u)::value, decltype(v)::value, decltype(d)::value>(c.lo, c.scale, points[i],
                                                                                           out[i]))
                return k;
        }
        return count;
    };
    using std::integral_constant;
    return c.d == 0   ? run(integral_constant<int, 1>{}, integral_constant<int, 2>{}, integral_constant<int, 0>{})
           : c.d == 1 ? run(integral_constant<int, 2>{}, integral_constant<int, 0>{}, integral_constant<int, 1>{})
                      : run(integral_constant<int, 0>{}, integral_constant<int, 1>{}, integral_constant<int, 2>{});
}

// Both overloads' checks of `out` and their error for a point that failed: its input, or the overflow.
std::optional<Error> wrong_output(std::span<const Double3> points, std::span<Double4> out) {
    if (out.size() == points.size()) return std::nullopt;
    return Error{"ortho_view_to_clip: the output holds " + std::to_string(out.size()) + " points for " +
                 std::to_string(points.size())};
}
Error bad_point(std::span<const Double3> points, std::size_t i) {
    const Double3& p = points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        return Error{"ortho_view_to_clip: point " + std::to_string(i) + " is not finite"};
    return Error{"ortho_view_to_clip: point " + std::to_string(i) + " overflows the double range in clip space"};
}

}  // namespace

Result<std::size_t> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points,
                                       std::vector<Double4>& out) {
    out.resize(points.size());
    return ortho_view_to_clip(view, points, std::span<Double4>(out));
}

Result<std::size_t> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points,
                                       std::span<Double4> out) {
    if (std::optional<Error> e = wrong_output(points, out)) return *e;
    const std::size_t bad =
        to_clip(clip_params(view), points, points.size(), [](std::size_t k) { return k; }, out.data());
    if (bad != points.size()) return bad_point(points, bad);  // the first offence
    return points.size();
}

Result<std::size_t> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points,
                                       std::span<const std::uint32_t> which, std::span<Double4> out) {
    if (std::optional<Error> e = wrong_output(points, out)) return *e;
    for (const std::uint32_t i : which)
        if (i >= points.size())
            return Error{"ortho_view_to_clip: index " + std::to_string(i) + " is out of range (" +
                         std::to_string(points.size()) + " points)"};
    const std::size_t bad =
        to_clip(clip_params(view), points, which.size(), [&](std::size_t k) { return std::size_t{which[k]}; }, out.data());
    if (bad != which.size()) return bad_point(points, which[bad]);
    return which.size();
}

Result<std::vector<Double4>> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points) {
    std::vector<Double4> out;
    Result<std::size_t> r = ortho_view_to_clip(view, points, out);
    if (!r) return r.error();
    return out;
}

ViewCell view_cell(const OrthoView& view) {
    const Double3 lo = view_axes(view, view.box_min);
    const Double3 hi = view_axes(view, view.box_max);
    double quantum = 0.0;
    switch (view.format) {
        case DepthFormat::D16: quantum = 1.0 / 65535.0; break;
        case DepthFormat::D24: quantum = 1.0 / 16777215.0; break;
        case DepthFormat::D32F: quantum = 1.0 / 16777216.0; break;
    }
    ViewCell c;
    c.dx = (hi.x - lo.x) / static_cast<double>(view.width);
    c.dy = (hi.y - lo.y) / static_cast<double>(view.height);
    c.dz = (hi.z - lo.z) * quantum;
    return c;
}

}  // namespace raster
