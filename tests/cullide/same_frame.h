// same_frame.h: the check that a frame run on an oracle device (OSMesa, lavapipe) matches the same
// frame on the emulator: the pairs, the query and rasterized-triangle counts, the PCS sizes, and the
// items left after every view. Shared by cullide_osmesa_test.cpp and cullide_vulkan_test.cpp.
#pragma once

#include <doctest/doctest.h>

#include <cstddef>

#include "cullide/pipeline.h"

namespace cullide_test {

inline void check_same_frame(const cullide::FrameResult& oracle, const cullide::FrameResult& emu) {
    CHECK(oracle.pairs == emu.pairs);
    CHECK(oracle.stats.queries == emu.stats.queries);
    CHECK(oracle.stats.triangles_rasterized == emu.stats.triangles_rasterized);
    CHECK(oracle.stats.pcs_boxes == emu.stats.pcs_boxes);
    CHECK(oracle.stats.pcs_objects == emu.stats.pcs_objects);
    CHECK(oracle.stats.pcs_subobjects == emu.stats.pcs_subobjects);
    REQUIRE(oracle.stats.views.size() == emu.stats.views.size());
    for (std::size_t v = 0; v < oracle.stats.views.size(); ++v) {
        CAPTURE(v);
        CHECK(oracle.stats.views[v].items_after == emu.stats.views[v].items_after);
    }
}

}  // namespace cullide_test
