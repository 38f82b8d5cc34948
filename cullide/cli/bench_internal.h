// cullide/cli/bench_internal.h: pieces shared by bench.cpp (the engine, output) and sweep.cpp (the
// comparison with the ground truth). Not installed, not a public API.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "options.h"

namespace cullide::cli::bench_detail {

// Options of bench and sweep (defaults filled in by the option table); lists are cross-multiplied.
struct BenchArgs {
    bool sweep = false;
    std::vector<std::string> scenes;
    std::vector<double> scales;
    std::vector<Method> methods;
    std::vector<int> resolutions;
    std::vector<raster::DepthFormat> depth_formats;
    std::vector<int> threads;
    int frames = 0;
    int first_frame = 0;
    int frame_step = 1;
    int warmup = 0;
    int reps = 0;
    RunOptions base;        // subobject, rounds, min-prune, object stage, broadphase, self
    SceneOptions scene_options;
    std::string csv_path, json_path;
    bool progress = true;
};

// A method's pairs against the ground truth of one frame (both sorted and unique).
struct Comparison {
    std::uint64_t false_negatives = 0;    // true pairs the method did not report
    std::uint64_t extra_pairs = 0;        // reported pairs that are not true pairs (must be 0)
    std::uint64_t missed_object_pairs = 0;  // true object pairs with no reported pair
    std::uint64_t true_objects = 0;       // objects in at least one true pair
};
[[nodiscard]] Comparison compare_with_truth(std::span<const TrianglePair> truth, std::span<const TrianglePair> got);

}  // namespace cullide::cli::bench_detail
