// cullide/cli/bench.h: `cullide bench` and `cullide sweep`, speed against error.
//
// Both run the cross product scene x scale x method x resolution x depth format x thread count over a
// fixed list of frames and compare every method's pairs with the ground truth (Method::Exact) of the
// same frame. They share one engine (bench.cpp) and differ in defaults and strictness:
//   bench  warm-up runs, timed repetitions, median and spread; a method that never misses
//          (exact, rcullide*, qcullide) whose pairs differ from the ground truth is an error and no time is
//          reported for it (exit 1); methods that may miss (cullide) are reported with their misses.
//   sweep  the grid resolution x depth format for the visibility methods (defaults: the option
//          table, cli/options.cpp; `cullide sweep --help` prints them), one timed run per frame, with PCS sizes per stage, false negatives and false
//          positives; a never-miss method that misses is recorded as MISMATCH and the exit status is 1.
// In both, a method whose repeated runs of one frame give different pairs (nondeterminism) or that
// reports a pair the exact test rejects is an error.
#pragma once

#include <functional>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/pipeline.h"
#include "cullide/result.h"

namespace cullide::cli {

// Runs one frame through one method: process_frame, or a test's stand-in (to check that a wrong
// result is caught).
using FrameRunner = std::function<Result<FrameResult>(std::span<const Mesh>, const RunOptions&)>;

// `cullide bench ...` / `cullide sweep ...` (args[0] is "bench" or "sweep"). Returns the exit status:
// 0 success, 1 a check failed or a run failed, 2 bad usage. `runner` null: process_frame with one
// FrameContext for the whole command.
int bench_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                  const FrameRunner* runner = nullptr);

// FNV-1a (64-bit) over a sorted pair list: each of object_a, triangle_a, object_b, triangle_b as
// 4 little-endian bytes. The digest printed by bench and sweep is this hash folded over the frames'
// digests in frame order (each fed as 8 little-endian bytes).
[[nodiscard]] std::uint64_t pairs_digest(std::span<const TrianglePair> pairs);

// True for the methods that never miss a colliding pair (exact, the R-CULLIDE variants, qcullide).
[[nodiscard]] bool never_misses(Method m);

}  // namespace cullide::cli
