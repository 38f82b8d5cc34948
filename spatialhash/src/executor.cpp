// The executor: oneTBB when available, a serial loop otherwise (embedded builds).
#include "spatialhash/detail/executor.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>

#if defined(CULLIDE_HAVE_TBB)
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <exception>
#include <system_error>
#include <thread>
#include <vector>
#endif

namespace spatialhash::detail {

namespace {

std::atomic<bool>& spread_flag() {
    static std::atomic<bool> flag{[] {
        const char* v = std::getenv("CULLIDE_SPREAD_SCHEDULE");
        return v != nullptr && std::strcmp(v, "1") == 0;
    }()};
    return flag;
}

#if defined(CULLIDE_HAVE_TBB)
// Item i on lane i % k: lane 0 here, ascending; lanes 1 .. k-1 on threads of their own, descending.
void run_spread(std::size_t k, std::size_t count, void (*fn)(void*, std::size_t), void* ctx) {
    std::vector<std::exception_ptr> errors(k);
    const auto lane = [&](std::size_t t) {
        try {
            if (t == 0) {
                for (std::size_t i = 0; i < count; i += k) fn(ctx, i);
                return;
            }
            for (std::size_t i = t + (count - 1 - t) / k * k;; i -= k) {  // t < k <= count
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
        // No thread to be had: the remaining lanes run here after lane 0.
    }
    lane(0);
    for (std::size_t t = started; t < k; ++t) lane(t);
    for (std::thread& h : helpers) h.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}
#endif

}  // namespace

void set_spread_schedule(bool on) { spread_flag().store(on, std::memory_order_relaxed); }
bool spread_schedule() { return spread_flag().load(std::memory_order_relaxed); }

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
        if (spread_schedule()) {
            run_spread(std::min<std::size_t>({static_cast<std::size_t>(concurrency_), count, 4}), count, fn, ctx);
            return;
        }
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
