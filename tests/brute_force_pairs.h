// The brute-force twin of cullide::exact_pairs, shared by the tests that compare against it: every
// triangle pair, no prefilter, one thread, and naive welding for self pairs (two triangles of one
// object that share a position are adjacent: docs/conventions.md). Slow (all pairs) on purpose.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/tri_tri.h"

namespace test {

inline std::vector<cullide::TrianglePair> brute_force_pairs(std::span<const cullide::Mesh> objects, bool self) {
    std::vector<cullide::TrianglePair> out;
    for (std::uint32_t a = 0; a < objects.size(); ++a) {
        for (std::uint32_t b = a; b < objects.size(); ++b) {
            if (a == b && !self) continue;
            const cullide::Mesh& ma = objects[a];
            const cullide::Mesh& mb = objects[b];
            for (std::uint32_t i = 0; i < ma.triangles.size(); ++i) {
                for (std::uint32_t j = (a == b ? i + 1 : 0); j < mb.triangles.size(); ++j) {
                    const auto& ta = ma.triangles[i];
                    const auto& tb = mb.triangles[j];
                    bool adjacent = false;
                    if (a == b) {
                        for (auto u : ta)
                            for (auto v : tb) adjacent = adjacent || ma.positions[u] == mb.positions[v];
                    }
                    if (!adjacent &&
                        cullide::tri_tri_intersect(ma.positions[ta[0]], ma.positions[ta[1]], ma.positions[ta[2]],
                                                   mb.positions[tb[0]], mb.positions[tb[1]], mb.positions[tb[2]])) {
                        out.push_back({a, i, b, j});
                    }
                }
            }
        }
    }
    std::sort(out.begin(), out.end());  // generated in (a, b, i, j) order; canonical is (a, i, b, j)
    return out;
}

}  // namespace test
