// raster/detail/parallel.h: the parallel-for of raster and of cullide (which links raster); not
// part of the raster API proper. spatialhash keeps its own executor (it must not depend on raster):
// docs/architecture.md, "Threading".
//
// The caller owns threading (after Box2D): every parallel entry point takes a thread count, with
// one rule everywhere: `threads` > 0 workers as given, 0 = all hardware threads. The caller cuts its
// work into items whose boundaries depend on the input only and makes each body(i) write only its
// own slot, so which worker runs which item never changes a bit of the result. With oneTBB the
// items run in a task_arena of that size (grain 1: items are already chunks); without it (the
// embedded build) serially, in order. No TBB type appears here.
#pragma once

#include <cstddef>
#include <type_traits>

namespace raster::detail {

// The workers a thread count asks for: threads > 0 as given, 0 = all hardware threads (oneTBB's
// default concurrency: the CPUs this process may run on). Always 1 in builds without oneTBB.
// (Negative counts are the caller's error to report; they are treated as 0 here.)
[[nodiscard]] int effective_threads(int threads);

// Runs fn(ctx, i) for every i in [0, n) on effective_threads(threads) workers and returns when all
// are done; serially in the calling thread when that is 1 or n <= 1.
void parallel_for_erased(int threads, std::size_t n, void (*fn)(void*, std::size_t), void* ctx);

// body(i) once for every i in [0, n), possibly concurrently. body must only write state owned by i.
template <class F>
void parallel_for(int threads, std::size_t n, F&& body) {
    using Body = std::remove_reference_t<F>;
    parallel_for_erased(
        threads, n, [](void* ctx, std::size_t i) { (*static_cast<Body*>(ctx))(i); },
        const_cast<void*>(static_cast<const void*>(&body)));
}

}  // namespace raster::detail
