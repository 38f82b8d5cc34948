// cullide_detail.h (private): view helpers of cullide.cpp shared with quick_cullide.cpp.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "cullide/cullide.h"
#include "cullide/quick_cullide.h"
#include "cullide/visibility.h"
#include "cullide/mesh.h"
#include "cullide/result.h"
#include "raster/transform.h"

namespace cullide::detail {

// The smallest box holding both (an empty box is the identity). Inline: the views unite every live
// item's box, thousands per view.
[[nodiscard]] inline Aabb unite(const Aabb& a, const Aabb& b) {
    if (a.empty()) return b;
    if (b.empty()) return a;
    return {{std::min(a.lo.x, b.lo.x), std::min(a.lo.y, b.lo.y), std::min(a.lo.z, b.lo.z)},
            {std::max(a.hi.x, b.hi.x), std::max(a.hi.y, b.hi.y), std::max(a.hi.z, b.hi.z)}};
}
// triangle_bounds written into `box` field by field: inline for the loops that box every triangle
// of a frame, where an Aabb returned by value and copied into a list was packed through the stack
// and read back before its stores had landed (store-forwarding stalls). std::min / std::max of two
// keep the first of equal values, as of a list: triangle_bounds' bits, signed zeros included.
inline void triangle_box(const Mesh& mesh, std::size_t triangle, Aabb& box) {
    const Tri& t = mesh.triangles[triangle];
    const Vec3& a = mesh.positions[t[0]];
    const Vec3& b = mesh.positions[t[1]];
    const Vec3& c = mesh.positions[t[2]];
    box.lo.x = std::min(std::min(a.x, b.x), c.x), box.hi.x = std::max(std::max(a.x, b.x), c.x);
    box.lo.y = std::min(std::min(a.y, b.y), c.y), box.hi.y = std::max(std::max(a.y, b.y), c.y);
    box.lo.z = std::min(std::min(a.z, b.z), c.z), box.hi.z = std::max(std::max(a.z, b.z), c.z);
}
// Grows [lo, hi] by a margin that keeps geometry on its faces inside the clip volume after the
// clip coordinates are rounded to float.
void widen(double& lo, double& hi);
// The orthographic view along `axis` fitted to `bounds` (widened as above), with `extra_depth` more
// world units before and after along the axis, of `size` pixels and `format`.
[[nodiscard]] Result<raster::OrthoView> make_view(int axis, const Aabb& bounds, double extra_depth, ViewSize size,
                                                  raster::DepthFormat format);

// A GL-exact view's clip-space depth as the batch's rules want it, rounded to float once: GL's z
// in [-1, 1] as it is, Vulkan's (z + 1) / 2 in [0, 1] (the same window depth).
[[nodiscard]] inline float gl_exact_clip_depth(double clip_z, raster::RasterRules rules) {
    return static_cast<float>(rules == raster::RasterRules::Vulkan ? (clip_z + 1.0) * 0.5 : clip_z);
}

// Points per parallel job of a view's transform: one job per object left the second thread idle
// where one object holds most of the points (the tree of leaves, the dragon, the cloth).
inline constexpr std::size_t kTransformPart = 4096;

// One part of an object's points into the same part of its clip arrays (spans of equal length), as
// every view's preparation does: double clip coordinates (raster::ortho_view_to_clip) and, when
// `clip` is not empty (GL-exact), the floats every device draws (one rounding per coordinate,
// gl_exact_clip_depth). False when the transform fails; the caller names the problem.
[[nodiscard]] bool transform_to_clip(const raster::OrthoView& view, std::span<const raster::Double3> points,
                                     std::span<raster::Double4> clip_d, std::span<raster::Float4> clip,
                                     raster::RasterRules rules);

// The checks every visibility method makes before drawing anything: option ranges, a valid scene,
// `active` strictly increasing and in range, and every active object's coordinates inside the
// exact range (with the ground truth's message, so all methods refuse alike). Returns the views'
// size: the one place a method's resolution is checked and its default applied. scene_checked:
// the caller has checked every object already (validate_mesh and validate_exact_range_of, as
// process_frame does before it runs a method), so those two scans are not repeated.
[[nodiscard]] Result<ViewSize> check_visibility_inputs(std::span<const Mesh> objects,
                                                       std::span<const std::uint32_t> active,
                                                       const VisibilityOptions& o, VisibilityMode mode,
                                                       bool scene_checked = false);

// The box of triangles [first, last) of `mesh`'s vertices (empty when first >= last): mesh_bounds is
// this over every triangle, and object_bounds over parts that it unites in order (the same bits).
[[nodiscard]] Aabb triangles_bounds(const Mesh& mesh, std::size_t first, std::size_t last);

// Every active object's mesh_bounds (the union of its triangles' boxes; empty without triangles), in
// jobs of at most kBoundsTriangles triangles on `threads` workers, folded in job order. std::min and
// std::max keep the earlier of equal values, so the boxes are mesh_bounds' bits (signed zeros
// included) for any thread count. One job per object left a thread alone with the one object that
// holds most of the triangles (the tree of leaves, the dragon, the cloth), and Quick-CULLIDE's box
// stage ran mesh_bounds serially.
inline constexpr std::size_t kBoundsTriangles = 8192;
[[nodiscard]] std::vector<Aabb> object_bounds(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                              int threads);

// True when validate_mesh and validate_exact_range_of find nothing in any object: each has
// triangles, every coordinate is inside the exact range (finite included) and every index is in
// range. In jobs of at most kCheckPart positions or triangles, so that one big object does not hold
// one thread alone; a caller runs the per-object checks only when this is false, for their messages.
inline constexpr std::size_t kCheckPart = 16384;
[[nodiscard]] bool scene_clean(std::span<const Mesh> objects, int threads);

// What Quick-CULLIDE's self stage may keep from one frame to the next (FrameContext): per object
// index, the triangle order it chose and that order's window, with the topology they are a function
// of (the triangles, the welded vertex ids and the group size). An entry is used only when all three
// are equal to the frame's, so a frame's results are the same with it, without it, or with one that
// other scenes filled. The order costs two breadth-first searches and two window scans per object
// per frame (about 10% of a `qcullide --self` cloth frame, on the calling thread alone), while a
// deforming mesh's topology, and so its order, rarely changes from frame to frame.
struct QuickSelfCache {
    struct Entry {
        std::vector<Tri> triangles;
        std::vector<std::uint32_t> weld;
        std::size_t group = 0;
        std::vector<std::uint32_t> order;
        std::uint32_t window = 0;
        bool valid = false;
    };
    std::vector<Entry> entries;  // by object index
};

// cullide_pairs and quick_cullide_pairs for a caller that has checked the scene (scene_checked as
// above); the public functions are these with scene_checked = false. `self_cache` (optional): see
// QuickSelfCache.
[[nodiscard]] Result<std::vector<TrianglePair>> cullide_pairs(std::span<const Mesh> objects,
                                                              std::span<const std::uint32_t> active,
                                                              const CullideOptions& options, QueryDevice& device,
                                                              CullideStats* stats, bool scene_checked);
[[nodiscard]] Result<std::vector<TrianglePair>> quick_cullide_pairs(std::span<const Mesh> objects,
                                                                    std::span<const std::uint32_t> active,
                                                                    const QuickOptions& options, QueryDevice& device,
                                                                    QuickStats* stats, bool scene_checked,
                                                                    QuickSelfCache* self_cache = nullptr);

// The order of one recorded Quick-CULLIDE pass over n items (quick_cullide.cpp, and the recorded
// form of raster::WindowedPasses): forward, for k = 0 .. n-1, query(k), then write(d) for every item
// d not yet written whose window ends at or before k (near_hi(d) <= k; near_hi non-decreasing), except
// after the last query; backward the mirror image with near_lo (non-decreasing too). The callbacks
// decide themselves whether an item is queried or drawn.
template <class NearLo, class NearHi, class Query, class Write>
void quick_pass_schedule(std::size_t n, bool forward, NearLo&& near_lo, NearHi&& near_hi, Query&& query, Write&& write) {
    std::size_t cursor = 0;  // draws scheduled so far, counted from the pass's start
    for (std::size_t step = 0; step < n; ++step) {
        const std::size_t k = forward ? step : n - 1 - step;
        query(k);
        if (step + 1 == n) break;  // nothing is queried after the last item
        for (; cursor < n; ++cursor) {
            const std::size_t d = forward ? cursor : n - 1 - cursor;
            if (forward ? near_hi(d) > k : near_lo(d) < k) break;
            write(d);
        }
    }
}

}  // namespace cullide::detail
