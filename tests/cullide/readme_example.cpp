#include <cstdio>

#include "cullide/pipeline.h"
#include "cullide/scenes.h"

int main() {
    auto scene = cullide::make_scene("cylinders", {});  // built-in scene, default seed
    if (!scene) return std::fprintf(stderr, "%s\n", scene.error().message.c_str()), 1;
    cullide::Frame objects = scene.value()->frame(0);  // a std::vector<cullide::Mesh>
    cullide::RunOptions options;                       // method rcullide, all cores
    auto result = cullide::process_frame(objects, options);
    if (!result) return std::fprintf(stderr, "%s\n", result.error().message.c_str()), 1;
    for (const cullide::TrianglePair& p : result.value().pairs)
        std::printf("object %u triangle %u meets object %u triangle %u\n", p.object_a, p.triangle_a,
                    p.object_b, p.triangle_b);
}
