// query_device.cpp: what every QueryDevice can do through clear and execute (execute_cleared and
// the recorded visibility pass).
#include "cullide/query_device.h"

#include <array>
#include <string>
#include <utility>

#include "cullide_detail.h"

namespace cullide {
namespace {

// The recorded passes' draw states: queries GEQUAL with the depth mask off, writes LEQUAL with it
// on, both in the exact-bounds mode.
std::pair<raster::DrawState, raster::DrawState> exact_bounds_states() {
    raster::DrawState query_state;
    query_state.mode = raster::RasterMode::ExactBounds;
    query_state.depth_func = raster::DepthFunc::GEqual;
    query_state.depth_write = false;
    raster::DrawState write_state = query_state;
    write_state.depth_func = raster::DepthFunc::LEqual;
    write_state.depth_write = true;
    return {query_state, write_state};
}

}  // namespace

Result<std::vector<std::uint8_t>> QueryDevice::visibility_pass(ViewSize size, raster::DepthFormat format,
                                                               std::span<const raster::VisibilityItem> items) {
    return recorded_visibility_pass(size, format, items);
}

Result<std::vector<raster::QueryResults>> QueryDevice::execute_cleared(
    int width, int height, raster::DepthFormat format, std::span<const raster::CommandBatch* const> batches) {
    std::vector<raster::QueryResults> results;
    results.reserve(batches.size());
    for (const raster::CommandBatch* batch : batches) {
        if (batch == nullptr) return Error{name() + ": execute_cleared: a batch is null"};
        if (Status s = clear(width, height, format); !s) return s.error();
        Result<raster::QueryResults> r = execute(*batch);
        if (!r) return r.error();
        results.push_back(std::move(r).value());
    }
    return results;
}

Result<std::vector<std::uint8_t>> QueryDevice::recorded_visibility_pass(
    ViewSize size, raster::DepthFormat format, std::span<const raster::VisibilityItem> items) {
    // Each object's items: [begin, end) runs of equal VisibilityItem::object.
    std::vector<std::pair<std::size_t, std::size_t>> objects;
    for (std::size_t b = 0; b < items.size();) {
        std::size_t e = b;
        while (e < items.size() && items[e].object == items[b].object) ++e;
        objects.emplace_back(b, e);
        b = e;
    }
    const std::pair<raster::DrawState, raster::DrawState> states = exact_bounds_states();
    const raster::DrawState& query_state = states.first;
    const raster::DrawState& write_state = states.second;

    // Both passes recorded, then run with execute_cleared (each on a cleared target).
    std::array<raster::CommandBatch, 2> batches = {raster::CommandBatch(size.width(), size.height()),
                                                   raster::CommandBatch(size.width(), size.height())};
    std::array<std::vector<std::uint32_t>, 2> query;
    for (int pass = 0; pass < 2; ++pass) {  // pass 1 forward, pass 2 backward
        raster::CommandBatch& batch = batches[static_cast<std::size_t>(pass)];
        std::vector<std::uint32_t>& q = query[static_cast<std::size_t>(pass)];
        q.resize(items.size());
        for (std::size_t k = 0; k < objects.size(); ++k) {
            const auto [begin, end] = objects[pass == 0 ? k : objects.size() - 1 - k];
            for (std::size_t i = begin; i < end; ++i) {
                q[i] = batch.begin_query(raster::QueryKind::AnySamplesPassed);
                batch.draw(items[i].mesh, query_state);
                batch.end_query();
            }
            if (k + 1 == objects.size()) continue;  // nothing is queried after the last object
            for (std::size_t i = begin; i < end; ++i) batch.draw(items[i].mesh, write_state);
        }
    }
    const raster::CommandBatch* const both[2] = {&batches[0], &batches[1]};
    Result<std::vector<raster::QueryResults>> r = execute_cleared(size.width(), size.height(), format, both);
    if (!r) return r.error();
    if (r.value().size() != 2) return Error{name() + " returned " + std::to_string(r.value().size()) + " passes for 2"};
    std::vector<std::uint8_t> passed(items.size(), 0);
    for (std::size_t pass = 0; pass < 2; ++pass) {
        const raster::QueryResults& res = r.value()[pass];
        if (res.size() != batches[pass].query_kinds().size())
            return Error{name() + " returned " + std::to_string(res.size()) + " query results for " +
                         std::to_string(batches[pass].query_kinds().size()) + " queries"};
        for (std::size_t i = 0; i < items.size(); ++i) passed[i] |= res[query[pass][i]] != 0 ? 1 : 0;
    }
    return passed;
}

Result<std::vector<std::uint8_t>> QueryDevice::quick_view(ViewSize size, raster::DepthFormat format,
                                                          std::span<const raster::WindowedItem> items,
                                                          std::span<const std::uint8_t> tags) {
    return recorded_quick_view(size, format, items, tags);
}

Result<std::vector<std::uint8_t>> QueryDevice::recorded_quick_view(ViewSize size, raster::DepthFormat format,
                                                                   std::span<const raster::WindowedItem> items,
                                                                   std::span<const std::uint8_t> tags) {
    if (tags.size() != items.size())
        return Error{name() + ": quick_view: " + std::to_string(tags.size()) + " tags for " +
                     std::to_string(items.size()) + " items"};
    const std::pair<raster::DrawState, raster::DrawState> states = exact_bounds_states();
    const raster::DrawState& query_state = states.first;
    const raster::DrawState& write_state = states.second;
    std::vector<std::uint8_t> out(tags.begin(), tags.end());
    std::vector<std::uint32_t> query(items.size());
    for (const bool forward : {true, false}) {  // pass 2 reads the tags pass 1 left
        const std::uint8_t proven = forward ? kQuickFFV : kQuickSFV;
        const std::uint8_t other = forward ? kQuickSFV : kQuickFFV;
        raster::CommandBatch batch(size.width(), size.height());
        detail::quick_pass_schedule(
            items.size(), forward, [&](std::size_t k) { return items[k].near_lo; },
            [&](std::size_t k) { return items[k].near_hi; },
            [&](std::size_t k) {
                if (out[k] & proven) return;
                query[k] = batch.begin_query(raster::QueryKind::AnySamplesPassed);
                batch.draw(items[k].mesh, query_state);
                batch.end_query();
            },
            [&](std::size_t d) {
                if (!(out[d] & other)) batch.draw(items[d].mesh, write_state);
            });
        // On a cleared target through execute_cleared, as Quick-CULLIDE's recorded GL passes: the
        // emulator then restores written tiles in their own tile tasks.
        const raster::CommandBatch* const one[1] = {&batch};
        Result<std::vector<raster::QueryResults>> run = execute_cleared(size.width(), size.height(), format, one);
        if (!run) return run.error();
        if (run.value().size() != 1)
            return Error{name() + " returned " + std::to_string(run.value().size()) + " result lists for 1 batch"};
        const raster::QueryResults& r = run.value()[0];
        if (r.size() != batch.query_kinds().size())
            return Error{name() + " returned " + std::to_string(r.size()) + " query results for " +
                         std::to_string(batch.query_kinds().size()) + " queries"};
        for (std::size_t k = 0; k < items.size(); ++k)
            if (!(out[k] & proven) && r[query[k]] == 0) out[k] |= proven;
    }
    return out;
}

}  // namespace cullide
