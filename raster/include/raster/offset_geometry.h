// raster/offset_geometry.h: R-CULLIDE's offset solids as ordinary triangles (Govindaraju, Lin,
// Manocha, "Fast and Reliable Collision Culling using Graphics Hardware", VRST 2004 / TVCG 2006).
//
// The paper makes pixel-centre rasterization conservative by drawing, instead of each triangle, the
// Minkowski sum of the triangle with a cube of side p = max(2 dx, 2 dy, 2 dz) (dx, dy: a pixel, dz:
// a depth quantum, in world units), in practice with a sphere of radius r = sqrt(3) p / 2 so any
// view axis works, and bounding that by a box. Whole objects use a union of oriented boxes (UOBB).
// The query draws the far faces (CullFace::Front culls the near ones) with GEQUAL and the mask off;
// the write draws the near faces (CullFace::Back) with LEQUAL and the mask on.
//
// Output: float clip-space vertices (w = 1) + indices for MeshView, drawn with RasterMode::GLExact
// (or through OSMesa: the same floats). Every box is closed (12 triangles, 8 corners) and wound so
// that, with FrontFace::CCW, its faces towards the viewer are front faces. Every double -> float
// conversion rounds outward (axis-aligned boxes: min down, max up per coordinate; oriented boxes:
// grown first by more than the float rounding of their corners), so each box contains the exact
// offset solid's box. Boxes are clamped to the view in clip space (x, y to [-2, 2], z to [-1, 1];
// GL has no depth clamp and its float clipper loses precision on huge boxes): the clamped box covers
// the same pixels, writes depth 0 where it reached past the near plane and is queried at depth 1
// where it reached past the far plane, both conservative. An oriented box that would need clamping
// is replaced by its clamped axis-aligned bounding box. View: raster/transform.h (OrthoView).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "raster/result.h"
#include "raster/transform.h"
#include "raster/types.h"

namespace raster {

struct OffsetMesh {
    std::vector<Float4> vertices;
    std::vector<std::uint32_t> indices;
    [[nodiscard]] MeshView view() const { return MeshView{vertices, indices}; }
};

// r = sqrt(3) p / 2 with p = max(2 dx, 2 dy, 2 dz) of view_cell(view), rounded up.
[[nodiscard]] double offset_radius(const OrthoView& view);

// (a) One axis-aligned box per triangle: the triangle's world bounding box grown by
// offset_radius(view) on every side. Box t occupies vertices [8t, 8t + 8) and indices [36t, 36t + 36).
// Fails (naming the triangle and the index) on an index out of range, a count not a multiple of 3,
// or a non-finite coordinate.
[[nodiscard]] Result<OffsetMesh> triangle_offset_boxes(const OrthoView& view,
                                                       std::span<const Double3> vertices,
                                                       std::span<const std::uint32_t> indices);

// (b) A union of oriented boxes for one object: its triangles in consecutive groups of
// `triangles_per_box` (index order), each group bounded by an oriented box grown by
// offset_radius(view). The box's frame is the least-volume one of: the view axes, and the group's
// largest triangle's normal with each of its edges. Same validation as (a); triangles_per_box >= 1.
[[nodiscard]] Result<OffsetMesh> object_offset_obbs(const OrthoView& view, std::span<const Double3> vertices,
                                                    std::span<const std::uint32_t> indices,
                                                    std::uint32_t triangles_per_box = 16);

}  // namespace raster
