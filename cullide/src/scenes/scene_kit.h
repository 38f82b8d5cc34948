// scene_kit.h: geometry helpers and per-scene factories shared by the scene generators.
//
// Private to cullide_lib. Every helper uses only + - * / sqrt and scene_math.h, in a fixed order, so a
// scene's bits are the same on every platform (see docs/scenes.md, "Determinism").
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "cullide/mesh.h"
#include "cullide/result.h"
#include "cullide/scenes.h"

namespace cullide::scene_kit {

// Frames per second of every scene's clock: frame f is at time f / kFramesPerSecond.
inline constexpr int kFramesPerSecond = 30;

[[nodiscard]] Vec3 normalized(Vec3 v);
// A unit vector perpendicular to the unit vector w (fixed choice, no branch on tiny values).
[[nodiscard]] Vec3 perpendicular(Vec3 w);

// A rotation as three orthonormal columns: apply(r, p) = p.x * u + p.y * v + p.z * w.
struct Rotation {
    Vec3 u{1, 0, 0}, v{0, 1, 0}, w{0, 0, 1};
};
[[nodiscard]] Vec3 apply(const Rotation& r, Vec3 p);
// Rz(yaw) * Ry(pitch) * Rx(roll), angles in radians, trigonometry from scene_math.h.
[[nodiscard]] Rotation rotation_from_angles(double yaw, double pitch, double roll);
// Rotation by `angle` about the unit axis (Rodrigues' formula).
[[nodiscard]] Rotation rotation_about(Vec3 axis, double angle);
// Rotation whose w column is the unit vector `w`.
[[nodiscard]] Rotation rotation_to(Vec3 w);

// Rounds a non-negative double to the nearest integer (ties up), at least `lo`.
[[nodiscard]] std::int64_t round_at_least(double x, std::int64_t lo);

// Appends a (cols x rows)-cell grid of quads, each split into two triangles, with vertex (i, j) at
// at(i, j) for i in [0, cols] (or [0, cols) when wrap_cols: the last column joins the first) and
// j in [0, rows] (or [0, rows) when wrap_rows). Adds 2 * cols * rows triangles; wrapped seams share
// vertices, so a tube or torus is welded.
void append_grid(Mesh& mesh, int cols, int rows, bool wrap_cols, bool wrap_rows,
                 const std::function<Vec3(int, int)>& at);

// A closed star-shaped surface with exactly `triangles` triangles (>= 8): a latitude-longitude
// sphere (pole fans + quad bands) mapped through at(direction) for unit directions; when the count
// cannot be met exactly, the last triangles (around the bottom pole) are left out, which opens a
// hole there, like the real bunny's base. Unused vertices are removed.
[[nodiscard]] Mesh make_blob(const std::string& name, std::int64_t triangles,
                             const std::function<Vec3(Vec3)>& at);

// Drops vertices no triangle uses, keeping the order of the others.
void compact_vertices(Mesh& mesh);

// Factories, one per scene (scale already validated: finite, in (0, 100]).
[[nodiscard]] std::unique_ptr<SceneGenerator> make_cylinders(const SceneOptions& options);
[[nodiscard]] std::unique_ptr<SceneGenerator> make_tori(const SceneOptions& options);
[[nodiscard]] Result<std::unique_ptr<SceneGenerator>> make_bunny_dragon(const SceneOptions& options);
[[nodiscard]] std::unique_ptr<SceneGenerator> make_breaking(const SceneOptions& options);
[[nodiscard]] std::unique_ptr<SceneGenerator> make_leaves(const SceneOptions& options);
[[nodiscard]] std::unique_ptr<SceneGenerator> make_cloth(const SceneOptions& options);

// Part numbers for det::stream_seed, one per scene, so scenes never share random streams.
enum ScenePart : std::uint64_t {
    kPartCylinders = 1,
    kPartTori = 2,
    kPartBunnyDragon = 3,
    kPartBreaking = 4,
    kPartLeaves = 5,
    kPartCloth = 6,
};

}  // namespace cullide::scene_kit
