// parallel.cpp: raster::detail::parallel_for on a oneTBB arena, a serial loop without oneTBB
// (raster/detail/parallel.h).
#include "raster/detail/parallel.h"

#include <algorithm>

#if defined(CULLIDE_HAVE_TBB)
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <map>
#include <memory>
#include <mutex>
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

#if defined(CULLIDE_HAVE_TBB)
namespace {

// One arena per worker count, made on first use and kept for the process (never destroyed: oneTBB may
// be torn down before static destructors run). An arena made per call looked right but its worker
// hardly ever joined: with oneTBB 2021.8 on the 2-core machine, 100 calls of 64 items took 32 items on
// the worker and 6368 on the caller, even with 300 ms of work per call; the first arena got the worker
// and the later ones did not. A kept arena shares the items (3062 / 3338 with 30 ms per call, loaded).
oneapi::tbb::task_arena& arena_of(int workers) {
    static std::mutex mutex;
    static auto* arenas = new std::map<int, std::unique_ptr<oneapi::tbb::task_arena>>();
    const std::lock_guard lock(mutex);
    std::unique_ptr<oneapi::tbb::task_arena>& a = (*arenas)[workers];
    if (!a) a = std::make_unique<oneapi::tbb::task_arena>(workers);
    return *a;
}

}  // namespace
#endif

void parallel_for_erased(int threads, std::size_t n, void (*fn)(void*, std::size_t), void* ctx) {
#if defined(CULLIDE_HAVE_TBB)
    const int workers = effective_threads(threads);
    if (workers > 1 && n > 1) {
        arena_of(workers).execute([&] {
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
