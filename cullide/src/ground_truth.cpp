#include "cullide/ground_truth.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <numeric>

#include "cullide/predicates.h"
#include "exact_stage.h"

namespace cullide {

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

    // Every triangle is a candidate set of its own (so the exact stage needs no separate list of
    // triangle boxes): it sweeps them per pair of objects whose boxes overlap (and per object with
    // self-collision).
    const std::size_t n = objects.size();
    std::vector<std::vector<std::uint32_t>> welded(options.self ? n : 0);
    std::vector<detail::ExactObject> exact(n);
    std::vector<detail::CandidateSet> sets;
    ExactStats st;
    for (const Mesh& m : objects) st.triangles += m.triangles.size();
    sets.reserve(st.triangles);
    for (std::size_t i = 0; i < n; ++i) {
        const Mesh& m = objects[i];
        const auto object = static_cast<std::uint32_t>(i);
        for (std::size_t t = 0; t < m.triangles.size(); ++t)
            sets.push_back({object, static_cast<std::uint32_t>(t), 1, triangle_bounds(m, t)});
        if (options.self) welded[i] = weld_vertices(m);
        exact[i] = {&m, object, mesh_bounds(m), {}, {},
                    options.self ? std::span<const std::uint32_t>(welded[i]) : std::span<const std::uint32_t>()};
    }
    detail::ExactStageResult r = detail::sweep_exact_stage(exact, sets, {options.self, false, options.threads});
    st.candidate_triangles = r.stats.task_triangles;
    st.box_pairs = r.stats.tests;
    st.adjacent_skipped = r.stats.adjacent_skipped;
    if (stats) *stats = st;
    return std::move(r.pairs);
}

}  // namespace cullide
