// cullide/mesh.h: the geometry a scene is made of, and nothing more.
//
// A Mesh is an indexed triangle list in double precision, positions kept exactly as read or
// generated: every exact predicate in cullide decides on exactly these values. Only positions and
// faces are modelled (no normals, texture coordinates or materials): a scene needs nothing else.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cullide/result.h"

namespace cullide {

struct Vec3 {
    double x = 0, y = 0, z = 0;

    constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    friend constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
    friend constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
    friend constexpr Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
    friend constexpr bool operator==(Vec3 a, Vec3 b) = default;
};

constexpr double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// Vertex indices of one triangle, into Mesh::positions.
using Tri = std::array<std::uint32_t, 3>;

struct Mesh {
    std::string name;              // object name (file name, OBJ group, or scene part); for messages
    std::vector<Vec3> positions;   // finite doubles
    std::vector<Tri> triangles;    // indices < positions.size(); degenerate triangles are allowed
};

// Axis-aligned box, closed. An empty box has lo > hi.
struct Aabb {
    Vec3 lo{1, 1, 1};
    Vec3 hi{0, 0, 0};

    [[nodiscard]] bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
};

// Box of one triangle / of a whole mesh (empty for a mesh without triangles).
[[nodiscard]] Aabb triangle_bounds(const Mesh& mesh, std::size_t triangle);
[[nodiscard]] Aabb mesh_bounds(const Mesh& mesh);
// Closed boxes overlap (touching counts). Inline: it is the inner test of every box prefilter.
[[nodiscard]] inline bool overlaps(const Aabb& a, const Aabb& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
}

// Checks a mesh a caller built: every position finite, every index in range, at least one
// triangle. The error names the mesh, the element and the limit.
[[nodiscard]] Status validate_mesh(const Mesh& mesh);
// validate_mesh's message for vertex index `index` of triangle `triangle` outside the vertex list of
// `mesh` (mesh.positions holds the list). Public so that callers holding signed or wider indices than
// Tri (cullide/eigen.h) word a negative or too-large index exactly as validate_mesh does.
[[nodiscard]] Error vertex_index_error(const Mesh& mesh, std::size_t triangle, std::int64_t index);
[[nodiscard]] Error vertex_index_error(const Mesh& mesh, std::size_t triangle, std::uint64_t index);
// The same over a scene; the message also names the object's index.
[[nodiscard]] Status validate_scene(std::span<const Mesh> objects);

}  // namespace cullide
