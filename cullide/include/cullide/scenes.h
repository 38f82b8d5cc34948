// cullide/scenes.h: built-in deterministic scene generators, one per scene of the papers.
//
// A scene is a function of (options, frame index): frame f can be generated without frames
// 0..f-1, and the same options give the same bits on every platform and thread count (only
// IEEE-exact operations: + - * / sqrt; the trigonometry is our own, see scene_math.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide {

// The largest SceneOptions::scale.
inline constexpr double kMaxSceneScale = 100.0;

struct SceneOptions {
    std::uint64_t seed = 1;
    // Where real meshes are looked for (bunny/dragon pair). Empty: procedural stand-ins only.
    std::string mesh_dir = "../shared/data/meshes";
    // Scale factor on the scene's size parameters (objects, triangles); 1 = the paper's scene.
    // What it multiplies differs per scene (docs/scenes.md): the cylinder count; the triangles per
    // torus / bunny / dragon / shell / ball / cloth; the falling and attached leaf counts. Counts are
    // rounded to the nearest integer with a small floor, so 0.05 gives tiny scenes. Must be finite,
    // > 0 and <= kMaxSceneScale.
    double scale = 1.0;
};

// One frame: the objects, in a fixed order, each a Mesh.
using Frame = std::vector<Mesh>;

class SceneGenerator {
   public:
    virtual ~SceneGenerator() = default;
    [[nodiscard]] virtual std::string name() const = 0;
    // One line, for `cullide scenes` (which prints "name: description"): sizes, motion, what scale
    // multiplies, and for bunny-dragon which meshes were used. Does not repeat the name.
    [[nodiscard]] virtual std::string description() const = 0;
    // Frame f (normally >= 0). Never fails once the generator was made. Any int is accepted (every motion is
    // periodic; negative f continues the period backwards). Const and free of hidden state, so
    // calls may run concurrently and in any order: frame f never depends on earlier calls.
    [[nodiscard]] virtual Frame frame(int f) const = 0;
};

// Built-in names: cylinders (default), tori, bunny-dragon, breaking, leaves, cloth.
[[nodiscard]] std::vector<std::string> scene_names();
// Fails for an unknown name (the message lists the valid names), absurd options (scale <= 0, not
// finite, or > 100), or, for bunny-dragon, a mesh file in options.mesh_dir that is present but does
// not parse (the reader's message). A missing folder or file is not an error: bunny-dragon then uses
// procedural stand-ins with the same triangle counts, and its description() says which was used.
[[nodiscard]] Result<std::unique_ptr<SceneGenerator>> make_scene(const std::string& name,
                                                                 const SceneOptions& options);

// FNV-1a (64-bit) over a frame's bits, for pinning scenes in tests and benchmarks: the object count,
// then per object its vertex count, each coordinate's IEEE bits (x, y, z), its triangle count and
// each index, every integer fed as little-endian bytes (8 bytes, indices 4). Names are not hashed.
[[nodiscard]] std::uint64_t frame_digest(const Frame& frame);

}  // namespace cullide
