// A downstream program: one frame of a built-in scene through the default method and through the
// exact ground truth, linked against the installed library. Exit status 0 only when the two pair
// lists are equal and not empty (cylinders frame 0 has colliding pairs).
#include <cstdio>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"

int main() {
    auto scene = cullide::make_scene("cylinders", {});
    if (!scene) return std::fprintf(stderr, "%s\n", scene.error().message.c_str()), 1;
    const cullide::Frame objects = scene.value()->frame(0);
    cullide::RunOptions options;  // rcullide, all cores
    auto culled = cullide::process_frame(objects, options);
    if (!culled) return std::fprintf(stderr, "%s\n", culled.error().message.c_str()), 1;
    auto exact = cullide::exact_pairs(objects);
    if (!exact) return std::fprintf(stderr, "%s\n", exact.error().message.c_str()), 1;
    const auto& pairs = culled.value().pairs;
    if (pairs.empty()) return std::fprintf(stderr, "consumer_check: no pairs on cylinders frame 0\n"), 1;
    if (pairs != exact.value()) {
        return std::fprintf(stderr, "consumer_check: rcullide found %zu pairs, the ground truth %zu\n", pairs.size(),
                            exact.value().size()),
               1;
    }
    std::printf("consumer_check: %zu pairs, equal to the ground truth\n", pairs.size());
    return 0;
}
