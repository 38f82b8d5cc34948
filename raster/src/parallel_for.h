// parallel_for.h (private): the raster's one way of running independent pieces of work.
//
// body(i) for i in [0, n), on `threads` workers of a oneTBB arena (serial with one thread, or when
// built without TBB). Callers make every body(i) write only its own slot (a tile, a piece, a band),
// so which worker runs which index never changes a bit of the result.
#pragma once

#include <cstddef>

#if defined(CULLIDE_HAVE_TBB)
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>
#endif

namespace raster::detail {

template <class F>
void run_parallel(int threads, std::size_t n, const F& body) {
#if defined(CULLIDE_HAVE_TBB)
    if (threads > 1 && n > 1) {
        oneapi::tbb::task_arena arena(threads);
        arena.execute([&] {
            oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 1),
                                      [&](const oneapi::tbb::blocked_range<std::size_t>& r) {
                                          for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                                      });
        });
        return;
    }
#else
    (void)threads;
#endif
    for (std::size_t i = 0; i < n; ++i) body(i);
}

}  // namespace raster::detail
