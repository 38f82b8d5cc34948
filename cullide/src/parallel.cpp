#include "parallel.h"

#include <algorithm>
#include <thread>

#if CULLIDE_HAVE_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#endif

namespace cullide::detail {

int effective_threads(int threads) {
#if CULLIDE_HAVE_TBB
    if (threads > 0) return threads;
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
#else
    (void)threads;
    return 1;
#endif
}

void parallel_chunks(int threads, std::size_t chunks, const std::function<void(std::size_t)>& fn) {
    const int workers = effective_threads(threads);
    if (workers <= 1 || chunks <= 1) {
        for (std::size_t c = 0; c < chunks; ++c) fn(c);
        return;
    }
#if CULLIDE_HAVE_TBB
    tbb::task_arena arena(workers);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t c = r.begin(); c != r.end(); ++c) fn(c);
        });
    });
#endif
}

}  // namespace cullide::detail
