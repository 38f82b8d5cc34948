#include "cullide/ground_truth.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <numeric>

#include "cullide/predicates.h"
#include "cullide/tri_tri.h"
#include "parallel.h"

namespace cullide {
namespace {

struct TriRef {
    std::uint32_t object;
    std::uint32_t triangle;
    Aabb box;
};

// Sweep-and-prune chunks are fixed-size ranges of the sorted list, independent of thread count.
constexpr std::size_t kSweepChunk = 2048;

bool share_welded_vertex(const std::array<std::uint32_t, 3>& a, const std::array<std::uint32_t, 3>& b) {
    for (std::uint32_t u : a) {
        for (std::uint32_t v : b) {
            if (u == v) return true;
        }
    }
    return false;
}

}  // namespace

std::vector<std::uint32_t> weld_vertices(const Mesh& mesh) {
    const std::size_t n = mesh.positions.size();
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    // Sort by value with the index as tie-break, so equal positions form runs whose first element
    // is the earliest vertex. -0.0 and 0.0 compare equal and so weld, as the exact test sees them.
    std::sort(order.begin(), order.end(), [&](std::uint32_t i, std::uint32_t j) {
        const Vec3& p = mesh.positions[i];
        const Vec3& q = mesh.positions[j];
        if (p.x != q.x) return p.x < q.x;
        if (p.y != q.y) return p.y < q.y;
        if (p.z != q.z) return p.z < q.z;
        return i < j;
    });
    std::vector<std::uint32_t> representative(n);
    for (std::size_t k = 0; k < n; ++k) {
        const bool starts_run = k == 0 || !(mesh.positions[order[k]] == mesh.positions[order[k - 1]]);
        representative[order[k]] = starts_run ? order[k] : representative[order[k - 1]];
    }
    // Dense ids in order of first appearance of each representative.
    std::vector<std::uint32_t> id(n, 0);
    std::vector<std::uint32_t> id_of_rep(n, UINT32_MAX);
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < n; ++v) {
        std::uint32_t& slot = id_of_rep[representative[v]];
        if (slot == UINT32_MAX) slot = next++;
        id[v] = slot;
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

Status validate_exact_range(std::span<const Mesh> objects) {
    // The exact predicates are exact only inside their range (predicates.h): refuse, never guess.
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Mesh& m = objects[i];
        for (std::size_t v = 0; v < m.positions.size(); ++v) {
            for (int k = 0; k < 3; ++k) {
                if (!predicate_coordinate_ok(m.positions[v][k])) {
                    char value[32];
                    std::snprintf(value, sizeof value, "%.17g", m.positions[v][k]);
                    return Error{"object " + std::to_string(i) + ": mesh '" + m.name + "': vertex " +
                                 std::to_string(v) + " coordinate " + "xyz"[k] + " = " + value +
                                 " is outside the exact range (0, or 2^-300 <= |x| <= 2^300)"};
                }
            }
        }
    }
    return {};
}

Result<std::vector<TrianglePair>> exact_pairs(std::span<const Mesh> objects, const ExactOptions& options,
                                              ExactStats* stats) {
    if (Status s = validate_scene(objects); !s) return s.error();
    if (objects.size() > UINT32_MAX) return Error{"too many objects (limit 2^32 - 1)"};
    if (Status s = validate_exact_range(objects); !s) return s.error();

    ExactStats st;
    const std::size_t n = objects.size();
    std::vector<Aabb> object_box(n);
    std::vector<std::vector<Aabb>> tri_box(n);
    for (std::size_t i = 0; i < n; ++i) {
        object_box[i] = mesh_bounds(objects[i]);
        st.triangles += objects[i].triangles.size();
        tri_box[i].resize(objects[i].triangles.size());
        for (std::size_t t = 0; t < tri_box[i].size(); ++t) tri_box[i][t] = triangle_bounds(objects[i], t);
    }

    // Tasks: each object with itself (self-collision), then each pair of objects whose boxes
    // overlap. A pair task keeps only the triangles whose boxes meet the intersection of the two
    // object boxes: no pair outside it can meet. Each task is swept on its own (sweep and prune,
    // on the axis where its boxes' centres spread most), so same-object neighbours never cost time.
    struct Task {
        std::vector<TriRef> refs;  // sorted by (lo[axis], object, triangle): a unique key
        int axis = 0;
        bool self = false;
    };
    std::vector<Task> tasks;
    std::vector<char> candidate(st.triangles, 0);  // flags, indexed by object offset + triangle
    std::vector<std::size_t> offset(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) offset[i + 1] = offset[i] + objects[i].triangles.size();

    auto add_task = [&](Task&& task) {
        if (task.refs.size() < 2) return;
        Aabb centres{task.refs[0].box.lo, task.refs[0].box.lo};
        for (const TriRef& r : task.refs) {
            for (int k = 0; k < 3; ++k) {
                const double c = 0.5 * r.box.lo[k] + 0.5 * r.box.hi[k];
                centres.lo[k] = std::min(centres.lo[k], c);
                centres.hi[k] = std::max(centres.hi[k], c);
            }
        }
        double best = -1;
        for (int k = 0; k < 3; ++k) {
            if (centres.hi[k] - centres.lo[k] > best) {
                best = centres.hi[k] - centres.lo[k];
                task.axis = k;
            }
        }
        const int axis = task.axis;
        std::sort(task.refs.begin(), task.refs.end(), [axis](const TriRef& a, const TriRef& b) {
            if (a.box.lo[axis] != b.box.lo[axis]) return a.box.lo[axis] < b.box.lo[axis];
            if (a.object != b.object) return a.object < b.object;
            return a.triangle < b.triangle;
        });
        tasks.push_back(std::move(task));
    };

    if (options.self) {
        for (std::size_t i = 0; i < n; ++i) {
            Task task;
            task.self = true;
            for (std::size_t t = 0; t < tri_box[i].size(); ++t) {
                task.refs.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(t), tri_box[i][t]});
                candidate[offset[i] + t] = 1;
            }
            add_task(std::move(task));
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = i + 1; j < n; ++j) {
            if (!overlaps(object_box[i], object_box[j])) continue;
            Aabb common;
            for (int k = 0; k < 3; ++k) {
                common.lo[k] = std::max(object_box[i].lo[k], object_box[j].lo[k]);
                common.hi[k] = std::min(object_box[i].hi[k], object_box[j].hi[k]);
            }
            Task task;
            for (std::size_t o : {i, j}) {
                for (std::size_t t = 0; t < tri_box[o].size(); ++t) {
                    if (!overlaps(tri_box[o][t], common)) continue;
                    task.refs.push_back({static_cast<std::uint32_t>(o), static_cast<std::uint32_t>(t), tri_box[o][t]});
                    candidate[offset[o] + t] = 1;
                }
            }
            add_task(std::move(task));
        }
    }
    for (char c : candidate) st.candidate_triangles += c != 0;

    std::vector<std::vector<std::uint32_t>> welded;
    if (options.self) {
        welded.resize(n);
        for (std::size_t i = 0; i < n; ++i) welded[i] = weld_vertices(objects[i]);
    }

    // Work units: fixed-size ranges of each task's sorted list, so big tasks (a bunny inside a
    // dragon) spread over threads too. Unit boundaries depend on the input only.
    struct Unit {
        std::uint32_t task;
        std::size_t begin, end;
    };
    std::vector<Unit> units;
    for (std::size_t t = 0; t < tasks.size(); ++t) {
        for (std::size_t b = 0; b < tasks[t].refs.size(); b += kSweepChunk) {
            units.push_back({static_cast<std::uint32_t>(t), b, std::min(tasks[t].refs.size(), b + kSweepChunk)});
        }
    }

    struct UnitOut {
        std::vector<TrianglePair> pairs;
        std::uint64_t box_pairs = 0;
        std::uint64_t adjacent = 0;
    };
    std::vector<UnitOut> out(units.size());
    detail::parallel_chunks(options.threads, units.size(), [&](std::size_t u) {
        const Task& task = tasks[units[u].task];
        const std::vector<TriRef>& refs = task.refs;
        const int axis = task.axis;
        UnitOut& o = out[u];
        for (std::size_t i = units[u].begin; i < units[u].end; ++i) {
            const TriRef& a = refs[i];
            for (std::size_t j = i + 1; j < refs.size() && refs[j].box.lo[axis] <= a.box.hi[axis]; ++j) {
                const TriRef& b = refs[j];
                if (a.object == b.object && !task.self) continue;
                if (!overlaps(a.box, b.box)) continue;
                const Mesh& ma = objects[a.object];
                const Mesh& mb = objects[b.object];
                const Tri& ta = ma.triangles[a.triangle];
                const Tri& tb = mb.triangles[b.triangle];
                if (task.self) {
                    const std::vector<std::uint32_t>& w = welded[a.object];
                    if (share_welded_vertex({w[ta[0]], w[ta[1]], w[ta[2]]}, {w[tb[0]], w[tb[1]], w[tb[2]]})) {
                        ++o.adjacent;
                        continue;
                    }
                }
                ++o.box_pairs;
                if (tri_tri_intersect(ma.positions[ta[0]], ma.positions[ta[1]], ma.positions[ta[2]],
                                      mb.positions[tb[0]], mb.positions[tb[1]], mb.positions[tb[2]])) {
                    TrianglePair p{a.object, a.triangle, b.object, b.triangle};
                    if (p.object_a > p.object_b || (p.object_a == p.object_b && p.triangle_a > p.triangle_b)) {
                        p = {b.object, b.triangle, a.object, a.triangle};
                    }
                    o.pairs.push_back(p);
                }
            }
        }
    });

    std::vector<TrianglePair> pairs;
    for (UnitOut& o : out) {
        pairs.insert(pairs.end(), o.pairs.begin(), o.pairs.end());
        st.box_pairs += o.box_pairs;
        st.adjacent_skipped += o.adjacent;
    }
    std::sort(pairs.begin(), pairs.end());
    if (stats) *stats = st;
    return pairs;
}

}  // namespace cullide
