// cullide/visibility.h: what the visibility methods (CULLIDE, R-CULLIDE: cullide.h; Quick-CULLIDE:
// quick_cullide.h) share: the rasterization mode, the view resolution with its one range and
// default, the options every method takes and the statistics every method returns. RunOptions
// (pipeline.h) extends the same VisibilityOptions and FrameStats the same VisibilityStats, so a
// run's options reach a method, and its statistics come back, as one assignment each.
//
// Every view of CULLIDE, R-CULLIDE and Quick-CULLIDE is a square orthographic view of `pixels` x
// `pixels` (raster/transform.h). Options carry the caller's request as a plain int (0 = the mode's
// default); each entry point (process_frame, cullide_pairs, quick_cullide_pairs) turns it into a
// ViewSize once, through view_size(), and everything below (views, devices, raster) takes the
// ViewSize, so the range is checked in one place against one constant.
#pragma once

#include <cstdint>
#include <vector>

#include "cullide/result.h"
#include "raster/types.h"

namespace cullide {

// The one range of a view's side, in pixels (the raster's depth-target limit).
inline constexpr int kMinViewResolution = 1;
inline constexpr int kMaxViewResolution = raster::kMaxTargetSize;

enum class VisibilityMode : std::uint8_t {
    // The original: pixel-centre sampling, depth at the pixel centre (raster GL-exact mode). Can
    // miss collisions (sampling and depth-precision errors, algorithms.md section 4).
    GLExact,
    // R-CULLIDE, exact bounds (ours): the triangles themselves in the emulator's conservative
    // raster mode (RasterMode::ExactBounds: every pixel a triangle touches, writes at the zmin and
    // queries at the zmax of the triangle over the pixel, rounded outward). Never misses. Runs only
    // on a device that implements that mode (the emulator).
    ExactBounds,
    // R-CULLIDE as the paper builds it: offset solids (raster/offset_geometry.h) drawn with
    // pixel-centre GL rules, so any GL runs it: object boxes and per-triangle boxes grown by
    // r = sqrt(3) p / 2, objects as unions of oriented boxes; queries draw the far faces
    // (CullFace::Front), writes the near ones (CullFace::Back). Never misses.
    Offset,
};

// Default view resolution per mode (pixels per side), measured (docs/cullide.md, "Defaults";
// docs/quick-cullide.md): the exact-bounds methods (rcullide, qcullide) never miss, their cost falls
// with the resolution and the exact stage removes the extra false positives, so they run best low;
// the pixel-centre modes miss less at high resolution.
inline constexpr int kDefaultResolutionExactBounds = 32;
inline constexpr int kDefaultResolutionOthers = 1024;
[[nodiscard]] constexpr int default_resolution(VisibilityMode m) {
    return m == VisibilityMode::ExactBounds ? kDefaultResolutionExactBounds : kDefaultResolutionOthers;
}

// A checked view side: kMinViewResolution <= pixels() <= kMaxViewResolution.
class ViewSize {
   public:
    [[nodiscard]] int pixels() const { return pixels_; }
    [[nodiscard]] int width() const { return pixels_; }
    [[nodiscard]] int height() const { return pixels_; }
    friend bool operator==(ViewSize, ViewSize) = default;

   private:
    friend Result<ViewSize> view_size(int requested, VisibilityMode mode);
    explicit ViewSize(int pixels) : pixels_(pixels) {}
    int pixels_;
};

// `requested` pixels per side, or default_resolution(mode) for 0. Fails outside
// kMinViewResolution..kMaxViewResolution: "resolution must be in 1..16384 (got -1)".
[[nodiscard]] Result<ViewSize> view_size(int requested, VisibilityMode mode);

// The most rounds of x, y, z views per stage a caller may ask for (max_rounds).
inline constexpr int kMaxRounds = 1000;

// The options every visibility method takes (CullideOptions and QuickOptions extend it).
struct VisibilityOptions {
    // View resolution (pixels per side), kMinViewResolution..kMaxViewResolution; 0 = the mode's
    // default_resolution (so choosing another method never silently keeps rcullide's 32 px).
    int resolution = 0;
    raster::DepthFormat depth_format = raster::DepthFormat::D24;
    int subobject_triangles = 4;  // triangles per sub-object, >= 1
    int max_rounds = 4;           // rounds of x, y, z views per stage, 1..kMaxRounds
    int threads = 0;              // workers (exact stage, emulator); 0 = all hardware threads.
                                  // Results do not depend on it.
    // Whose rasterization rules the GL-exact views follow (raster::RasterRules): OpenGL on llvmpipe
    // (clip z in [-1, 1]) or Vulkan as lavapipe (clip z in [0, 1]; the batches are recorded that
    // way, so a Vulkan device runs them as they are). Changes which pixels a view covers, so the
    // GL-exact mode's misses may differ (docs/raster.md); the reliable modes' answers do not depend
    // on it (exact bounds is conservative under both) and the offset mode refuses Vulkan.
    raster::RasterRules gpu_rules = raster::RasterRules::GlLlvmpipe;
};

enum class CullStage : std::uint8_t { Boxes, Objects, SubObjects };
[[nodiscard]] const char* to_string(CullStage s);

// One orthographic view (both passes).
struct ViewStats {
    CullStage stage = CullStage::Boxes;
    int axis = 0;                            // 0 x, 1 y, 2 z: the viewing direction
    std::uint64_t items_before = 0;          // live items (objects or sub-objects) entering the view
    std::uint64_t items_after = 0;           // live items after it
    std::uint64_t queries = 0;               // occlusion queries issued (both passes)
    std::uint64_t triangles_rasterized = 0;  // triangles submitted in draws (queries and writes)
};

// The statistics every visibility method returns (CullideStats, QuickStats and FrameStats extend
// it; each method's header says what its PCS sizes count). Counts are deterministic; times are
// wall-clock milliseconds.
struct VisibilityStats {
    std::uint64_t objects_in = 0;           // objects entering the visibility stages
    std::uint64_t pcs_boxes = 0;            // the PCS after the box stage
    std::uint64_t pcs_objects = 0;          // after the object stage
    std::uint64_t subobjects = 0;           // sub-objects entering the sub-object stage
    std::uint64_t pcs_subobjects = 0;       // left after it
    std::uint64_t candidate_triangles = 0;  // triangles reaching the exact stage
    std::uint64_t exact_tests = 0;          // triangle pairs sent to the exact test (boxes overlap)
    std::uint64_t adjacent_skipped = 0;     // self pairs skipped because they share a (welded) vertex
    std::uint64_t queries = 0;
    std::uint64_t triangles_rasterized = 0;
    std::vector<ViewStats> views;           // in the order they ran
    double boxes_ms = 0, objects_ms = 0, subobjects_ms = 0, exact_ms = 0;
};

}  // namespace cullide
