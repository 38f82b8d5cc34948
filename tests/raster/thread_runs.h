// thread_runs.h: the thread settings every raster thread suite runs (threads, SIMD, visibility),
// shared so that each covers oneTBB's schedule and the spread schedule alike.
#pragma once

#include "raster/detail/parallel.h"

namespace raster_test {

// The thread settings of the thread suites: 1, 2, 3 and 8 workers on oneTBB's schedule, then 2 and
// 3 on the spread schedule (raster/detail/parallel.h), where threads of their own must take items,
// in descending order: oneTBB alone often runs a small input's every item on the calling thread.
struct ThreadRun {
    int threads;
    bool spread;
};
inline constexpr ThreadRun kThreadRuns[] = {{1, false}, {2, false}, {3, false},
                                            {8, false}, {2, true},  {3, true}};

}  // namespace raster_test
