// spatialhash/detail/grid_stages.h: the stages of the uniform-grid broad phase, one function each,
// exposed for the tests. Algorithm: GPU Gems 3 ch. 32 (S. Le Grand, "Broad-Phase Collision
// Detection with CUDA", 2007); the CPU port, the key layout and the outlier handling are ours.
// docs/spatialhash.md explains every stage and why it is correct.
//
//   bounding_spheres / bounding_cubes   per-object bounding volume (spheres; boxes use cubes)
//   plan_grid            bounding volumes -> cell size, origin, key layout, huge (outlier) objects
//   build_cell_ids       cell-ID array: 8 slots per object (home first, phantoms, sentinels),
//                        object array (id << 1 | phantom bit), control bits per object
//   build_cell_entries   the same entries without sentinels, straight into compact arrays (CPU
//                        addition; = drop_sentinels(build_cell_ids)); the pipeline uses this one
//   radix_sort           stable LSD radix sort of (key, value), per-chunk histograms merged in order
//   build_collision_cells  scan of the sorted keys -> cells with >= 1 H and >= 2 occupants
//   filter_boxes         float boxes per object for the pre-tests of collide_cells (CPU addition)
//   collide_cells        the 8 passes by cell type with the chapter's duplicate-avoidance rule;
//                        one visit per cell into per-item buffers -> scan -> copy
//   collide_huge         huge objects against every object; count -> scan -> fill
//   sort_pairs           the final canonical order
// Each stage also has a form that writes into caller-kept arrays (GridWorkspace, behind
// spatialhash::Workspace); the by-value forms call those with fresh arrays.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "spatialhash/broad_phase.h"
#include "spatialhash/detail/executor.h"
#include "spatialhash/result.h"

namespace spatialhash::detail {

inline constexpr int kDims = 3;
inline constexpr int kSlots = 1 << kDims;  // 2^d cell slots per object
// The chapter scales bounding spheres by sqrt(2) before finding phantom cells; docs/spatialhash.md
// proves it enough in any dimension and tests/spatialhash/sizing_test.cpp checks it.
inline constexpr double kCoverageScale = 1.4142135623730951;
// Automatic cell edge = kAutoCellFactor x the largest scaled diameter (the chapter's 1.5).
inline constexpr double kAutoCellFactor = 1.5;
// An object belongs in the grid only when cell >= kMinCellFactor x its scaled diameter. The
// duplicate-avoidance rule needs cell > (2 + sqrt 2) r = 1.207 x the scaled diameter
// (docs/spatialhash.md); 1.25 leaves room for rounding.
inline constexpr double kMinCellFactor = 1.25;
// Automatic sizing: an object whose scaled diameter exceeds kOutlierFactor x the 99th percentile
// is "huge" and tested apart, so that a few giants do not coarsen the grid for everyone.
inline constexpr double kOutlierFactor = 8.0;
inline constexpr double kOutlierQuantile = 0.99;
// Cell coordinates are measured from the grid origin and must stay at or below 2^50, so that they
// convert to integers exactly. The padding of bounding spheres (2^-46 x |centre|) already bounds
// them by about 2^46 for every gridded object (docs/spatialhash.md, "Keys and limits"), so this
// limit is a guard that valid input does not reach; plan_grid still checks it.
inline constexpr double kMaxCellCoordinate = 0x1.0p50;
// Keys keep at most 21 bits per axis; larger coordinates wrap modulo 2^21 (parity is kept, and
// wrapped cells are 2^21 cells apart, so aliasing adds candidates but never changes the result).
inline constexpr unsigned kMaxAxisBits = 21;

// A conservative bounding sphere: the object lies inside it even after rounding (the radius is
// padded by 2^-46 x (radius + max |centre[k]|), see docs/spatialhash.md).
// For box input through bounding_cubes the same struct holds a bounding cube (max-norm ball).
struct BoundingSphere {
    double centre[3];
    double radius;
};

// Bounding spheres of boxes (centre = box centre, radius = half diagonal, padded) and of spheres
// (the sphere, padded). Inputs must be valid (find_pairs validates them first).
[[nodiscard]] std::vector<BoundingSphere> bounding_spheres(std::span<const Box> boxes, Executor& ex);
[[nodiscard]] std::vector<BoundingSphere> bounding_spheres(std::span<const Sphere> spheres, Executor& ex);
// Bounding cubes of boxes (the max-norm ball: centre = box centre, radius = half the longest edge,
// padded like the spheres). Used with kCubeKnobs; find_pairs grids boxes this way.
[[nodiscard]] std::vector<BoundingSphere> bounding_cubes(std::span<const Box> boxes, Executor& ex);
// The three into a caller's vector (a Workspace's: its capacity is reused).
void bounding_spheres(std::span<const Sphere> spheres, Executor& ex, std::vector<BoundingSphere>& out);
void bounding_cubes(std::span<const Box> boxes, Executor& ex, std::vector<BoundingSphere>& out);

struct GridPlan {
    double cell_size = 0.0;
    double origin[3] = {0.0, 0.0, 0.0};
    unsigned axis_bits = 1;               // b: key = x << 2b | y << b | z
    std::uint64_t sentinel = 0;           // 2^(3b), above every real key
    unsigned key_bits = 0;                // 3b + 1: the bits the radix sort must look at
    std::vector<std::uint8_t> huge;       // per object: 1 = tested apart, not in the grid
    std::vector<std::uint32_t> huge_ids;  // ascending
    // Test knobs (the defaults are the library's; tests lower them to show they matter).
    double coverage_scale = kCoverageScale;
};

struct PlanKnobs {
    double coverage_scale = kCoverageScale;
    double min_cell_factor = kMinCellFactor;
    double auto_cell_factor = kAutoCellFactor;
};

// Box input is gridded through its bounding CUBE instead (bounding_cubes: centre = box centre,
// "radius" = half the longest edge, padded; a ball of the max-norm). For cubes the completeness
// argument needs the coverage cube scaled by 2 (the larger of two overlapping cubes then always
// covers the smaller one's home cell), and the duplicate-avoidance rule needs cell >= 4 rho_max,
// which is exactly the scaled diameter: factor 1.0. For the AABB of a sphere this cell is 4 r
// against the bounding sphere's 1.25 * 2 sqrt2 * sqrt3 r = 6.1 r (automatic: 7.35 r), so cells hold
// (7.35 / 4.4)^3 ~ 4.7x fewer objects. docs/spatialhash.md, "Sizing: boxes"; sizing_test checks it.
inline constexpr double kCubeCoverageScale = 2.0;
inline constexpr double kCubeMinCellFactor = 1.0;
// Automatic cell for cubes: kCubeAutoCellFactor x the largest scaled diameter (4 rho). Measured
// on the benchmark's scenes (docs/spatialhash.md, "Performance log"): a smaller cell means fewer
// proposals per object but more phantom entries to sort.
inline constexpr double kCubeAutoCellFactor = 1.1;
inline constexpr PlanKnobs kCubeKnobs{kCubeCoverageScale, kCubeMinCellFactor, kCubeAutoCellFactor};

// Chooses the cell edge (requested_cell_size > 0, or automatic when 0), the outliers and the key
// layout. Fails when a gridded object's cell coordinate would exceed kMaxCellCoordinate, naming it.
[[nodiscard]] Result<GridPlan> plan_grid(std::span<const BoundingSphere> spheres, double requested_cell_size,
                                         Executor& ex, const PlanKnobs& knobs = {});
// The same into a caller's plan and scratch (reused by a Workspace).
struct PlanScratch {
    std::vector<double> diameters;
    std::vector<double> sorted;
};
[[nodiscard]] Result<bool> plan_grid(std::span<const BoundingSphere> spheres, double requested_cell_size, Executor& ex,
                                     const PlanKnobs& knobs, GridPlan& plan, PlanScratch& scratch);

// The cell key of integer cell coordinates (already wrapped to axis_bits), and its type (parity).
[[nodiscard]] constexpr std::uint64_t cell_key(std::uint64_t x, std::uint64_t y, std::uint64_t z, unsigned b) {
    return (x << (2 * b)) | (y << b) | z;
}
[[nodiscard]] constexpr unsigned cell_type_of_key(std::uint64_t key, unsigned b) {
    return static_cast<unsigned>(((key >> (2 * b)) & 1U) | (((key >> b) & 1U) << 1) | ((key & 1U) << 2));
}

// Control bits of one object: bits 0-2 the type of its home cell, bits 3-10 the mask of the cell
// types it overlaps (home included). 0 for huge objects (they are not in the grid).
[[nodiscard]] constexpr unsigned home_type(std::uint16_t control) { return control & 7U; }
[[nodiscard]] constexpr unsigned type_mask(std::uint16_t control) { return (control >> 3) & 0xFFU; }

// Object-array value: object id << 1 | 1 when the entry is a phantom (P), 0 when home (H).
[[nodiscard]] constexpr std::uint32_t entry_object(std::uint32_t value) { return value >> 1; }
[[nodiscard]] constexpr bool entry_is_phantom(std::uint32_t value) { return (value & 1U) != 0; }

// Stage 1. Slot-major arrays of kSlots * n entries: entry s * n + i is slot s of object i. Slot 0
// is the home cell, slots 1.. the phantom cells in (x, y, z) order, the rest hold plan.sentinel.
// Slot-major layout puts every H entry before every P entry, so a stable sort keeps H first
// within each cell.
struct CellIdArray {
    std::vector<std::uint64_t> cell_ids;
    std::vector<std::uint32_t> objects;
    std::vector<std::uint16_t> control;  // per object
};
[[nodiscard]] CellIdArray build_cell_ids(std::span<const BoundingSphere> spheres, const GridPlan& plan, Executor& ex);

// Between stages 1 and 2 (a CPU addition): removes the sentinel entries, keeping the others in
// order, so the sort moves only real entries (about 3.4 per object instead of 8 in the benchmark's
// scenes). The sorted result equals the non-sentinel prefix that sorting the full array gives.
// Afterwards keys fit plan.key_bits - 1 bits.
void drop_sentinels(CellIdArray& ids, const GridPlan& plan, Executor& ex);

// Stage 1 and drop_sentinels in one: count (entries per chunk and slot) -> scan -> fill, without
// ever writing the 8n array. Equals drop_sentinels(build_cell_ids(...)) (tested); the pipeline
// uses this one.
[[nodiscard]] CellIdArray build_cell_entries(std::span<const BoundingSphere> spheres, const GridPlan& plan,
                                             Executor& ex);
void build_cell_entries(std::span<const BoundingSphere> spheres, const GridPlan& plan, Executor& ex, CellIdArray& out,
                        std::vector<std::size_t>& offset_scratch);

// Stage 2. Stable LSD radix sort by the low key_bits bits of keys, digits of at most 11 bits (the
// fewest passes); values follow
// their keys. Digits on which every key agrees are skipped. values may be empty (keys only).
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits, Executor& ex);
// The same over bits [first_bit, end_bit) only, with caller-kept scratch arrays (a Workspace's):
// after the call the scratch holds the previous buffers (the sort swaps them), sized >= keys.
struct RadixScratch {
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> values;
    std::vector<std::size_t> hist;
    std::vector<std::size_t> digit_start;
};
void radix_sort_bits(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned first_bit,
                     unsigned end_bit, Executor& ex, RadixScratch& scratch);

// Stage 3. One collision cell: entries [start, start + homes + phantoms) of the sorted arrays, H
// entries first.
struct CollisionCell {
    std::uint32_t start;
    std::uint32_t homes;
    std::uint32_t phantoms;
    std::uint32_t type;
};
struct CollisionCells {
    std::vector<CollisionCell> cells;  // in key order
    std::uint64_t entries = 0;         // non-sentinel entries
};
[[nodiscard]] CollisionCells build_collision_cells(std::span<const std::uint64_t> sorted_keys,
                                                   std::span<const std::uint32_t> sorted_objects,
                                                   const GridPlan& plan, Executor& ex);
void build_collision_cells(std::span<const std::uint64_t> sorted_keys, std::span<const std::uint32_t> sorted_objects,
                           const GridPlan& plan, Executor& ex, CollisionCells& out,
                           std::vector<std::uint32_t>& starts_scratch);

// The exact test between objects i and j of the caller's input.
struct Objects {
    std::span<const Box> boxes;      // exactly one of boxes / spheres is non-empty (or both empty)
    std::span<const Sphere> spheres;
    [[nodiscard]] std::size_t size() const { return boxes.empty() ? spheres.size() : boxes.size(); }
    [[nodiscard]] bool overlap(std::uint32_t i, std::uint32_t j) const {
        return boxes.empty() ? overlaps(spheres[i], spheres[j]) : overlaps(boxes[i], boxes[j]);
    }
};

// Single-precision boxes per object for the pre-test of stage 6.
//   outer: lo rounded down, hi rounded up (beyond float range: +-inf or +-FLT_MAX on the safe
//          side). Boxes get their own box; spheres get their padded bounding sphere's box, which
//          contains every point the sphere predicate can accept (the padding covers its rounding,
//          docs/spatialhash.md). Outer boxes that miss prove that the objects do not overlap.
//   inner: boxes only, lo rounded up, hi rounded down (spheres: empty). Inner boxes that meet
//          prove that the double boxes overlap (x.lo <= inner x.lo <= inner y.hi <= y.hi).
// Only pairs that the two tests leave undecided (near-touching within float rounding, and every
// sphere pair) reach the exact double test, so results stay exact.
struct FilterBox {
    float lo[3];
    float hi[3];
    float inner_lo[3];
    float inner_hi[3];
};
[[nodiscard]] std::vector<FilterBox> filter_boxes(const Objects& objects, std::span<const BoundingSphere> spheres,
                                                  Executor& ex);
void filter_boxes(const Objects& objects, std::span<const BoundingSphere> spheres, Executor& ex,
                  std::vector<FilterBox>& out);
[[nodiscard]] constexpr bool outer_overlap(const FilterBox& x, const FilterBox& y) {
    return x.lo[0] <= y.hi[0] && y.lo[0] <= x.hi[0] && x.lo[1] <= y.hi[1] && y.lo[1] <= x.hi[1] &&
           x.lo[2] <= y.hi[2] && y.lo[2] <= x.hi[2];
}
[[nodiscard]] constexpr bool inner_overlap(const FilterBox& x, const FilterBox& y) {
    return x.inner_lo[0] <= y.inner_hi[0] && y.inner_lo[0] <= x.inner_hi[0] && x.inner_lo[1] <= y.inner_hi[1] &&
           y.inner_lo[1] <= x.inner_hi[1] && x.inner_lo[2] <= y.inner_hi[2] && y.inner_lo[2] <= x.inner_hi[2];
}

// The chapter's rule: in a pass over cells of type t, skip a pair when, for x in {a, b}, the type
// T of x's home cell is < t and both objects overlap a cell of type T (they then share x's home,
// where the pair was tested in pass T).
[[nodiscard]] constexpr bool tested_in_earlier_pass(std::uint16_t ca, std::uint16_t cb, unsigned t) {
    const unsigned both = type_mask(ca) & type_mask(cb);
    const unsigned ta = home_type(ca);
    const unsigned tb = home_type(cb);
    return (ta < t && ((both >> ta) & 1U) != 0) || (tb < t && ((both >> tb) & 1U) != 0);
}

// What stage 6 did: pairs the cells proposed (H-H and H-P, before anything is skipped) and exact
// (double) tests run after the float pre-test and the duplicate-avoidance rule.
struct CollideCounts {
    std::uint64_t cell_pairs = 0;
    std::uint64_t exact_tests = 0;
};

// Stages 4-5. The 2^d passes, one per cell type; in a cell each H entry is tested against every
// later entry (never P-P). A pair goes through the outer float test (filter, one entry per object),
// then the duplicate-avoidance rule, then the inner float test and, if that cannot decide, the exact
// test. Pairs come out with a < b, pass by pass,
// cells in key order; they are not yet sorted.
[[nodiscard]] std::vector<Pair> collide_cells(const CollisionCells& cells, std::span<const std::uint32_t> sorted_objects,
                                              std::span<const std::uint16_t> control, const Objects& objects,
                                              std::span<const FilterBox> filter, Executor& ex,
                                              CollideCounts* counts = nullptr);
// The same into `out`, with the per-item buffers kept in `scratch` between calls (a Workspace's).
struct CollideScratch {
    struct Item {
        std::uint32_t begin;  // into cells.cells
        std::uint32_t end;
    };
    std::vector<Item> items;
    std::vector<std::array<std::vector<Pair>, kSlots>> found;  // per item, per cell type
    std::vector<CollideCounts> item_counts;
    std::vector<std::size_t> offsets;
};
CollideCounts collide_cells(const CollisionCells& cells, std::span<const std::uint32_t> sorted_objects,
                            std::span<const std::uint16_t> control, const Objects& objects,
                            std::span<const FilterBox> filter, Executor& ex, std::vector<Pair>& out,
                            CollideScratch& scratch);

// Huge objects against every object (each pair once), count -> scan -> fill.
[[nodiscard]] std::vector<Pair> collide_huge(std::span<const std::uint32_t> huge_ids, std::span<const std::uint8_t> huge,
                                             const Objects& objects, Executor& ex,
                                             std::uint64_t* candidate_tests = nullptr);

// Sorts pairs by (a, b) (radix sort on a << 32 | b).
void sort_pairs(std::vector<Pair>& pairs, std::size_t object_count, Executor& ex);
// The same with caller-kept scratch (a Workspace's). Radix sort on the bits of a in use, then each
// run of equal a sorted by b (the pairs must be unique, as every stage's output is).
void sort_pairs(std::vector<Pair>& pairs, std::size_t object_count, Executor& ex, std::vector<std::uint64_t>& keys,
                RadixScratch& scratch);

// Every array of the grid pipeline, kept between calls by spatialhash::Workspace so that a frame
// of the same or a smaller scene allocates nothing proportional to n or to the pairs.
struct GridWorkspace {
    std::vector<BoundingSphere> bounds;
    GridPlan plan;
    PlanScratch plan_scratch;
    CellIdArray ids;
    std::vector<std::size_t> entry_offsets;
    RadixScratch radix;        // the cell-key sort
    RadixScratch radix_pairs;  // the pair sort (its own, so that the two sizes never trade buffers)
    CollisionCells cells;
    std::vector<std::uint32_t> cell_starts;
    std::vector<FilterBox> filter;
    CollideScratch collide;
    std::vector<std::uint64_t> pair_keys;
};

// The whole grid pipeline on validated input (find_pairs calls it after validation).
[[nodiscard]] Result<PairSet> grid_find_pairs(const Objects& objects, std::span<const BoundingSphere> spheres,
                                              double requested_cell_size, Executor& ex, const PlanKnobs& knobs = {});
// The same with the workspace's arrays; the bounding volumes must already be in ws.bounds. The pairs
// go into `pairs` (its capacity reused), the statistics are returned.
[[nodiscard]] Result<Stats> grid_find_pairs(const Objects& objects, double requested_cell_size, Executor& ex,
                                            const PlanKnobs& knobs, GridWorkspace& ws, std::vector<Pair>& pairs);

}  // namespace spatialhash::detail
