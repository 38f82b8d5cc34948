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
inline constexpr std::uint32_t kObbTrianglesPerBox = 16;  // (b)'s default group
[[nodiscard]] Result<OffsetMesh> object_offset_obbs(const OrthoView& view, std::span<const Double3> vertices,
                                                    std::span<const std::uint32_t> indices,
                                                    std::uint32_t triangles_per_box = kObbTrianglesPerBox);

// Parts of (a) and (b), written in place, for callers that prepare one large object per view on
// several threads and keep the memory between views. `out` must already hold every box of the whole
// list (size_offset_boxes(boxes, out); (a) has one box per triangle, (b) ceil(triangles /
// triangles_per_box)); the call writes boxes [first_box, last_box) only (vertices [8 first_box,
// 8 last_box), indices [36 first_box, 36 last_box)), the same values as the whole call writes there,
// so parts over disjoint ranges may run at once. It validates the triangles of its part only (a whole
// call validates the whole list before any box: a caller that runs parts on unvalidated input and
// wants the whole call's first error validates first) and fails, naming the triangle or box, on the
// same problems as the whole call, or when `out` is not sized for `total_boxes` or the range lies
// beyond it. Returns the part's largest overshoot of the clip depth range, max(0, z - 1, -1 - z) over
// its box corners (the solids of a view that fits have none).
[[nodiscard]] Result<double> triangle_offset_boxes_part(const OrthoView& view, std::span<const Double3> vertices,
                                                        std::span<const std::uint32_t> indices, std::size_t first_box,
                                                        std::size_t last_box, OffsetMesh& out);
[[nodiscard]] Result<double> object_offset_obbs_part(const OrthoView& view, std::span<const Double3> vertices,
                                                     std::span<const std::uint32_t> indices, std::size_t first_box,
                                                     std::size_t last_box, OffsetMesh& out,
                                                     std::uint32_t triangles_per_box = kObbTrianglesPerBox);
// What triangle_offset_boxes_part would return for the same boxes (their overshoot, or the same
// failure), without writing them: for a caller that draws only some of a view's boxes but fits the
// view to all of them.
[[nodiscard]] Result<double> triangle_offset_boxes_overshoot(const OrthoView& view, std::span<const Double3> vertices,
                                                             std::span<const std::uint32_t> indices,
                                                             std::size_t first_box, std::size_t last_box);
// Sizes `out` for `boxes` boxes (8 vertices and 36 indices each), keeping its capacity.
void size_offset_boxes(std::size_t boxes, OffsetMesh& out);

}  // namespace raster
