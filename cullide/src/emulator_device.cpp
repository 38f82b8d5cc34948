// emulator_device.cpp: the built-in QueryDevice (emulator_device.h).
#include "emulator_device.h"

#include <cstdint>

#include "parallel.h"
#include "raster/command_batch.h"
#include "raster/visibility.h"

namespace cullide {
namespace detail {

EmulatorDevice::EmulatorDevice(int threads) : threads_(effective_threads(threads)) {}

void EmulatorDevice::set_threads(int threads) { threads_ = effective_threads(threads); }

Result<bool> EmulatorDevice::ensure_target(int width, int height, raster::DepthFormat format) {
    if (target_ && target_->width() == width && target_->height() == height && target_->format() == format)
        return false;
    raster::Result<raster::DepthTarget> t = raster::DepthTarget::create(width, height, format);
    if (!t) return Error{"emulator device: " + t.error().message};
    target_.emplace(std::move(t).value());  // cleared to 1.0
    return true;
}

Status EmulatorDevice::clear(int width, int height, raster::DepthFormat format) {
    Result<bool> created = ensure_target(width, height, format);
    if (!created) return created.error();
    if (created.value()) return Status{};
    // Only the 8 x 8 blocks where a writing draw of raster::execute passed the depth test can
    // differ from depth 1.0 (the target's record, DepthTarget's fast clear): an empty batch with
    // clear_depth restores exactly those, each tile's in its own task, which gives the same buffer
    // as a full clear.
    raster::ExecuteOptions options = execute_options();
    options.clear_depth = 1.0;
    raster::Result<raster::QueryResults> r = raster::execute(*target_, raster::CommandBatch(width, height), options);
    if (!r) return Error{"emulator device: " + r.error().message};
    return Status{};
}

raster::ExecuteOptions EmulatorDevice::execute_options() const {
    raster::ExecuteOptions eo;
    eo.threads = threads_;
    return eo;
}

Result<std::vector<raster::QueryResults>> EmulatorDevice::execute_cleared(
    int width, int height, raster::DepthFormat format, std::span<const raster::CommandBatch* const> batches) {
    if (Result<bool> created = ensure_target(width, height, format); !created) return created.error();
    // Each batch on a cleared target, as clear() before it, but each written block is restored by
    // its tile's own task before it draws there (ExecuteOptions::clear_depth): in parallel with the
    // other tiles' work and while the tile is in that core's cache, without a pass of its own.
    raster::ExecuteOptions options = execute_options();
    options.clear_depth = 1.0;
    // Only the results are wanted (query_device.h): draws that no query observes are skipped.
    options.queries_only = true;
    raster::Result<std::vector<raster::QueryResults>> r = raster::execute_sequence(*target_, batches, options);
    if (!r) return Error{"emulator device: " + r.error().message};
    return std::move(r).value();
}

Result<raster::QueryResults> EmulatorDevice::execute(const raster::CommandBatch& batch) {
    if (!target_) return Error{"emulator device: execute before clear (no depth target yet)"};
    raster::Result<raster::QueryResults> r = raster::execute(*target_, batch, execute_options());
    // A failed batch was rejected before anything was drawn (raster/raster.h).
    if (!r) return Error{"emulator device: " + r.error().message};
    return std::move(r).value();
}

// Both passes in one rasterization per item (raster/visibility.h), bit-identical to the recorded
// passes (tests/cullide/fused_visibility_test.cpp).
Result<std::vector<std::uint8_t>> EmulatorDevice::visibility_pass(ViewSize size, raster::DepthFormat format,
                                                                  std::span<const raster::VisibilityItem> items) {
    // One per calling thread, shared by every device and frame: a device made per frame (process_frame
    // without a FrameContext) would otherwise fault its buffers in afresh each frame. It keeps no
    // answer from one call to the next, so results cannot depend on what ran before.
    thread_local raster::VisibilityPass pass;
    raster::Result<std::vector<std::uint8_t>> r = pass.run(size.width(), size.height(), format, items, threads_);
    if (!r) return Error{"emulator device: " + r.error().message};
    return std::move(r).value();
}

// Quick-CULLIDE's two passes with each item rasterized once (raster/visibility.h), the same tags as
// the recorded passes (tests/cullide/quick_cullide_test.cpp compares the two).
Result<std::vector<std::uint8_t>> EmulatorDevice::quick_view(ViewSize size, raster::DepthFormat format,
                                                             std::span<const raster::WindowedItem> items,
                                                             std::span<const std::uint8_t> tags) {
    if (static_cast<std::int64_t>(size.width()) * size.height() > raster::WindowedPasses::kMaxWindowedPixels)
        return recorded_quick_view(size, format, items, tags);
    if (tags.size() != items.size())
        return Error{"emulator device: quick_view: " + std::to_string(tags.size()) + " tags for " +
                     std::to_string(items.size()) + " items"};
    // Items proven apart both ways (BFV) are neither queried nor written by either pass (pass 1 adds
    // only FFV, so pass 2 queries the same items and writes a subset of pass 1's). The items go to
    // prepare as given when their `used` already says so (Quick-CULLIDE's native view sets it: a
    // copy of every item per view was 3% of a 2-thread bunny-dragon frame), else as a copy.
    const auto used = [&](std::size_t k) { return (tags[k] & (kQuickFFV | kQuickSFV)) != (kQuickFFV | kQuickSFV); };
    bool as_given = true;
    for (std::size_t k = 0; k < items.size() && as_given; ++k) as_given = items[k].used == used(k);
    std::vector<raster::WindowedItem> copied;
    if (!as_given) {
        copied.assign(items.begin(), items.end());
        for (std::size_t k = 0; k < items.size(); ++k) copied[k].used = used(k);
    }
    const std::span<const raster::WindowedItem> prepared_items = as_given ? items : std::span<const raster::WindowedItem>(copied);
    thread_local raster::WindowedPasses passes;  // buffers kept, no answer kept (as visibility_pass)
    raster::Result<std::size_t> prepared = passes.prepare(size.width(), size.height(), format, prepared_items, threads_);
    if (!prepared) return Error{"emulator device: " + prepared.error().message};
    std::vector<std::uint8_t> out(tags.begin(), tags.end());
    std::vector<std::uint8_t> query(items.size()), write(items.size());
    for (const bool forward : {true, false}) {  // pass 2 reads the tags pass 1 left
        const std::uint8_t proven = forward ? kQuickFFV : kQuickSFV;
        const std::uint8_t other = forward ? kQuickSFV : kQuickFFV;
        for (std::size_t k = 0; k < items.size(); ++k) {
            query[k] = (out[k] & proven) ? 0 : 1;
            write[k] = (out[k] & other) ? 0 : 1;
        }
        raster::Result<std::vector<std::uint8_t>> passed = passes.run(forward, query, write);
        if (!passed) return Error{"emulator device: " + passed.error().message};
        for (std::size_t k = 0; k < items.size(); ++k)
            if (query[k] && !passed.value()[k]) out[k] |= proven;
    }
    return out;
}

}  // namespace detail

std::unique_ptr<QueryDevice> make_emulator_device(int threads) {
    return std::make_unique<detail::EmulatorDevice>(threads);
}

}  // namespace cullide
