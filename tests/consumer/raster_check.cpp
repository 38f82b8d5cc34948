// A downstream program using cullide::raster and cullide::spatialhash alone, against the installed
// headers and libraries. Exit status 0 only when every answer is the one worked out by hand.
#include <cstdint>
#include <cstdio>
#include <vector>

#include "raster/command_batch.h"
#include "raster/depth_target.h"
#include "spatialhash/broad_phase.h"

namespace {

int fail(const char* what) { return std::fprintf(stderr, "raster_check: %s\n", what), 1; }

}  // namespace

int main() {
    // A full-screen quad at z = 0 (window depth 0.5) drawn on a 32 x 32 target; then the same quad
    // farther away (z = 0.5) queried with LESS: no sample passes. Nearer (z = -0.5): all 1024 pass.
    auto target = raster::DepthTarget::create(32, 32, raster::DepthFormat::D24);
    if (!target) return fail(target.error().message.c_str());
    const std::vector<std::uint32_t> quad = {0, 1, 2, 0, 2, 3};
    auto corners = [](float z) {
        return std::vector<raster::Float4>{{-1, -1, z, 1}, {1, -1, z, 1}, {1, 1, z, 1}, {-1, 1, z, 1}};
    };
    const auto mid = corners(0.0f), far = corners(0.5f), near = corners(-0.5f);
    raster::CommandBatch batch(32, 32);
    batch.draw({mid, quad}, raster::DrawState{});
    raster::DrawState query_state;
    query_state.depth_write = false;
    for (const auto* v : {&far, &near}) {
        batch.begin_query(raster::QueryKind::SamplesPassed);
        batch.draw({*v, quad}, query_state);
        batch.end_query();
    }
    auto counts = raster::execute(target.value(), batch);
    if (!counts) return fail(counts.error().message.c_str());
    if (counts.value() != raster::QueryResults{0, 1024}) return fail("unexpected samples-passed counts");

    // Three boxes: 0 touches 1 (closed boxes), 2 is apart. Grid and brute force agree on {(0, 1)}.
    const std::vector<spatialhash::Box> boxes = {
        {{0, 0, 0}, {1, 1, 1}}, {{1, 0, 0}, {2, 1, 1}}, {{5, 5, 5}, {6, 6, 6}}};
    for (const auto method : {spatialhash::Method::SpatialHash, spatialhash::Method::BruteForce}) {
        spatialhash::Options o;
        o.method = method;
        auto pairs = spatialhash::find_pairs(std::span<const spatialhash::Box>(boxes), o);
        if (!pairs) return fail(pairs.error().message.c_str());
        if (pairs.value().pairs != std::vector<spatialhash::Pair>{{0, 1}}) return fail("unexpected box pairs");
    }
    std::printf("raster_check: queries 0 and 1024, box pairs {(0, 1)}: as expected\n");
    return 0;
}
