// exact_stage.cpp: the one exact stage and the one sweep and prune (see exact_stage.h).
#include "exact_stage.h"

#include <algorithm>
#include <array>

#include "cullide/tri_tri.h"
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

// One swept task: the refs of one object (self) or of two, sorted along `axis`.
struct Task {
    std::vector<SweepRef> refs;
    int axis = 0;
    bool self = false;
};

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
        Task task;
        task.self = true;
        for (std::uint32_t s = set_begin_[o]; s < set_begin_[o + 1]; ++s) {
            in_task_[s] = 1;
            task.refs.push_back(whole_ref(s));
        }
        add(std::move(task), nullptr);
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
        Task task;
        std::size_t from_i = 0;
        for (const std::uint32_t o : {i, j}) {
            for (std::uint32_t s = set_begin_[o]; s < set_begin_[o + 1]; ++s) {
                if (!overlaps(sets_[s].box, common)) continue;
                in_task_[s] = 1;
                task.refs.push_back(whole_ref(s));
            }
            if (o == i) from_i = task.refs.size();
        }
        if (from_i == 0 || from_i == task.refs.size()) return;  // one side has nothing there
        add(std::move(task), &common);
    }

    std::vector<Task> take_tasks() { return std::move(tasks_); }

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

    // Chooses the axis, replaces loose sets by their triangles inside `common`, and sorts. A self
    // task (no `common`) always sweeps triangles: a set's own pairs are pairs of its triangles.
    void add(Task&& task, const Aabb* common) {
        if (task.refs.size() < 2 && (common != nullptr || task.refs.empty() || sets_[task.refs[0].set].count < 2))
            return;
        task.axis = spread_axis(task.refs);
        const bool all_triangles = std::all_of(task.refs.begin(), task.refs.end(),
                                               [](const SweepRef& r) { return r.part != kWholeSet; });
        if (!all_triangles && (common == nullptr || loose(task.refs, task.axis))) {
            std::vector<SweepRef> tris;
            for (const SweepRef& r : task.refs) {
                const CandidateSet& set = sets_[r.set];
                const std::span<const Aabb> boxes = objects_[set.object].triangle_boxes;
                for (std::uint32_t p = set.first; p < set.first + set.count; ++p)
                    if (common == nullptr || overlaps(boxes[p], *common)) tris.push_back({boxes[p], set.object, r.set, p});
            }
            task.refs = std::move(tris);
        }
        sort_along(task.refs, task.axis);
        tasks_.push_back(std::move(task));
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
    std::vector<Task> tasks_;
};

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
    const int axis = spread_axis(refs);
    sort_along(refs, axis);
    const std::size_t units = (refs.size() + kSweepChunk - 1) / kSweepChunk;
    std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> found(units);
    parallel_chunks(threads, units, [&](std::size_t u) {
        sweep_overlaps(refs, axis, u * kSweepChunk, std::min(refs.size(), (u + 1) * kSweepChunk), true,
                       [&](const SweepRef& a, const SweepRef& b) {
                           found[u].emplace_back(std::min(a.set, b.set), std::max(a.set, b.set));
                       });
    });
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    for (const auto& f : found) out.insert(out.end(), f.begin(), f.end());
    std::sort(out.begin(), out.end());
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
    const std::vector<Task> tasks = builder.take_tasks();

    struct Unit {
        std::uint32_t task;
        std::size_t begin, end;
    };
    std::vector<Unit> units;
    for (std::size_t t = 0; t < tasks.size(); ++t)
        for (std::size_t b = 0; b < tasks[t].refs.size(); b += kSweepChunk)
            units.push_back({static_cast<std::uint32_t>(t), b, std::min(tasks[t].refs.size(), b + kSweepChunk)});

    const PairTester tester(objects, sets);
    std::vector<UnitOut> out(units.size());
    parallel_chunks(options.threads, units.size(), [&](std::size_t u) {
        const Task& task = tasks[units[u].task];
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
        sweep_overlaps(task.refs, task.axis, units[u].begin, units[u].end, task.self, visit);
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

}  // namespace cullide::detail
