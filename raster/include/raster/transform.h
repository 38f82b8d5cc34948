// raster/transform.h: CPU-side matrices and the deterministic object -> clip transform.
//
// Feeding clip coordinates to both the rasterizer and GL avoids a GPU-side matrix multiply (which
// may be fused differently), so both see identical floats. All arithmetic here is in double with
// a fixed operation order (no FMA contraction: -ffp-contract=off), rounded to float once at the end.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "raster/result.h"
#include "raster/types.h"

namespace raster {

// Column-major 4x4 (GL layout): m[col * 4 + row].
struct Mat4 {
    std::array<double, 16> m{};
    [[nodiscard]] static Mat4 identity();
};

struct Double3 {
    double x = 0.0;
    double y = 0.0;
    double z = 0.0;
};

// glOrtho(left, right, bottom, top, near, far). Fails when a pair is equal or non-finite.
[[nodiscard]] Result<Mat4> ortho(double left, double right, double bottom, double top, double near_z,
                                 double far_z);
// gluPerspective(fovy_degrees, aspect, near, far). Fails unless 0 < fovy < 180, aspect > 0,
// 0 < near < far, all finite.
[[nodiscard]] Result<Mat4> perspective(double fovy_degrees, double aspect, double near_z, double far_z);
// a * b (apply b first).
[[nodiscard]] Mat4 multiply(const Mat4& a, const Mat4& b);

// clip = m * (p, 1) for each point, each row summed left to right, then rounded to float.
// Fails (naming the index) on a non-finite input or result.
[[nodiscard]] Result<std::vector<Float4>> transform_to_clip(const Mat4& m, std::span<const Double3> points);

// ---- Orthographic views along a world axis (CULLIDE's views; docs/reliable-raster.md) ----

enum class Axis : std::uint8_t { X, Y, Z };

// An orthographic view of the world box [box_min, box_max] along `axis`, onto a width x height
// target of depth format `format`. The screen axes (u, v) and the depth axis d are a cyclic
// permutation of (x, y, z), so the map keeps orientation:
//   Axis::Z: (u, v, d) = (x, y, z)    Axis::X: (u, v, d) = (y, z, x)    Axis::Y: (u, v, d) = (z, x, y)
// Clip coordinates (w = 1): clip_u = 2 (u - u_min) / (u_max - u_min) - 1, likewise v and d, so the
// box fills the viewport and clip z = -1 (window depth 0, nearest) is the box's min along the axis:
// the viewer looks in the +axis direction. Built only by make_ortho_view (validated).
struct OrthoView {
    Axis axis = Axis::Z;
    Double3 box_min;
    Double3 box_max;
    int width = 1;
    int height = 1;
    DepthFormat format = DepthFormat::D24;
};

// Fails (naming the field) unless every bound is finite, box_min < box_max on every axis (strictly,
// also after the scale 2 / (max - min) is formed: no overflow to inf or 0), 1 <= width, height <=
// kMaxTargetSize and the format is one of the three.
[[nodiscard]] Result<OrthoView> make_ortho_view(Axis axis, Double3 box_min, Double3 box_max, int width, int height,
                                                DepthFormat format);

// The world axis index (0 = x, 1 = y, 2 = z) that becomes screen u, v and depth d for `axis`: the
// cyclic permutation above. For loops over many points, which then need not decode it per point.
void view_axis_indices(Axis axis, int& u, int& v, int& d);

// World -> (u, v, d) of the view (the cyclic permutation above; exact).
[[nodiscard]] Double3 view_axes(const OrthoView& view, Double3 world);

// World points -> double clip coordinates (w = 1) by the formula above, evaluated in double as
// ((u - u_min) * s_u) - 1 with s_u = 2 / (u_max - u_min): each result is within 3 ulp(max(1, |clip|))
// + 2^-52 of the exact value, far inside the exact-bounds mode's margin (>= 2^-40 clip units,
// docs/reliable-raster.md), so the composition stays conservative. Fails on a non-finite point or
// result (naming the index).
[[nodiscard]] Result<std::vector<Double4>> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points);
// The same into `out` (resized to the point count; its storage is reused, so a caller transforming
// the same geometry view after view allocates only while it grows). On failure `out` is unspecified.
[[nodiscard]] Result<std::size_t> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points,
                                                     std::vector<Double4>& out);
// The same into a caller's span of exactly points.size() elements (an error otherwise), so that
// parts of one large point list can be transformed in parallel into their own parts of one output.
// Errors name the index within `points`.
[[nodiscard]] Result<std::size_t> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points,
                                                     std::span<Double4> out);
// The same for the points that `which` names only (out[i] = the transform of points[i] for each i in
// `which`, by the same arithmetic, so bit for bit the values above; a point may be named several
// times; the other elements of `out` are left as they are): for a caller whose draws read only
// some of a mesh's vertices. `out` must hold points.size() elements; an index out of range is an
// error, and so is a non-finite point or result (naming its index in `points`).
[[nodiscard]] Result<std::size_t> ortho_view_to_clip(const OrthoView& view, std::span<const Double3> points,
                                                     std::span<const std::uint32_t> which, std::span<Double4> out);

// The view's cell in world units: dx, dy = one pixel along u, v; dz = one depth quantum along d
// (D16: 1/65535, D24: 1/16777215, D32F: 2^-24, the largest float spacing in [0.5, 1]) times the
// box's depth extent. R-CULLIDE's offset uses p = max(2 dx, 2 dy, 2 dz) (raster/offset_geometry.h).
struct ViewCell {
    double dx = 0;
    double dy = 0;
    double dz = 0;
};
[[nodiscard]] ViewCell view_cell(const OrthoView& view);

}  // namespace raster
