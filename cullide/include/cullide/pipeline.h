// cullide/pipeline.h: one frame through a collision method, with its statistics.
//
// This is the library's front door: the CLI is a thin layer over process_frame. Every method returns
// the same canonical pair list, so results of different methods compare directly. Stages of a frame:
// optional broad phase (spatialhash::find_pairs on the objects' boxes: an object overlapping no
// other box leaves at once) -> the method (exact, or CULLIDE's visibility stages, cullide/cullide.h)
// -> sorted pairs and FrameStats.
#pragma once

#include <cstdint>
#include <memory>
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
    // The adaptive never-miss method, the default: per frame, a deterministic estimate from counts
    // (triangles, object boxes and their overlaps; never a clock) decides whether R-CULLIDE's views
    // can prune more exact-stage work than they cost; if so the frame runs as RCullide, otherwise
    // straight to the exact stage (as Exact). Either way its pairs are the ground truth's. With
    // self-collision it runs as Exact. The rule and its figures: docs/cullide.md, "The default: auto".
    Auto,
};

// Method::Auto's estimate for one frame (plan_auto): the exact stage's work, counted as the
// triangles its object-pair tasks would hold (each object's triangles times the share of its box
// that the pair's common box covers, per axis, summed over the overlapping object pairs; boxes of
// the vertex lists, read in linear passes), against
// the triangles a round of three R-CULLIDE views would rasterize. Deterministic: counts and box
// extents only, so the choice is the same for any thread count and machine.
struct AutoPlan {
    std::uint64_t triangles = 0;         // triangles of the kept objects
    std::uint64_t paired_triangles = 0;  // of those, in objects whose box overlaps another's
    std::uint64_t object_pairs = 0;      // overlapping object-box pairs
    double task_triangles = 0;           // estimated triangles of the exact stage's tasks
    bool views = false;                  // run R-CULLIDE's views (else straight to the exact stage)
};

// Views run when the estimated task triangles reach this many times the paired triangles
// (docs/cullide.md, "The default: auto": a 32 px view costs about as much per triangle as the exact
// stage per task triangle, a frame of R-CULLIDE runs at least six views, and on heaps of spheres
// the views only broke even at a ratio of 7 and won at 13).
inline constexpr double kAutoViewsPay = 8.0;
// Below this many paired triangles a frame always goes straight to the exact stage: set-up
// (views fitted, buffers cleared) outweighs any pruning (docs/cullide.md, "Tiny frames").
inline constexpr std::uint64_t kAutoMinViewTriangles = 4096;

// The plan Method::Auto follows for `objects` restricted to `active` (strictly increasing indices
// into `objects`; the broad phase's survivors). It reads positions and triangle counts only, never
// an index, so it is safe on meshes not yet checked (process_frame plans an `auto` frame before
// exact_pairs checks the scene; an invalid scene's plan is meaningless, and the frame fails).
[[nodiscard]] AutoPlan plan_auto(std::span<const Mesh> objects, std::span<const std::uint32_t> active);
// The same, on `threads` workers (the same rule as RunOptions::threads); the same plan for any count.
[[nodiscard]] AutoPlan plan_auto(std::span<const Mesh> objects, std::span<const std::uint32_t> active, int threads);

// The optional first stage, on the objects' axis-aligned boxes (spatialhash/broad_phase.h).
enum class BroadPhase { None, SpatialHash, SweepAndPrune, BruteForce };

[[nodiscard]] const char* to_string(BroadPhase b);
// "none", "spatialhash", "sap", "brute"; the error lists the valid names.
[[nodiscard]] Result<BroadPhase> parse_broadphase(std::string_view name);
[[nodiscard]] const char* to_string(raster::DepthFormat f);
// "d16", "d24", "d32f"; the error lists the valid names.
[[nodiscard]] Result<raster::DepthFormat> parse_depth_format(std::string_view name);
[[nodiscard]] const char* to_string(raster::RasterRules r);
// "gl" (OpenGL on llvmpipe), "vulkan" (Vulkan as lavapipe); the error lists the valid names.
[[nodiscard]] Result<raster::RasterRules> parse_gpu_rules(std::string_view name);

[[nodiscard]] const char* to_string(Method m);
// Parses a method name; the error lists the valid names.
[[nodiscard]] Result<Method> parse_method(std::string_view name);
// Names accepted by parse_method, in order.
[[nodiscard]] std::vector<std::string> method_names();

// The method's default view resolution: default_resolution of its VisibilityMode (visibility.h),
// 32 for rcullide, qcullide and auto (its views are rcullide's), 1024 for the others.
[[nodiscard]] int default_resolution(Method m);

// A run: the visibility methods' shared options (visibility.h: resolution, 0 = the method's
// default_resolution; depth format; sub-object size; rounds; threads, which also drive the broad
// phase, the exact method and the emulator) and the run's own. process_frame hands the shared part
// to the method as it is.
struct RunOptions : VisibilityOptions {
    Method method = Method::Auto;  // adaptive: R-CULLIDE's views where they pay, else the exact stage;
                                   // never misses
    bool self = false;        // also report pairs inside one object (adjacent triangles excluded);
                              // exact, qcullide, qcullide-gl and auto (as exact) only (CULLIDE
                              // never tests an object against itself)
    double min_prune = -1.0;      // CullideOptions::min_prune (cullide, rcullide, rcullide-offset)
    ObjectStage object_stage = ObjectStage::Auto;  // CullideOptions::object_stage (same methods)
    BroadPhase broadphase = BroadPhase::None;  // with self on, no object is dropped by it
    // Where the visibility passes run; nullptr: the built-in emulator with `threads` workers.
    // Not owned; must outlive the call. Used by tests and benchmarks to run on a real GL.
    QueryDevice* device = nullptr;
};

// Per-frame figures: the visibility methods' (visibility.h; zero for exact, which fills only
// candidate_triangles, exact_tests and adjacent_skipped; with self-collision pcs_boxes and
// pcs_objects are all objects: none leaves at object level) and the frame's own. Counts are
// deterministic; times are wall-clock milliseconds.
struct FrameStats : VisibilityStats {
    std::uint64_t objects = 0;
    std::uint64_t triangles = 0;
    double time_ms = 0;
    // Broad phase (all objects when none ran).
    std::uint64_t broadphase_objects = 0;  // objects kept by the broad phase
    std::uint64_t broadphase_pairs = 0;    // overlapping object-box pairs it found
    double broadphase_ms = 0;
    // Pieces paired for the exact stage: CULLIDE's sub-object pairs holding a tested triangle pair
    // (CullideStats::subobject_pairs), Quick-CULLIDE's kept item pairs (QuickStats::item_pairs_kept).
    std::uint64_t subobject_pairs = 0;
    // Method::Auto: its plan for this frame (default-constructed for the other methods).
    AutoPlan auto_plan;
};

struct FrameResult {
    std::vector<TrianglePair> pairs;         // sorted, canonical (ground_truth.h)
    std::vector<ObjectPair> object_pairs;    // derived from pairs
    FrameStats stats;
};

// What process_frame keeps from one frame to the next when the caller holds it: the emulator device
// with its depth target, and Quick-CULLIDE's self-collision triangle order per object with the
// topology it came from (used only while the triangles and welded vertices stay the same). A frame
// costs milliseconds of set-up without one (a depth target allocated and cleared, worker threads
// woken) and microseconds with one, which is what fuzzers and per-frame simulation loops need
// (docs/cullide.md, "Tiny frames"). It holds no answer: a frame's results are the same bits with a
// fresh context, a reused one, or none, whatever frames of whatever sizes, methods and options ran
// through it before.
// Movable, not copyable; one frame at a time (not for concurrent calls from several threads).
class FrameContext {
   public:
    FrameContext();
    ~FrameContext();
    FrameContext(FrameContext&&) noexcept;
    FrameContext& operator=(FrameContext&&) noexcept;
    FrameContext(const FrameContext&) = delete;
    FrameContext& operator=(const FrameContext&) = delete;

    struct State;  // defined in src/process_frame.cpp

   private:
    friend Result<FrameResult> process_frame(std::span<const Mesh>, const RunOptions&, FrameContext&);
    std::unique_ptr<State> state_;
};

// For a process that runs frames in a loop, on glibc: keeps freed memory in the process instead of
// handing it back to the kernel between frames. A frame allocates and frees buffers of megabytes;
// with glibc's defaults the pages of some of them are returned when freed (the heap's top beyond its
// trim threshold, or blocks above its mmap threshold) and faulted in and zeroed again by the next
// frame, in some runs and not in others, depending on what the process freed before (up to 1.2x a
// frame's time: docs/cullide.md, "Freed memory between frames"). This sets glibc's mmap threshold to
// 32 MB (the most its own adjustment reaches) and its trim threshold to 256 MB. The process's peak
// memory does not grow: what is kept was in use before. Process-wide, so the library never calls it
// on its own; the `cullide` command and the benchmarks do. Returns whether the settings were made:
// false on other C libraries, under an allocator that refuses them (a sanitizer's), and when
// GLIBC_TUNABLES names a glibc.malloc setting (the user's own choice is left alone).
bool retain_freed_memory();

// Runs one frame. Fails on invalid meshes or options, naming what is wrong (the context keeps its
// buffers and stays usable). The first form uses a temporary FrameContext.
[[nodiscard]] Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options);
[[nodiscard]] Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options,
                                                FrameContext& context);

}  // namespace cullide
