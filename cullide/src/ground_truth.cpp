#include "cullide/ground_truth.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <string>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cullide/predicates.h"
#include "exact_stage.h"
#include "kept.h"
#include "parallel.h"

namespace cullide {

std::vector<std::uint32_t> weld_vertices(const Mesh& mesh) {
    // One pass in vertex order over a hash table of the positions met so far (open addressing,
    // linear probing, a slot holding the first vertex of its position): a vertex takes the id of
    // the first vertex with an equal position, or the next id. That numbers ids by first
    // appearance, as the definition says. It replaced a comparison sort of the vertex indices by
    // position (3.7% of a qcullide --self cloth frame; the twin in tests/cullide/ground_truth_test.cpp).
    // Equality is the positions' ==: -0.0 and 0.0 hash alike (x + 0.0 is +0.0 for either), and a
    // position with a NaN coordinate equals nothing, itself included, so it gets an id of its own.
    const std::size_t n = mesh.positions.size();
    std::vector<std::uint32_t> id(n);
    std::size_t capacity = 16;
    while (capacity < 2 * n) capacity <<= 1;
    const std::size_t mask = capacity - 1;
    constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> slot(capacity, kEmpty);
    const auto bits = [](double d) { return std::bit_cast<std::uint64_t>(d + 0.0); };
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < n; ++v) {
        const Vec3& p = mesh.positions[v];
        if (!(p == p)) {  // a NaN coordinate
            id[v] = next++;
            continue;
        }
        std::uint64_t h = bits(p.x) * 0x9e3779b97f4a7c15ull;
        h = (h ^ (h >> 29) ^ bits(p.y)) * 0xbf58476d1ce4e5b9ull;
        h = (h ^ (h >> 31) ^ bits(p.z)) * 0x94d049bb133111ebull;
        std::size_t k = static_cast<std::size_t>(h ^ (h >> 32)) & mask;
        while (slot[k] != kEmpty && !(mesh.positions[slot[k]] == p)) k = (k + 1) & mask;
        if (slot[k] == kEmpty) {
            slot[k] = static_cast<std::uint32_t>(v);
            id[v] = next++;
        } else {
            id[v] = id[slot[k]];
        }
    }
    return id;
}

std::vector<ObjectPair> object_pairs(std::span<const TrianglePair> pairs) {
    std::vector<ObjectPair> out;
    for (const TrianglePair& p : pairs) {
        ObjectPair o{p.object_a, p.object_b};
        if (out.empty() || out.back() != o) out.push_back(o);
    }
    // Input is sorted by (object_a, triangle_a, object_b, ...): object pairs may interleave.
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

namespace detail {

Status validate_exact_range_of(const Mesh& m, std::size_t index) {
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
        for (int k = 0; k < 3; ++k) {
            if (!predicate_coordinate_ok(m.positions[v][k])) {
                char value[32];
                std::snprintf(value, sizeof value, "%.17g", m.positions[v][k]);
                return Error{"object " + std::to_string(index) + ": mesh '" + m.name + "': vertex " + std::to_string(v) +
                             " coordinate " + "xyz"[k] + " = " + value +
                             " is outside the exact range (0, or 2^-300 <= |x| <= 2^300)"};
            }
        }
    }
    return {};
}

}  // namespace detail

Status validate_exact_range(std::span<const Mesh> objects) {
    // The exact predicates are exact only inside their range (predicates.h): refuse, never guess.
    for (std::size_t i = 0; i < objects.size(); ++i)
        if (Status s = detail::validate_exact_range_of(objects[i], i); !s) return s;
    return {};
}

namespace {

// 1 when x is outside the exact range, else 0: !predicate_coordinate_ok(x) on the bits. |x|'s bits
// as an integer grow with |x| (infinities and NaNs above every finite value), so the range is one
// unsigned compare, and 0 the one exception. Comparisons of doubles branched on every coordinate of
// the scan's vertex jobs.
constexpr unsigned coordinate_bad(double x) {
    constexpr std::uint64_t kLo = std::bit_cast<std::uint64_t>(kPredicateMinAbs);
    constexpr std::uint64_t kHi = std::bit_cast<std::uint64_t>(kPredicateMaxAbs);
    const std::uint64_t m = std::bit_cast<std::uint64_t>(x) & 0x7fffffffffffffffULL;
    return static_cast<unsigned>(m - kLo > kHi - kLo) & static_cast<unsigned>(m != 0);
}
constexpr bool same_as_predicate(double x) { return coordinate_bad(x) == (predicate_coordinate_ok(x) ? 0u : 1u); }
static_assert(same_as_predicate(0.0) && same_as_predicate(-0.0) && same_as_predicate(1.0) && same_as_predicate(-3.5e7));
static_assert(same_as_predicate(kPredicateMinAbs) && same_as_predicate(-kPredicateMinAbs) &&
              same_as_predicate(kPredicateMaxAbs) && same_as_predicate(-kPredicateMaxAbs));
constexpr double step_bits(double x, std::int64_t by) {  // by floats in x's magnitude, for the checks
    return std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) + static_cast<std::uint64_t>(by));
}
static_assert(same_as_predicate(step_bits(kPredicateMinAbs, -1)) && same_as_predicate(step_bits(kPredicateMaxAbs, 1)) &&
              same_as_predicate(step_bits(-kPredicateMinAbs, -1)) && same_as_predicate(step_bits(-kPredicateMaxAbs, 1)) &&
              same_as_predicate(0x1p-1074) && same_as_predicate(-0x1p-1074) && same_as_predicate(1e308));
static_assert(same_as_predicate(std::numeric_limits<double>::infinity()) &&
              same_as_predicate(-std::numeric_limits<double>::infinity()) &&
              same_as_predicate(std::numeric_limits<double>::quiet_NaN()) &&
              same_as_predicate(-std::numeric_limits<double>::quiet_NaN()));

// One job of exact_pairs' first pass: triangles [first, last) of an object (indices in range, and
// their boxes) or its positions [first, last) (coordinates in the exact range).
struct ScanJob {
    std::uint32_t object = 0;
    bool positions = false;
    std::size_t first = 0, last = 0;
};
// A multiple of detail::kBoxBlock. Small enough that a big object makes many jobs: oneTBB splits the
// job list in halves and a thread that runs dry steals whole jobs, so the tree of leaves' 3 triangle
// jobs of 16 K and 2 vertex jobs, first in the list, kept the first thread busy while the second
// finished the 300 small ones (a model of that list, 5 big jobs then 300 small, on a 2-thread
// arena: 1202 units on the caller, 598 on the worker; as 17 jobs a third the size: 980 and 810).
constexpr std::size_t kScanChunk = 4096;

// An array the scan jobs construct in place: std::vector's resize would first write every element,
// on one thread (12 MB on bunny-dragon). Only trivially destructible elements, each constructed by a
// job before anything reads it. Its storage is kept by the calling thread between calls (kept.h:
// otherwise its pages may be faulted in afresh every frame); Tag names the array.
template <class T, class Tag>
class ScanArray {
    static_assert(std::is_trivially_destructible_v<T>);
    static_assert(alignof(T) <= __STDCPP_DEFAULT_NEW_ALIGNMENT__);

   public:
    explicit ScanArray(std::size_t n)
        : data_(reinterpret_cast<T*>(kept_->reserve(std::max<std::size_t>(n, 1) * sizeof(T)))) {}
    [[nodiscard]] T* data() const { return data_; }

   private:
    detail::Kept<detail::KeptBytes, Tag> kept_;
    T* data_;
};
struct TriangleBoxesTag;
struct FloatBoxesTag;
struct BlockBoxesTag;

}  // namespace

Result<std::vector<TrianglePair>> exact_pairs(std::span<const Mesh> objects, const ExactOptions& options,
                                              ExactStats* stats) {
    // One parallel pass checks the scene (indices, coordinates in the exact range) and computes every
    // triangle's box and every object's box (mesh_bounds: the union of its triangles' boxes). When it
    // finds a problem, the serial checks name the first one, with the messages they always give.
    const std::size_t n = objects.size();
    bool ok = std::all_of(objects.begin(), objects.end(), [](const Mesh& m) { return !m.triangles.empty(); }) &&
              n <= UINT32_MAX;
    std::vector<std::size_t> first_triangle(n + 1, 0), first_block(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
        first_triangle[i + 1] = first_triangle[i] + objects[i].triangles.size();
        first_block[i + 1] = first_block[i] + (objects[i].triangles.size() + detail::kBoxBlock - 1) / detail::kBoxBlock;
    }
    ScanArray<Aabb, TriangleBoxesTag> boxes(ok ? first_triangle[n] : 0);
    ScanArray<detail::FloatBox, FloatBoxesTag> floats(ok ? first_triangle[n] : 0);
    ScanArray<Aabb, BlockBoxesTag> blocks(ok ? first_block[n] : 0);
    std::vector<detail::ExactObject> exact(n);
    if (ok) {
        std::vector<ScanJob> jobs;
        for (std::size_t i = 0; i < n; ++i) {
            const auto object = static_cast<std::uint32_t>(i);
            for (std::size_t f = 0; f < objects[i].triangles.size(); f += kScanChunk)
                jobs.push_back({object, false, f, std::min(objects[i].triangles.size(), f + kScanChunk)});
            for (std::size_t f = 0; f < objects[i].positions.size(); f += kScanChunk)
                jobs.push_back({object, true, f, std::min(objects[i].positions.size(), f + kScanChunk)});
        }
        std::vector<unsigned char> job_ok(jobs.size(), 1);
        std::vector<Aabb> job_box(jobs.size());
        detail::parallel_chunks(options.threads, jobs.size(), [&](std::size_t j) {
            const ScanJob& job = jobs[j];
            const Mesh& m = objects[job.object];
            if (job.positions) {
                // Branch-free into a local flag: a store to job_ok (bytes, which may alias anything)
                // in the loop made the compiler reload the mesh on every coordinate.
                // Counted as integers (bitwise on bool is what clang's -Wbitwise-instead-of-logical
                // rejects; short-circuit || would bring the branches back).
                unsigned bad = 0;
                for (std::size_t v = job.first; v < job.last; ++v) {
                    const Vec3 p = m.positions[v];
                    bad |= coordinate_bad(p.x) | coordinate_bad(p.y) | coordinate_bad(p.z);
                }
                if (bad != 0) job_ok[j] = 0;
                return;
            }
            const std::size_t count = m.positions.size();
            Aabb* const box_out = boxes.data() + first_triangle[job.object];
            detail::FloatBox* const float_out = floats.data() + first_triangle[job.object];
            Aabb* const block_out = blocks.data() + first_block[job.object];
            Aabb all{{HUGE_VAL, HUGE_VAL, HUGE_VAL}, {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}};
            const Vec3* const pos = m.positions.data();
            const Tri* const tris = m.triangles.data();
#if defined(__SSE2__)
            const detail::RoundDownScope round_down;  // for float_box_round_down; this job's thread only
#endif
            for (std::size_t b0 = job.first; b0 < job.last; b0 += detail::kBoxBlock) {
                const std::size_t b1 = std::min(job.last, b0 + detail::kBoxBlock);
#if defined(__SSE2__)
                // x and y in the two lanes of one register, z alone. std::min(a, b) is (b < a ? b : a),
                // which is _mm_min_pd(b, a) (MINPD returns its second operand on ties, so signed zeros
                // keep the scalar code's choice); std::max(a, b) is _mm_max_pd(b, a) likewise.
                __m128d blo_xy = _mm_set1_pd(HUGE_VAL), blo_z = blo_xy, bhi_xy = _mm_set1_pd(-HUGE_VAL), bhi_z = bhi_xy;
                for (std::size_t t = b0; t < b1; ++t) {
                    const Tri tri = tris[t];
                    if (tri[0] >= count || tri[1] >= count || tri[2] >= count) {
                        job_ok[j] = 0;
                        return;
                    }
                    const double* const a = &pos[tri[0]].x;
                    const double* const b = &pos[tri[1]].x;
                    const double* const c = &pos[tri[2]].x;
                    const __m128d a_xy = _mm_loadu_pd(a), b_xy = _mm_loadu_pd(b), c_xy = _mm_loadu_pd(c);
                    const __m128d a_z = _mm_load_sd(a + 2), b_z = _mm_load_sd(b + 2), c_z = _mm_load_sd(c + 2);
                    const __m128d lo_xy = _mm_min_pd(c_xy, _mm_min_pd(b_xy, a_xy));
                    const __m128d lo_z = _mm_min_sd(c_z, _mm_min_sd(b_z, a_z));
                    const __m128d hi_xy = _mm_max_pd(c_xy, _mm_max_pd(b_xy, a_xy));
                    const __m128d hi_z = _mm_max_sd(c_z, _mm_max_sd(b_z, a_z));
                    blo_xy = _mm_min_pd(lo_xy, blo_xy);
                    blo_z = _mm_min_sd(lo_z, blo_z);
                    bhi_xy = _mm_max_pd(hi_xy, bhi_xy);
                    bhi_z = _mm_max_sd(hi_z, bhi_z);
                    std::construct_at(box_out + t, detail::aabb_sse2(lo_xy, lo_z, hi_xy, hi_z));
                    std::construct_at(float_out + t, detail::float_box_round_down(lo_xy, lo_z, hi_xy, hi_z));
                }
                const Aabb block = detail::aabb_sse2(blo_xy, blo_z, bhi_xy, bhi_z);
#else
                double bx0 = HUGE_VAL, by0 = HUGE_VAL, bz0 = HUGE_VAL, bx1 = -HUGE_VAL, by1 = -HUGE_VAL, bz1 = -HUGE_VAL;
                for (std::size_t t = b0; t < b1; ++t) {
                    const Tri tri = tris[t];
                    if (tri[0] >= count || tri[1] >= count || tri[2] >= count) {
                        job_ok[j] = 0;
                        return;
                    }
                    const Vec3 a = pos[tri[0]];
                    const Vec3 b = pos[tri[1]];
                    const Vec3 c = pos[tri[2]];
                    // Component by component (Vec3's operator[] branches on the index); the first of
                    // equal values wins, as std::min({a, b, c}) picks it (signed zeros keep their sign).
                    const Vec3 lo{std::min(std::min(a.x, b.x), c.x), std::min(std::min(a.y, b.y), c.y),
                                  std::min(std::min(a.z, b.z), c.z)};
                    const Vec3 hi{std::max(std::max(a.x, b.x), c.x), std::max(std::max(a.y, b.y), c.y),
                                  std::max(std::max(a.z, b.z), c.z)};
                    bx0 = std::min(bx0, lo.x);
                    by0 = std::min(by0, lo.y);
                    bz0 = std::min(bz0, lo.z);
                    bx1 = std::max(bx1, hi.x);
                    by1 = std::max(by1, hi.y);
                    bz1 = std::max(bz1, hi.z);
                    std::construct_at(box_out + t, Aabb{lo, hi});
                    std::construct_at(float_out + t, detail::float_box(lo, hi));
                }
                const Aabb block{{bx0, by0, bz0}, {bx1, by1, bz1}};
#endif
                std::construct_at(block_out + b0 / detail::kBoxBlock, block);
                all.lo = {std::min(all.lo.x, block.lo.x), std::min(all.lo.y, block.lo.y), std::min(all.lo.z, block.lo.z)};
                all.hi = {std::max(all.hi.x, block.hi.x), std::max(all.hi.y, block.hi.y), std::max(all.hi.z, block.hi.z)};
            }
            job_box[j] = all;
        });
        ok = std::all_of(job_ok.begin(), job_ok.end(), [](unsigned char c) { return c != 0; });
        for (std::size_t j = 0; ok && j < jobs.size(); ++j) {
            if (jobs[j].positions) continue;
            Aabb& box = exact[jobs[j].object].box;
            if (jobs[j].first == 0) {
                box = job_box[j];
                continue;
            }
            for (int k = 0; k < 3; ++k) {
                box.lo[k] = std::min(box.lo[k], job_box[j].lo[k]);
                box.hi[k] = std::max(box.hi[k], job_box[j].hi[k]);
            }
        }
    }
    if (!ok) {
        if (Status s = validate_scene(objects); !s) return s.error();
        if (objects.size() > UINT32_MAX) return Error{"too many objects (limit 2^32 - 1)"};
        if (Status s = validate_exact_range(objects); !s) return s.error();
        return Error{"exact_pairs: the scene check failed but named no problem (a bug)"};
    }

    // Every triangle is a candidate of its own: the exact stage sweeps them per pair of objects whose
    // boxes overlap (and per object with self-collision).
    std::vector<std::vector<std::uint32_t>> welded(options.self ? n : 0);
    if (options.self) detail::parallel_chunks(options.threads, n, [&](std::size_t i) { welded[i] = weld_vertices(objects[i]); });
    ExactStats st;
    std::vector<detail::TriangleBoxes> more(n);
    for (std::size_t i = 0; i < n; ++i) {
        st.triangles += objects[i].triangles.size();
        detail::ExactObject& e = exact[i];
        e.mesh = &objects[i];
        e.object = static_cast<std::uint32_t>(i);
        const std::size_t count = objects[i].triangles.size();
        e.triangle_boxes = {boxes.data() + first_triangle[i], count};
        more[i].floats = {floats.data() + first_triangle[i], count};
        more[i].blocks = {blocks.data() + first_block[i], first_block[i + 1] - first_block[i]};
        if (options.self) e.weld = welded[i];
    }
    detail::ExactStageResult r = detail::sweep_exact_triangles(exact, more, {options.self, false, options.threads});
    st.candidate_triangles = r.stats.task_triangles;
    st.box_pairs = r.stats.tests;
    st.adjacent_skipped = r.stats.adjacent_skipped;
    if (stats) *stats = st;
    return std::move(r.pairs);
}

}  // namespace cullide
