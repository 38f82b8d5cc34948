// The executor: oneTBB when available, a serial loop otherwise (embedded builds).
#include "spatialhash/detail/executor.h"

#include <algorithm>

#if defined(CULLIDE_HAVE_TBB)
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#endif

namespace spatialhash::detail {

struct Executor::Impl {
#if defined(CULLIDE_HAVE_TBB)
    explicit Impl(int threads) : arena(threads) {}
    tbb::task_arena arena;
#endif
};

Executor::Executor(unsigned threads) {
#if defined(CULLIDE_HAVE_TBB)
    unsigned all = static_cast<unsigned>(tbb::info::default_concurrency());
    if (all == 0) all = 1;
    // More threads than the process allows would only make TBB print a warning and ignore them.
    const auto allowed = static_cast<unsigned>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    concurrency_ = threads == 0 ? all : std::min(threads, std::max(allowed, 1U));
    if (concurrency_ > 1) impl_ = std::make_unique<Impl>(static_cast<int>(concurrency_));
#else
    (void)threads;
    concurrency_ = 1;
#endif
}

Executor::~Executor() = default;

void Executor::run(std::size_t count, void (*fn)(void*, std::size_t), void* ctx) {
#if defined(CULLIDE_HAVE_TBB)
    if (impl_ && count > 1) {
        impl_->arena.execute([&] {
            // grainsize 1: items are already chunks of kChunk elements.
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i) fn(ctx, i);
                              });
        });
        return;
    }
#endif
    for (std::size_t i = 0; i < count; ++i) fn(ctx, i);
}

}  // namespace spatialhash::detail
