// scene_gen.h: random command batches for the raster tests (shared by the conformance, unit and
// threading tests). splitmix64 only: no std distributions, so the same seed gives the same scene
// with every standard library.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "raster/raster.h"

namespace raster_test {

struct SplitMix64 {
    std::uint64_t s;
    explicit SplitMix64(std::uint64_t seed) : s(seed) {}
    std::uint64_t next() {
        std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    // [0, n)
    std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>((next() >> 32) % n); }
    // [lo, hi) in float, from 24 random bits (exact).
    float uniform(float lo, float hi) {
        const float u = static_cast<float>(next() >> 40) * (1.0f / 16777216.0f);
        return lo + (hi - lo) * u;
    }
    bool chance(std::uint32_t percent) { return below(100) < percent; }
};

// Owns the meshes a batch views (deque: stable addresses).
struct Scene {
    std::deque<std::vector<raster::Float4>> vertices;
    std::deque<std::vector<std::uint32_t>> indices;
    raster::CommandBatch batch{1, 1};
    double clear_depth = 1.0;
    std::size_t query_count = 0;
};

struct SceneOptions {
    int width = 64;
    int height = 64;
    int objects = 100;        // query + draw pairs (plus some plain draws)
    bool allow_cull = true;
    bool allow_viewport = true;
    // The batch's rules; Vulkan maps every generated clip z to (z + w) / 2, so the scenes cross
    // Vulkan's near plane z = 0 as often as GL's z = -w.
    raster::RasterRules rules = raster::RasterRules::GlLlvmpipe;
};

// A random vertex: one of several flavours that stress the rules (pixel centres, 1/256 grid,
// off-screen, near/far crossing, perspective w).
raster::Float4 random_vertex(SplitMix64& rng, int width, int height, int flavour);

// Builds a random scene: per object a query (random function, mask usually off) over a small mesh,
// then usually a draw of it (mask on), mixed with occluder draws; equal-depth repeats for ties.
void build_scene(Scene& scene, SplitMix64& rng, const SceneOptions& options);

}  // namespace raster_test
