// bench_frames.h: frames of the built-in scenes for the benchmarks, generated once per process.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cullide/scenes.h"

namespace cullide_bench {

// Frame `f` of a built-in scene at its default scale, with the shared meshes where present
// (CULLIDE_SHARED_MESH_DIR). A scene that cannot be made stops the program with its message: a
// benchmark of a missing scene would report nothing meaningful.
inline const std::vector<cullide::Mesh>& scene_frame(const std::string& scene, int f) {
    static std::map<std::pair<std::string, int>, std::vector<cullide::Mesh>> cache;
    const auto key = std::make_pair(scene, f);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    cullide::SceneOptions options;
    options.mesh_dir = CULLIDE_SHARED_MESH_DIR;
    auto g = cullide::make_scene(scene, options);
    if (!g) {
        std::fprintf(stderr, "%s\n", g.error().message.c_str());
        std::exit(1);
    }
    return cache.emplace(key, g.value()->frame(f)).first->second;
}

}  // namespace cullide_bench
