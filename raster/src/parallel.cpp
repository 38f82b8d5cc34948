// parallel.cpp: raster::detail::parallel_for on a oneTBB arena, a serial loop without oneTBB
// (raster/detail/parallel.h).
#include "raster/detail/parallel.h"

#include <algorithm>

#if defined(CULLIDE_HAVE_TBB)
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>
#endif

namespace raster::detail {

int effective_threads(int threads) {
#if defined(CULLIDE_HAVE_TBB)
    if (threads > 0) return threads;
    return std::max(1, oneapi::tbb::info::default_concurrency());
#else
    (void)threads;
    return 1;
#endif
}

void parallel_for_erased(int threads, std::size_t n, void (*fn)(void*, std::size_t), void* ctx) {
#if defined(CULLIDE_HAVE_TBB)
    const int workers = effective_threads(threads);
    if (workers > 1 && n > 1) {
        oneapi::tbb::task_arena arena(workers);
        arena.execute([&] {
            oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 1),
                                      [&](const oneapi::tbb::blocked_range<std::size_t>& r) {
                                          for (std::size_t i = r.begin(); i != r.end(); ++i) fn(ctx, i);
                                      });
        });
        return;
    }
#else
    (void)threads;
#endif
    for (std::size_t i = 0; i < n; ++i) fn(ctx, i);
}

}  // namespace raster::detail
