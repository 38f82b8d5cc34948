// recorded_visibility.h: the recorded exact-bounds passes that raster::VisibilityPass and
// raster::WindowedPasses answer without recording, run through raster::execute_reference (or the
// tiled execute): the reference answers of the visibility tests (tests/raster/visibility_test.cpp)
// and of fuzz/raster_visibility_fuzz.cpp. recorded_visibility: CULLIDE's two passes, as
// cullide.cpp records them. Per object in order (pass 2: reverse order), each of its items
// queried (GEQUAL, mask off, any-samples), then each written (LEQUAL, mask on). Per item: 1 if one of
// its two queries passed a sample. An empty optional, and `error` set, when a batch fails to run.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace test {

// The query's and the write's draw states of the recorded exact-bounds passes.
inline raster::DrawState exact_bounds_query_state() {
    raster::DrawState q;
    q.mode = raster::RasterMode::ExactBounds;
    q.depth_func = raster::DepthFunc::GEqual;
    q.depth_write = false;
    return q;
}
inline raster::DrawState exact_bounds_write_state() {
    raster::DrawState d = exact_bounds_query_state();
    d.depth_func = raster::DepthFunc::LEqual;
    d.depth_write = true;
    return d;
}

inline std::optional<std::vector<std::uint8_t>> recorded_visibility(
    const std::vector<raster::Double4>& vertices, const std::vector<std::vector<std::uint32_t>>& item_indices,
    const std::vector<std::uint32_t>& item_object, std::uint32_t objects, int w, int h, raster::DepthFormat f,
    int threads, bool reference, std::string* error = nullptr) {
    std::vector<std::uint8_t> any(item_indices.size(), 0);
    for (int pass = 0; pass < 2; ++pass) {
        raster::CommandBatch batch(w, h);
        std::vector<std::uint32_t> query_item;
        for (std::uint32_t k = 0; k < objects; ++k) {
            const std::uint32_t o = pass == 0 ? k : objects - 1 - k;
            const raster::DrawState q = exact_bounds_query_state(), d = exact_bounds_write_state();
            for (std::size_t i = 0; i < item_indices.size(); ++i) {
                if (item_object[i] != o) continue;
                batch.begin_query(raster::QueryKind::AnySamplesPassed);
                batch.draw(raster::MeshViewD{vertices, item_indices[i]}, q);
                batch.end_query();
                query_item.push_back(static_cast<std::uint32_t>(i));
            }
            for (std::size_t i = 0; i < item_indices.size(); ++i)
                if (item_object[i] == o) batch.draw(raster::MeshViewD{vertices, item_indices[i]}, d);
        }
        auto target = raster::DepthTarget::create(w, h, f);
        if (!target.ok()) {
            if (error != nullptr) *error = target.error().message;
            return std::nullopt;
        }
        auto r = reference ? raster::execute_reference(target.value(), batch, raster::ExecuteOptions{1})
                           : raster::execute(target.value(), batch, raster::ExecuteOptions{threads});
        if (!r.ok()) {
            if (error != nullptr) *error = r.error().message;
            return std::nullopt;
        }
        for (std::size_t q = 0; q < query_item.size(); ++q)
            if (r.value()[q] != 0) any[query_item[q]] = 1;
    }
    return any;
}

// The recorded form of one raster::WindowedPasses pass (raster/visibility.h): forward, for each item
// k in order, query k (if query[k]), then write every item not yet written whose window ends at or
// before k (hi[j] <= k; if write[j]; nothing after the last query); backward mirrored (lo[j] >= k).
// Per item: 1 if it was queried and its query passed a sample. Empty, with `error` set, when the
// batch fails to run.
inline std::optional<std::vector<std::uint8_t>> recorded_windowed(
    const std::vector<raster::Double4>& vertices, const std::vector<std::vector<std::uint32_t>>& item_indices,
    const std::vector<std::uint32_t>& lo, const std::vector<std::uint32_t>& hi, const std::vector<std::uint8_t>& query,
    const std::vector<std::uint8_t>& write, bool forward, int w, int h, raster::DepthFormat f,
    std::string* error = nullptr) {
    const std::size_t n = item_indices.size();
    const raster::DrawState q = exact_bounds_query_state(), d = exact_bounds_write_state();
    raster::CommandBatch batch(w, h);
    std::vector<std::int64_t> slot(n, -1);
    std::size_t cursor = 0;
    for (std::size_t step = 0; step < n; ++step) {
        const std::size_t k = forward ? step : n - 1 - step;
        if (query[k]) {
            slot[k] = batch.begin_query(raster::QueryKind::AnySamplesPassed);
            batch.draw(raster::MeshViewD{vertices, item_indices[k]}, q);
            batch.end_query();
        }
        if (step + 1 == n) break;
        for (; cursor < n; ++cursor) {
            const std::size_t j = forward ? cursor : n - 1 - cursor;
            if (forward ? hi[j] > k : lo[j] < k) break;
            if (write[j]) batch.draw(raster::MeshViewD{vertices, item_indices[j]}, d);
        }
    }
    auto target = raster::DepthTarget::create(w, h, f);
    if (!target.ok()) {
        if (error != nullptr) *error = target.error().message;
        return std::nullopt;
    }
    auto r = raster::execute_reference(target.value(), batch, raster::ExecuteOptions{1});
    if (!r.ok()) {
        if (error != nullptr) *error = r.error().message;
        return std::nullopt;
    }
    std::vector<std::uint8_t> passed(n, 0);
    for (std::size_t k = 0; k < n; ++k)
        if (slot[k] >= 0 && r.value()[static_cast<std::size_t>(slot[k])] != 0) passed[k] = 1;
    return passed;
}

}  // namespace test
