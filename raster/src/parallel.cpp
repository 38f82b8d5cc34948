// parallel.cpp: raster::detail::parallel_for on a oneTBB arena, a serial loop without oneTBB
// (raster/detail/parallel.h).
#include "raster/detail/parallel.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>

#if defined(CULLIDE_HAVE_TBB)
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>
#endif

namespace raster::detail {

namespace {
// Made on first use (so no static initializer can see it unset): on when the environment says so.
std::atomic<bool>& spread_flag() {
    static std::atomic<bool> flag{[] {
        const char* v = std::getenv("CULLIDE_SPREAD_SCHEDULE");
        return v != nullptr && std::strcmp(v, "1") == 0;
    }()};
    return flag;
}
}  // namespace

void set_spread_schedule(bool on) { spread_flag().store(on, std::memory_order_relaxed); }
bool spread_schedule() { return spread_flag().load(std::memory_order_relaxed); }

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

// The spread schedule (parallel.h): item i on lane i % k, lane 0 (the caller) ascending, the other
// lanes on threads of their own, descending.
void run_spread(std::size_t k, std::size_t n, void (*fn)(void*, std::size_t), void* ctx) {
    std::vector<std::exception_ptr> errors(k);
    const auto lane = [&](std::size_t t) {
        try {
            if (t == 0) {
                for (std::size_t i = 0; i < n; i += k) fn(ctx, i);
                return;
            }
            for (std::size_t i = t + (n - 1 - t) / k * k;; i -= k) {  // t < k <= n: at least one item
                fn(ctx, i);
                if (i < k) break;
            }
        } catch (...) {
            errors[t] = std::current_exception();
        }
    };
    std::vector<std::thread> helpers;
    helpers.reserve(k - 1);
    std::size_t started = 1;
    try {
        for (; started < k; ++started) helpers.emplace_back(lane, started);
    } catch (const std::system_error&) {
        // No thread to be had: the lanes left run here, after lane 0 (still every item once).
    }
    lane(0);
    for (std::size_t t = started; t < k; ++t) lane(t);
    for (std::thread& h : helpers) h.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace
#endif

void parallel_for_erased(int threads, std::size_t n, void (*fn)(void*, std::size_t), void* ctx) {
#if defined(CULLIDE_HAVE_TBB)
    const int workers = effective_threads(threads);
    if (workers > 1 && n > 1) {
        if (spread_schedule()) {
            run_spread(std::min<std::size_t>({static_cast<std::size_t>(workers), n, 4}), n, fn, ctx);
            return;
        }
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
