// cullide/pipeline.h: one frame through a collision method, with its statistics.
//
// This is the library's front door: the CLI is a thin layer over process_frame. Every method returns
// the same canonical pair list, so results of different methods compare directly. Stages of a frame:
// optional broad phase (spatialhash::find_pairs on the objects' boxes: an object overlapping no
// other box leaves at once) -> the method (exact, or CULLIDE's visibility stages, cullide/cullide.h)
// -> sorted pairs and FrameStats.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cullide/cullide.h"
#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/quick_cullide.h"
#include "cullide/result.h"

namespace cullide {

enum class Method {
    Exact,    // ground truth: box prefilter + exact triangle test (ground_truth.h)
    Cullide,         // CULLIDE, GL-exact visibility (may miss collisions, like the GPU original)
    RCullide,        // R-CULLIDE in the emulator's exact-bounds raster mode (never misses; emulator only)
    RCullideOffset,  // R-CULLIDE with the paper's offset solids, pixel-centre GL (never misses; any device)
    QCullide,        // Quick-CULLIDE, exact-bounds mode (never misses; emulator only; self-collision)
    QCullideGL,      // Quick-CULLIDE, GL-exact mode (may miss; any device; self-collision)
};

// The optional first stage, on the objects' axis-aligned boxes (spatialhash/broad_phase.h).
enum class BroadPhase { None, SpatialHash, SweepAndPrune, BruteForce };

[[nodiscard]] const char* to_string(BroadPhase b);
// "none", "spatialhash", "sap", "brute"; the error lists the valid names.
[[nodiscard]] Result<BroadPhase> parse_broadphase(std::string_view name);
[[nodiscard]] const char* to_string(raster::DepthFormat f);
// "d16", "d24", "d32f"; the error lists the valid names.
[[nodiscard]] Result<raster::DepthFormat> parse_depth_format(std::string_view name);

[[nodiscard]] const char* to_string(Method m);
// Parses a method name; the error lists the valid names.
[[nodiscard]] Result<Method> parse_method(std::string_view name);
// Names accepted by parse_method, in order.
[[nodiscard]] std::vector<std::string> method_names();

// Default view resolution per method (pixels per side), measured (docs/cullide.md, "Defaults";
// docs/quick-cullide.md): the exact-bounds methods (rcullide, qcullide) never miss, their cost falls
// with the resolution and the exact stage removes the extra false positives, so they run best low;
// the pixel-centre methods miss less at high resolution.
inline constexpr int kDefaultResolutionRCullide = 32;
inline constexpr int kDefaultResolutionQCullide = 32;
inline constexpr int kDefaultResolutionOthers = 1024;
[[nodiscard]] int default_resolution(Method m);

struct RunOptions {
    Method method = Method::RCullide;  // R-CULLIDE (exact-bounds): never misses, ends in the exact test
    int threads = 0;          // 0 = all hardware threads; results do not depend on it
    // View resolution of the visibility methods (pixels per side), 1..16384; 0 = the method's own
    // default_resolution (so choosing another method never silently keeps rcullide's 32 px).
    int resolution = 0;
    bool self = false;        // also report pairs inside one object (adjacent triangles excluded);
                              // exact, qcullide and qcullide-gl only (CULLIDE never tests an object
                              // against itself)
    raster::DepthFormat depth_format = raster::DepthFormat::D24;  // visibility methods
    int subobject_triangles = 4;  // triangles per sub-object (visibility methods), >= 1
    int max_rounds = 4;           // rounds of x, y, z views per visibility stage, >= 1
    double min_prune = -1.0;      // CullideOptions::min_prune (cullide, rcullide, rcullide-offset)
    ObjectStage object_stage = ObjectStage::Auto;  // CullideOptions::object_stage (same methods)
    BroadPhase broadphase = BroadPhase::None;  // with self on, no object is dropped by it
    // Where the visibility passes run; nullptr: the built-in emulator with `threads` workers.
    // Not owned; must outlive the call. Used by tests and benchmarks to run on a real GL.
    QueryDevice* device = nullptr;
};

// Per-frame figures. Counts are deterministic; times are wall-clock milliseconds.
struct FrameStats {
    std::uint64_t objects = 0;
    std::uint64_t triangles = 0;
    std::uint64_t candidate_triangles = 0;  // triangles surviving the object-box prefilter
    std::uint64_t exact_tests = 0;          // triangle pairs sent to the exact test
    std::uint64_t adjacent_skipped = 0;     // self pairs skipped because they share a (welded) vertex
    double time_ms = 0;
    // Broad phase (all objects when none ran) and visibility stages (zero for exact; the PCS and
    // per-view figures of cullide/cullide.h: pcs_* are the PCS after each stage).
    std::uint64_t broadphase_objects = 0;  // objects kept by the broad phase
    std::uint64_t broadphase_pairs = 0;    // overlapping object-box pairs it found
    std::uint64_t pcs_boxes = 0;
    std::uint64_t pcs_objects = 0;
    std::uint64_t subobjects = 0;
    std::uint64_t pcs_subobjects = 0;
    std::uint64_t subobject_pairs = 0;
    std::uint64_t queries = 0;
    std::uint64_t triangles_rasterized = 0;
    std::vector<ViewStats> views;
    double broadphase_ms = 0, boxes_ms = 0, objects_ms = 0, subobjects_ms = 0, exact_ms = 0;
};

struct FrameResult {
    std::vector<TrianglePair> pairs;         // sorted, canonical (ground_truth.h)
    std::vector<ObjectPair> object_pairs;    // derived from pairs
    FrameStats stats;
};

// Runs one frame. Fails on invalid meshes or options, naming what is wrong.
[[nodiscard]] Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options);

}  // namespace cullide
