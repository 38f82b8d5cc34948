// cullide.cpp: CULLIDE's visibility stages and exact stage (see cullide/cullide.h, docs/cullide.md).
#include "cullide/cullide.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>

#include "cullide/predicates.h"
#include "cullide_detail.h"
#include "exact_stage.h"
#include "parallel.h"
#include "raster/command_batch.h"
#include "raster/offset_geometry.h"
#include "raster/transform.h"
#include "raster/visibility.h"

namespace cullide {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// The 12 triangles of a box over its 8 corners; corner c takes x from bit 0, y from bit 1 and z
// from bit 2 (lo when the bit is 0). Winding is irrelevant: boxes are drawn without face culling.
constexpr std::array<std::uint32_t, 36> kBoxIndices = {
    0, 4, 6, 0, 6, 2,  // -x
    1, 3, 7, 1, 7, 5,  // +x
    0, 1, 5, 0, 5, 4,  // -y
    2, 6, 7, 2, 7, 3,  // +y
    0, 2, 3, 0, 3, 1,  // -z
    4, 5, 7, 4, 7, 6,  // +z
};

// One unit of the PCS: an object (box or whole mesh) or one sub-object. Its triangles are the
// index range [first_index, first_index + index_count) of its object's index list.
struct Item {
    std::uint32_t first_index = 0;
    std::uint32_t index_count = 0;
    Aabb box;
    bool live = true;
    std::array<std::uint32_t, 2> query{};  // this view's query index in pass 1 and pass 2
};

struct ObjectGeometry {
    std::uint32_t active_index = 0;          // position in `active`
    std::vector<raster::Double3> positions;  // world coordinates
    std::vector<std::uint32_t> indices;      // three per triangle
    std::vector<Item> items;
    std::vector<Aabb> triangle_boxes;        // sub-object stage only: one per triangle
    // The current view's geometry, by mode: float clip positions (GLExact), double clip positions
    // (ExactBounds), or the offset solids (Offset; per-triangle boxes at the box and sub-object
    // stages, a union of oriented boxes at the object stage).
    std::vector<raster::Float4> clip;
    std::vector<raster::Double4> clip_d;
    raster::OffsetMesh offset;
};

// One parallel job's share of a mesh: its positions or its triangles [first, last), at most `part`
// of them, of mesh k. mesh_parts cuts meshes 0 .. n-1 (mesh_of(k)), positions then triangles each, so
// that one big mesh does not hold one thread alone (the tree of leaves, the cloth).
struct MeshPart {
    std::size_t k;
    bool positions;  // else triangles
    std::size_t first, last;
};
template <class MeshOf>
std::vector<MeshPart> mesh_parts(std::size_t n, MeshOf&& mesh_of, std::size_t part) {
    std::vector<MeshPart> parts;
    for (std::size_t k = 0; k < n; ++k) {
        const Mesh& m = mesh_of(k);
        for (std::size_t f = 0; f < m.positions.size(); f += part)
            parts.push_back({k, true, f, std::min(m.positions.size(), f + part)});
        for (std::size_t f = 0; f < m.triangles.size(); f += part)
            parts.push_back({k, false, f, std::min(m.triangles.size(), f + part)});
    }
    return parts;
}

}  // namespace

// Shared with quick_cullide.cpp (cullide_detail.h).
namespace detail {

// Grows [lo, hi] so that geometry on its faces stays inside the clip volume after the clip
// coordinates are rounded to float (relative error 2^-24 of the unit range): 1/1024 of the extent
// is far above that and costs 0.2% of the resolution. A flat extent gets a margin relative to the
// coordinates' magnitude (or 1 at the origin) so the range never collapses.
void widen(double& lo, double& hi) {
    const double extent = hi - lo;
    const double magnitude = std::max(std::fabs(lo), std::fabs(hi));
    double margin = std::max(extent * (1.0 / 1024.0), magnitude * 0x1p-40);
    if (!(margin > 0.0)) margin = 1.0;
    lo -= margin;
    hi += margin;
}

// The orthographic view along `axis` (raster::OrthoView: window axes are the next two in cyclic
// order, depth grows along the axis) fitted to `bounds` widened as above, with `extra_depth` more
// world units before and after along the axis (Offset mode).
Result<raster::OrthoView> make_view(int axis, const Aabb& bounds, double extra_depth, ViewSize size,
                                    raster::DepthFormat format) {
    std::array<double, 3> lo{bounds.lo.x, bounds.lo.y, bounds.lo.z};
    std::array<double, 3> hi{bounds.hi.x, bounds.hi.y, bounds.hi.z};
    for (std::size_t k = 0; k < 3; ++k) {
        widen(lo[k], hi[k]);
        if (static_cast<int>(k) == axis) {
            lo[k] -= extra_depth;
            hi[k] += extra_depth;
        }
        if (!std::isfinite(hi[k] - lo[k]))
            return Error{std::string("the scene's extent along ") + "xyz"[k] + " overflows a double"};
    }
    raster::Result<raster::OrthoView> v =
        raster::make_ortho_view(static_cast<raster::Axis>(axis), {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]},
                                size.width(), size.height(), format);
    if (!v) return Error{"view: " + v.error().message};
    return v.value();
}

bool transform_to_clip(const raster::OrthoView& view, std::span<const raster::Double3> points,
                       std::span<raster::Double4> clip_d, std::span<raster::Float4> clip, raster::RasterRules rules) {
    if (!raster::ortho_view_to_clip(view, points, clip_d)) return false;
    for (std::size_t i = 0; i < clip.size(); ++i) {
        const raster::Double4& d = clip_d[i];
        clip[i] = {static_cast<float>(d.x), static_cast<float>(d.y), gl_exact_clip_depth(d.z, rules), 1.0f};
    }
    return true;
}

}  // namespace detail

namespace {

using detail::make_view;
using detail::unite;

// Offset solids' boxes per parallel job of a view's preparation (prepare_view): one job per object
// left the second thread idle where one object holds most of the triangles (the tree of leaves: 7 ms
// per sub-object view on one thread, whatever the PCS).
constexpr std::size_t kOffsetPartTriangles = 4096;

// How many offset solids (boxes) object `og` has at `stage`.
std::size_t offset_boxes(const ObjectGeometry& og, CullStage stage) {
    const std::size_t tris = og.indices.size() / 3;
    if (stage == CullStage::Boxes) return 1;
    if (stage == CullStage::Objects) return (tris + raster::kObbTrianglesPerBox - 1) / raster::kObbTrianglesPerBox;
    return tris;
}
std::size_t offset_part_boxes(CullStage stage) {
    return stage == CullStage::Objects ? kOffsetPartTriangles / raster::kObbTrianglesPerBox : kOffsetPartTriangles;
}

// This view's offset solids [first, last) of one object (see ObjectGeometry), written into its
// offset mesh (sized for every box by the caller); returns their overshoot of the depth range.
raster::Result<double> prepare_offset_part(ObjectGeometry& og, CullStage stage, const raster::OrthoView& view,
                                           std::size_t first, std::size_t last) {
    // The box of the degenerate triangle (lo, hi, lo) is the object's box.
    static constexpr std::array<std::uint32_t, 3> kBoxCorners{0, 7, 0};
    return stage == CullStage::Objects ? raster::object_offset_obbs_part(view, og.positions, og.indices, first, last,
                                                                         og.offset, raster::kObbTrianglesPerBox)
           : stage == CullStage::Boxes ? raster::triangle_offset_boxes_part(view, og.positions, kBoxCorners, first,
                                                                            last, og.offset)
                                       : raster::triangle_offset_boxes_part(view, og.positions, og.indices, first, last,
                                                                            og.offset);
}

std::uint64_t count_live(const std::vector<ObjectGeometry>& g) {
    std::uint64_t n = 0;
    for (const ObjectGeometry& og : g)
        for (const Item& it : og.items) n += it.live ? 1 : 0;
    return n;
}

// Draws one item as a query (GEQUAL, mask off) or a write (LEQUAL, mask on); returns the triangles
// submitted.
std::uint64_t draw_item(raster::CommandBatch& batch, const ObjectGeometry& og, const Item& it, CullStage stage,
                        VisibilityMode mode, bool query) {
    raster::DrawState state;
    state.depth_func = query ? raster::DepthFunc::GEqual : raster::DepthFunc::LEqual;
    state.depth_write = !query;
    const auto indices = std::span<const std::uint32_t>(og.indices).subspan(it.first_index, it.index_count);
    switch (mode) {
        case VisibilityMode::GLExact:
            batch.draw(raster::MeshView{og.clip, indices}, state);
            return it.index_count / 3;
        case VisibilityMode::ExactBounds:
            state.mode = raster::RasterMode::ExactBounds;
            batch.draw(raster::MeshViewD{og.clip_d, indices}, state);
            return it.index_count / 3;
        case VisibilityMode::Offset: {
            // Far faces for the query, near faces for the write (R-CULLIDE).
            state.cull_face = query ? raster::CullFace::Front : raster::CullFace::Back;
            std::span<const std::uint32_t> solid = og.offset.indices;
            if (stage == CullStage::SubObjects)  // 36 indices per triangle's box
                solid = solid.subspan(std::size_t{it.first_index} * 12, std::size_t{it.index_count} * 12);
            batch.draw(raster::MeshView{og.offset.vertices, solid}, state);
            return solid.size() / 3;
        }
    }
    return 0;
}

// Records one pass (Lemma 2) over the live objects `order`: per object, query every live item,
// then write them all (except after the last object: nothing is queried after it).
void record_pass(raster::CommandBatch& batch, std::vector<ObjectGeometry>& g, const std::vector<std::size_t>& order,
                 int pass, VisibilityMode mode, ViewStats& vs) {
    for (std::size_t k = 0; k < order.size(); ++k) {
        ObjectGeometry& og = g[order[k]];
        for (Item& it : og.items) {
            if (!it.live) continue;
            it.query[static_cast<std::size_t>(pass)] = batch.begin_query(raster::QueryKind::AnySamplesPassed);
            vs.triangles_rasterized += draw_item(batch, og, it, vs.stage, mode, true);
            batch.end_query();
            ++vs.queries;
        }
        if (k + 1 == order.size()) continue;
        for (const Item& it : og.items) {
            if (!it.live) continue;
            vs.triangles_rasterized += draw_item(batch, og, it, vs.stage, mode, false);
        }
    }
}

// What one view pruned: items and their triangles.
struct Pruned {
    std::uint64_t items = 0, triangles = 0;
};

// Both passes of one exact-bounds view as the device's visibility pass (query_device.h); prunes
// the fully visible items. The fused and the recorded form give the same answers
// (tests/cullide/fused_visibility_test.cpp compares the two).
// The queries and triangles of the two passes record_pass would record for `order` (the fused
// pass, and a view answered without passes, report what they replace): each live item is queried in
// both passes and written in both except after each pass's last object (order.back() forward,
// order.front() backward), so with L live items of T triangles in all, 2 L queries and
// 4 T - T(back) - T(front) triangles. `each` sees every live item with its position in `order`.
template <class Each>
void count_passes(std::vector<ObjectGeometry>& g, const std::vector<std::size_t>& order, ViewStats& vs, Each&& each) {
    std::uint64_t items = 0, triangles = 0, first_triangles = 0, last_triangles = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
        ObjectGeometry& og = g[order[k]];
        std::uint64_t object_triangles = 0;
        for (Item& it : og.items) {
            if (!it.live) continue;
            each(og, it, k);
            ++items;
            object_triangles += it.index_count / 3;
        }
        triangles += object_triangles;
        if (k == 0) first_triangles = object_triangles;
        if (k + 1 == order.size()) last_triangles = object_triangles;
    }
    vs.queries += 2 * items;
    vs.triangles_rasterized += 4 * triangles - last_triangles - first_triangles;
}

Result<Pruned> visibility_view(std::vector<ObjectGeometry>& g, const std::vector<std::size_t>& order,
                               const CullideOptions& o, ViewSize size, QueryDevice& device, ViewStats& vs) {
    // Kept per thread (capacity only), as the views of a frame follow one another.
    thread_local std::vector<raster::VisibilityItem> items;
    thread_local std::vector<Item*> refs;
    items.clear();
    refs.clear();
    count_passes(g, order, vs, [&](ObjectGeometry& og, Item& it, std::size_t k) {
        items.push_back({raster::MeshViewD{og.clip_d, std::span<const std::uint32_t>(og.indices)
                                                          .subspan(it.first_index, it.index_count)},
                         static_cast<std::uint32_t>(k)});
        refs.push_back(&it);
    });
    Result<std::vector<std::uint8_t>> r = o.fused_visibility
                                              ? device.visibility_pass(size, o.depth_format, items)
                                              : device.recorded_visibility_pass(size, o.depth_format, items);
    if (!r) return r.error();
    Pruned pruned;
    for (std::size_t i = 0; i < refs.size(); ++i) {
        if (r.value()[i] == 0) {
            refs[i]->live = false;
            ++pruned.items;
            pruned.triangles += refs[i]->index_count / 3;
        }
    }
    return pruned;
}

// Both passes of one GL-exact or offset view, recorded and run on the device; prunes the fully
// visible items.
Result<Pruned> recorded_view(std::vector<ObjectGeometry>& g, std::vector<std::size_t> order,
                                    const CullideOptions& o, ViewSize size, QueryDevice& device, ViewStats& vs) {
    // Both passes are recorded first and run as one sequence, each on a cleared target: a device
    // may share their work (the emulator sets each triangle up once for both).
    // Kept per thread (capacity only: reset empties them), so the lists do not grow afresh in
    // every view (page faults and copies on the serial path: perf, issue #17).
    thread_local std::array<raster::CommandBatch, 2> batches = {raster::CommandBatch(1, 1), raster::CommandBatch(1, 1)};
    for (raster::CommandBatch& b : batches) b.reset(size.width(), size.height(), o.gpu_rules);
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) std::reverse(order.begin(), order.end());  // pass 2 runs backward
        record_pass(batches[static_cast<std::size_t>(pass)], g, order, pass, o.mode, vs);
    }
    const raster::CommandBatch* const both[2] = {&batches[0], &batches[1]};
    Result<std::vector<raster::QueryResults>> run = device.execute_cleared(size.width(), size.height(), o.depth_format, both);
    if (!run) return run.error();
    std::vector<raster::QueryResults>& results = run.value();
    if (results.size() != 2) return Error{"device returned " + std::to_string(results.size()) + " passes for 2"};
    for (std::size_t pass = 0; pass < 2; ++pass)
        if (results[pass].size() != batches[pass].query_kinds().size())
            return Error{"device returned " + std::to_string(results[pass].size()) + " query results for " +
                         std::to_string(batches[pass].query_kinds().size()) + " queries"};
    Pruned pruned;
    for (std::size_t i : order) {
        for (Item& it : g[i].items) {
            if (it.live && results[0][it.query[0]] == 0 && results[1][it.query[1]] == 0) {
                it.live = false;
                ++pruned.items;
                pruned.triangles += it.index_count / 3;
            }
        }
    }
    return pruned;
}

// Fits the view and prepares the live objects' geometry for it. Offset mode: widens the depth range
// until no offset solid reaches past the near or far plane (the offset radius depends on the pixel
// size, which widening the depth range does not change, and on the depth quantum, which it barely
// changes, so this settles in one or two steps).
Status prepare_view(std::vector<ObjectGeometry>& g, const std::vector<std::size_t>& order, CullStage stage, int axis,
                    const Aabb& bounds, const CullideOptions& o, ViewSize size) {
    double extra_depth = 0.0;
    for (int attempt = 0;; ++attempt) {
        Result<raster::OrthoView> view = make_view(axis, bounds, extra_depth, size, o.depth_format);
        if (!view) return view.error();
        if (o.mode != VisibilityMode::Offset) {
            // Parts of detail::kTransformPart points per parallel job, each writing only its own
            // part of its object's clip arrays; the first failure in order is reported, named by
            // the whole object's transform. Exact-bounds sub-object views read only the live items'
            // vertices: where those items hold fewer indices than the object has points (every
            // view after the first on the leaves and the cylinders), only the points they name
            // are transformed, one job per such object (`items`: neighbouring items share points,
            // so no two jobs write one), by the same arithmetic, so those points get the same
            // values and nothing reads the others.
            struct Part {
                std::size_t k, b, e;  // points [b, e) of order[k]; with `items`, its items [b, e)
                bool items;
            };
            std::vector<Part> parts;
            const bool sparse_ok = o.mode == VisibilityMode::ExactBounds && stage == CullStage::SubObjects;
            for (std::size_t k = 0; k < order.size(); ++k) {
                ObjectGeometry& og = g[order[k]];
                const std::size_t n = og.positions.size();
                og.clip_d.resize(n);
                if (o.mode == VisibilityMode::GLExact) og.clip.resize(n);
                std::size_t live = 0;
                for (const Item& it : og.items) live += it.live ? it.index_count : 0;
                if (sparse_ok && live < n) {  // one part: neighbouring items share points
                    parts.push_back({k, 0, og.items.size(), true});
                    continue;
                }
                for (std::size_t b = 0; b < n; b += detail::kTransformPart)
                    parts.push_back({k, b, std::min(n, b + detail::kTransformPart), false});
            }
            std::vector<char> ok(parts.size(), 0);
            detail::parallel_chunks(o.threads, parts.size(), [&](std::size_t j) {
                ObjectGeometry& og = g[order[parts[j].k]];
                if (parts[j].items) {
                    // Runs of adjacent live items as one index span each.
                    ok[j] = 1;
                    for (std::size_t i = parts[j].b; i < parts[j].e && ok[j];) {
                        if (!og.items[i].live) {
                            ++i;
                            continue;
                        }
                        const std::size_t first = og.items[i].first_index;
                        std::size_t end = first + og.items[i].index_count;
                        for (++i; i < parts[j].e && og.items[i].live && og.items[i].first_index == end; ++i)
                            end += og.items[i].index_count;
                        ok[j] = raster::ortho_view_to_clip(
                                    view.value(), og.positions,
                                    std::span<const std::uint32_t>(og.indices).subspan(first, end - first), og.clip_d)
                                    ? 1 : 0;
                    }
                    return;
                }
                const std::size_t b = parts[j].b, len = parts[j].e - parts[j].b;
                const std::span<raster::Float4> clip =
                    o.mode == VisibilityMode::GLExact ? std::span<raster::Float4>(og.clip).subspan(b, len)
                                                      : std::span<raster::Float4>();
                ok[j] = detail::transform_to_clip(view.value(), std::span<const raster::Double3>(og.positions).subspan(b, len),
                                                  std::span<raster::Double4>(og.clip_d).subspan(b, len), clip, o.gpu_rules)
                            ? 1 : 0;
            });
            for (std::size_t j = 0; j < parts.size(); ++j) {
                if (ok[j]) continue;
                ObjectGeometry& og = g[order[parts[j].k]];
                raster::Result<std::size_t> c = raster::ortho_view_to_clip(view.value(), og.positions, og.clip_d);
                if (c) return Error{"view transform: a part of an object failed but the whole object passed"};
                return Error{"view transform: " + c.error().message};
            }
            return Status{};
        }
        // Offset solids: parts of about kOffsetPartTriangles triangles per parallel job, each
        // writing only its own boxes of its object's offset mesh (sized here; the memory is kept
        // between views). The sub-object stage writes the boxes of live items only (no draw reads
        // the others), but fits the view to every box of the live objects as before: the other
        // boxes give their overshoot without being written. The first failure in order is
        // reported (the objects were validated before the first view, so what can fail is a box's
        // own arithmetic, named by its triangle), and the overshoot is the largest of the parts'.
        struct Part {
            std::size_t k, first, last;  // boxes [first, last) of order[k]; sub-objects: items
        };
        std::vector<Part> parts;
        const std::size_t per_part = offset_part_boxes(stage);
        for (std::size_t k = 0; k < order.size(); ++k) {
            ObjectGeometry& og = g[order[k]];
            const std::size_t n = offset_boxes(og, stage);
            raster::size_offset_boxes(n, og.offset);
            if (stage != CullStage::SubObjects) {
                for (std::size_t b = 0; b < n; b += per_part) parts.push_back({k, b, std::min(n, b + per_part)});
                continue;
            }
            for (std::size_t i = 0, tris = 0, first = 0; i < og.items.size(); ++i) {
                tris += og.items[i].index_count / 3;
                if (tris >= per_part || i + 1 == og.items.size()) {
                    parts.push_back({k, first, i + 1});
                    first = i + 1;
                    tris = 0;
                }
            }
        }
        std::vector<raster::Result<double>> prepared(parts.size(), 0.0);
        detail::parallel_chunks(o.threads, parts.size(), [&](std::size_t j) {
            ObjectGeometry& og = g[order[parts[j].k]];
            if (stage != CullStage::SubObjects) {
                prepared[j] = prepare_offset_part(og, stage, view.value(), parts[j].first, parts[j].last);
                return;
            }
            // Runs of items alike in liveness (the items cover the triangles in order).
            double over = 0.0;
            for (std::size_t i = parts[j].first; i < parts[j].last;) {
                const bool live = og.items[i].live;
                std::size_t e = i + 1;
                while (e < parts[j].last && og.items[e].live == live) ++e;
                const std::size_t b0 = og.items[i].first_index / 3;
                const std::size_t b1 = (og.items[e - 1].first_index + og.items[e - 1].index_count) / 3;
                raster::Result<double> r =
                    live ? prepare_offset_part(og, stage, view.value(), b0, b1)
                         : raster::triangle_offset_boxes_overshoot(view.value(), og.positions, og.indices, b0, b1);
                if (!r) {
                    prepared[j] = std::move(r);
                    return;
                }
                over = std::max(over, r.value());
                i = e;
            }
            prepared[j] = over;
        });
        double overshoot = 0.0;  // in clip units beyond [-1, 1]
        for (const raster::Result<double>& p : prepared) {
            if (!p) return Error{"offset geometry: " + p.error().message};
            overshoot = std::max(overshoot, p.value());
        }
        if (overshoot == 0.0) return Status{};
        if (attempt == 8) return Error{"offset solids do not fit the view's depth range after 8 attempts"};
        const double world_per_clip =
            0.5 * ((axis == 0 ? view.value().box_max.x - view.value().box_min.x
                    : axis == 1 ? view.value().box_max.y - view.value().box_min.y
                                : view.value().box_max.z - view.value().box_min.z));
        extra_depth += 2.0 * overshoot * world_per_clip;
    }
}

// Whether every live item's closed box overlaps (or touches) the closed box of a live item of
// another object: then no exact-bounds view of the stage can prune any of them. Where the boxes of
// items A and B (objects a != b) share a point p, the view's transform, monotone along each axis,
// keeps them sharing a point in clip space; a pixel whose closed square holds p's window position
// meets a face of each box on both sides of p along the view axis, and the exact-bounds mode
// covers it with depth intervals rounded outward from the faces'. So there A's largest zmax is >=
// p's depth >= B's smallest zmin, and one of the two passes, the one that draws B before querying
// A, finds A not fully visible there (and B likewise); both stay live, so the next view sees the
// same pairs (induction over the views). Box items are also exactly their corners' box, so this is
// used for the box stage (one item per object), where R-CULLIDE's views are then known to prune
// nothing without running them (CullideOptions::box_stage has the same argument). Sweep and prune
// along x over the items sorted by box.lo.x, stopping with false after kMaxOverlapChecks per item
// (boxes piled along x: the views then run as before). Not detail::overlapping_sets: it lists every
// overlapping pair (quadratic in a heap of boxes that all overlap), where this only needs a partner
// for each box and gives up early.
bool all_boxes_overlapped(const std::vector<ObjectGeometry>& g) {
    constexpr std::size_t kMaxOverlapChecks = 64;
    struct Entry {
        const Aabb* box;
        std::uint32_t object;
    };
    std::vector<Entry> e;
    for (std::size_t i = 0; i < g.size(); ++i)
        for (const Item& it : g[i].items)
            if (it.live) e.push_back({&it.box, static_cast<std::uint32_t>(i)});
    if (e.size() < 2) return false;
    for (const Entry& x : e)
        if (!(x.box->lo.x <= x.box->hi.x && x.box->lo.y <= x.box->hi.y && x.box->lo.z <= x.box->hi.z))
            return false;  // an empty box (an object without triangles) overlaps nothing
    std::sort(e.begin(), e.end(), [](const Entry& a, const Entry& b) { return a.box->lo.x < b.box->lo.x; });
    std::vector<std::uint8_t> seen(e.size(), 0);
    std::size_t checks = 0;
    for (std::size_t i = 0; i < e.size(); ++i) {
        const Aabb& a = *e[i].box;
        for (std::size_t j = i + 1; j < e.size() && e[j].box->lo.x <= a.hi.x; ++j) {
            if (++checks > kMaxOverlapChecks * e.size()) return false;
            const Aabb& b = *e[j].box;
            if (e[j].object != e[i].object && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
                b.lo.z <= a.hi.z)
                seen[i] = seen[j] = 1;
        }
        if (!seen[i]) return false;  // every later box starts after a.hi.x or was checked
    }
    return true;
}

// Views along x, y, z in turn until three views in a row are unproductive (CullideOptions::min_prune;
// with 0, three views that prune nothing: then the PCS, and so every further view, is unchanged) or
// 3 * max_rounds views ran.
Status run_stage(std::vector<ObjectGeometry>& g, CullStage stage, const CullideOptions& o, ViewSize size,
                 QueryDevice& device, CullideStats& st) {
    const double min_prune =
        o.min_prune >= 0.0 ? o.min_prune : o.mode == VisibilityMode::ExactBounds ? kDefaultMinPruneExactBounds : 0.0;
    int quiet = 0;
    std::vector<std::size_t> order;
    // Exact-bounds box views where every box overlaps another: answered without running them (each
    // prunes nothing, all_boxes_overlapped); the statistics count the passes they stand for, as the
    // fused pass's do (issue #16: 0.3-0.8 ms of a 1-thread frame on tori and breaking, whose boxes
    // all overlap).
    const bool none_prunable = o.settle_box_views && o.mode == VisibilityMode::ExactBounds &&
                               stage == CullStage::Boxes && all_boxes_overlapped(g);
    for (int view = 0; view < 3 * o.max_rounds && quiet < 3; ++view) {
        // One pass over the items: the objects with live items (order), the union of the live
        // items' boxes, and how many items and triangles are live.
        order.clear();
        Aabb bounds;
        std::uint64_t items_before = 0, tris_before = 0;
        for (std::size_t i = 0; i < g.size(); ++i) {
            bool any = false;
            for (const Item& it : g[i].items) {
                if (!it.live) continue;
                any = true;
                bounds = unite(bounds, it.box);
                ++items_before;
                tris_before += it.index_count / 3;
            }
            if (any) order.push_back(i);
        }
        if (order.size() < 2) {  // nothing left to collide with
            for (ObjectGeometry& og : g)
                for (Item& it : og.items) it.live = false;
            return Status{};
        }
        const int axis = view % 3;
        ViewStats vs;
        vs.stage = stage;
        vs.axis = axis;
        vs.items_before = items_before;
        Result<Pruned> pruned = Pruned{};
        if (none_prunable) {
            // The view is still fitted, so that a scene whose extent overflows fails here as before.
            if (Result<raster::OrthoView> v = make_view(axis, bounds, 0.0, size, o.depth_format); !v) return v.error();
            count_passes(g, order, vs, [](ObjectGeometry&, Item&, std::size_t) {});
            ++st.box_views_settled;
        } else {
            if (Status sv = prepare_view(g, order, stage, axis, bounds, o, size); !sv) return sv;
            pruned = o.mode == VisibilityMode::ExactBounds ? visibility_view(g, order, o, size, device, vs)
                                                           : recorded_view(g, order, o, size, device, vs);
        }
        if (!pruned) return pruned.error();
        // Exact-bounds views read only the live items, so the pruned ones are dropped (in order):
        // each later view, and the exact stage, then scan only what is left (the tree of leaves:
        // 11,212 sub-objects, 4,689 after the first view, 286 after the sixth). The offset mode
        // keeps them: its views are fitted to every item's box.
        if (o.mode == VisibilityMode::ExactBounds && stage == CullStage::SubObjects && pruned.value().items > 0)
            for (const std::size_t i : order) std::erase_if(g[i].items, [](const Item& it) { return !it.live; });
        vs.items_after = vs.items_before - pruned.value().items;
        st.queries += vs.queries;
        st.triangles_rasterized += vs.triangles_rasterized;
        st.views.push_back(vs);
        // Unproductive: pruned fewer triangles than min_prune of those live (none pruned: always).
        const std::uint64_t pruned_tris = pruned.value().triangles;
        const bool unproductive =
            pruned_tris == 0 || static_cast<double>(pruned_tris) < min_prune * static_cast<double>(tris_before);
        quiet = unproductive ? quiet + 1 : 0;
    }
    return Status{};
}

Result<ViewSize> check_inputs(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                              const CullideOptions& o, bool scene_checked) {
    if (!(o.min_prune < 1.0))  // NaN too
        return Error{"min_prune must be below 1 (negative: the mode's default; got " + std::to_string(o.min_prune) +
                     ")"};
    if (o.object_stage != ObjectStage::Auto && o.object_stage != ObjectStage::On && o.object_stage != ObjectStage::Off)
        return Error{"object_stage is not Auto, On or Off"};
    return detail::check_visibility_inputs(objects, active, o, o.mode, scene_checked);
}

// The triangles of the surviving sub-objects, paired across objects and tested exactly: each live
// sub-object is a candidate set of the exact stage (exact_stage.h).
std::vector<TrianglePair> exact_stage(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                      const std::vector<ObjectGeometry>& g, int threads, CullideStats& st) {
    std::vector<detail::ExactObject> exact(g.size());
    std::vector<detail::CandidateSet> sets;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const std::uint32_t object = active[g[i].active_index];
        exact[i] = {&objects[object], object, Aabb{}, g[i].triangle_boxes, {}, {}};
        for (const Item& it : g[i].items) {
            if (!it.live) continue;
            sets.push_back({static_cast<std::uint32_t>(i), it.first_index / 3, it.index_count / 3, it.box});
            exact[i].box = unite(exact[i].box, it.box);
            st.candidate_triangles += it.index_count / 3;
        }
    }
    detail::ExactStageResult r = detail::sweep_exact_stage(exact, sets, {false, true, threads});
    st.exact_tests = r.stats.tests;
    st.subobject_pairs = r.stats.set_pairs;
    return std::move(r.pairs);
}

// Stage 1's geometry: each active object's box as one item of 12 triangles.
std::vector<ObjectGeometry> box_geometry(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                         int threads) {
    const std::vector<Aabb> bounds = detail::object_bounds(objects, active, threads);
    std::vector<ObjectGeometry> boxes(active.size());
    detail::parallel_chunks(threads, active.size(), [&](std::size_t k) {  // each fills its own geometry
        ObjectGeometry& og = boxes[k];
        og.active_index = static_cast<std::uint32_t>(k);
        const Aabb& b = bounds[k];
        og.positions.resize(8);
        for (std::size_t c = 0; c < 8; ++c)
            og.positions[c] = {(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z};
        og.indices.assign(kBoxIndices.begin(), kBoxIndices.end());
        og.items.push_back({0, 36, b, true, {}});
    });
    return boxes;
}

// Stage 2's geometry: the mesh of each object whose box survived, as one item.
std::vector<ObjectGeometry> object_geometry(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                            const std::vector<ObjectGeometry>& boxes, int threads) {
    std::vector<const ObjectGeometry*> live;
    for (const ObjectGeometry& b : boxes)
        if (b.items[0].live) live.push_back(&b);
    std::vector<ObjectGeometry> whole(live.size());
    detail::parallel_chunks(threads, live.size(), [&](std::size_t k) {  // each sizes its own geometry
        const ObjectGeometry& b = *live[k];
        const Mesh& m = objects[active[b.active_index]];
        ObjectGeometry& og = whole[k];
        og.active_index = b.active_index;
        og.positions.resize(m.positions.size());
        og.indices.resize(m.triangles.size() * 3);
        og.items.push_back({0, static_cast<std::uint32_t>(og.indices.size()), b.items[0].box, true, {}});
    });
    // The copies in parts of at most kCopyPart positions or triangles, each job writing its own
    // range: one job per object left a thread alone with the tree of leaves (perf, 2 threads).
    constexpr std::size_t kCopyPart = 16384;
    const std::vector<MeshPart> parts = mesh_parts(
        live.size(), [&](std::size_t k) -> const Mesh& { return objects[active[live[k]->active_index]]; }, kCopyPart);
    detail::parallel_chunks(threads, parts.size(), [&](std::size_t j) {
        const MeshPart& part = parts[j];
        const Mesh& m = objects[active[live[part.k]->active_index]];
        ObjectGeometry& og = whole[part.k];
        if (part.positions) {
            for (std::size_t i = part.first; i < part.last; ++i)
                og.positions[i] = {m.positions[i].x, m.positions[i].y, m.positions[i].z};
            return;
        }
        for (std::size_t t = part.first; t < part.last; ++t)
            std::copy(m.triangles[t].begin(), m.triangles[t].end(), og.indices.begin() + static_cast<std::ptrdiff_t>(3 * t));
    });
    return whole;
}

// Stage 3's geometry: each surviving object split into sub-objects of `group` consecutive triangles
// (neighbours in meshes stored strip- or patch-wise; see docs/cullide.md for what this choice costs
// on scrambled meshes), with its triangles' boxes for the exact stage.
std::vector<ObjectGeometry> subobject_geometry(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                               std::vector<ObjectGeometry>&& whole, std::size_t group, int threads) {
    std::vector<ObjectGeometry> subs;
    for (ObjectGeometry& og : whole)
        if (og.items[0].live) subs.push_back(std::move(og));
    // Parts of whole sub-objects (about kBoxPart triangles) per parallel job, each filling only its
    // own triangle boxes and items: one job per object left the second thread idle where one object
    // holds most of the triangles (the tree of leaves, the dragon, the cloth).
    constexpr std::size_t kBoxPart = 4096;
    const std::size_t per_part = group * std::max<std::size_t>(1, kBoxPart / group);
    struct Part {
        std::size_t k, first, last;  // triangles [first, last) of subs[k]
    };
    std::vector<Part> parts;
    for (std::size_t k = 0; k < subs.size(); ++k) {
        const std::size_t n = objects[active[subs[k].active_index]].triangles.size();
        for (std::size_t first = 0; first < n; first += per_part) parts.push_back({k, first, std::min(n, first + per_part)});
    }
    detail::parallel_chunks(threads, subs.size(), [&](std::size_t k) {  // sized per object, in parallel too
        ObjectGeometry& og = subs[k];
        const std::size_t n = objects[active[og.active_index]].triangles.size();
        og.triangle_boxes.resize(n);
        og.items.resize((n + group - 1) / group);
    });
    detail::parallel_chunks(threads, parts.size(), [&](std::size_t j) {
        ObjectGeometry& og = subs[parts[j].k];
        const Mesh& m = objects[active[og.active_index]];
        // One pass: each triangle's box, written in place (detail::triangle_box: an Aabb returned
        // by triangle_bounds and copied in stalled store forwarding; this loop was 10% of a
        // 1-thread cloth / rcullide frame), folded into its sub-object's box as unite folds them
        // (a triangle's box is never empty). A part starts at a multiple of `group`, so its items
        // are counted on from first / group.
        std::size_t item = parts[j].first / group;
        for (std::size_t first = parts[j].first; first < parts[j].last; first += group, ++item) {
            const std::size_t last = std::min(parts[j].last, first + group);
            double lx = 0, ly = 0, lz = 0, hx = 0, hy = 0, hz = 0;
            for (std::size_t t = first; t < last; ++t) {
                Aabb& box = og.triangle_boxes[t];
                detail::triangle_box(m, t, box);
                if (t == first) {
                    lx = box.lo.x, ly = box.lo.y, lz = box.lo.z, hx = box.hi.x, hy = box.hi.y, hz = box.hi.z;
                } else {
                    lx = std::min(lx, box.lo.x), ly = std::min(ly, box.lo.y), lz = std::min(lz, box.lo.z);
                    hx = std::max(hx, box.hi.x), hy = std::max(hy, box.hi.y), hz = std::max(hz, box.hi.z);
                }
            }
            Item& it = og.items[item];
            it.first_index = static_cast<std::uint32_t>(first * 3);
            it.index_count = static_cast<std::uint32_t>((last - first) * 3);
            it.box.lo.x = lx, it.box.lo.y = ly, it.box.lo.z = lz;
            it.box.hi.x = hx, it.box.hi.y = hy, it.box.hi.z = hz;
            it.live = true;
            it.query = {};
        }
    });
    return subs;
}

}  // namespace

Result<std::vector<TrianglePair>> cullide_pairs(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                                const CullideOptions& options, QueryDevice& device,
                                                CullideStats* stats) {
    return detail::cullide_pairs(objects, active, options, device, stats, false);
}

Result<std::vector<TrianglePair>> detail::cullide_pairs(std::span<const Mesh> objects,
                                                        std::span<const std::uint32_t> active,
                                                        const CullideOptions& options, QueryDevice& device,
                                                        CullideStats* stats, bool scene_checked) {
    Result<ViewSize> checked = check_inputs(objects, active, options, scene_checked);
    if (!checked) return checked.error();
    const ViewSize size = checked.value();
    CullideStats st;
    st.objects_in = active.size();

    auto t0 = Clock::now();
    std::vector<ObjectGeometry> boxes = box_geometry(objects, active, options.threads);
    if (options.box_stage)
        if (Status s = run_stage(boxes, CullStage::Boxes, options, size, device, st); !s) return s.error();
    st.pcs_boxes = count_live(boxes);
    st.boxes_ms = ms_since(t0);

    t0 = Clock::now();
    std::vector<ObjectGeometry> whole = object_geometry(objects, active, boxes, options.threads);
    const bool object_stage = options.object_stage == ObjectStage::On ||
                              (options.object_stage == ObjectStage::Auto && options.mode != VisibilityMode::ExactBounds);
    if (object_stage)
        if (Status s = run_stage(whole, CullStage::Objects, options, size, device, st); !s) return s.error();
    st.pcs_objects = count_live(whole);
    st.objects_ms = ms_since(t0);

    t0 = Clock::now();
    std::vector<ObjectGeometry> subs =
        subobject_geometry(objects, active, std::move(whole), static_cast<std::size_t>(options.subobject_triangles),
                           options.threads);
    for (const ObjectGeometry& og : subs) st.subobjects += og.items.size();
    if (Status s = run_stage(subs, CullStage::SubObjects, options, size, device, st); !s) return s.error();
    st.pcs_subobjects = count_live(subs);
    st.subobjects_ms = ms_since(t0);

    t0 = Clock::now();
    std::vector<TrianglePair> pairs = exact_stage(objects, active, subs, options.threads, st);
    st.exact_ms = ms_since(t0);
    if (stats != nullptr) *stats = std::move(st);
    return pairs;
}

}  // namespace cullide

namespace cullide::detail {

std::vector<Aabb> object_bounds(std::span<const Mesh> objects, std::span<const std::uint32_t> active, int threads) {
    struct Job {
        std::size_t k, first, last;  // triangles [first, last) of objects[active[k]]
    };
    std::vector<Job> jobs;
    for (std::size_t k = 0; k < active.size(); ++k) {
        const std::size_t n = objects[active[k]].triangles.size();
        for (std::size_t f = 0; f < n; f += kBoundsTriangles) jobs.push_back({k, f, std::min(n, f + kBoundsTriangles)});
    }
    std::vector<Aabb> job_box(jobs.size());
    parallel_chunks(threads, jobs.size(), [&](std::size_t j) {
        job_box[j] = triangles_bounds(objects[active[jobs[j].k]], jobs[j].first, jobs[j].last);
    });
    // In job order: unite takes the first job's box as it is (the empty box is its identity), then
    // std::min / std::max with the box so far first.
    std::vector<Aabb> boxes(active.size());
    for (std::size_t j = 0; j < jobs.size(); ++j) boxes[jobs[j].k] = unite(boxes[jobs[j].k], job_box[j]);
    return boxes;
}

bool scene_clean(std::span<const Mesh> objects, int threads) {
    for (const Mesh& m : objects)
        if (m.triangles.empty()) return false;
    const std::vector<MeshPart> jobs =
        mesh_parts(objects.size(), [&](std::size_t k) -> const Mesh& { return objects[k]; }, kCheckPart);
    std::vector<char> ok(jobs.size(), 0);
    parallel_chunks(threads, jobs.size(), [&](std::size_t j) {
        const MeshPart& job = jobs[j];
        const Mesh& m = objects[job.k];
        // Flags ANDed without branches (the scan runs to the end of its part either way).
        const auto u = [](bool b) { return static_cast<std::uint32_t>(b); };
        std::uint32_t good = 1;
        if (job.positions) {
            // predicate_coordinate_ok is false for NaN and infinities: validate_mesh's check too.
            for (std::size_t v = job.first; v < job.last; ++v) {
                const Vec3& p = m.positions[v];
                good &= u(predicate_coordinate_ok(p.x)) & u(predicate_coordinate_ok(p.y)) & u(predicate_coordinate_ok(p.z));
            }
        } else {
            const std::size_t n = m.positions.size();
            for (std::size_t t = job.first; t < job.last; ++t)
                good &= u(m.triangles[t][0] < n) & u(m.triangles[t][1] < n) & u(m.triangles[t][2] < n);
        }
        ok[j] = good != 0 ? 1 : 0;
    });
    return std::all_of(ok.begin(), ok.end(), [](char c) { return c != 0; });
}

Result<ViewSize> check_visibility_inputs(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                                         const VisibilityOptions& o, VisibilityMode mode, bool scene_checked) {
    Result<ViewSize> size = view_size(o.resolution, mode);
    if (!size) return size.error();
    if (o.subobject_triangles < 1)
        return Error{"sub-object size must be >= 1 triangle (got " + std::to_string(o.subobject_triangles) + ")"};
    if (o.max_rounds < 1 || o.max_rounds > kMaxRounds)
        return Error{"max_rounds must be in 1.." + std::to_string(kMaxRounds) + " (got " + std::to_string(o.max_rounds) + ")"};
    if (o.threads < 0) return Error{"threads must be >= 0 (got " + std::to_string(o.threads) + ")"};
    if (o.gpu_rules != raster::RasterRules::GlLlvmpipe && o.gpu_rules != raster::RasterRules::Vulkan)
        return Error{"gpu rules: unknown value " + std::to_string(static_cast<int>(o.gpu_rules))};
    if (mode == VisibilityMode::Offset && o.gpu_rules != raster::RasterRules::GlLlvmpipe)
        return Error{"the offset mode (R-CULLIDE's offset solids) is built for the GL rules only; use --gpu-rules gl"};
    // Each object's scan in its own parallel job (they were serial work on the calling thread of
    // every frame); the problems are then reported in the order of the serial checks, so the same
    // first one is named.
    // (Skipped when the caller checked every object already: process_frame. The scans were 5-7% of
    // a cloth / rcullide frame, perf, after the items-alone pre-pass.)
    std::vector<Status> mesh_ok(objects.size()), range_ok(active.size());
    if (!scene_checked) detail::parallel_chunks(o.threads, objects.size() + active.size(), [&](std::size_t j) {
        if (j < objects.size()) {
            mesh_ok[j] = validate_mesh(objects[j]);
            return;
        }
        const std::size_t k = j - objects.size();
        if (active[k] < objects.size())  // (beyond: reported below)
            range_ok[k] = detail::validate_exact_range_of(objects[active[k]], active[k]);
    });
    for (std::size_t i = 0; i < objects.size(); ++i)  // validate_scene's first problem
        if (!mesh_ok[i]) return Error{"object " + std::to_string(i) + ": " + mesh_ok[i].error().message};
    if (objects.size() > UINT32_MAX) return Error{"too many objects (limit 2^32 - 1)"};
    for (std::size_t k = 0; k < active.size(); ++k) {
        if (active[k] >= objects.size())
            return Error{"active object " + std::to_string(k) + " = " + std::to_string(active[k]) +
                         " is beyond the object list (size " + std::to_string(objects.size()) + ")"};
        if (k > 0 && active[k] <= active[k - 1])
            return Error{"active objects must be strictly increasing (entry " + std::to_string(k) + ")"};
        const Mesh& m = objects[active[k]];
        if (m.triangles.size() > UINT32_MAX / 3)
            return Error{"object " + std::to_string(active[k]) + ": too many triangles (limit 2^32 / 3)"};
        if (!range_ok[k]) return range_ok[k].error();
    }
    return size;
}

}  // namespace cullide::detail
