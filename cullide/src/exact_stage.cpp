// exact_stage.cpp: the one exact stage and the one sweep and prune (see exact_stage.h).
#include "exact_stage.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cullide/tri_tri.h"
#include "kept.h"
#include "parallel.h"

namespace cullide::detail {
namespace {

// Sweep units are fixed-size ranges of a task's sorted list, so big tasks (a bunny inside a dragon)
// spread over threads too; listed units are fixed runs of pairs. Both depend on the input only.
constexpr std::size_t kSweepChunk = 2048;
constexpr std::size_t kPairChunk = 64;

struct UnitOut {
    std::vector<TrianglePair> pairs;
    std::vector<std::uint64_t> set_pairs;  // (lower set << 32 | higher set), per tested pair or set pair
    std::uint64_t tests = 0, near_tests = 0, adjacent = 0;
};

std::uint64_t set_pair_key(std::uint32_t a, std::uint32_t b) {
    return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

// Tests triangle pairs of candidate sets; every counter goes to the unit's output.
class PairTester {
   public:
    PairTester(std::span<const ExactObject> objects, std::span<const CandidateSet> sets)
        : objects_(objects), sets_(sets) {}

    // Positions pa of object oa and pb of object ob, boxes known to overlap: adjacency (one
    // object), then the exact test. Returns whether the pair went to the exact test.
    bool test(std::uint32_t oa, std::uint32_t pa, std::uint32_t ob, std::uint32_t pb, bool near, UnitOut& out) const {
        return test_if(oa, pa, ob, pb, near, out, [] { return true; });
    }

    // test() for a pair whose boxes are not yet known to overlap: overlaps(box_a, box_b) && test(),
    // with adjacency decided before the boxes are read. Two triangles of one object that share a
    // welded vertex share that point (welded ids are equal exactly when positions compare equal),
    // so their closed boxes, exact minima and maxima of their vertices, always overlap: the same
    // pairs are counted adjacent and tested either way, and the adjacent pairs, most of a self
    // task's candidates (the folded cloth: 123 K of 148 K), skip the two box loads.
    bool test_if_overlapping(std::uint32_t oa, std::uint32_t pa, std::uint32_t ob, std::uint32_t pb,
                             std::span<const Aabb> boxes_a, std::span<const Aabb> boxes_b, bool near,
                             UnitOut& out) const {
        return test_if(oa, pa, ob, pb, near, out, [&] { return overlaps(boxes_a[pa], boxes_b[pb]); });
    }

    // The triangle pairs of sets sa and sb (sa == sb: the set's own pairs) whose boxes overlap.
    // Returns how many went to the exact test.
    std::uint64_t test_sets(std::uint32_t sa, std::uint32_t sb, bool near, UnitOut& out) const {
        const CandidateSet& a = sets_[sa];
        const CandidateSet& b = sets_[sb];
        const std::span<const Aabb> boxes_a = objects_[a.object].triangle_boxes;
        const std::span<const Aabb> boxes_b = objects_[b.object].triangle_boxes;
        std::uint64_t tested = 0;
        for (std::uint32_t pa = a.first; pa < a.first + a.count; ++pa) {
            for (std::uint32_t pb = sa == sb ? pa + 1 : b.first; pb < b.first + b.count; ++pb)
                if (overlaps(boxes_a[pa], boxes_b[pb])) tested += test(a.object, pa, b.object, pb, near, out) ? 1 : 0;
        }
        return tested;
    }

   private:
    // Adjacency (one object), then, if `boxes_meet()`, the exact test. Returns whether the pair went
    // to the exact test.
    template <class BoxesMeet>
    bool test_if(std::uint32_t oa, std::uint32_t pa, std::uint32_t ob, std::uint32_t pb, bool near, UnitOut& out,
                 BoxesMeet&& boxes_meet) const {
        const ExactObject& a = objects_[oa];
        const ExactObject& b = objects_[ob];
        std::uint32_t ta = a.order.empty() ? pa : a.order[pa];
        std::uint32_t tb = b.order.empty() ? pb : b.order[pb];
        const Tri& tri_a = a.mesh->triangles[ta];
        const Tri& tri_b = b.mesh->triangles[tb];
        if (oa == ob && share_welded_vertex(a, tri_a, tri_b)) {
            ++out.adjacent;
            return false;
        }
        if (!boxes_meet()) return false;
        ++out.tests;
        out.near_tests += near ? 1 : 0;
        const std::vector<Vec3>& va = a.mesh->positions;
        const std::vector<Vec3>& vb = b.mesh->positions;
        if (tri_tri_intersect(va[tri_a[0]], va[tri_a[1]], va[tri_a[2]], vb[tri_b[0]], vb[tri_b[1]], vb[tri_b[2]])) {
            TrianglePair p{a.object, ta, b.object, tb};
            if (p.object_a > p.object_b || (p.object_a == p.object_b && p.triangle_a > p.triangle_b))
                p = {b.object, tb, a.object, ta};
            out.pairs.push_back(p);
        }
        return true;
    }

    static bool share_welded_vertex(const ExactObject& o, const Tri& a, const Tri& b) {
        for (std::uint32_t u : a)
            for (std::uint32_t v : b)
                if (o.weld[u] == o.weld[v]) return true;
        return false;
    }

    std::span<const ExactObject> objects_;
    std::span<const CandidateSet> sets_;
};

ExactStageResult merge(std::vector<UnitOut>& units, bool count_set_pairs) {
    ExactStageResult r;
    std::vector<std::uint64_t> keys;
    for (UnitOut& u : units) {
        r.pairs.insert(r.pairs.end(), u.pairs.begin(), u.pairs.end());
        if (count_set_pairs) keys.insert(keys.end(), u.set_pairs.begin(), u.set_pairs.end());
        r.stats.tests += u.tests;
        r.stats.near_tests += u.near_tests;
        r.stats.adjacent_skipped += u.adjacent;
    }
    std::sort(r.pairs.begin(), r.pairs.end());
    std::sort(keys.begin(), keys.end());
    r.stats.set_pairs = static_cast<std::uint64_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
    return r;
}

// One swept task: the refs of one object (self) or of two, binned into a grid of cells over the
// two axes other than the sweep axis, each cell's refs sorted along `axis`. A 1-D sweep alone met
// about 650 box intervals per 3-D overlap on tori and 4000 on bunny-dragon (long surfaces project onto
// any one axis densely); a cell meets only the refs near it. A ref sits in every cell its box touches,
// and a pair is visited only in the cell holding the low corner of its boxes' intersection
// (max of the two cells of the boxes' lows), so each overlapping pair is visited once, as before.
// A ref in a cell, with the cell of its box's low corner (u | v << 16): 64 bytes.
struct CellRef {
    SweepRef ref;
    std::uint32_t low_cell = 0;
};

struct Task {
    std::vector<CellRef> refs;              // cell by cell; in a cell the first object's refs, then
                                            // the second's (self: all one run); each run is sorted
                                            // along `axis` by the unit that sweeps the cell (sorting
                                            // small runs in parallel beats one big serial sort)
    std::vector<std::uint32_t> cell_begin;  // cell c: refs [cell_begin[c], cell_begin[c + 1])
    std::vector<std::uint32_t> cell_split;  // cell c: the second object's refs start there
    int axis = 0;
    int grid_u = 1, grid_v = 1;             // cells along the two other axes
    bool self = false;
};

// The grid over the common box: cell of coordinate x along an axis is floor((x - lo) * scale),
// clamped; monotone in x, so the cell of max(lo_a, lo_b) is the larger of the two low cells.
struct GridAxis {
    int axis = 0, cells = 1;
    double lo = 0.0, scale = 0.0;
    // Clamped first, then truncated: the same cell as floor then clamp (truncation is floor on
    // [0, cells - 1]), without std::floor, which x86-64 without SSE4.1 has no instruction for (5% of
    // a breaking frame, three cells per gathered triangle).
    [[nodiscard]] std::uint32_t cell(double x) const {
        if (cells == 1) return 0;
        return static_cast<std::uint32_t>(std::clamp((x - lo) * scale, 0.0, static_cast<double>(cells - 1)));
    }
};

// Cells along one axis: about kCellPerExtent mean ref extents per cell (a ref then touches few cells),
// at most kMaxCellsPerAxis.
constexpr double kCellPerExtent = 4.0;
constexpr int kMaxCellsPerAxis = 256;
// A cell should hold about this many refs at least, so binning costs less than it saves.
constexpr std::size_t kRefsPerCell = 16;

GridAxis make_grid_axis(std::span<const SweepRef> refs, const Aabb& bounds, int axis, int max_cells) {
    GridAxis g;
    g.axis = axis;
    const double extent = bounds.hi[axis] - bounds.lo[axis];
    if (!(extent > 0.0) || refs.empty() || max_cells <= 1) return g;
    double sum = 0.0;
    for (const SweepRef& r : refs)
        sum += std::min(r.box.hi[axis], bounds.hi[axis]) - std::max(r.box.lo[axis], bounds.lo[axis]);
    const double mean = sum / static_cast<double>(refs.size());
    const double want = mean > 0.0 ? extent / (kCellPerExtent * mean) : static_cast<double>(max_cells);
    g.cells = static_cast<int>(std::clamp(want, 1.0, static_cast<double>(std::min(max_cells, kMaxCellsPerAxis))));
    g.lo = bounds.lo[axis];
    g.scale = static_cast<double>(g.cells) / extent;
    return g;
}

// Refs per binning job of a big task (bin_task, TaskBuilder::make_task).
constexpr std::size_t kBinChunk = 8192;

// Bins `refs` (the first `first_count` are the first object's) into the grid over `bounds`: count,
// scan, fill, so each cell holds each side's refs as one run, in ref order. A big task (a bunny
// inside a dragon: one task, tens of thousands of refs) counts and fills in chunks of refs on up to
// `threads` workers: each chunk's refs go after the earlier chunks' in every cell, so the order, and
// everything swept from it, is the serial one whatever the chunks.
void bin_task(Task& task, const std::vector<SweepRef>& refs, std::size_t first_count, const Aabb& bounds, int threads) {
    const int u = (task.axis + 1) % 3, v = (task.axis + 2) % 3;
    const std::size_t budget = std::max<std::size_t>(1, refs.size() / kRefsPerCell);
    GridAxis gu = make_grid_axis(refs, bounds, u, static_cast<int>(std::min<std::size_t>(budget, kMaxCellsPerAxis)));
    const std::size_t left = std::max<std::size_t>(1, budget / static_cast<std::size_t>(gu.cells));
    GridAxis gv = make_grid_axis(refs, bounds, v, static_cast<int>(std::min<std::size_t>(left, kMaxCellsPerAxis)));
    task.grid_u = gu.cells;
    task.grid_v = gv.cells;
    const std::size_t cells = static_cast<std::size_t>(gu.cells) * static_cast<std::size_t>(gv.cells);
    const std::size_t slots = 2 * cells;  // slot 2 * c + side: the refs of one side in cell c
    struct Span {
        std::uint32_t u0, u1, v0, v1;
    };
    std::vector<Span> spans(refs.size());
    // (At most 32 chunks: each holds a count per slot.)
    const std::size_t chunks = std::min<std::size_t>(
        (refs.size() + kBinChunk - 1) / kBinChunk, std::min<std::size_t>(32, 4 * static_cast<std::size_t>(effective_threads(threads))));
    const std::size_t per_chunk = chunks > 0 ? (refs.size() + chunks - 1) / chunks : 0;
    // at[chunk * slots + k]: chunk's count in slot k, then (after the scan) where it writes there.
    std::vector<std::uint32_t> at(chunks * slots, 0);
    const auto chunk_range = [&](std::size_t ch) {
        return std::pair{ch * per_chunk, std::min(refs.size(), (ch + 1) * per_chunk)};
    };
    parallel_chunks(chunks > 1 ? threads : 1, chunks, [&](std::size_t ch) {
        std::uint32_t* counts = at.data() + ch * slots;
        const auto [b, e] = chunk_range(ch);
        for (std::size_t i = b; i < e; ++i) {
            const Aabb& box = refs[i].box;
            spans[i] = {gu.cell(box.lo[u]), gu.cell(box.hi[u]), gv.cell(box.lo[v]), gv.cell(box.hi[v])};
            const std::size_t side = i < first_count ? 0 : 1;
            for (std::uint32_t cv = spans[i].v0; cv <= spans[i].v1; ++cv)
                for (std::uint32_t cu = spans[i].u0; cu <= spans[i].u1; ++cu) ++counts[2 * (cv * gu.cells + cu) + side];
        }
    });
    task.cell_begin.resize(cells + 1);
    task.cell_split.resize(cells);
    std::uint32_t next = 0;
    for (std::size_t k = 0; k < slots; ++k) {
        if (k % 2 == 0) task.cell_begin[k / 2] = next;
        else task.cell_split[k / 2] = next;
        for (std::size_t ch = 0; ch < chunks; ++ch) {
            const std::uint32_t c = at[ch * slots + k];
            at[ch * slots + k] = next;
            next += c;
        }
    }
    task.cell_begin[cells] = next;
    task.refs.resize(next);
    parallel_chunks(chunks > 1 ? threads : 1, chunks, [&](std::size_t ch) {
        std::uint32_t* pos = at.data() + ch * slots;
        const auto [b, e] = chunk_range(ch);
        for (std::size_t i = b; i < e; ++i) {
            const std::size_t side = i < first_count ? 0 : 1;
            const std::uint32_t low = spans[i].u0 | (spans[i].v0 << 16);
            for (std::uint32_t cv = spans[i].v0; cv <= spans[i].v1; ++cv)
                for (std::uint32_t cu = spans[i].u0; cu <= spans[i].u1; ++cu)
                    task.refs[pos[2 * (cv * gu.cells + cu) + side]++] = {refs[i], low};
        }
    });
}

// Whether cell (cu, cv) holds the low corner of the intersection of boxes with low cells a and b.
inline bool owns_pair(std::uint32_t cell_uv, std::uint32_t a, std::uint32_t b) {
    const std::uint32_t u = std::max(a & 0xffffu, b & 0xffffu), v = std::max(a >> 16, b >> 16);
    return (u | (v << 16)) == cell_uv;
}

// Sorts each run of cell c along the axis by (lo, set, part): a unique key, so the order does not
// depend on the sort algorithm.
void sort_cell(Task& task, std::size_t c) {
    const int axis = task.axis;
    const auto less = [axis](const CellRef& x, const CellRef& y) {
        const SweepRef& a = x.ref;
        const SweepRef& b = y.ref;
        if (a.box.lo[axis] != b.box.lo[axis]) return a.box.lo[axis] < b.box.lo[axis];
        if (a.set != b.set) return a.set < b.set;
        return a.part < b.part;
    };
    const auto base = task.refs.begin();
    std::sort(base + task.cell_begin[c], base + task.cell_split[c], less);
    std::sort(base + task.cell_split[c], base + task.cell_begin[c + 1], less);
}

// Visits every overlapping pair of refs owned by cell c of `task` (see Task), its runs sorted
// (sort_cell): a sweep of the cell's one run (self) or a two-run sweep (the pairs of one side are
// never met, unlike one merged run).
template <class Visit>
void sweep_cell(const Task& task, std::size_t c, Visit&& visit) {
    const std::uint32_t cell_uv = static_cast<std::uint32_t>(c % static_cast<std::size_t>(task.grid_u)) |
                                  static_cast<std::uint32_t>(c / static_cast<std::size_t>(task.grid_u)) << 16;
    const int axis = task.axis;
    const CellRef* cell_refs = task.refs.data();
    const std::size_t begin = task.cell_begin[c], split = task.cell_split[c], end = task.cell_begin[c + 1];
    const auto try_pair = [&](std::size_t i, std::size_t j) {
        const CellRef& a = cell_refs[i];
        const CellRef& b = cell_refs[j];
        if (overlaps(a.ref.box, b.ref.box) && owns_pair(cell_uv, a.low_cell, b.low_cell)) visit(a.ref, b.ref);
    };
    const auto lo = [&](std::size_t i) { return cell_refs[i].ref.box.lo[axis]; };
    const auto hi = [&](std::size_t i) { return cell_refs[i].ref.box.hi[axis]; };
    if (task.self) {
        for (std::size_t i = begin; i < end; ++i) {
            const double i_hi = hi(i);
            for (std::size_t j = i + 1; j < end && lo(j) <= i_hi; ++j) try_pair(i, j);
        }
        return;
    }
    // Two sorted runs: the ref with the lower low (ties: the first run's) meets the other run's refs
    // from its cursor on while they start before it ends; every pair overlapping along the axis is
    // met once, from the one that starts first.
    std::size_t i = begin, j = split;
    while (i < split && j < end) {
        if (lo(i) <= lo(j)) {
            const double i_hi = hi(i);
            for (std::size_t k = j; k < end && lo(k) <= i_hi; ++k) try_pair(i, k);
            ++i;
        } else {
            const double j_hi = hi(j);
            for (std::size_t k = i; k < split && lo(k) <= j_hi; ++k) try_pair(k, j);
            ++j;
        }
    }
}

// Builds the tasks of sweep_exact_stage (see exact_stage.h); `in_task` flags the sets in some task's
// common box.
class TaskBuilder {
   public:
    TaskBuilder(std::span<const ExactObject> objects, std::span<const CandidateSet> sets)
        : objects_(objects), sets_(sets), set_begin_(objects.size() + 1, 0), in_task_(sets.size(), 0) {
        for (const CandidateSet& s : sets) ++set_begin_[s.object + 1];
        for (std::size_t o = 0; o < objects.size(); ++o) set_begin_[o + 1] += set_begin_[o];
    }

    void add_self(std::uint32_t o) {
        std::vector<SweepRef> refs;
        for (std::uint32_t s = set_begin_[o]; s < set_begin_[o + 1]; ++s) {
            in_task_[s] = 1;
            refs.push_back(whole_ref(s));
        }
        add(std::move(refs), 0, nullptr);
    }

    void add_pair(std::uint32_t i, std::uint32_t j) {
        const Aabb& bi = objects_[i].box;
        const Aabb& bj = objects_[j].box;
        if (bi.empty() || bj.empty() || !overlaps(bi, bj)) return;
        Aabb common;
        for (int k = 0; k < 3; ++k) {
            common.lo[k] = std::max(bi.lo[k], bj.lo[k]);
            common.hi[k] = std::min(bi.hi[k], bj.hi[k]);
        }
        std::vector<SweepRef> refs;
        std::size_t from_i = 0;
        for (const std::uint32_t o : {i, j}) {
            for (std::uint32_t s = set_begin_[o]; s < set_begin_[o + 1]; ++s) {
                if (!overlaps(sets_[s].box, common)) continue;
                in_task_[s] = 1;
                refs.push_back(whole_ref(s));
            }
            if (o == i) from_i = refs.size();
        }
        if (from_i == 0 || from_i == refs.size()) return;  // one side has nothing there
        add(std::move(refs), from_i, &common);
    }

    // The tasks added, in the order added; made on up to `threads` workers (binning a task is the
    // stage's largest serial cost otherwise): one task per job or, with fewer tasks than workers (a
    // bunny inside a dragon: one), each task in turn with every worker (make_task's chunks).
    std::vector<Task> take_tasks(int threads) {
        std::vector<Task> tasks(pending_.size());
        const auto make = [&](std::size_t t, int inner) {
            PendingTask& p = pending_[t];
            tasks[t] = make_task(std::move(p.refs), p.first_count, p.self ? nullptr : &p.common, inner);
        };
        if (pending_.size() < static_cast<std::size_t>(effective_threads(threads))) {
            for (std::size_t t = 0; t < pending_.size(); ++t) make(t, threads);
        } else {
            parallel_chunks(threads, pending_.size(), [&](std::size_t t) { make(t, 1); });
        }
        pending_.clear();
        return tasks;
    }

    std::uint64_t task_triangles() const {
        std::uint64_t n = 0;
        for (std::size_t s = 0; s < sets_.size(); ++s) n += in_task_[s] ? sets_[s].count : 0;
        return n;
    }

   private:
    SweepRef whole_ref(std::uint32_t s) const {
        const CandidateSet& set = sets_[s];
        return {set.box, set.object, s, set.count == 1 ? set.first : kWholeSet};
    }

    // `refs` come object by object: the first object's first_count, then the second's (self: one
    // object, first_count unused). The task is made later, in parallel (take_tasks).
    void add(std::vector<SweepRef>&& refs, std::size_t first_count, const Aabb* common) {
        if (refs.size() < 2 && (common != nullptr || refs.empty() || sets_[refs[0].set].count < 2)) return;
        pending_.push_back({std::move(refs), first_count, common != nullptr ? *common : Aabb{}, common == nullptr});
    }

    // Chooses the axis, replaces loose sets by their triangles inside the common box and bins the
    // refs (bin_task). A self task (no common box) always sweeps triangles: a set's own pairs are
    // pairs of its triangles. Reads only the builder's inputs, so tasks are made concurrently.
    Task make_task(std::vector<SweepRef>&& refs, std::size_t first_count, const Aabb* common, int threads) const {
        Task task;
        task.self = common == nullptr;
        task.axis = spread_axis(refs);
        const bool all_triangles =
            std::all_of(refs.begin(), refs.end(), [](const SweepRef& r) { return r.part != kWholeSet; });
        if (!all_triangles && (common == nullptr || loose(refs, task.axis))) {
            // Each set's triangles inside the common box, in ref order: counted per ref, then
            // written at the counted offsets, in chunks of refs on up to `threads` workers.
            const std::size_t n = refs.size();
            std::vector<std::size_t> at(n + 1, 0);
            const auto each_triangle = [&](std::size_t r, auto&& f) {
                const CandidateSet& set = sets_[refs[r].set];
                const std::span<const Aabb> boxes = objects_[set.object].triangle_boxes;
                for (std::uint32_t p = set.first; p < set.first + set.count; ++p)
                    if (common == nullptr || overlaps(boxes[p], *common)) f(SweepRef{boxes[p], set.object, refs[r].set, p});
            };
            constexpr std::size_t kSetChunk = 1024;
            const std::size_t chunks = (n + kSetChunk - 1) / kSetChunk;
            const int inner = chunks > 1 ? threads : 1;
            parallel_chunks(inner, chunks, [&](std::size_t c) {
                for (std::size_t r = c * kSetChunk; r < std::min(n, (c + 1) * kSetChunk); ++r) {
                    std::size_t count = 0;
                    each_triangle(r, [&](const SweepRef&) { ++count; });
                    at[r + 1] = count;
                }
            });
            for (std::size_t r = 0; r < n; ++r) at[r + 1] += at[r];
            std::vector<SweepRef> tris(at[n]);
            parallel_chunks(inner, chunks, [&](std::size_t c) {
                for (std::size_t r = c * kSetChunk; r < std::min(n, (c + 1) * kSetChunk); ++r) {
                    std::size_t w = at[r];
                    each_triangle(r, [&](const SweepRef& t) { tris[w++] = t; });
                }
            });
            refs = std::move(tris);  // still object by object
            if (common != nullptr)
                first_count = static_cast<std::size_t>(
                    std::find_if(refs.begin(), refs.end(), [&](const SweepRef& r) { return r.object != refs[0].object; }) -
                    refs.begin());
        }
        if (task.self) first_count = refs.size();
        Aabb bounds = common != nullptr ? *common : refs.front().box;
        if (common == nullptr)
            for (const SweepRef& r : refs)
                for (int k = 0; k < 3; ++k) {
                    bounds.lo[k] = std::min(bounds.lo[k], r.box.lo[k]);
                    bounds.hi[k] = std::max(bounds.hi[k], r.box.hi[k]);
                }
        bin_task(task, refs, first_count, bounds, threads);
        return task;
    }

    // Sets whose boxes' summed extent along `axis` is more than 4 times their triangles' (on the
    // thinned bunny-dragon a set sweep met 1.4 million sub-object pairs for 218 triangle pairs).
    bool loose(const std::vector<SweepRef>& refs, int axis) const {
        double set_extent = 0.0, triangle_extent = 0.0;
        for (const SweepRef& r : refs) {
            set_extent += r.box.hi[axis] - r.box.lo[axis];
            const CandidateSet& set = sets_[r.set];
            const std::span<const Aabb> boxes = objects_[set.object].triangle_boxes;
            for (std::uint32_t p = set.first; p < set.first + set.count; ++p)
                triangle_extent += boxes[p].hi[axis] - boxes[p].lo[axis];
        }
        return set_extent > 4.0 * triangle_extent;
    }

    std::span<const ExactObject> objects_;
    std::span<const CandidateSet> sets_;
    std::vector<std::uint32_t> set_begin_;  // sets of object o: [set_begin_[o], set_begin_[o + 1])
    std::vector<char> in_task_;
    struct PendingTask {
        std::vector<SweepRef> refs;
        std::size_t first_count = 0;
        Aabb common;
        bool self = false;
    };
    std::vector<PendingTask> pending_;
};

// ---- The ground truth's sweep (sweep_exact_triangles) ---------------------------------------------
//
// Every triangle is a candidate of its own, so the per-triangle data is made as small as the sweep
// needs: a float box rounded outward (it holds the double box, so it never drops an overlapping
// pair; pairs it lets through are checked on the double boxes before the exact test, so the counts
// are those of the double boxes), the triangle's position and its low cell: 32 bytes. Cells hold
// 4-byte indices, sorted by 8-byte keys (the low along the axis as an ordered integer, then the
// index). A big task (a bunny inside a dragon) is cut into slabs of grid rows that are binned and
// swept on their own, so it spreads over threads too.

// A float's order as an unsigned integer (negative floats reversed below the positive ones).
std::uint32_t float_order(float f) {
    const auto bits = std::bit_cast<std::uint32_t>(f);
    return (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
}

struct TriRef {
    // gather writes every field of a ref in place in its list: built in a local and pushed, its
    // 4-byte field stores were read back by push_back's 16-byte loads before they had landed
    // (store-forwarding stalls; push_back was 5% of a 1-thread `exact` frame, perf, most of it on
    // those loads), and emplace_back() would zero the 32 bytes first. TriRef() stays trivial.
    struct Uninitialized {};
    TriRef() = default;
    explicit TriRef(Uninitialized) {}  // NOLINT: every field is set by gather
    float lo[3], hi[3];                // the triangle's box, rounded outward
    std::uint32_t pos;                 // position in its object
    std::uint32_t low;                 // cell of the box's low corner, u | v << 16
};

struct TriTask {
    std::uint32_t a = 0, b = 0;  // ExactObject indices; a == b: a self task
    Aabb common;                 // pair task: the intersection of the two object boxes
    int axis = 0;
    GridAxis gu, gv;
    std::vector<std::uint16_t> row_slab;  // slab of each grid row along v
    int slabs = 1;
    [[nodiscard]] bool self() const { return a == b; }
};

constexpr std::size_t kGatherChunk = 16384;  // triangles per gather job
constexpr std::size_t kSlabRefs = 8192;      // about this many refs per slab job
constexpr std::size_t kSpatialMin = 2048;    // an object worth a spatial order: this many triangles
constexpr std::uint32_t kSpatialTasks = 8;   // in this many pair tasks (tori: 4-5 tasks an object, 12% slower
                                             // with the order), its blocks loose (loose_blocks)

// The refs a gather job found, per slab of its task.
using SlabRefs = std::vector<std::vector<TriRef>>;

struct GatherJob {
    std::uint32_t task = 0, side = 0;
    std::uint32_t first = 0, last = 0;  // positions
};

// Scratch of one cell sweep, structure of arrays in the sorted order (reused by a slab job).
struct CellScratch {
    std::vector<float> lo, hi, lu, hu, lv, hv;
    std::vector<std::uint32_t> low, pos;
    std::vector<std::uint64_t> keys;
    // `idx` in the sweep's order when `sorted` (sweep_slab bins the refs in sorted order), else
    // sorted here by the same key.
    void fill(const std::vector<TriRef>& refs, std::span<const std::uint32_t> idx, int axis, int u, int v,
              std::size_t at, bool sorted) {
        const std::size_t n = idx.size();
        if (!sorted) {
            if (keys.size() < n) keys.resize(n);
            for (std::size_t k = 0; k < n; ++k)
                keys[k] = std::uint64_t{float_order(refs[idx[k]].lo[axis])} << 32 | idx[k];
            std::sort(keys.begin(), keys.begin() + static_cast<std::ptrdiff_t>(n));
        }
        for (std::size_t k = 0; k < n; ++k) {
            const TriRef& r = refs[sorted ? idx[k] : static_cast<std::uint32_t>(keys[k])];
            lo[at + k] = r.lo[axis];
            hi[at + k] = r.hi[axis];
            lu[at + k] = r.lo[u];
            hu[at + k] = r.hi[u];
            lv[at + k] = r.lo[v];
            hv[at + k] = r.hi[v];
            low[at + k] = r.low;
            pos[at + k] = r.pos;
        }
    }
    void reserve(std::size_t n) {
        if (lo.size() >= n) return;
        for (auto* f : {&lo, &hi, &lu, &hu, &lv, &hv}) f->resize(n);
        low.resize(n);
        pos.resize(n);
    }
};

GridAxis grid_axis(const Aabb& bounds, int axis, double mean, std::size_t max_cells) {
    GridAxis g;
    g.axis = axis;
    const double extent = bounds.hi[axis] - bounds.lo[axis];
    if (!(extent > 0.0) || max_cells <= 1) return g;
    const double want = mean > 0.0 ? extent / (kCellPerExtent * mean) : static_cast<double>(max_cells);
    g.cells = static_cast<int>(
        std::clamp(want, 1.0, static_cast<double>(std::min<std::size_t>(max_cells, kMaxCellsPerAxis))));
    g.lo = bounds.lo[axis];
    g.scale = static_cast<double>(g.cells) / extent;
    return g;
}

// The task's axis (its bounds' widest), grid and slabs. Its refs are estimated by the triangles of
// the blocks meeting the common box, their mean extents from about 128 triangles per side (these
// only steer the speed: the pairs found do not depend on them).
void plan_task(TriTask& t, std::span<const ExactObject> objects, std::span<const TriangleBoxes> more) {
    const Aabb& bounds = t.self() ? objects[t.a].box : t.common;
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (bounds.hi[k] - bounds.lo[k] > bounds.hi[axis] - bounds.lo[axis]) axis = k;
    t.axis = axis;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    double sum_u = 0.0, sum_v = 0.0;
    std::size_t members = 0, refs = 0;
    for (const std::uint32_t o : {t.a, t.b}) {
        const std::span<const Aabb> boxes = objects[o].triangle_boxes;
        const std::span<const Aabb> blocks = more[o].blocks;
        for (std::size_t b = 0; b < blocks.size(); ++b)
            if (t.self() || overlaps(blocks[b], bounds)) refs += std::min(kBoxBlock, boxes.size() - b * kBoxBlock);
        const std::size_t stride = std::max<std::size_t>(1, boxes.size() / 128);
        for (std::size_t p = 0; p < boxes.size(); p += stride) {
            const Aabb& b = boxes[p];
            if (!t.self() && !overlaps(b, bounds)) continue;
            ++members;
            sum_u += std::min(b.hi[u], bounds.hi[u]) - std::max(b.lo[u], bounds.lo[u]);
            sum_v += std::min(b.hi[v], bounds.hi[v]) - std::max(b.lo[v], bounds.lo[v]);
        }
        if (t.self()) break;
    }
    const double mean_u = members > 0 ? sum_u / static_cast<double>(members) : 0.0;
    const double mean_v = members > 0 ? sum_v / static_cast<double>(members) : 0.0;
    const auto budget = std::max<std::size_t>(1, refs / kRefsPerCell);
    t.gu = grid_axis(bounds, u, mean_u, budget);
    t.gv = grid_axis(bounds, v, mean_v, std::max<std::size_t>(1, budget / static_cast<std::size_t>(t.gu.cells)));
    t.slabs = static_cast<int>(std::clamp<std::size_t>(refs / kSlabRefs, 1, static_cast<std::size_t>(t.gv.cells)));
    t.row_slab.resize(static_cast<std::size_t>(t.gv.cells));
    for (int r = 0; r < t.gv.cells; ++r) t.row_slab[static_cast<std::size_t>(r)] = static_cast<std::uint16_t>(r * t.slabs / t.gv.cells);
}

// Gathers the triangles of one side of a task in positions [first, last) meeting its common box
// (self: all), into the slabs their rows touch; flags them in `in_task` (pair tasks).
// An object's triangles in a spatial order (Morton order of their box centres, 4 bits an axis over
// the object's box) with the box of each block of kBoxBlock of them. For an object in several pair
// tasks whose mesh order leaves blocks loose (loose_blocks): a scrambled mesh has every task read
// all its triangles.
struct SpatialOrder {
    std::vector<std::uint32_t> positions;  // positions in spatial order; empty: the mesh's order
    std::vector<Aabb> blocks;              // blocks[b]: the box of positions[b * kBoxBlock ...]
};

// Spreads the 10 low bits of x to every third bit.
std::uint32_t spread_bits(std::uint32_t x) {
    x &= 0x3ffu;
    x = (x | (x << 16)) & 0x030000ffu;
    x = (x | (x << 8)) & 0x0300f00fu;
    x = (x | (x << 4)) & 0x030c30c3u;
    x = (x | (x << 2)) & 0x09249249u;
    return x;
}

// One counting sort on a 12-bit Morton code (4 bits an axis: 4,096 cells over the object's box),
// stable, so a cell keeps the mesh's order; made in jobs of kOrderChunk triangles (histogram per
// job, scan in (cell, job) order, scatter per job), so the order is the same for any thread count.
// The full 30-bit code in three radix passes, on one thread, was a third of a leaves frame.
constexpr std::size_t kOrderChunk = 8192;
constexpr std::uint32_t kOrderCells = 1u << 12;

SpatialOrder spatial_order(const ExactObject& o, int threads) {
    const std::span<const Aabb> boxes = o.triangle_boxes;
    const std::size_t n = boxes.size();
    std::array<double, 3> scale{};
    for (int k = 0; k < 3; ++k) {
        const double extent = o.box.hi[k] - o.box.lo[k];
        scale[static_cast<std::size_t>(k)] = extent > 0.0 ? 15.0 / extent : 0.0;
    }
    const std::size_t jobs = (n + kOrderChunk - 1) / kOrderChunk;
    std::vector<std::uint16_t> code(n);
    std::vector<std::uint32_t> start(jobs * kOrderCells, 0);  // counts, then cursors, of (job, cell)
    parallel_chunks(threads, jobs, [&](std::size_t j) {
        std::uint32_t* count = start.data() + j * kOrderCells;
        const std::size_t end = std::min(n, (j + 1) * kOrderChunk);
        for (std::size_t p = j * kOrderChunk; p < end; ++p) {
            std::uint32_t c = 0;
            for (int k = 0; k < 3; ++k) {
                const double centre = 0.5 * boxes[p].lo[k] + 0.5 * boxes[p].hi[k];
                const double q = std::clamp((centre - o.box.lo[k]) * scale[static_cast<std::size_t>(k)], 0.0, 15.0);
                c |= spread_bits(static_cast<std::uint32_t>(q)) << k;
            }
            code[p] = static_cast<std::uint16_t>(c);
            ++count[c];
        }
    });
    std::uint32_t sum = 0;
    for (std::uint32_t c = 0; c < kOrderCells; ++c)
        for (std::size_t j = 0; j < jobs; ++j) sum += std::exchange(start[j * kOrderCells + c], sum);
    SpatialOrder s;
    s.positions.resize(n);
    parallel_chunks(threads, jobs, [&](std::size_t j) {
        std::uint32_t* cursor = start.data() + j * kOrderCells;
        const std::size_t end = std::min(n, (j + 1) * kOrderChunk);
        for (std::size_t p = j * kOrderChunk; p < end; ++p) s.positions[cursor[code[p]]++] = static_cast<std::uint32_t>(p);
    });
    s.blocks.resize((n + kBoxBlock - 1) / kBoxBlock);
    constexpr std::size_t kBlocksPerJob = kOrderChunk / kBoxBlock;
    parallel_chunks(threads, (s.blocks.size() + kBlocksPerJob - 1) / kBlocksPerJob, [&](std::size_t j) {
        const std::size_t end = std::min(n, (j + 1) * kOrderChunk);
        for (std::size_t q = j * kOrderChunk; q < end; ++q) {
            const Aabb& t = boxes[s.positions[q]];
            Aabb& block = s.blocks[q / kBoxBlock];
            if (q % kBoxBlock == 0) block = t;
            for (int k = 0; k < 3; ++k) {
                block.lo[k] = std::min(block.lo[k], t.lo[k]);
                block.hi[k] = std::max(block.hi[k], t.hi[k]);
            }
        }
    });
    return s;
}

// Whether the mesh's own order leaves an object's blocks loose: their mean size (the sum of a box's
// three extents) is more than kLooseBlocks of the object's. A mesh made strip by strip or part by
// part keeps neighbours together (the tree of leaves, 43.6 K triangles in 57 pair tasks: 0.087, and
// the order cost a third of the frame's instructions for nothing); a scrambled one does not (the same
// tree shuffled: 0.73, where the order halves the frame). The loosest fragment of breaking (0.34) is
// about even either way.
constexpr double kLooseBlocks = 0.4;
bool loose_blocks(const ExactObject& o, const TriangleBoxes& boxes) {
    const auto size = [](const Aabb& b) { return (b.hi.x - b.lo.x) + (b.hi.y - b.lo.y) + (b.hi.z - b.lo.z); };
    double sum = 0.0;
    for (const Aabb& b : boxes.blocks) sum += size(b);
    const double whole = size(o.box);
    return sum > kLooseBlocks * static_cast<double>(boxes.blocks.size()) * whole;
}

void gather(const TriTask& t, const ExactObject& o, const TriangleBoxes& boxes, const SpatialOrder& order,
            std::uint32_t first, std::uint32_t last, std::span<unsigned char> in_task,
            std::span<std::vector<TriRef>> out) {
    const FloatBox common = float_box(t.common);
    const int u = t.gu.axis, v = t.gv.axis;
    const bool spatial = !order.positions.empty();
    const std::span<const Aabb> blocks = spatial ? std::span<const Aabb>(order.blocks) : boxes.blocks;
    const bool one_slab = t.slabs == 1;
#if defined(__SSE2__)
    // The low cell along u and v in one SSE2 step, the same cells as GridAxis::cell: (x - lo) * scale
    // in doubles, clamped to [0, cells - 1] and truncated (an axis of one cell has lo = scale = 0, or
    // a range [0, 0]: 0; MAXPD returns its second operand, 0, for an infinite x times 0).
    const __m128d cell_lo = _mm_setr_pd(t.gu.lo, t.gv.lo), cell_scale = _mm_setr_pd(t.gu.scale, t.gv.scale);
    const __m128d cell_max = _mm_setr_pd(static_cast<double>(t.gu.cells - 1), static_cast<double>(t.gv.cells - 1));
    const auto low_cells = [&](const FloatBox& fb) {
        const __m128d x = _mm_cvtps_pd(_mm_setr_ps(fb.lo[u], fb.lo[v], 0.0f, 0.0f));
        const __m128d c = _mm_min_pd(_mm_max_pd(_mm_mul_pd(_mm_sub_pd(x, cell_lo), cell_scale), _mm_setzero_pd()), cell_max);
        const __m128i i = _mm_cvttpd_epi32(c);
        const auto cu = static_cast<std::uint32_t>(_mm_cvtsi128_si32(i));
        const auto cv = static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_shuffle_epi32(i, 1)));
        return cu | cv << 16;
    };
#else
    const auto low_cells = [&](const FloatBox& fb) {
        return t.gu.cell(static_cast<double>(fb.lo[u])) | t.gv.cell(static_cast<double>(fb.lo[v])) << 16;
    };
#endif
#if defined(__SSE2__)
    // float_overlaps(fb, common) as two compares of four lanes: fb's floats 0-3 (lo, hi.x) against
    // (common.hi, +inf), floats 2-5 (lo.z, hi) against (-inf, common.lo); the extra lanes always hold.
    constexpr float kInf = std::numeric_limits<float>::infinity();
    const __m128 c_hi = _mm_setr_ps(common.hi[0], common.hi[1], common.hi[2], kInf);
    const __m128 c_lo = _mm_setr_ps(-kInf, common.lo[0], common.lo[1], common.lo[2]);
    const auto meets = [&](const FloatBox& fb) {
        const auto* const f = reinterpret_cast<const float*>(&fb);
        return _mm_movemask_ps(_mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(f), c_hi), _mm_cmpge_ps(_mm_loadu_ps(f + 2), c_lo))) == 0xf;
    };
#else
    const auto meets = [&](const FloatBox& fb) { return float_overlaps(fb, common); };
#endif
    // Block by block (first is a multiple of kBoxBlock): a block whose box misses the common box holds
    // no triangle meeting it. One loop per case (self or not, spatial order or not): the compiler did
    // not take the two tests out of the loop.
    const auto blocks_of = [&](auto self_tag, auto spatial_tag) {
        constexpr bool self = decltype(self_tag)::value;
        for (std::uint32_t b0 = first; b0 < last; b0 += static_cast<std::uint32_t>(kBoxBlock)) {
            if (!self && !overlaps(blocks[b0 / kBoxBlock], t.common)) continue;
            const std::uint32_t b1 = std::min(last, b0 + static_cast<std::uint32_t>(kBoxBlock));
            for (std::uint32_t q = b0; q < b1; ++q) {
                std::uint32_t p = q;
                if constexpr (decltype(spatial_tag)::value) p = order.positions[q];
                const FloatBox& fb = boxes.floats[p];
                if constexpr (!self) {
                    // The float box holds the double box: disjoint from the common box (rounded
                    // outward), the double box is too; otherwise the double box decides.
                    if (!meets(fb) || !overlaps(o.triangle_boxes[p], t.common)) continue;
                    std::atomic_ref<unsigned char>(in_task[p]).store(1, std::memory_order_relaxed);
                }
                // The ref, written in place in the list of the first slab its rows reach (a lambda
                // call here was a third of the gather; a local copied in by push_back stalled:
                // TriRef), then copied to the further ones.
                const std::uint32_t low = low_cells(fb);
                std::uint16_t s0 = 0, s1 = 0;
                if (!one_slab) {
                    s0 = t.row_slab[low >> 16];
                    s1 = t.row_slab[t.gv.cell(static_cast<double>(fb.hi[v]))];
                    if (s1 < s0) continue;  // no slab (never: cells and slabs are monotone)
                }
                TriRef& r = out[s0].emplace_back(TriRef::Uninitialized{});
                for (int k = 0; k < 3; ++k) {
                    r.lo[k] = fb.lo[k];
                    r.hi[k] = fb.hi[k];
                }
                r.pos = p;
                r.low = low;
                for (std::uint16_t s = s0; s < s1;) out[++s].push_back(out[s0].back());
            }
        }
    };
    using Yes = std::true_type;
    using No = std::false_type;
    if (t.self()) {
        if (spatial) blocks_of(Yes{}, Yes{});
        else blocks_of(Yes{}, No{});
    } else {
        if (spatial) blocks_of(No{}, Yes{});
        else blocks_of(No{}, No{});
    }
}

// A ref's cells in sweep_slab: rows [v0, v1] of the slab, columns [u0, u0 + width) of each; `first`
// is the (cell, side) slot of (u0, v0).
struct SlabSpan {
    std::uint32_t first, width, rows;
};
struct SlabScratch {
    std::vector<std::uint32_t> next, begin, idx;
    std::vector<SlabSpan> spans;
    std::vector<std::uint32_t> key, order, key_tmp, order_tmp;  // sorted_refs
};

// The refs' indices in the sweep's order: by the low along `axis` as an ordered integer
// (float_order), ties by index, into `order`. A stable LSD radix sort on the 32-bit key, one byte a
// pass, starting from the index order, so equal keys keep increasing indices; a pass whose byte is
// the same for every key moves nothing and is skipped. Every cell's list, binned from this order,
// is then the list sorted by the 64-bit key (float_order << 32 | index) that each cell used to sort
// on its own: about 14% of a tori or bunny-dragon `exact` frame went to those sorts, most refs
// sitting in one cell of 64-512. The four byte histograms come from the one pass that makes the
// keys (counts do not depend on the order), and keys already in order need no pass at all.
// sweep_slab sorts this way when its cells hold at least kPresortMeanList entries on average (and
// kRadixMinRefs in all); with a few refs a cell, each cell's own sort is cheaper. (The folded
// cloth's slabs, ~1,200 refs in 3 cells in nearly sorted runs, are 3% slower this way, 3 us a
// frame; the cut-offs were measured on the six scenes: docs/ground-truth.md.)
constexpr std::size_t kRadixMinRefs = 64;
constexpr std::size_t kPresortMeanList = 16;
void sorted_refs(const std::vector<TriRef>& refs, int axis, SlabScratch& sc) {
    const std::size_t n = refs.size();
    sc.key.resize(n);
    sc.order.resize(n);
    sc.key_tmp.resize(n);
    sc.order_tmp.resize(n);
    // The keys and the four byte histograms in one pass; keys already in order need no pass.
    std::array<std::array<std::uint32_t, 257>, 4> count{};
    bool in_order = true;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t k = float_order(refs[i].lo[axis]);
        sc.key[i] = k;
        sc.order[i] = static_cast<std::uint32_t>(i);
        in_order = in_order && (i == 0 || sc.key[i - 1] <= k);
        for (int b = 0; b < 4; ++b) ++count[static_cast<std::size_t>(b)][((k >> (8 * b)) & 0xffu) + 1];
    }
    if (in_order) return;
    for (int b = 0; b < 4; ++b) {
        std::array<std::uint32_t, 257>& c = count[static_cast<std::size_t>(b)];
        const int shift = 8 * b;
        if (c[((sc.key[0] >> shift) & 0xffu) + 1] == n) continue;  // one byte value: a no-op
        for (std::size_t v = 0; v < 256; ++v) c[v + 1] += c[v];
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t at = c[(sc.key[i] >> shift) & 0xffu]++;
            sc.key_tmp[at] = sc.key[i];
            sc.order_tmp[at] = sc.order[i];
        }
        sc.key.swap(sc.key_tmp);
        sc.order.swap(sc.order_tmp);
    }
}

// Bins the refs of slab `s` of task `t` (the first `n0` are side a's) into its cells and sweeps
// every cell, calling visit(position in a, position in b) for each pair of refs whose float boxes
// overlap, in the cell owning it.
template <class Visit>
void sweep_slab(const TriTask& t, int s, const std::vector<TriRef>& refs, std::size_t n0, Visit&& visit) {
    const auto slab = static_cast<std::uint16_t>(s);
    const auto r0 = static_cast<std::uint32_t>(std::find(t.row_slab.begin(), t.row_slab.end(), slab) - t.row_slab.begin());
    auto r1 = r0;
    while (r1 < t.row_slab.size() && t.row_slab[r1] == slab) ++r1;
    const auto gu = static_cast<std::uint32_t>(t.gu.cells);
    const std::size_t cells = static_cast<std::size_t>(r1 - r0) * gu;
    // Per-thread scratch kept between calls (kept.h: fresh vectors faulted their pages in again
    // every frame); nothing in a slab job runs another one on this thread.
    thread_local SlabScratch scratch;
    std::vector<std::uint32_t>& next = scratch.next;  // counts, then fill cursors, of (cell, side)
    next.assign(2 * cells + 1, 0);
    // Each ref's cells (SlabSpan; its slot is 2 * cell + side). Most refs touch one cell: a direct
    // slot for them (these two passes were 14% of a breaking frame with the double loop and its
    // index arithmetic for every ref).
    using Span = SlabSpan;
    std::vector<Span>& spans = scratch.spans;
    spans.resize(refs.size());
    const int u = t.gu.axis, v = t.gv.axis;
    for (std::size_t i = 0; i < refs.size(); ++i) {
        const TriRef& r = refs[i];
        const std::uint32_t u0 = r.low & 0xffffu, u1 = t.gu.cell(static_cast<double>(r.hi[u]));
        const std::uint32_t v0 = std::max(r.low >> 16, r0), v1 = std::min(t.gv.cell(static_cast<double>(r.hi[v])), r1 - 1);
        const std::uint32_t side = i < n0 ? 0 : 1;
        spans[i] = {2 * ((v0 - r0) * gu + u0) + side, u1 - u0 + 1, v1 >= v0 ? v1 - v0 + 1 : 0};  // rows meet the slab's
    }
    const auto for_slots = [&](const Span& sp, auto&& f) {
        if (sp.width == 1 && sp.rows == 1) {
            f(sp.first);
            return;
        }
        for (std::uint32_t row = 0, at = sp.first; row < sp.rows; ++row, at += 2 * gu)
            for (std::uint32_t k = 0; k < sp.width; ++k) f(at + 2 * k);
    };
    for (const Span& sp : spans) for_slots(sp, [&](std::uint32_t slot) { ++next[slot + 1]; });
    for (std::size_t k = 0; k < 2 * cells; ++k) next[k + 1] += next[k];
    std::vector<std::uint32_t>& begin = scratch.begin;  // (cell, side) c: [begin[c], begin[c + 1])
    begin.assign(next.begin(), next.end());
    std::vector<std::uint32_t>& idx = scratch.idx;
    idx.resize(next[2 * cells]);
    // Each (cell, side) list comes out sorted for the sweep where the refs are sorted first (many
    // refs: sorted_refs), else each cell sorts its own (CellScratch::fill).
    const std::size_t entries = next[2 * cells];
    const bool presorted = entries >= kRadixMinRefs && entries >= kPresortMeanList * cells;
    if (presorted) {
        sorted_refs(refs, t.axis, scratch);
        for (const std::uint32_t i : scratch.order) for_slots(spans[i], [&](std::uint32_t slot) { idx[next[slot]++] = i; });
    } else {
        for (std::size_t i = 0; i < refs.size(); ++i)
            for_slots(spans[i], [&](std::uint32_t slot) { idx[next[slot]++] = static_cast<std::uint32_t>(i); });
    }

    thread_local CellScratch sc;
    const bool self = t.self();
    for (std::size_t c = 0; c < cells; ++c) {
        const std::uint32_t b0 = begin[2 * c], split = begin[2 * c + 1], e = begin[2 * c + 2];
        if (self ? e - b0 < 2 : (split == b0 || e == split)) continue;
        const std::size_t n = e - b0, na = split - b0;
        sc.reserve(n);
        const std::span<const std::uint32_t> cell_idx(idx.data() + b0, n);
        sc.fill(refs, cell_idx.subspan(0, na), t.axis, u, v, 0, presorted);
        if (!self) sc.fill(refs, cell_idx.subspan(na), t.axis, u, v, na, presorted);
        const std::uint32_t cell_uv = static_cast<std::uint32_t>(c % gu) | (static_cast<std::uint32_t>(c / gu) + r0) << 16;
        const float* lo = sc.lo.data();
        const float* hi = sc.hi.data();
        const float* lu = sc.lu.data();
        const float* hu = sc.hu.data();
        const float* lv = sc.lv.data();
        const float* hv = sc.hv.data();
        const std::uint32_t* low = sc.low.data();
        const std::uint32_t* pos = sc.pos.data();
        // Calls check(x, k) (a_first: check(k, x)) for k in [from, to) while lo[k] <= hi[x], k's box
        // meeting x's across the axis and the cell owning the pair; four k at a time with SSE2 (every
        // x86-64 CPU has it) where built for x86-64. lo is sorted, so the refs starting before x ends
        // are a prefix.
        const auto scan = [&](std::size_t x, std::size_t from, std::size_t to, bool x_is_a) {
            const float h = hi[x];
            const auto hit = [&](std::size_t k) {
                if (owns_pair(cell_uv, low[x], low[k])) {
                    if (x_is_a) visit(pos[x], pos[k]);
                    else visit(pos[k], pos[x]);
                }
            };
            std::size_t k = from;
#if defined(__SSE2__)
            const __m128 vh = _mm_set1_ps(h), vlu = _mm_set1_ps(lu[x]), vhu = _mm_set1_ps(hu[x]);
            const __m128 vlv = _mm_set1_ps(lv[x]), vhv = _mm_set1_ps(hv[x]);
            for (; k + 4 <= to; k += 4) {
                const int started = _mm_movemask_ps(_mm_cmple_ps(_mm_loadu_ps(lo + k), vh));
                const __m128 across = _mm_and_ps(
                    _mm_and_ps(_mm_cmple_ps(vlu, _mm_loadu_ps(hu + k)), _mm_cmple_ps(_mm_loadu_ps(lu + k), vhu)),
                    _mm_and_ps(_mm_cmple_ps(vlv, _mm_loadu_ps(hv + k)), _mm_cmple_ps(_mm_loadu_ps(lv + k), vhv)));
                for (int bits = _mm_movemask_ps(across) & started; bits != 0; bits &= bits - 1)
                    hit(k + static_cast<std::size_t>(std::countr_zero(static_cast<unsigned>(bits))));
                if (started != 0xf) return;
            }
#endif
            for (; k < to && lo[k] <= h; ++k)
                if (lu[x] <= hu[k] && lu[k] <= hu[x] && lv[x] <= hv[k] && lv[k] <= hv[x]) hit(k);
        };
        if (self) {
            for (std::size_t i = 0; i < n; ++i) scan(i, i + 1, n, true);
            continue;
        }
        // Two sorted runs, as sweep_cell.
        std::size_t i = 0, j = na;
        while (i < na && j < n) {
            if (lo[i] <= lo[j]) {
                scan(i, j, n, true);
                ++i;
            } else {
                scan(j, i, na, false);
                ++j;
            }
        }
    }
}

// The pairs (i < j) of objects whose non-empty boxes overlap, sorted: a sweep along x over the boxes
// sorted by their low x. The double loop over every pair was a serial 3% of a leaves frame (151
// objects, 11 K box tests for 57 overlaps).
std::vector<std::pair<std::uint32_t, std::uint32_t>> overlapping_objects(std::span<const ExactObject> objects) {
    std::vector<std::uint32_t> order;
    order.reserve(objects.size());
    for (std::uint32_t o = 0; o < objects.size(); ++o)
        if (!objects[o].box.empty()) order.push_back(o);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const double la = objects[a].box.lo.x, lb = objects[b].box.lo.x;
        return la != lb ? la < lb : a < b;
    });
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::size_t p = 0; p < order.size(); ++p) {
        const Aabb& a = objects[order[p]].box;
        // Boxes further on start at or after a's low x: they meet it along x while they start by its high.
        for (std::size_t q = p + 1; q < order.size() && objects[order[q]].box.lo.x <= a.hi.x; ++q)
            if (overlaps(a, objects[order[q]].box))
                pairs.emplace_back(std::min(order[p], order[q]), std::max(order[p], order[q]));
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

// The number of set flags (each 0 or 1), eight at a time: the bytes of a word summed by one multiply
// (the top byte of x * 0x0101010101010101 is the sum of x's bytes, at most 8 here).
std::uint64_t count_flags(std::span<const unsigned char> flags) {
    std::uint64_t n = 0;
    std::size_t i = 0;
    for (; i + 8 <= flags.size(); i += 8) {
        std::uint64_t w = 0;
        std::memcpy(&w, flags.data() + i, 8);
        n += (w * 0x0101010101010101ULL) >> 56;
    }
    for (; i < flags.size(); ++i) n += flags[i];
    return n;
}

}  // namespace

int spread_axis(std::span<const SweepRef> refs) {
    if (refs.empty()) return 0;
    std::array<double, 3> lo{}, hi{};
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0.5 * refs[0].box.lo[k] + 0.5 * refs[0].box.hi[k];
    for (const SweepRef& r : refs) {
        for (int k = 0; k < 3; ++k) {
            const double c = 0.5 * r.box.lo[k] + 0.5 * r.box.hi[k];
            lo[k] = std::min(lo[k], c);
            hi[k] = std::max(hi[k], c);
        }
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    return axis;
}

void sort_along(std::vector<SweepRef>& refs, int axis) {
    std::sort(refs.begin(), refs.end(), [axis](const SweepRef& a, const SweepRef& b) {
        if (a.box.lo[axis] != b.box.lo[axis]) return a.box.lo[axis] < b.box.lo[axis];
        if (a.set != b.set) return a.set < b.set;
        return a.part < b.part;
    });
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> overlapping_sets(std::vector<SweepRef> refs, int threads) {
    std::uint64_t overlapping = 0;
    return overlapping_sets(std::move(refs), threads, nullptr, overlapping);
}

// overlapping_sets' grid over the two axes other than the sweep's: a sweep along one axis meets
// every box whose interval overlaps along it, which on a ring of thin triangles (the tori split into
// single triangles) is a whole slab of the ring for each: 16% of a 1-thread tori / qcullide frame
// (perf). Each box goes into the cells its box covers; each cell is swept on its own (its list keeps
// the refs' sorted order), and a pair is reported only in the cell holding the low corner of the
// two boxes' common part, which both boxes cover: exactly once. Cells about twice the mean extent a
// side, at most kGridMaxCells a side and one cell per ref in all.
constexpr std::size_t kGridMinRefs = 1024;  // below: the plain sweep
constexpr int kGridMaxCells = 1024;
constexpr std::uint64_t kGridMaxEntries = 8;  // cell entries per ref, at most
struct SweepGrid {
    int u = 0, v = 0;          // the axes
    int nu = 1, nv = 1;        // cells per axis
    double lo_u = 0, lo_v = 0, scale_u = 0, scale_v = 0;
    [[nodiscard]] int cell_u(double x) const {
        return std::clamp(static_cast<int>((x - lo_u) * scale_u), 0, nu - 1);
    }
    [[nodiscard]] int cell_v(double x) const {
        return std::clamp(static_cast<int>((x - lo_v) * scale_v), 0, nv - 1);
    }
};
SweepGrid sweep_grid(std::span<const SweepRef> refs, int axis) {
    SweepGrid g;
    g.u = (axis + 1) % 3;
    g.v = (axis + 2) % 3;
    double lo[2] = {refs[0].box.lo[g.u], refs[0].box.lo[g.v]}, hi[2] = {refs[0].box.hi[g.u], refs[0].box.hi[g.v]};
    double ext[2] = {0.0, 0.0};
    for (const SweepRef& r : refs) {
        for (int k = 0; k < 2; ++k) {
            const int a = k == 0 ? g.u : g.v;
            lo[k] = std::min(lo[k], r.box.lo[a]);
            hi[k] = std::max(hi[k], r.box.hi[a]);
            ext[k] += r.box.hi[a] - r.box.lo[a];
        }
    }
    int cells[2] = {1, 1};
    for (int k = 0; k < 2; ++k) {
        const double range = hi[k] - lo[k];
        const double size = std::max(2.0 * ext[k] / static_cast<double>(refs.size()), range / kGridMaxCells);
        if (range > 0.0 && size > 0.0 && std::isfinite(range / size))
            cells[k] = std::clamp(static_cast<int>(range / size), 1, kGridMaxCells);
    }
    while (static_cast<std::size_t>(cells[0]) * static_cast<std::size_t>(cells[1]) > refs.size()) {
        int& big = cells[0] >= cells[1] ? cells[0] : cells[1];
        big = (big + 1) / 2;
    }
    g.nu = cells[0];
    g.nv = cells[1];
    g.lo_u = lo[0];
    g.lo_v = lo[1];
    g.scale_u = g.nu > 1 ? g.nu / (hi[0] - lo[0]) : 0.0;
    g.scale_v = g.nv > 1 ? g.nv / (hi[1] - lo[1]) : 0.0;
    return g;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> overlapping_sets(
    std::vector<SweepRef> refs, int threads, const std::function<bool(std::uint32_t, std::uint32_t)>& keep,
    std::uint64_t& overlapping) {
    const int axis = spread_axis(refs);
    sort_along(refs, axis);
    const SweepGrid g = refs.size() >= kGridMinRefs ? sweep_grid(refs, axis) : SweepGrid{};
    bool grid = g.nu * g.nv > 1;
    // Each ref's cells, [u0, u1] x [v0, v1], found once for the count and the fill below.
    struct CellRange {
        int u0, u1, v0, v1;
    };
    std::vector<CellRange> range;
    if (grid) {  // a few large boxes could fill every cell: the plain sweep beyond kGridMaxEntries a ref
        range.reserve(refs.size());
        std::uint64_t total = 0;
        for (const SweepRef& r : refs) {
            const CellRange c{g.cell_u(r.box.lo[g.u]), g.cell_u(r.box.hi[g.u]), g.cell_v(r.box.lo[g.v]),
                              g.cell_v(r.box.hi[g.v])};
            total += static_cast<std::uint64_t>(c.u1 - c.u0 + 1) * static_cast<std::uint64_t>(c.v1 - c.v0 + 1);
            range.push_back(c);
        }
        grid = total <= kGridMaxEntries * refs.size();
    }
    // The cells' lists (CSR, in the refs' sorted order), then units of whole cells of about
    // kSweepChunk entries; without a grid, units of kSweepChunk starting refs.
    std::vector<std::uint32_t> cell_start, entries;
    std::vector<std::size_t> unit_first;  // per unit, its first cell; then the cell count
    std::size_t units = (refs.size() + kSweepChunk - 1) / kSweepChunk;
    if (grid) {
        const std::size_t n_cells = static_cast<std::size_t>(g.nu) * static_cast<std::size_t>(g.nv);
        // Calls f(cell) for every cell of ref i, row by row.
        const auto for_cells = [&](std::size_t i, auto&& f) {
            const CellRange& c = range[i];
            for (int cv = c.v0; cv <= c.v1; ++cv)
                for (int cu = c.u0; cu <= c.u1; ++cu)
                    f(static_cast<std::size_t>(cv) * static_cast<std::size_t>(g.nu) + static_cast<std::size_t>(cu));
        };
        cell_start.assign(n_cells + 1, 0);
        for (std::size_t i = 0; i < refs.size(); ++i) for_cells(i, [&](std::size_t c) { ++cell_start[c + 1]; });
        for (std::size_t c = 0; c < n_cells; ++c) cell_start[c + 1] += cell_start[c];
        entries.resize(cell_start[n_cells]);
        std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
        for (std::size_t i = 0; i < refs.size(); ++i)
            for_cells(i, [&](std::size_t c) { entries[fill[c]++] = static_cast<std::uint32_t>(i); });
        unit_first.push_back(0);
        for (std::size_t c = 0; c < n_cells; ++c)
            if (cell_start[c + 1] - cell_start[unit_first.back()] >= kSweepChunk && c + 1 < n_cells) unit_first.push_back(c + 1);
        unit_first.push_back(n_cells);
        units = unit_first.size() - 1;
    }
    std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> found(units);
    std::vector<std::uint64_t> seen(units, 0);
    parallel_chunks(threads, units, [&](std::size_t u) {
        const auto visit = [&](const SweepRef& a, const SweepRef& b) {
            ++seen[u];
            const std::uint32_t lo = std::min(a.set, b.set), hi = std::max(a.set, b.set);
            if (!keep || keep(lo, hi)) found[u].emplace_back(lo, hi);
        };
        if (!grid) {
            sweep_overlaps(refs, axis, u * kSweepChunk, std::min(refs.size(), (u + 1) * kSweepChunk), true, visit);
        } else {
            for (std::size_t c = unit_first[u]; c < unit_first[u + 1]; ++c) {
                const std::uint32_t* list = entries.data() + cell_start[c];
                const std::size_t len = cell_start[c + 1] - cell_start[c];
                const int cu = static_cast<int>(c % static_cast<std::size_t>(g.nu));
                const int cv = static_cast<int>(c / static_cast<std::size_t>(g.nu));
                for (std::size_t i = 0; i < len; ++i) {
                    const SweepRef& a = refs[list[i]];
                    const double a_hi = a.box.hi[axis];
                    for (std::size_t j = i + 1; j < len && refs[list[j]].box.lo[axis] <= a_hi; ++j) {
                        const SweepRef& b = refs[list[j]];
                        if (!overlaps(a.box, b.box)) continue;
                        // Reported in the cell of the low corner of the common part only.
                        if (g.cell_u(std::max(a.box.lo[g.u], b.box.lo[g.u])) != cu ||
                            g.cell_v(std::max(a.box.lo[g.v], b.box.lo[g.v])) != cv)
                            continue;
                        visit(a, b);
                    }
                }
            }
        }
        // Each unit's pairs sorted in its own job; the runs are merged below. The serial sort of
        // all of them was 1.9% of a qcullide --self cloth frame (perf). The same sorted multiset.
        std::sort(found[u].begin(), found[u].end());
    });
    overlapping = 0;
    for (std::uint64_t n : seen) overlapping += n;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    std::vector<std::size_t> run_start;  // out's sorted runs, one per non-empty chunk
    for (const auto& f : found) {
        if (f.empty()) continue;
        run_start.push_back(out.size());
        out.insert(out.end(), f.begin(), f.end());
    }
    // Merge neighbouring runs pairwise until one is left (log2 of the run count rounds).
    while (run_start.size() > 1) {
        std::vector<std::size_t> next;
        for (std::size_t r = 0; r < run_start.size(); r += 2) {
            next.push_back(run_start[r]);
            if (r + 1 == run_start.size()) break;
            const std::size_t end = r + 2 < run_start.size() ? run_start[r + 2] : out.size();
            std::inplace_merge(out.begin() + static_cast<std::ptrdiff_t>(run_start[r]),
                               out.begin() + static_cast<std::ptrdiff_t>(run_start[r + 1]),
                               out.begin() + static_cast<std::ptrdiff_t>(end));
        }
        run_start = std::move(next);
    }
    return out;
}

ExactStageResult sweep_exact_stage(std::span<const ExactObject> objects, std::span<const CandidateSet> sets,
                                   const SweepOptions& options) {
    TaskBuilder builder(objects, sets);
    const auto n = static_cast<std::uint32_t>(objects.size());
    if (options.self)
        for (std::uint32_t o = 0; o < n; ++o) builder.add_self(o);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t j = i + 1; j < n; ++j) builder.add_pair(i, j);
    std::vector<Task> tasks = builder.take_tasks(options.threads);

    // Units: runs of consecutive cells of one task holding about kSweepChunk refs (fixed by the
    // input), so a big task (a bunny inside a dragon) spreads over threads.
    struct Unit {
        std::uint32_t task;
        std::size_t begin, end;  // cells
    };
    std::vector<Unit> units;
    for (std::size_t t = 0; t < tasks.size(); ++t) {
        const Task& task = tasks[t];
        const std::size_t cells = task.cell_begin.size() - 1;
        std::size_t from = 0;
        for (std::size_t c = 0; c < cells; ++c) {
            if (task.cell_begin[c + 1] - task.cell_begin[from] >= kSweepChunk || c + 1 == cells) {
                units.push_back({static_cast<std::uint32_t>(t), from, c + 1});
                from = c + 1;
            }
        }
    }

    const PairTester tester(objects, sets);
    std::vector<UnitOut> out(units.size());
    parallel_chunks(options.threads, units.size(), [&](std::size_t u) {
        Task& task = tasks[units[u].task];  // the unit owns its cells' refs
        UnitOut& o = out[u];
        const auto visit = [&](const SweepRef& a, const SweepRef& b) {
            if (a.part != kWholeSet && b.part != kWholeSet) {  // two triangles, boxes overlapping
                if (tester.test(a.object, a.part, b.object, b.part, false, o) && options.count_set_pairs)
                    o.set_pairs.push_back(set_pair_key(a.set, b.set));
                return;
            }
            if (tester.test_sets(a.set, b.set, false, o) != 0 && options.count_set_pairs)
                o.set_pairs.push_back(set_pair_key(a.set, b.set));
        };
        for (std::size_t c = units[u].begin; c < units[u].end; ++c) {
            sort_cell(task, c);
            sweep_cell(task, c, visit);
        }
    });
    ExactStageResult r = merge(out, options.count_set_pairs);
    r.stats.task_triangles = builder.task_triangles();
    return r;
}

ExactStageResult listed_exact_stage(std::span<const ExactObject> objects, std::span<const CandidateSet> sets,
                                    std::span<const CandidatePair> pairs, int threads) {
    const PairTester tester(objects, sets);
    const std::size_t units = (pairs.size() + kPairChunk - 1) / kPairChunk;
    std::vector<UnitOut> out(units);
    parallel_chunks(threads, units, [&](std::size_t u) {
        const std::size_t end = std::min(pairs.size(), (u + 1) * kPairChunk);
        for (std::size_t p = u * kPairChunk; p < end; ++p) (void)tester.test_sets(pairs[p].a, pairs[p].b, pairs[p].near, out[u]);
    });
    return merge(out, false);
}

ExactStageResult sweep_exact_triangles(std::span<const ExactObject> objects,
                                       std::span<const TriangleBoxes> boxes, const SweepOptions& options) {
    const auto n = static_cast<std::uint32_t>(objects.size());
    std::vector<TriTask> tasks;
    if (options.self)
        for (std::uint32_t o = 0; o < n; ++o)
            if (objects[o].triangle_boxes.size() >= 2) tasks.push_back({o, o, {}, 0, {}, {}, {}, 1});
    for (const auto& [i, j] : overlapping_objects(objects)) {
        const Aabb& bi = objects[i].box;
        const Aabb& bj = objects[j].box;
        TriTask t;
        t.a = i;
        t.b = j;
        for (int k = 0; k < 3; ++k) {
            t.common.lo[k] = std::max(bi.lo[k], bj.lo[k]);
            t.common.hi[k] = std::min(bi.hi[k], bj.hi[k]);
        }
        tasks.push_back(std::move(t));
    }
    // A spatial order for the big objects read by many pair tasks.
    std::vector<std::uint32_t> pair_tasks(n, 0), to_order;
    for (const TriTask& t : tasks)
        if (!t.self()) ++pair_tasks[t.a], ++pair_tasks[t.b];
    for (std::uint32_t o = 0; o < n; ++o)
        if (pair_tasks[o] >= kSpatialTasks && objects[o].triangle_boxes.size() >= kSpatialMin && loose_blocks(objects[o], boxes[o]))
            to_order.push_back(o);
    std::vector<SpatialOrder> orders(n);
    for (const std::uint32_t o : to_order) orders[o] = spatial_order(objects[o], options.threads);  // parallel inside
    std::vector<std::vector<unsigned char>> in_task(n);
    for (std::uint32_t o = 0; o < n; ++o) in_task[o].assign(objects[o].triangle_boxes.size(), 0);

    // Sweeps slab s of task ti, its refs side a's (the first n0) then side b's, into `o`.
    const PairTester tester(objects, {});
    const auto sweep_refs = [&](std::uint32_t ti, int s, const std::vector<TriRef>& refs, std::size_t n0, UnitOut& o) {
        const TriTask& t = tasks[ti];
        if (refs.size() < 2) return;
        if (!t.self() && (n0 == 0 || n0 == refs.size())) return;
        const std::span<const Aabb> boxes_a = objects[t.a].triangle_boxes;
        const std::span<const Aabb> boxes_b = objects[t.b].triangle_boxes;
        sweep_slab(t, s, refs, n0, [&](std::uint32_t pa, std::uint32_t pb) {
            if (t.self())
                (void)tester.test_if_overlapping(t.a, pa, t.b, pb, boxes_a, boxes_b, false, o);
            else if (overlaps(boxes_a[pa], boxes_b[pb]))
                (void)tester.test(t.a, pa, t.b, pb, false, o);
        });
    };

    // One job per task plans it (plan_task); a task of one slab (every task of breaking, leaves,
    // cylinders) is then gathered and swept in the same job, side a then side b into one thread-local
    // list: no more phases, no copies. Phases cost: each ends with every thread waiting for the last.
    std::vector<UnitOut> out(tasks.size());
    parallel_chunks(options.threads, tasks.size(), [&](std::size_t ti) {
        TriTask& t = tasks[ti];
        plan_task(t, objects, boxes);
        if (t.slabs != 1) return;
        thread_local std::vector<TriRef> refs;
        refs.clear();
        gather(t, objects[t.a], boxes[t.a], orders[t.a], 0, static_cast<std::uint32_t>(objects[t.a].triangle_boxes.size()),
               in_task[t.a], {&refs, 1});
        const std::size_t n0 = refs.size();
        if (!t.self())  // even when side a found nothing: side b's in-task flags are counted
            gather(t, objects[t.b], boxes[t.b], orders[t.b], 0, static_cast<std::uint32_t>(objects[t.b].triangle_boxes.size()),
                   in_task[t.b], {&refs, 1});
        sweep_refs(static_cast<std::uint32_t>(ti), 0, refs, n0, out[ti]);
    });

    // Tasks cut into slabs (a bunny inside a dragon): gather jobs, chunks of each side, side a's then
    // side b's, then one job per slab.
    std::vector<GatherJob> jobs;
    std::vector<std::size_t> task_jobs(tasks.size() + 1, 0);  // jobs of task t: [task_jobs[t], task_jobs[t + 1])
    std::vector<std::size_t> side_b(tasks.size(), 0);         // its first side-b job
    for (std::size_t t = 0; t < tasks.size(); ++t) {
        task_jobs[t] = jobs.size();
        side_b[t] = jobs.size();
        if (tasks[t].slabs == 1) continue;
        for (std::uint32_t side = 0; side < (tasks[t].self() ? 1u : 2u); ++side) {
            if (side == 1) side_b[t] = jobs.size();
            const auto count = static_cast<std::uint32_t>(objects[side == 0 ? tasks[t].a : tasks[t].b].triangle_boxes.size());
            for (std::uint32_t f = 0; f < count; f += kGatherChunk)
                jobs.push_back({static_cast<std::uint32_t>(t), side, f,
                                static_cast<std::uint32_t>(std::min<std::size_t>(count, f + kGatherChunk))});
        }
        if (tasks[t].self()) side_b[t] = jobs.size();
    }
    task_jobs[tasks.size()] = jobs.size();
    // Kept by the calling thread between calls (kept.h), each list emptied before its job fills it.
    const Kept<std::vector<SlabRefs>, struct GatheredTag> kept_gathered;
    std::vector<SlabRefs>& gathered = *kept_gathered;
    if (gathered.size() < jobs.size()) gathered.resize(jobs.size());
    parallel_chunks(options.threads, jobs.size(), [&](std::size_t j) {
        const GatherJob& g = jobs[j];
        const TriTask& t = tasks[g.task];
        const std::uint32_t o = g.side == 0 ? t.a : t.b;
        gathered[j].resize(static_cast<std::size_t>(t.slabs));
        for (std::vector<TriRef>& refs : gathered[j]) refs.clear();
        gather(t, objects[o], boxes[o], orders[o], g.first, g.last, in_task[o], gathered[j]);
    });
    struct SlabJob {
        std::uint32_t task;
        int slab;
    };
    std::vector<SlabJob> slabs;
    for (std::size_t t = 0; t < tasks.size(); ++t)
        if (tasks[t].slabs > 1)
            for (int s = 0; s < tasks[t].slabs; ++s) slabs.push_back({static_cast<std::uint32_t>(t), s});
    out.resize(tasks.size() + slabs.size());
    parallel_chunks(options.threads, slabs.size(), [&](std::size_t sj) {
        const std::uint32_t ti = slabs[sj].task;
        const auto s = static_cast<std::size_t>(slabs[sj].slab);
        thread_local std::vector<TriRef> refs;
        refs.clear();
        for (std::size_t j = task_jobs[ti]; j < side_b[ti]; ++j)
            refs.insert(refs.end(), gathered[j][s].begin(), gathered[j][s].end());
        const std::size_t n0 = refs.size();
        for (std::size_t j = side_b[ti]; j < task_jobs[ti + 1]; ++j)
            refs.insert(refs.end(), gathered[j][s].begin(), gathered[j][s].end());
        sweep_refs(ti, slabs[sj].slab, refs, n0, out[tasks.size() + sj]);
    });
    ExactStageResult r = merge(out, false);
    for (std::uint32_t o = 0; o < n; ++o) {
        if (options.self) {
            r.stats.task_triangles += objects[o].triangle_boxes.size();
            continue;
        }
        r.stats.task_triangles += count_flags(in_task[o]);
    }
    return r;
}

}  // namespace cullide::detail
