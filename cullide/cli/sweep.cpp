// cullide/cli/sweep.cpp: `cullide sweep`, the grid resolution x depth format x method x scene, and
// the comparison of a method's pairs with the ground truth (algorithms.md section 9). The engine that
// runs the grid is bench.cpp's.
#include <algorithm>
#include <iterator>
#include <set>

#include "bench.h"
#include "bench_internal.h"

namespace cullide::cli::bench_detail {

const char* const kSweepUsage =
    "usage: cullide sweep [options]\n"
    "\n"
    "Runs every combination scene x scale x method x resolution x depth format x threads over the\n"
    "same frames and reports, per combination: time per frame, PCS size per stage, false negatives\n"
    "(true colliding triangle pairs not reported) and false positives (candidate triangle pairs sent\n"
    "to the exact test that do not collide) against the ground truth. A method that never misses\n"
    "(exact, rcullide, rcullide-offset, qcullide) but misses is marked MISMATCH and the exit status\n"
    "is 1.\n"
    "Defaults: --methods cullide,rcullide,rcullide-offset --resolutions 32,64,128,256,512,1024\n"
    "--depth-formats d24 --frames 2 --warmup 0 --reps 1. The options are those of 'cullide bench'\n"
    "(cullide bench --help); a progress bar goes to stderr when it is a terminal.\n";

void apply_sweep_defaults(BenchArgs& a) {
    if (a.methods.empty()) a.methods = {Method::Cullide, Method::RCullide, Method::RCullideOffset};
    if (a.resolutions.empty()) a.resolutions = {32, 64, 128, 256, 512, 1024};
    if (a.frames == 0) a.frames = 2;
    if (a.reps == 0) a.reps = 1;
    if (a.warmup < 0) a.warmup = 0;
}

Comparison compare_with_truth(std::span<const TrianglePair> truth, std::span<const TrianglePair> got) {
    Comparison c;
    std::vector<TrianglePair> missing, extra;
    std::set_difference(truth.begin(), truth.end(), got.begin(), got.end(), std::back_inserter(missing));
    std::set_difference(got.begin(), got.end(), truth.begin(), truth.end(), std::back_inserter(extra));
    c.false_negatives = missing.size();
    c.extra_pairs = extra.size();
    const std::vector<ObjectPair> t = object_pairs(truth), g = object_pairs(got);
    std::vector<ObjectPair> missed;
    std::set_difference(t.begin(), t.end(), g.begin(), g.end(), std::back_inserter(missed));
    c.missed_object_pairs = missed.size();
    std::set<std::uint32_t> objs;
    for (const ObjectPair& p : t) {
        objs.insert(p.a);
        objs.insert(p.b);
    }
    c.true_objects = objs.size();
    return c;
}

}  // namespace cullide::cli::bench_detail
