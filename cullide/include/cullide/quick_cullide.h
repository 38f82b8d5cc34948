// cullide/quick_cullide.h: Quick-CULLIDE, the visibility classification that keeps per-object tags
// across passes, rounds and view axes, and its self-collision use.
//
// After Govindaraju, Lin and Manocha, "Quick-CULLIDE: Fast Inter- and Intra-Object Collision
// Culling Using Graphics Hardware" (IEEE VR 2005). The code is ours; ../shared/docs/algorithms.md
// section 5 is the specification and docs/quick-cullide.md records the choices made where the
// paper is silent (above all how adjacent triangles are kept out of the visibility test).
//
// Items (object boxes, objects, sub-objects, triangles) sit in one fixed global order, each with a
// tag: NFV (nothing proven), FFV (apart from every earlier item), SFV (apart from every later
// item), BFV (both: pruned). Each view runs
//   pass 1 (forward):  query the item if it is not FFV, draw it if it is not SFV; fully visible -> +FFV
//   pass 2 (backward): query the item if it is not SFV, draw it if it is not FFV; fully visible -> +SFV
// Tags are geometric facts, so they persist across views and rounds, and are inherited by the
// pieces of an item at the next, finer stage (a piece of a box that is FFV is FFV too).
//
// "Every earlier item" excludes the item's NEAR items: the items of the same object when
// self-collision is off (CULLIDE's rule: the pieces of one object are never tested against each
// other), and, with self-collision on, the items of the same object within W positions of it in
// that object's order, where W (the window) is the largest order distance between two items whose
// triangles share a welded vertex. Exclusion is done by deferral: in pass 1 an item is drawn right
// after the query of its last near item (in pass 2, of its first), so no query ever sees a near
// item in the depth buffer. Each object's triangles are put in a bandwidth-reducing order first
// (their input order or a Cuthill-McKee breadth-first order, whichever gives the smaller W).
//
// Pair generation: item pairs whose boxes overlap (sweep and prune); a pair (a before b) that is
// not near is skipped when b is FFV or a is SFV; near pairs of one object are kept only with
// self-collision on (they are what the window could not test). Then triangle pairs by box, welded
// adjacency dropped (self pairs), and the exact test of tri_tri.h.
//
// Stages: self-collision off: object boxes -> objects -> sub-objects of `subobject_triangles`
// triangles -> single triangles (when sub-objects have more than one). Self-collision on: one stage
// over the sub-objects of every object (tags cannot be inherited across a change of the near
// relation, and with self-collision every object stays a candidate), after a box classification
// on the CPU (ours): the item boxes are paired once by sweep and prune, and an item whose box meets
// no earlier (later) non-near item's box is FFV (SFV) before any pass, so the passes draw only the
// items that have a far neighbour in space (none on a flat sheet alone).
//
// Views: orthographic, fitted to the live items' bounds, starting along the axis of least extent of
// the stage's first bounds and then cycling, until three views in a row are quiet (each gains at
// most 1/64 of the live items' count in new tags; ours, see docs/quick-cullide.md) or
// 3 * max_rounds views ran.
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

// Quick-CULLIDE's options: the shared ones (visibility.h) and its own.
struct QuickOptions : VisibilityOptions {
    // ExactBounds (reliable, emulator only) or GLExact (pixel centres, may miss like the GPU).
    // Offset is refused.
    VisibilityMode mode = VisibilityMode::ExactBounds;
    bool self = false;  // also pairs inside one object (welded-adjacent triangles excluded)
    // Benchmarks only: skip the visibility passes (every item stays NFV), which leaves the
    // box-prefiltered all-pairs test (sweep and prune on item boxes, then triangle boxes, adjacency,
    // exact test): the peer the culling is measured against.
    bool skip_visibility = false;
    // ExactBounds: answer each view's two passes with the device's quick_view (on the emulator
    // raster::WindowedPasses: each item rasterized once per view instead of up to four times, the
    // same tags bit for bit). The statistics still count the queries and triangles of the recorded
    // passes it replaces. false records and executes the passes (tests compare the two).
    bool fused_visibility = true;
};

// The shared figures (visibility.h) read as follows, and Quick-CULLIDE's own:
//  pcs_boxes       not BFV after the box stage (self off: object boxes through the passes; self on:
//                  item boxes by sweep and prune)
//  pcs_objects     after the object stage (self off)
//  subobjects, pcs_subobjects  items entering the sub-object stage, not BFV after it
//  candidate_triangles  triangles in kept item pairs (counted per item once)
//  subobjects_ms   includes the triangle stage
struct QuickStats : VisibilityStats {
    std::uint64_t triangles_in = 0;     // items entering the triangle stage (self off, sub-objects > 1)
    std::uint64_t pcs_triangles = 0;    // not BFV after it
    std::uint64_t window_max = 0;       // largest self window W over the objects (items)
    std::uint64_t item_pairs = 0;       // item pairs with overlapping boxes (sweep and prune)
    std::uint64_t item_pairs_kept = 0;  // of those, not proven apart by tags (sent on)
    std::uint64_t near_item_pairs = 0;  // of the kept, near pairs (self window)
    std::uint64_t near_exact_tests = 0; // of exact_tests, from near item pairs
};

// Colliding triangle pairs found by Quick-CULLIDE among the objects listed in `active` (increasing
// indices into `objects`), canonical and sorted as ground_truth.h; with options.self, also pairs
// inside one object whose triangles share no welded vertex. Every reported pair collides;
// ExactBounds reports every colliding pair, GLExact may miss some. Fails, naming what is wrong, on
// invalid meshes, coordinates outside the exact range, bad options (Offset mode among them), an
// unsorted or out-of-range `active`, or a device error.
[[nodiscard]] Result<std::vector<TrianglePair>> quick_cullide_pairs(std::span<const Mesh> objects,
                                                                    std::span<const std::uint32_t> active,
                                                                    const QuickOptions& options, QueryDevice& device,
                                                                    QuickStats* stats = nullptr);

}  // namespace cullide
