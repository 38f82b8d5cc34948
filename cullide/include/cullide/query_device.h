// cullide/query_device.h: where the visibility passes of CULLIDE / R-CULLIDE run.
//
// The culling algorithm (cullide/cullide.h) only records raster::CommandBatch objects (draws and
// occlusion queries in GL order) and asks a device to run them; it never touches a depth buffer
// itself. So the very same pass sequence runs on the built-in emulator (raster/, the default) and
// on a real GL (the OSMesa device of tests/oracle, for tests and benchmarks only).
//
// Contract of a device, mirroring one GL context with one depth-only framebuffer:
//  - clear(width, height, format) makes a width x height depth target of `format` current and
//    clears it to depth 1.0 (glClearDepth(1); glClear); the target may be reused between calls;
//  - execute(batch) runs every command of the batch in order on the current target and returns
//    the query results indexed like the batch's begin_query() calls (raster/command_batch.h);
//  - execute_cleared(width, height, format, batches) runs each batch on a cleared target, as clear
//    and execute per batch would (a device may share work between the batches);
//  - visibility_pass(size, format, items) answers CULLIDE's two exact-bounds passes of one view
//    (raster/visibility.h). Every device can: the base class records the two passes and runs them
//    with clear and execute (recorded_visibility_pass); the emulator answers them natively with
//    raster::VisibilityPass, the same answers bit for bit at a quarter of the rasterization;
//  - quick_view(size, format, items, tags) answers Quick-CULLIDE's two exact-bounds passes of one
//    view the same way: recorded by the base class, natively by the emulator (raster::WindowedPasses).
// Results must not depend on the thread count (the emulator's are bit-identical for any count).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cullide/result.h"
#include "cullide/visibility.h"
#include "raster/command_batch.h"
#include "raster/types.h"
#include "raster/visibility.h"

namespace cullide {

class QueryDevice {
   public:
    QueryDevice() = default;
    QueryDevice(const QueryDevice&) = delete;
    QueryDevice& operator=(const QueryDevice&) = delete;
    virtual ~QueryDevice() = default;

    // Fails (changing nothing) when the size or format cannot be made, naming the limit.
    [[nodiscard]] virtual Status clear(int width, int height, raster::DepthFormat format) = 0;
    // Fails when no target was cleared yet or when the batch is invalid (the raster message).
    [[nodiscard]] virtual Result<raster::QueryResults> execute(const raster::CommandBatch& batch) = 0;
    // For reports: "emulator", "osmesa (llvmpipe ...)".
    [[nodiscard]] virtual std::string name() const = 0;

    // Each batch on a freshly cleared width x height target of `format`, in order: the results of
    // clear then execute for each batch in turn (the default does exactly that). All batches are
    // recorded before the call, so a device may share work between them: the emulator sets each
    // triangle up once for all of them (raster::execute_sequence), and skips the draws that no query
    // can observe (ExecuteOptions::queries_only: the same results). Only the results are defined:
    // the target's content afterwards is unspecified (clear before the next execute). Fails as clear
    // and execute fail; the emulator validates every batch before running any.
    [[nodiscard]] virtual Result<std::vector<raster::QueryResults>> execute_cleared(
        int width, int height, raster::DepthFormat format, std::span<const raster::CommandBatch* const> batches);

    // For each item, 1 when one of its two recorded queries passes a sample, 0 when it is fully
    // visible with respect to every other object's items (raster/visibility.h), on a target of
    // `size` and `format`. Items are listed in pass-1 order with their objects' items consecutive
    // (VisibilityItem::object non-decreasing). Pass 1 runs the objects forward, pass 2 backward;
    // per object: query each item (exact-bounds, GEQUAL, mask off), then write them (LEQUAL, mask
    // on), except after the pass's last object. Fails as clear and execute fail, or on invalid
    // items (naming the item). The default is recorded_visibility_pass; an override must give
    // the same answers.
    [[nodiscard]] virtual Result<std::vector<std::uint8_t>> visibility_pass(ViewSize size, raster::DepthFormat format,
                                                                            std::span<const raster::VisibilityItem> items);
    // The two passes recorded as command batches and run with clear and execute.
    [[nodiscard]] Result<std::vector<std::uint8_t>> recorded_visibility_pass(
        ViewSize size, raster::DepthFormat format, std::span<const raster::VisibilityItem> items);

    // Quick-CULLIDE's tags (cullide/quick_cullide.h): apart from every earlier item that is not near
    // (FFV), from every later one (SFV).
    static constexpr std::uint8_t kQuickFFV = 1;
    static constexpr std::uint8_t kQuickSFV = 2;
    // Quick-CULLIDE's two exact-bounds passes of one view (raster/visibility.h, WindowedPasses) on a
    // target of `size` and `format`, each on a cleared target: pass 1 forward queries the items
    // whose tag lacks kQuickFFV and writes those lacking kQuickSFV; an item whose query passes no
    // sample gains kQuickFFV; then pass 2 backward queries the items lacking kQuickSFV and writes
    // those lacking kQuickFFV (tags as pass 1 left them); an item whose query passes no sample
    // gains kQuickSFV. Returns the new tags (one per item; `tags` holds the old ones). Fails as
    // clear and execute fail, or on invalid items. The default is recorded_quick_view; an override
    // must give the same tags.
    [[nodiscard]] virtual Result<std::vector<std::uint8_t>> quick_view(ViewSize size, raster::DepthFormat format,
                                                                       std::span<const raster::WindowedItem> items,
                                                                       std::span<const std::uint8_t> tags);
    // The two passes recorded as command batches (quick_pass_schedule order) and run with clear and
    // execute.
    [[nodiscard]] Result<std::vector<std::uint8_t>> recorded_quick_view(ViewSize size, raster::DepthFormat format,
                                                                        std::span<const raster::WindowedItem> items,
                                                                        std::span<const std::uint8_t> tags);
};

// The built-in device: raster::execute on a raster::DepthTarget, on `threads` worker threads
// (0 = all hardware threads; the results do not depend on it).
[[nodiscard]] std::unique_ptr<QueryDevice> make_emulator_device(int threads);

}  // namespace cullide
