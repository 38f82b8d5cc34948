// cullide/cli/sweep.cpp: the comparison of a method's pairs with the ground truth, which `cullide
// sweep` reports per grid point (algorithms.md section 9). The engine that runs the grid is
// bench.cpp's; the sweep's defaults are in the option table (options.cpp).
#include <algorithm>
#include <iterator>
#include <set>

#include "bench.h"
#include "bench_internal.h"

namespace cullide::cli::bench_detail {

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
