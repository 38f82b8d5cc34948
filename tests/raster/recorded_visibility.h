// recorded_visibility.h: the two recorded exact-bounds passes that raster::VisibilityPass fuses, as
// cullide.cpp records them, run through raster::execute_reference (or the tiled execute): the
// reference answer of the visibility tests (tests/raster/visibility_test.cpp) and of
// fuzz/raster_visibility_fuzz.cpp. Per object in order (pass 2: reverse order), each of its items
// queried (GEQUAL, mask off, any-samples), then each written (LEQUAL, mask on). Per item: 1 if one of
// its two queries passed a sample. An empty optional, and `error` set, when a batch fails to run.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace test {

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
            raster::DrawState q;
            q.mode = raster::RasterMode::ExactBounds;
            q.depth_func = raster::DepthFunc::GEqual;
            q.depth_write = false;
            raster::DrawState d = q;
            d.depth_func = raster::DepthFunc::LEqual;
            d.depth_write = true;
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

}  // namespace test
