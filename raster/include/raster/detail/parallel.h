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

// A testing aid for the rule above, which oneTBB alone cannot check: it may run every item of a
// call on the calling thread (in up to half the calls of some thread suites on a 2-core machine),
// and then a body that reads the wrong thread's state (a thread_local named inside a job is the job
// thread's, not the caller's) or depends on the items' order passes. While the spread schedule is
// on, a parallel_for that would use k = min(workers, n, 4) > 1 threads runs item i on thread i % k
// instead: the caller runs its items in ascending order, k - 1 fresh std::threads each run theirs
// in descending order, all at once, and the call returns after joining them (rethrowing the first
// lane's exception, in lane order). So every item whose index is not a multiple of k runs on a
// thread that never ran one before, in an order unlike the serial one. Process-wide; for tests only
// (each call starts threads). Off unless the environment variable CULLIDE_SPREAD_SCHEDULE is 1 when
// it is first read (CI runs the whole unit suite so once). Without oneTBB (one worker always) it
// has no effect.
void set_spread_schedule(bool on);
[[nodiscard]] bool spread_schedule();

// Turns the spread schedule on for a scope (when `on`) and restores the previous setting when it
// ends.
class SpreadScheduleScope {
   public:
    explicit SpreadScheduleScope(bool on = true) : was_(spread_schedule()) {
        if (on) set_spread_schedule(true);
    }
    ~SpreadScheduleScope() { set_spread_schedule(was_); }
    SpreadScheduleScope(const SpreadScheduleScope&) = delete;
    SpreadScheduleScope& operator=(const SpreadScheduleScope&) = delete;

   private:
    bool was_;
};

// body(i) once for every i in [0, n), possibly concurrently. body must only write state owned by i.
template <class F>
void parallel_for(int threads, std::size_t n, F&& body) {
    using Body = std::remove_reference_t<F>;
    parallel_for_erased(
        threads, n, [](void* ctx, std::size_t i) { (*static_cast<Body*>(ctx))(i); },
        const_cast<void*>(static_cast<const void*>(&body)));
}

}  // namespace raster::detail
