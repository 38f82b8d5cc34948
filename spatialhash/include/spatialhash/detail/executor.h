// spatialhash/detail/executor.h: the one place where work is spread over threads.
//
// Callers cut their work into a fixed number of items that does not depend on the thread count
// (chunks of kChunk elements) and merge per-item results in item order, so every output is
// identical for any thread count. With oneTBB (CULLIDE_HAVE_TBB) items run in a
// tbb::task_arena of the requested size; without it they run serially in order. No TBB type
// appears here. Thread counts follow the project's one rule (0 = all hardware threads); raster has
// the same primitive for raster and cullide (raster/detail/parallel.h), but spatialhash must not
// depend on raster, and this executor keeps its arena in the caller's Workspace between frames
// (docs/architecture.md, "Threading").
#pragma once

#include <cstddef>
#include <memory>
#include <type_traits>

namespace spatialhash::detail {

// Elements per work item. Fixed, so that chunk boundaries never depend on the thread count.
inline constexpr std::size_t kChunk = std::size_t{1} << 14;

[[nodiscard]] constexpr std::size_t chunk_count(std::size_t n, std::size_t chunk = kChunk) {
    return (n + chunk - 1) / chunk;
}

// The spread schedule, a testing aid (the twin of raster/detail/parallel.h's, which spatialhash may not
// include): while on, an Executor of k > 1 threads runs item i on lane i % min(k, count, 4), lane 0
// on the caller in ascending order and every other lane on a fresh std::thread in descending order,
// so a test of thread counts sees workers really run items (oneTBB may keep a small input on the
// caller). Off unless set, or the environment variable CULLIDE_SPREAD_SCHEDULE is 1 when first read.
// No effect without oneTBB.
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

class Executor {
   public:
    // threads = 0: all hardware threads. 1: serial in the calling thread.
    explicit Executor(unsigned threads);
    ~Executor();
    Executor(const Executor&) = delete;
    Executor& operator=(const Executor&) = delete;

    [[nodiscard]] unsigned concurrency() const { return concurrency_; }

    // Calls f(i) once for every i in [0, count), possibly concurrently, and returns when all are
    // done. f must only write state owned by item i.
    template <class F>
    void for_each(std::size_t count, F&& f) {
        run(count, &invoke<std::remove_reference_t<F>>, static_cast<void*>(&f));
    }

   private:
    template <class F>
    static void invoke(void* ctx, std::size_t i) {
        (*static_cast<F*>(ctx))(i);
    }
    void run(std::size_t count, void (*fn)(void*, std::size_t), void* ctx);

    struct Impl;
    std::unique_ptr<Impl> impl_;
    unsigned concurrency_ = 1;
};

}  // namespace spatialhash::detail
