// cullide/pipeline.h: one frame through a collision method, with its statistics.
//
// This is the library's front door: the CLI is a thin layer over process_frame. Methods other than
// `exact` (CULLIDE, R-CULLIDE, Quick-CULLIDE) plug in here as they land; each returns the same
// canonical pair list, so results of different methods compare directly.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide {

enum class Method {
    Exact,  // ground truth: box prefilter + exact triangle test (ground_truth.h)
};

[[nodiscard]] const char* to_string(Method m);
// Parses a method name; the error lists the valid names.
[[nodiscard]] Result<Method> parse_method(std::string_view name);
// Names accepted by parse_method, in order.
[[nodiscard]] std::vector<std::string> method_names();

struct RunOptions {
    Method method = Method::Exact;
    int threads = 0;          // 0 = all hardware threads; results do not depend on it
    int resolution = 1024;    // view resolution of the visibility methods (pixels per side)
    bool self = false;        // also report pairs inside one object (adjacent triangles excluded)
};

// Per-frame figures. Counts are deterministic; times are wall-clock milliseconds.
struct FrameStats {
    std::uint64_t objects = 0;
    std::uint64_t triangles = 0;
    std::uint64_t candidate_triangles = 0;  // triangles surviving the object-box prefilter
    std::uint64_t exact_tests = 0;          // triangle pairs sent to the exact test
    std::uint64_t adjacent_skipped = 0;     // self pairs skipped because they share a (welded) vertex
    double time_ms = 0;
};

struct FrameResult {
    std::vector<TrianglePair> pairs;         // sorted, canonical (ground_truth.h)
    std::vector<ObjectPair> object_pairs;    // derived from pairs
    FrameStats stats;
};

// Runs one frame. Fails on invalid meshes or options, naming what is wrong.
[[nodiscard]] Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options);

}  // namespace cullide
