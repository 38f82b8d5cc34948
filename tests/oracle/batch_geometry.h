// batch_geometry.h: one vertex and one index buffer for a whole raster::CommandBatch, as the oracle
// devices (gl_batch_runner.cpp, vulkan_device.cpp) upload it: each draw is a range of indices at a
// base vertex, and draws over the same vertex span (CULLIDE's sub-object draws all index their
// object's vertices) share one copy: copying the span per draw made batches of a large object
// gigabytes (GL_OUT_OF_MEMORY). Tests and benchmarks only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "raster/raster.h"

namespace cullide_oracle {

struct BatchGeometry {
    struct Range {
        std::size_t first_index, count, base_vertex;
    };
    std::vector<raster::Float4> vertices;
    std::vector<std::uint32_t> indices;
    std::vector<Range> draws;  // one per draw command, in command order

    explicit BatchGeometry(const raster::CommandBatch& batch) {
        std::map<std::pair<const raster::Float4*, std::size_t>, std::size_t> span_base;
        for (const auto& c : batch.commands()) {
            if (c.kind != raster::Command::Kind::Draw) continue;
            const auto key = std::make_pair(c.mesh.vertices.data(), c.mesh.vertices.size());
            auto [it, fresh] = span_base.try_emplace(key, vertices.size());
            if (fresh) vertices.insert(vertices.end(), c.mesh.vertices.begin(), c.mesh.vertices.end());
            draws.push_back({indices.size(), c.mesh.indices.size(), it->second});
            indices.insert(indices.end(), c.mesh.indices.begin(), c.mesh.indices.end());
        }
    }
};

}  // namespace cullide_oracle
