// spatialhash/broad_phase.h: all overlapping pairs among n boxes or spheres.
//
// Three methods with one contract (house style: every fast path has a reference twin):
//   SpatialHash    the uniform-grid broad phase of GPU Gems 3 ch. 32 (Le Grand, "Broad-Phase
//                  Collision Detection with CUDA", 2007), ported to CPU threads;
//   SweepAndPrune  sort on the axis of greatest spread, then sweep (Ericson, Real-Time Collision
//                  Detection, 7.5.2; Baraff's sort-and-sweep);
//   BruteForce     every one of the n(n-1)/2 pairs.
// Contract: the output is every pair (a, b), a < b, of overlapping objects, exactly once, sorted by
// (a, b), and bit-identical for any thread count and any method. Boxes are closed (touching counts);
// spheres are closed too and are tested with the floating-point predicate documented in
// docs/spatialhash.md (the same function in every method, so the methods agree exactly).
// The grid's cell keys, sizing rule, huge-object handling and limits: docs/spatialhash.md.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "spatialhash/result.h"

namespace spatialhash {

// An axis-aligned box, closed: it contains its faces. Requires finite lo <= hi on each axis.
struct Box {
    double lo[3];
    double hi[3];
};

// A closed ball (the predicate is documented in docs/spatialhash.md). Requires finite coordinates with |centre[k]| <= kMaxSphereMagnitude and
// 0 <= radius <= kMaxSphereMagnitude (so that squared distances cannot overflow).
struct Sphere {
    double centre[3];
    double radius;
};
inline constexpr double kMaxSphereMagnitude = 1e150;

// One overlapping pair, always a < b.
struct Pair {
    std::uint32_t a;
    std::uint32_t b;
    friend bool operator==(const Pair&, const Pair&) = default;
};

enum class Method { SpatialHash, SweepAndPrune, BruteForce };

// The largest object count (the grid keeps 8 entries per object and 32-bit entry indices).
inline constexpr std::size_t kMaxObjects = std::size_t{1} << 28;

struct Options {
    Method method = Method::SpatialHash;
    // Worker threads; 0 = all hardware threads. The result does not depend on it.
    unsigned threads = 0;
    // SpatialHash only. 0 = automatic (the chapter's rule, with outliers handled apart, see
    // docs/spatialhash.md). Otherwise a finite positive cell edge; objects too large for it are
    // handled apart, never dropped.
    double cell_size = 0.0;
};

// What the method did, for reports and benchmarks. Fields a method does not use stay 0.
struct Stats {
    double cell_size = 0.0;             // SpatialHash: the cell edge used
    unsigned axis_bits = 0;             // SpatialHash: bits per axis in the cell key
    std::uint32_t huge_objects = 0;     // SpatialHash: objects tested apart (too large for the grid)
    std::uint64_t cell_entries = 0;     // SpatialHash: home + phantom entries (non-sentinel)
    std::uint64_t collision_cells = 0;  // SpatialHash: cells with >= 1 home and >= 2 occupants
    std::uint64_t cell_pairs = 0;       // SpatialHash: H-H and H-P pairs its cells propose (before any test)
    std::uint64_t candidate_tests = 0;  // all methods: exact (double) overlap tests performed
    int sweep_axis = -1;                // SweepAndPrune: the axis swept
};

struct PairSet {
    std::vector<Pair> pairs;  // sorted by (a, b), unique, a < b
    Stats stats;
};

// All overlapping pairs among `boxes`. Fails, naming the index, on a non-finite coordinate or
// lo > hi; on more than kMaxObjects objects; on a bad cell_size. SpatialHash also guards its key
// limit (2^50 cells from the origin per axis) with an error, which valid input cannot reach
// (docs/spatialhash.md, "Keys and limits").
Result<PairSet> find_pairs(std::span<const Box> boxes, const Options& options = {});

// All overlapping pairs among `spheres`, same contract. Fails, naming the index, on a non-finite
// or out-of-range centre or radius (see Sphere).
Result<PairSet> find_pairs(std::span<const Sphere> spheres, const Options& options = {});

// Reusable buffers for repeated calls (one per simulation, frame after frame). A frame through a
// Workspace allocates nothing proportional to n or to the pairs once an earlier frame was at least
// as large (SpatialHash; the other methods and the huge-object path still allocate), and keeps the
// thread arena. The result is the same as find_pairs without a workspace, for any scene: the
// buffers' contents never reach the output. Not for two threads at once; movable, not copyable
// (a moved-from workspace starts afresh on its next use).
namespace detail {
struct WorkspaceState;
struct WorkspaceAccess;
}
class Workspace {
   public:
    Workspace();
    ~Workspace();
    Workspace(Workspace&&) noexcept;
    Workspace& operator=(Workspace&&) noexcept;
    Workspace(const Workspace&) = delete;
    Workspace& operator=(const Workspace&) = delete;
    // Bytes of capacity held (for reports).
    [[nodiscard]] std::size_t capacity_bytes() const;

   private:
    friend struct detail::WorkspaceAccess;
    std::unique_ptr<detail::WorkspaceState> state_;
};

// As find_pairs above, through `workspace`, into `pairs` (its capacity is reused; its old content is
// replaced). Returns the statistics; on an error `pairs` is left empty.
Result<Stats> find_pairs(std::span<const Box> boxes, const Options& options, Workspace& workspace,
                         std::vector<Pair>& pairs);
Result<Stats> find_pairs(std::span<const Sphere> spheres, const Options& options, Workspace& workspace,
                         std::vector<Pair>& pairs);

// The exact overlap predicates every method uses (exposed so that callers and tests share them).
[[nodiscard]] bool overlaps(const Box& x, const Box& y);
[[nodiscard]] bool overlaps(const Sphere& x, const Sphere& y);

}  // namespace spatialhash
