#include "cullide/mesh.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace cullide {

Aabb triangle_bounds(const Mesh& mesh, std::size_t triangle) {
    const Tri& t = mesh.triangles[triangle];
    const Vec3& a = mesh.positions[t[0]];
    const Vec3& b = mesh.positions[t[1]];
    const Vec3& c = mesh.positions[t[2]];
    Aabb box;
    for (int k = 0; k < 3; ++k) {
        box.lo[k] = std::min({a[k], b[k], c[k]});
        box.hi[k] = std::max({a[k], b[k], c[k]});
    }
    return box;
}

Aabb mesh_bounds(const Mesh& mesh) {
    Aabb box;
    bool first = true;
    for (const Tri& t : mesh.triangles) {
        for (std::uint32_t v : t) {
            const Vec3& p = mesh.positions[v];
            for (int k = 0; k < 3; ++k) {
                box.lo[k] = first ? p[k] : std::min(box.lo[k], p[k]);
                box.hi[k] = first ? p[k] : std::max(box.hi[k], p[k]);
            }
            first = false;
        }
    }
    return box;
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
