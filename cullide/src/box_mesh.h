// box_mesh.h: an axis-aligned box as a mesh, for the hunt's generators and for tests that build
// scenes by hand (tests add cullide/src to their include path).
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "cullide/mesh.h"

namespace cullide::detail {

// The box [lo, hi]: 8 shared vertices (x from bit 0, y from bit 1, z from bit 2), 12 triangles
// facing out, two per face.
inline Mesh box_mesh(std::string name, Vec3 lo, Vec3 hi) {
    Mesh m;
    m.name = std::move(name);
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
    const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : q) {
        m.triangles.push_back({f[0], f[1], f[2]});
        m.triangles.push_back({f[0], f[2], f[3]});
    }
    return m;
}

}  // namespace cullide::detail
