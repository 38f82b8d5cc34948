#include "cullide/mesh.h"

#include "cullide_detail.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace cullide {

Aabb triangle_bounds(const Mesh& mesh, std::size_t triangle) {
    Aabb box;
    detail::triangle_box(mesh, triangle, box);
    return box;
}

Aabb mesh_bounds(const Mesh& mesh) { return detail::triangles_bounds(mesh, 0, mesh.triangles.size()); }

Aabb detail::triangles_bounds(const Mesh& mesh, std::size_t first, std::size_t last) {
    if (first >= last) return Aabb{};
    // The first vertex, then std::min / std::max with every vertex of every triangle in order (the
    // earlier of equal values kept, signed zeros included), six doubles in registers.
    const Vec3* const pos = mesh.positions.data();
    const Vec3& p0 = pos[mesh.triangles[first][0]];
    double x0 = p0.x, y0 = p0.y, z0 = p0.z, x1 = p0.x, y1 = p0.y, z1 = p0.z;
    for (std::size_t t = first; t < last; ++t) {
        for (const std::uint32_t v : mesh.triangles[t]) {
            const Vec3& p = pos[v];
            x0 = std::min(x0, p.x);
            y0 = std::min(y0, p.y);
            z0 = std::min(z0, p.z);
            x1 = std::max(x1, p.x);
            y1 = std::max(y1, p.y);
            z1 = std::max(z1, p.z);
        }
    }
    return Aabb{{x0, y0, z0}, {x1, y1, z1}};
}

namespace {
std::string mesh_label(const Mesh& mesh) { return "mesh '" + mesh.name + "'"; }
}  // namespace

Error vertex_index_error(const Mesh& mesh, std::size_t triangle, std::uint64_t index) {
    return Error{mesh_label(mesh) + ": triangle " + std::to_string(triangle) + " vertex index " + std::to_string(index) +
                 " is beyond the vertex list (size " + std::to_string(mesh.positions.size()) + ")"};
}

Error vertex_index_error(const Mesh& mesh, std::size_t triangle, std::int64_t index) {
    if (index >= 0) return vertex_index_error(mesh, triangle, static_cast<std::uint64_t>(index));
    return Error{mesh_label(mesh) + ": triangle " + std::to_string(triangle) + " vertex index " + std::to_string(index) +
                 " is negative (the vertex list has size " + std::to_string(mesh.positions.size()) + ")"};
}

Status validate_mesh(const Mesh& mesh) {
    const std::string who = mesh_label(mesh);
    if (mesh.triangles.empty()) return Error{who + ": has no triangles"};
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3& p = mesh.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            return Error{who + ": vertex " + std::to_string(i) + " has a non-finite coordinate"};
        }
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t v = mesh.triangles[i][k];
            if (v >= mesh.positions.size()) return vertex_index_error(mesh, i, std::uint64_t{v});
        }
    }
    return {};
}

Status validate_scene(std::span<const Mesh> objects) {
    for (std::size_t i = 0; i < objects.size(); ++i) {
        Status s = validate_mesh(objects[i]);
        if (!s) return Error{"object " + std::to_string(i) + ": " + s.error().message};
    }
    return {};
}

}  // namespace cullide
