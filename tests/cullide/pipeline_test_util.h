// Helpers shared by the pipeline test programs (cullide_pipeline_test, cullide_slow_test): the
// ground truth of a frame, one frame through a method, and the miss count of a method's pairs.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"

namespace test {

inline std::vector<cullide::TrianglePair> truth(const std::vector<cullide::Mesh>& objects) {
    auto r = cullide::exact_pairs(objects);
    REQUIRE(r.ok());
    return r.value();
}

inline cullide::FrameResult run(const std::vector<cullide::Mesh>& objects, cullide::Method m, int resolution,
                                int threads = 2, cullide::BroadPhase bp = cullide::BroadPhase::None,
                                bool self = false) {
    cullide::RunOptions o;
    o.method = m;
    o.resolution = resolution;
    o.threads = threads;
    o.broadphase = bp;
    o.self = self;
    auto r = cullide::process_frame(objects, o);
    if (!r) FAIL(r.error().message);
    return r.value();
}

// Exact pairs a method's result lacks; its pairs must be a subset of the truth (no false pair).
inline std::size_t misses(const std::vector<cullide::TrianglePair>& found,
                          const std::vector<cullide::TrianglePair>& exact) {
    CHECK(std::includes(exact.begin(), exact.end(), found.begin(), found.end()));
    return exact.size() - found.size();
}

}  // namespace test
