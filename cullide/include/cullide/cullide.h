// cullide/cullide.h: CULLIDE and R-CULLIDE, the visibility-based potentially colliding set (PCS).
//
// After Govindaraju, Redon, Lin and Manocha, "CULLIDE: Interactive Collision Detection Between
// Complex Models in Large Environments using Graphics Hardware" (Graphics Hardware 2003), and
// Govindaraju, Lin and Manocha, "Fast and Reliable Collision Culling using Graphics Hardware"
// (R-CULLIDE, VRST 2004). The code is ours; ../shared/docs/algorithms.md sections 1-4 is the
// specification and docs/cullide.md records every choice made where the papers are silent.
//
// Stages of one frame (each conservative with respect to the one before it):
//  1. object boxes: each object's axis-aligned box (12 triangles) through the two passes of
//     Lemma 2, in orthographic views along x, y, z fitted to the bounds of the live PCS, in rounds
//     cycling the axis until three views in a row are unproductive (min_prune below; with 0, until
//     three views prune nothing: a fixpoint, the same PCS gives the same view) or 3 * max_rounds
//     views ran;
//  2. objects: the same with each object's triangles (skipped by default for ExactBounds: see
//     ObjectStage);
//  3. sub-objects: each live object split into groups of `subobject_triangles` consecutive
//     triangles; in each pass all sub-objects of an object are queried before any is written;
//  4. exact: per pair of objects whose live boxes overlap, the live sub-objects meeting the two
//     boxes' intersection swept and pruned on their boxes (or on their triangles' boxes when the
//     sub-object boxes are loose), then the triangle pairs whose boxes overlap, then the exact test
//     of tri_tri.h: the exact stage every method shares (the ground truth included), with the live
//     sub-objects as its candidate sets.
// Views run on a QueryDevice (query_device.h): GLExact and Offset record each pass as a command
// batch; ExactBounds hands both passes of a view to QueryDevice::visibility_pass at once.
// Pass k of a view: clear depth; for each live object in order (pass 1) or reverse order (pass 2):
// query its live items (GEQUAL, depth mask off, one any-samples query each), then write them
// (LEQUAL, mask on). An item whose queries pass no sample in both passes is fully visible with
// respect to all others in that view and leaves the PCS for good. No face culling (except the
// offset solids of VisibilityMode::Offset, see below). The last object of a pass is not written:
// nothing is queried after it.
//
// Views: raster::OrthoView (raster/transform.h) over the live PCS's bounds widened by 1/1024 of
// their extent on each side (so float rounding never pushes geometry out of the clip volume); in
// Offset mode the depth range is widened further until every offset solid lies inside it (a solid
// clipped at the near or far plane would lose the faces that make it conservative).
//
// Objects that have nothing left to collide with (fewer than two objects with live items) are
// pruned without a view. Self-collision is not supported (as in the papers: the sub-objects of one
// object are never tested against each other).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/query_device.h"
#include "cullide/result.h"
#include "cullide/visibility.h"

namespace cullide {

// Stage 2 (whole objects). A sub-object view prunes every object that an object view of the same
// PCS would prune (an object's fragments are the union of its sub-objects', tested against the same
// depths, so the object is fully visible iff each of its sub-objects is), and rasterizes the same
// triangles; it only issues more queries, which costs on a real GPU and nothing on the emulator.
// Auto: run stage 2 for GLExact and Offset (the published pipelines, reproduced with their misses)
// and skip it for ExactBounds (R-CULLIDE on the emulator), where it only costs views.
enum class ObjectStage : std::uint8_t { Auto, On, Off };
inline constexpr double kDefaultMinPruneExactBounds = 0.5;

// CULLIDE's options: the shared ones (visibility.h) and its own.
struct CullideOptions : VisibilityOptions {
    VisibilityMode mode = VisibilityMode::GLExact;
    // A view counts as unproductive when the triangles of the items it prunes are fewer than this
    // fraction of the stage's live triangles before it; a stage stops after three unproductive
    // views in a row (one per axis). 0: stop only when three views in a row prune nothing (the
    // published rule). Negative: the mode's default, kDefaultMinPruneExactBounds for ExactBounds
    // (measured in docs/cullide.md: later views cost as much as the first and prune little, while
    // the exact stage absorbs what they would have pruned) and 0 for GLExact and Offset.
    double min_prune = -1.0;      // < 1
    ObjectStage object_stage = ObjectStage::Auto;
    // ExactBounds: answer each view's two passes with the device's fused visibility pass
    // (QueryDevice::visibility_pass: on the emulator raster::VisibilityPass, the same answers, bit
    // for bit, at a quarter of the rasterization). The statistics still count the queries and
    // triangles of the two recorded passes it replaces. false records and executes the passes
    // (QueryDevice::recorded_visibility_pass; tests compare the two).
    bool fused_visibility = true;
    // Stage 1, views of each object's box (12 triangles), runs when true. With ExactBounds its views
    // can prune only objects whose closed box overlaps no other active object's box: where two boxes
    // overlap, each pass finds one of the two behind (or level with) the other at a pixel both cover,
    // so neither is fully visible in both (docs/cullide.md, "The box stage after a broad phase").
    // A broad phase leaves exactly the objects that overlap another, so after one the stage prunes
    // nothing and process_frame turns it off for rcullide. false is always safe (the stage only
    // prunes): the later stages then start from every active object.
    bool box_stage = true;
    // ExactBounds: when every live object's closed box overlaps another's before the box stage, its
    // views are known to prune nothing (the argument above) and are answered without running them;
    // the statistics still count the queries and triangles of the passes they stand for (as
    // fused_visibility's do), so every figure is the same as with the views run. false runs them
    // (tests compare the two).
    bool settle_box_views = true;
};

// The shared figures (visibility.h: pcs_boxes, pcs_objects, pcs_subobjects are the PCS after each
// stage; candidate_triangles the triangles in the surviving sub-objects) and CULLIDE's own.
struct CullideStats : VisibilityStats {
    std::uint64_t subobject_pairs = 0;  // sub-object pairs across objects holding a triangle pair
                                        // whose boxes overlap (a pair the exact stage tests)
    std::uint64_t box_views_settled = 0;  // box views answered without running them (settle_box_views)
};

// Colliding triangle pairs found by CULLIDE among the objects listed in `active` (increasing
// indices into `objects`; the others are treated as already pruned), canonical and sorted as
// ground_truth.h. Every reported pair collides (exact stage); GLExact may miss pairs. Fails, naming
// what is wrong, on invalid meshes, coordinates outside the exact range (predicates.h), bad
// options, an unsorted or out-of-range `active`, a scene whose extent overflows, or a device error.
[[nodiscard]] Result<std::vector<TrianglePair>> cullide_pairs(std::span<const Mesh> objects,
                                                              std::span<const std::uint32_t> active,
                                                              const CullideOptions& options, QueryDevice& device,
                                                              CullideStats* stats = nullptr);

}  // namespace cullide
