// raster/transform.h: CPU-side matrices and the deterministic object -> clip transform.
//
// Feeding clip coordinates to both the rasterizer and GL avoids a GPU-side matrix multiply (which
// may be fused differently), so both see identical floats. All arithmetic here is in double with
// a fixed operation order (no FMA contraction: -ffp-contract=off), rounded to float once at the end.
#pragma once

#include <array>
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

}  // namespace raster
