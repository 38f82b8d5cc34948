// exact_stage.h (private): the one exact stage every method ends in, and the one sweep and prune.
//
// Input: candidate sets (runs of one object's triangles with a box: a whole mesh's triangles one by
// one for the ground truth, live sub-objects for CULLIDE, tagged items for Quick-CULLIDE) and which
// pairs of sets to look at: either every pair whose boxes overlap (`sweep_exact_stage`, swept per
// pair of overlapping objects) or a list the caller already filtered (`listed_exact_stage`). Output:
// the colliding triangle pairs, canonical and sorted (ground_truth.h), and counts. A triangle pair
// is tested exactly (tri_tri.h) when its two boxes overlap and, inside one object, when the two
// triangles share no welded vertex (adjacent: counted, never tested).
//
// Deterministic: work is cut into units fixed by the input (runs of a task's grid cells holding
// about kSweepChunk refs, kPairChunk listed pairs), units run on up to `threads` workers (cullide/src/parallel.h), and
// the outputs are merged in unit order and sorted on unique keys. This is the place to make the
// exact stage fast; callers only say which sets may meet.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"

namespace cullide::detail {

// validate_exact_range (ground_truth.h) for one object, named as object `index` of its scene.
[[nodiscard]] Status validate_exact_range_of(const Mesh& m, std::size_t index);

// ---- The sweep and prune -------------------------------------------------------------------------

// A box in a sweep: a whole candidate set (part == kWholeSet) or one triangle (part = its position
// in its object). (set, part) makes the sort key unique (ties on the box are broken by it), so the
// order, and anything merged in it, does not depend on the sort algorithm.
inline constexpr std::uint32_t kWholeSet = 0xffffffffu;
struct SweepRef {
    Aabb box;
    std::uint32_t object = 0;  // pairs of one object are skipped unless the sweep allows them
    std::uint32_t set = 0;
    std::uint32_t part = kWholeSet;
};

// The axis where the boxes' centres spread most (a sweep along it meets the fewest false overlaps).
[[nodiscard]] int spread_axis(std::span<const SweepRef> refs);
// Sorts `refs` by (box.lo[axis], set, part).
void sort_along(std::vector<SweepRef>& refs, int axis);

// Calls visit(refs[i], refs[j]) for every i in [begin, end) and j > i whose boxes overlap, `refs`
// sorted by sort_along(axis); refs of one object only when `same_object`. Any [begin, end) split of
// the list visits each pair once. The object test comes before the box test: it is one integer
// compare, and in a task of two objects half the refs the sweep meets are the same object's.
template <class Visit>
void sweep_overlaps(std::span<const SweepRef> refs, int axis, std::size_t begin, std::size_t end, bool same_object,
                    Visit&& visit) {
    for (std::size_t i = begin; i < end; ++i) {
        const SweepRef& a = refs[i];
        const double a_hi = a.box.hi[axis];
        for (std::size_t j = i + 1; j < refs.size() && refs[j].box.lo[axis] <= a_hi; ++j) {
            if (!same_object && refs[j].object == a.object) continue;
            if (overlaps(a.box, refs[j].box)) visit(a, refs[j]);
        }
    }
}

// Pairs (a < b) of the `set` values of `refs` whose boxes overlap (any objects), sorted. `refs` is
// sorted here, along its spread axis.
[[nodiscard]] std::vector<std::pair<std::uint32_t, std::uint32_t>> overlapping_sets(std::vector<SweepRef> refs,
                                                                                    int threads);
// The same pairs, only those keep(a, b) accepts (a < b; keep is called concurrently), with
// `overlapping` set to how many pairs overlap in all (kept or not).
[[nodiscard]] std::vector<std::pair<std::uint32_t, std::uint32_t>> overlapping_sets(
    std::vector<SweepRef> refs, int threads, const std::function<bool(std::uint32_t, std::uint32_t)>& keep,
    std::uint64_t& overlapping);

// A box in floats rounded outward (it holds the double box it was made from): a cheap, never-missing
// filter; float_overlaps(a, b) false means the double boxes are disjoint too.
struct FloatBox {
    float lo[3] = {1, 1, 1};
    float hi[3] = {0, 0, 0};
};

// The largest float <= x and the smallest float >= x (beyond the float range: +-infinity on the
// outer side, +-the largest float on the inner one). Branch-free: half of all conversions round the
// wrong way, so branches on it are mispredicted half the time.
[[nodiscard]] inline float float_down(double x) {
    constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
    const auto f = static_cast<float>(std::clamp(x, -kMax, kMax));
    // Floats as sign-magnitude integers, mapped to two's complement to step one float down.
    auto ordered = std::bit_cast<std::int32_t>(f);
    ordered ^= (ordered >> 31) & 0x7fffffff;
    ordered -= static_cast<double>(f) > x ? 1 : 0;
    return std::bit_cast<float>(ordered ^ ((ordered >> 31) & 0x7fffffff));
}
[[nodiscard]] inline float float_up(double x) { return -float_down(-x); }

[[nodiscard]] inline FloatBox float_box(const Aabb& b) {
    FloatBox f;
    for (int k = 0; k < 3; ++k) {
        f.lo[k] = float_down(b.lo[k]);
        f.hi[k] = float_up(b.hi[k]);
    }
    return f;
}

#if defined(__SSE2__)
// The box whose lows are (lo_xy, lo_z) and highs (hi_xy, hi_z), x and y in the two lanes, z in the
// low lane: the layout of the SSE2 min/max loops (the ground truth's scan, the auto plan's boxes).
[[nodiscard]] inline Aabb aabb_sse2(__m128d lo_xy, __m128d lo_z, __m128d hi_xy, __m128d hi_z) {
    Aabb box;
    _mm_storeu_pd(&box.lo.x, lo_xy);
    _mm_store_sd(&box.lo.z, lo_z);
    _mm_storeu_pd(&box.hi.x, hi_xy);
    _mm_store_sd(&box.hi.z, hi_z);
    return box;
}

// float_box of the box whose lows are (lo_xy, lo_z) and highs (hi_xy, hi_z), x and y in the two
// lanes, z in the low lane: the scan hands its SSE2 registers over as they are.
[[nodiscard]] inline FloatBox float_box_sse2(__m128d lo_xy, __m128d lo_z, __m128d hi_xy, __m128d hi_z) {
    // The six float_down arguments lo.x, lo.y | lo.z, -hi.x | -hi.y, -hi.z (float_up(x) = -float_down(-x)).
    constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
    const __m128d neg = _mm_set1_pd(-0.0);
    const __m128d nhi_xy = _mm_xor_pd(hi_xy, neg), nhi_z = _mm_xor_pd(hi_z, neg);
    const __m128d x0 = lo_xy, x1 = _mm_unpacklo_pd(lo_z, nhi_xy), x2 = _mm_shuffle_pd(nhi_xy, nhi_z, 1);
    const auto down4 = [&](__m128d a, __m128d b) {
        const __m128d ca = _mm_min_pd(_mm_max_pd(a, _mm_set1_pd(-kMax)), _mm_set1_pd(kMax));
        const __m128d cb = _mm_min_pd(_mm_max_pd(b, _mm_set1_pd(-kMax)), _mm_set1_pd(kMax));
        const __m128 fa = _mm_cvtpd_ps(ca), fb = _mm_cvtpd_ps(cb);
        const __m128 both = _mm_movelh_ps(fa, fb);
        // Lanes whose float lies above its (unclamped) double step one float down.
        const __m128d above_a = _mm_cmpgt_pd(_mm_cvtps_pd(fa), a), above_b = _mm_cmpgt_pd(_mm_cvtps_pd(fb), b);
        const __m128i above = _mm_castps_si128(
            _mm_shuffle_ps(_mm_castpd_ps(above_a), _mm_castpd_ps(above_b), _MM_SHUFFLE(2, 0, 2, 0)));
        const __m128i magnitude = _mm_set1_epi32(0x7fffffff);
        __m128i ordered = _mm_castps_si128(both);
        ordered = _mm_xor_si128(ordered, _mm_and_si128(_mm_srai_epi32(ordered, 31), magnitude));
        ordered = _mm_add_epi32(ordered, above);  // above: -1 in the lanes that step
        return _mm_castsi128_ps(_mm_xor_si128(ordered, _mm_and_si128(_mm_srai_epi32(ordered, 31), magnitude)));
    };
    alignas(16) float d[8];
    _mm_store_ps(d, down4(x0, x1));
    _mm_store_ps(d + 4, down4(x2, x2));
    FloatBox f;
    f.lo[0] = d[0];
    f.lo[1] = d[1];
    f.lo[2] = d[2];
    f.hi[0] = -d[3];
    f.hi[1] = -d[4];
    f.hi[2] = -d[5];
    return f;
}

// The same bits as float_box_sse2 by the conversion's own rounding: float_down(x) is x rounded
// toward -infinity (IEEE 754 directed rounding: beyond the float range it gives -infinity below and
// the largest float above, as float_down does; a tiny x gives 0 or -denorm_min, again as float_down;
// signed zeros stay) and float_up(x) is -float_down(-x). So with MXCSR set to round down (a
// RoundDownScope alive on this thread), three CVTPD2PS and two sign flips replace float_down's
// clamp, compare and one-step correction: 9 instructions a box instead of about 40, in the
// ground truth's scan, where the rounding was a third of breaking's per-triangle instructions.
[[nodiscard]] inline FloatBox float_box_round_down(__m128d lo_xy, __m128d lo_z, __m128d hi_xy, __m128d hi_z) {
    const __m128d neg = _mm_set1_pd(-0.0);
    const __m128d nhi_xy = _mm_xor_pd(hi_xy, neg), nhi_z = _mm_xor_pd(hi_z, neg);
    // lo.x, lo.y, lo.z, -hi.x rounded down; then -hi.y, -hi.z rounded down; the hi lanes negated back.
    const __m128 first = _mm_movelh_ps(_mm_cvtpd_ps(lo_xy), _mm_cvtpd_ps(_mm_unpacklo_pd(lo_z, nhi_xy)));
    const __m128 second = _mm_cvtpd_ps(_mm_shuffle_pd(nhi_xy, nhi_z, 1));
    static_assert(sizeof(FloatBox) == 6 * sizeof(float));  // lo then hi, no padding
    FloatBox f;
    auto* const bounds = reinterpret_cast<float*>(&f);  // the whole object: no store past a member array
    _mm_storeu_ps(bounds, _mm_xor_ps(first, _mm_castsi128_ps(_mm_set_epi32(INT32_MIN, 0, 0, 0))));
    _mm_storel_pi(reinterpret_cast<__m64*>(bounds + 4), _mm_xor_ps(second, _mm_set1_ps(-0.0f)));
    return f;
}

// MXCSR set to round toward -infinity for float_box_round_down while alive, the caller's MXCSR
// restored after (MXCSR is per thread: make one inside each parallel job). The mode is set whole
// (every exception masked, no flush-to-zero, no denormals-are-zero), so a caller's FTZ or DAZ
// cannot change the bits.
class RoundDownScope {
   public:
    RoundDownScope() : saved_(_mm_getcsr()) { _mm_setcsr(0x1f80u | 0x2000u); }
    ~RoundDownScope() { _mm_setcsr(saved_); }
    RoundDownScope(const RoundDownScope&) = delete;
    RoundDownScope& operator=(const RoundDownScope&) = delete;

   private:
    unsigned saved_;
};
#endif

// float_box of the box [lo, hi], every bound as float_down / float_up give it (the same bits; x86-64:
// four bounds per SSE2 step, the same round-to-nearest conversion and one-step correction). The
// ground truth's scan rounds every triangle's box, 6 bounds each: scalar, that was a quarter of its
// time on breaking and leaves.
[[nodiscard]] inline FloatBox float_box(const Vec3& lo, const Vec3& hi) {
#if defined(__SSE2__)
    return float_box_sse2(_mm_set_pd(lo.y, lo.x), _mm_set_sd(lo.z), _mm_set_pd(hi.y, hi.x), _mm_set_sd(hi.z));
#else
    FloatBox f;
    for (int k = 0; k < 3; ++k) {
        f.lo[k] = float_down(lo[k]);
        f.hi[k] = float_up(hi[k]);
    }
    return f;
#endif
}

[[nodiscard]] inline bool float_overlaps(const FloatBox& a, const FloatBox& b) {
    return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] &&
           a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2];
}

// ---- The exact stage -----------------------------------------------------------------------------

// One object's triangles as the exact stage reads them: position p is mesh triangle order[p]
// (p itself when `order` is empty), with box triangle_boxes[p]. Spans must outlive the call.
struct ExactObject {
    const Mesh* mesh = nullptr;
    std::uint32_t object = 0;              // reported in the pairs (index into the caller's objects)
    Aabb box;                              // holds every set of the object (sweep_exact_stage's tasks)
    std::span<const Aabb> triangle_boxes;  // by position; sweep_exact_stage never reads it when every
                                           // set of the object holds one triangle (the set's box is
                                           // the triangle's), so it may be empty then
    std::span<const std::uint32_t> order;  // mesh triangle by position; empty: the identity
    std::span<const std::uint32_t> weld;   // welded vertex ids (weld_vertices); needed for self pairs
};

// Positions [first, first + count) of exact object `object` (an index into the ExactObject list);
// `box` holds their triangle boxes. Sets of one object are listed consecutively, objects in order.
struct CandidateSet {
    std::uint32_t object = 0;
    std::uint32_t first = 0, count = 0;
    Aabb box;
};

// Two sets to test against each other (a <= b; a == b: the set's own triangle pairs). `near`
// only feeds ExactStageStats::near_tests.
struct CandidatePair {
    std::uint32_t a = 0, b = 0;
    bool near = false;
};

struct ExactStageStats {
    std::uint64_t task_triangles = 0;  // sweep: triangles of sets meeting the common box of two
                                       // overlapping objects (every set's with self)
    std::uint64_t tests = 0;           // triangle pairs sent to the exact test
    std::uint64_t near_tests = 0;      // listed: of those, from near pairs
    std::uint64_t adjacent_skipped = 0;
    std::uint64_t set_pairs = 0;       // sweep with count_set_pairs: set pairs holding a tested pair
};

struct ExactStageResult {
    std::vector<TrianglePair> pairs;  // canonical, sorted, unique
    ExactStageStats stats;
};

struct SweepOptions {
    bool self = false;              // pairs of one object's sets too (one task per object)
    bool count_set_pairs = false;   // fill ExactStageStats::set_pairs
    int threads = 0;
};

// Every triangle pair of overlapping boxes from sets of two objects whose boxes overlap (and of one
// object with `self`). One task per such pair of objects holds the sets meeting the two boxes'
// intersection (no pair outside it can meet) and is swept on its own, in a grid of cells over the
// two axes other than the sweep axis (each overlapping pair visited once, in the cell holding the
// low corner of the two boxes' intersection); it sweeps the triangles
// instead of the sets when the sets are loose (their boxes' summed extent along the axis is more
// than 4 times their triangles': consecutive triangles of a scrambled or thinned mesh lie far apart,
// and a set sweep would meet more overlaps than a triangle sweep). The pairs tested are the same
// either way. A self task (one object's sets) always sweeps its triangles.
[[nodiscard]] ExactStageResult sweep_exact_stage(std::span<const ExactObject> objects,
                                                 std::span<const CandidateSet> sets, const SweepOptions& options);

// The ground truth's stage: every triangle of every object a candidate of its own (each object's
// triangle_boxes holds all its triangles' boxes, `order` is empty). The same pairs and statistics as
// sweep_exact_stage with one single-triangle set per triangle (task_triangles: triangles meeting
// some task's common box, all with `self`), on leaner data: float boxes rounded outward in the sweep
// (exact double boxes decide), and big tasks cut into slabs of grid rows so they spread over threads.
// What sweep_exact_triangles reads besides an object's triangle_boxes: those boxes rounded outward,
// and the box of each block of kBoxBlock consecutive triangles (a gather skips a block missing the
// common box at once: meshes list neighbouring triangles close together).
inline constexpr std::size_t kBoxBlock = 64;
struct TriangleBoxes {
    std::span<const FloatBox> floats;  // floats[p] = float_box(triangle_boxes[p])
    std::span<const Aabb> blocks;      // blocks[b]: the box of triangles [b * kBoxBlock, (b + 1) * kBoxBlock)
};
[[nodiscard]] ExactStageResult sweep_exact_triangles(std::span<const ExactObject> objects,
                                                     std::span<const TriangleBoxes> boxes, const SweepOptions& options);

// The triangle pairs of exactly the listed set pairs.
[[nodiscard]] ExactStageResult listed_exact_stage(std::span<const ExactObject> objects,
                                                  std::span<const CandidateSet> sets,
                                                  std::span<const CandidatePair> pairs, int threads);

}  // namespace cullide::detail
