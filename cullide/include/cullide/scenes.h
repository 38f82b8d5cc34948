// cullide/scenes.h: built-in deterministic scene generators, one per scene of the papers.
//
// A scene is a function of (options, frame index): frame f can be generated without frames
// 0..f-1, and the same options give the same bits on every platform and thread count (only
// IEEE-exact operations: + - * / sqrt; the trigonometry is our own, see det_math.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide {

struct SceneOptions {
    std::uint64_t seed = 1;
    // Where real meshes are looked for (bunny/dragon pair). Empty: procedural stand-ins only.
    std::string mesh_dir = "../shared/data/meshes";
    // Scale factor on the scene's size parameters (objects, triangles); 1 = the paper's scene.
    double scale = 1.0;
};

// One frame: the objects, in a fixed order, each a Mesh.
using Frame = std::vector<Mesh>;

class SceneGenerator {
   public:
    virtual ~SceneGenerator() = default;
    [[nodiscard]] virtual std::string name() const = 0;
    [[nodiscard]] virtual std::string description() const = 0;  // one line, for `cullide scenes`
    // Frame f >= 0. Never fails once the generator was made.
    [[nodiscard]] virtual Frame frame(int f) const = 0;
};

// Built-in names: cylinders (default), tori, bunny-dragon, breaking, leaves, cloth.
[[nodiscard]] std::vector<std::string> scene_names();
// Fails for an unknown name or absurd options (scale <= 0 or too large).
[[nodiscard]] Result<std::unique_ptr<SceneGenerator>> make_scene(const std::string& name,
                                                                 const SceneOptions& options);

}  // namespace cullide
