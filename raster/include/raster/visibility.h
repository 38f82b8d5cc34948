// raster/visibility.h: CULLIDE's two visibility passes (Lemma 2) in the exact-bounds mode, fused
// into one emulator-native pass (docs/reliable-raster.md, "The fused visibility pass").
//
// The recorded form (cullide/cullide.h): clear depth to 1; for each object in order, query each of
// its items (exact-bounds, GEQUAL against the item's zmax, mask off, any-samples), then write them
// all (exact-bounds, LEQUAL with the zmin, mask on); a second pass does the same in reverse object
// order. An item is fully visible iff neither of its two queries passes a sample.
//
// Fused: the stored depth that a query of object k's item meets at pixel p in pass 1 is
// min(clear, zmin of every item of objects before k covering p), in pass 2 the same over the
// objects after k (LEQUAL writes keep the minimum; an object's own writes come after its queries).
// The item passes a query iff some covered pixel has zmax >= that value, so it passes one of the two
// iff some covered pixel has zmax >= min(clear, zmin of every item of every OTHER object) (the OR of
// the two passes, pixel by pixel, since min(A, B) <= z iff A <= z or B <= z). One rasterization per
// item gives both of its encoded depths per pixel (the very per-pixel values the recorded draws
// would compute: the same setup, traversal and outward quantization); per pixel the pass keeps the
// smallest zmin with its object and the smallest zmin of any other object, which is all the test
// needs. So the answer equals the two-pass answer bit for bit, for any order of the objects, at a
// quarter of the rasterization (one draw per item instead of four) and without the depth target.
//
// Tiled (64 x 64; 16 or 32 on targets up to 128 or 256 pixels, to keep several tasks) and
// threaded like raster::execute; every tile is computed by one task in a fixed
// order and the per-item answers are ORs, so the result does not depend on the thread count. Where
// the triangles are large (boxes of 16 pixels or more on average) the tiles are 16 x 16 and
// per-triangle depth bounds settle a tile without visiting its pixels where no query can pass
// there; items already found are not tested again (the same answer, less work:
// docs/reliable-raster.md, "Tiles settled without per-pixel work").
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "raster/result.h"
#include "raster/types.h"

namespace raster {

// One PCS item: its triangles (double clip space, the exact-bounds input rules of
// CommandBatch::draw(MeshViewD, ...): finite, w = 1, |x|, |y|, |z| <= kMaxExactBoundsCoordinate)
// and the object it belongs to (items of one object never hide each other).
struct VisibilityItem {
    MeshViewD mesh;
    std::uint32_t object = 0;
};

// What the settling pre-pass of one VisibilityPass::run() did.
struct PresettleStats {
    bool ran = false;
    std::uint64_t items_hit = 0;      // certainly not fully visible
    std::uint64_t items_hit_by_face = 0;  // of those, shown by a flat triangle's inner pixel, not a vertex
    std::uint64_t items_not_hit = 0;  // certainly fully visible
    std::uint64_t items_open = 0;     // answered by the pass
    std::uint64_t triangles_left_out = 0;  // neither set up nor drawn
};

// Reusable state (buffers kept between calls, so a pipeline allocates only while they grow).
class VisibilityPass {
   public:
    VisibilityPass();
    ~VisibilityPass();
    VisibilityPass(const VisibilityPass&) = delete;
    VisibilityPass& operator=(const VisibilityPass&) = delete;

    // For each item, 1 when it is NOT fully visible (one of its two recorded queries would pass a
    // sample), 0 when it is fully visible with respect to every other object's items, on a
    // width x height target of `format` cleared to 1, in the exact-bounds mode (full viewport). Fails,
    // naming the item, triangle position and vertex, on invalid input (nothing is computed then).
    // threads: workers, 0 = all hardware threads, negative = an error; the answer never depends on it.
    [[nodiscard]] Result<std::vector<std::uint8_t>> run(int width, int height, DepthFormat format,
                                                        std::span<const VisibilityItem> items, int threads);

    // The triangles of the last successful run() that were neither set up nor drawn: those of items
    // alone in the view (no other object's triangle reaches a pixel near theirs, and none reaches
    // the far plane), whose answer is 0 without drawing (visibility.cpp, State::alone). Work only:
    // the answers are the same whether or not an item is found alone. The pre-pass that finds them
    // runs while it pays (its last run on calls of this shape, object, item and triangle counts,
    // spared 30% or more of their triangles), and now and then otherwise; 0 when it did not run.
    [[nodiscard]] std::uint64_t last_spared_triangles() const;

    // The settling pre-pass (on by default; visibility.cpp, State::presettle; docs/reliable-raster.md,
    // "Items settled before drawing"): on targets of one tile (up to 128 pixels a side) the items
    // whose answer bounds from the vertices alone already decide take it without drawing, and only
    // the items that can change an open item's answer are set up and drawn. Work only: the answers
    // are the same with it on or off (off: for tests and measurements). It runs while it pays (it
    // left out 75% of a call's triangles or more the last time a call of this shape ran it), and now
    // and then otherwise. last_presettle(): what it did in the last run() (ran = false when it did
    // not run, or did not apply: larger targets, large triangles, input that fails a check).
    void set_presettle(bool on);
    [[nodiscard]] PresettleStats last_presettle() const;

   private:
    struct State;
    std::unique_ptr<State> s_;
};

// Quick-CULLIDE's passes (Govindaraju, Knott, Lin, Manocha 2005; cullide/quick_cullide.h) in the
// exact-bounds mode, each item rasterized once per view instead of up to four times.
//
// The recorded form: on a target cleared to 1, a forward pass runs k = 0 .. n-1: the query of item k
// (exact bounds, GEQUAL against its zmax, mask off, any samples), then the writes (exact bounds,
// LEQUAL with the zmin, mask on) of every item d whose window [near_lo, near_hi] ends at or before
// k and that has not been written yet; nothing is written after the last query. The backward pass
// runs k = n-1 .. 0 the same way with the windows' starts. So the stored depth that the query of
// item k meets at pixel p is min(clear, zmin at p of every written item d with near_hi[d] < k)
// forward, near_lo[d] > k backward (LEQUAL writes keep the minimum), and the query passes iff
// some covered pixel has zmax >= that value.
//
// Native: prepare() sets every item's triangles up and keeps, per item and covered pixel, the
// smallest zmin and the largest zmax of its fragments (the very per-pixel values the recorded draws
// compute: the same setup, traversal and outward quantization), on any number of threads; run()
// then replays one pass over those values on one depth array: the same stored depth before every
// query, so the same answers bit for bit, for any thread count.
struct WindowedItem {
    MeshViewD mesh;
    // The items this one is never tested against (in the recorded form: its writes wait until the
    // query of item near_hi forward, and of item near_lo backward). Both non-decreasing over the
    // items, near_lo <= near_hi < the item count.
    std::uint32_t near_lo = 0, near_hi = 0;
    // false: no pass run on this preparation queries or writes the item, so it is not rasterized
    // (Quick-CULLIDE's items proven apart both ways); run() refuses masks that use it.
    bool used = true;
};

class WindowedPasses {
   public:
    WindowedPasses();
    ~WindowedPasses();
    WindowedPasses(const WindowedPasses&) = delete;
    WindowedPasses& operator=(const WindowedPasses&) = delete;

    // Rasterizes every item once on a width x height target of `format` (exact bounds, full
    // viewport). The per-pixel record needs width * height <= kMaxWindowedPixels. Fails, naming the
    // item, position and vertex or window, on invalid input; run() then answers nothing.
    // threads: workers, 0 = all hardware threads, negative = an error; nothing depends on it.
    [[nodiscard]] Result<std::size_t> prepare(int width, int height, DepthFormat format,
                                              std::span<const WindowedItem> items, int threads);
    // One pass over the prepared items (forward or backward, as above): item k is queried iff
    // query[k] != 0 and written iff write[k] != 0. Returns per item 1 when it was queried and its
    // query passed a sample, else 0. Fails when prepare() did not succeed or a mask's size is not
    // the item count, or a mask uses an item prepared as unused.
    [[nodiscard]] Result<std::vector<std::uint8_t>> run(bool forward, std::span<const std::uint8_t> query,
                                                        std::span<const std::uint8_t> write) const;

    static constexpr std::int64_t kMaxWindowedPixels = std::int64_t{512} * 512;

   private:
    struct State;
    std::unique_ptr<State> s_;
};

}  // namespace raster
