// parallel_test.cpp: the one thread-count rule (0 = all hardware threads, negative = an error) and
// the parallel-for that raster and cullide share (raster/detail/parallel.h).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "raster/detail/parallel.h"
#include "raster/raster.h"
#include "raster/visibility.h"
#include "scene_gen.h"

TEST_CASE("effective_threads: a positive count as given, 0 = all hardware threads, 1 without oneTBB") {
    const int all = raster::detail::effective_threads(0);
    CHECK(all >= 1);
#if defined(CULLIDE_TEST_HAVE_TBB)
    CHECK(raster::detail::effective_threads(1) == 1);
    CHECK(raster::detail::effective_threads(3) == 3);
    CHECK(raster::detail::effective_threads(8) == 8);
#else
    CHECK(raster::detail::effective_threads(3) == all);
#endif
}

TEST_CASE("parallel_for calls the body once per index for 0, 1, 2, 3 and 8 threads") {
    for (const int threads : {0, 1, 2, 3, 8}) {
        for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
            CAPTURE(threads);
            CAPTURE(n);
            std::vector<std::atomic<int>> calls(n);
            for (auto& c : calls) c.store(0);
            raster::detail::parallel_for(threads, n, [&](std::size_t i) { calls[i].fetch_add(1); });
            for (std::size_t i = 0; i < n; ++i) CHECK(calls[i].load() == 1);
        }
    }
}

TEST_CASE("The spread schedule runs every item once, item i on lane i % k, the other lanes on threads of their own") {
    // Off unless a test turns it on, or CULLIDE_SPREAD_SCHEDULE=1 (CI's run of every unit test on it).
    const char* env = std::getenv("CULLIDE_SPREAD_SCHEDULE");
    const bool from_env = env != nullptr && std::string(env) == "1";
    CHECK(raster::detail::spread_schedule() == from_env);
    const std::thread::id caller = std::this_thread::get_id();
    for (const int threads : {1, 2, 3, 8}) {
        for (const std::size_t n :
             {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{7}, std::size_t{1000}}) {
            CAPTURE(threads);
            CAPTURE(n);
            const raster::detail::SpreadScheduleScope schedule;
            CHECK(raster::detail::spread_schedule());
            std::vector<std::atomic<int>> calls(n);
            for (auto& c : calls) c.store(0);
            std::vector<std::thread::id> ran_on(n);
            std::vector<std::size_t> step(n);  // the item's place in its thread's order
            raster::detail::parallel_for(threads, n, [&](std::size_t i) {
                calls[i].fetch_add(1);
                ran_on[i] = std::this_thread::get_id();
                // Items this thread ran in this call (a helper is a fresh thread: it starts at 0).
                thread_local std::size_t seen = 0;
                step[i] = std::this_thread::get_id() == caller ? i : seen++;
            });
            for (std::size_t i = 0; i < n; ++i) CHECK(calls[i].load() == 1);
#if defined(CULLIDE_TEST_HAVE_TBB)
            const std::size_t k = std::min<std::size_t>({static_cast<std::size_t>(threads), n, 4});
#else
            const std::size_t k = 1;  // one worker without oneTBB: no spread
#endif
            for (std::size_t i = 0; i < n; ++i) {
                CAPTURE(i);
                if (k <= 1 || i % k == 0) {
                    CHECK(ran_on[i] == caller);
                    continue;
                }
                CHECK(ran_on[i] != caller);
                // Each lane has a thread of its own, which runs its items from the last down.
                if (i + k < n) {
                    CHECK(ran_on[i + k] == ran_on[i]);
                    CHECK(step[i + k] + 1 == step[i]);
                }
                if (i + 1 < n && (i + 1) % k != 0) CHECK(ran_on[i + 1] != ran_on[i]);
            }
        }
    }
    CHECK(raster::detail::spread_schedule() == from_env);  // each scope restored the setting
}

TEST_CASE("On the spread schedule an item's exception reaches the caller after every lane has finished") {
    const raster::detail::SpreadScheduleScope schedule;
    for (const std::size_t bad : {std::size_t{0}, std::size_t{5}, std::size_t{998}}) {
        CAPTURE(bad);
        std::vector<std::atomic<int>> calls(1000);
        for (auto& c : calls) c.store(0);
        bool thrown = false;
        try {
            raster::detail::parallel_for(3, calls.size(), [&](std::size_t i) {
                calls[i].fetch_add(1);
                if (i == bad) throw std::runtime_error("item " + std::to_string(i));
            });
        } catch (const std::runtime_error& e) {
            thrown = true;
            CHECK(std::string(e.what()) == "item " + std::to_string(bad));
        }
#if defined(CULLIDE_TEST_HAVE_TBB)
        CHECK(thrown);
        // The lanes without the bad item ran all of theirs; none ran an item twice.
        for (std::size_t i = 0; i < calls.size(); ++i) {
            CAPTURE(i);
            CHECK(calls[i].load() <= 1);
            if (i % 3 != bad % 3) CHECK(calls[i].load() == 1);
        }
#else
        CHECK(thrown);  // serially: the loop stops at the bad item
        CHECK(calls[bad].load() == 1);
#endif
    }
}

TEST_CASE("execute with 0 threads (all hardware threads) gives the bits of one thread") {
    raster_test::SplitMix64 rng(1515);
    raster_test::Scene scene;
    raster_test::SceneOptions o;
    o.width = 200;
    o.height = 130;
    o.objects = 150;
    raster_test::build_scene(scene, rng, o);
    std::vector<std::uint32_t> depth[2];
    raster::QueryResults results[2];
    for (const int threads : {0, 1}) {
        CAPTURE(threads);
        auto t = raster::DepthTarget::create(o.width, o.height, raster::DepthFormat::D24);
        REQUIRE(t.ok());
        REQUIRE(t.value().clear(scene.clear_depth).ok());
        auto r = raster::execute(t.value(), scene.batch, raster::ExecuteOptions{threads});
        REQUIRE(r.ok());
        results[threads] = r.value();
        depth[threads].assign(t.value().values().begin(), t.value().values().end());
    }
    CHECK(results[0] == results[1]);
    CHECK(depth[0] == depth[1]);
}

TEST_CASE("A negative thread count is an error naming the value, and changes nothing") {
    auto t = raster::DepthTarget::create(16, 16, raster::DepthFormat::D24);
    REQUIRE(t.ok());
    REQUIRE(t.value().clear(1.0).ok());
    const std::vector<raster::Float4> v = {{-1, -1, 0, 1}, {1, -1, 0, 1}, {0, 1, 0, 1}};
    const std::vector<std::uint32_t> idx = {0, 1, 2};
    raster::CommandBatch batch(16, 16);
    batch.draw(raster::MeshView{v, idx}, raster::DrawState{});
    const std::vector<std::uint32_t> before(t.value().values().begin(), t.value().values().end());
    auto r = raster::execute(t.value(), batch, raster::ExecuteOptions{-2});
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "execute: threads = -2 is out of range: it must be >= 0 (0 = all hardware threads)");
    CHECK(std::vector<std::uint32_t>(t.value().values().begin(), t.value().values().end()) == before);

    raster::VisibilityPass pass;
    auto p = pass.run(16, 16, raster::DepthFormat::D24, {}, -1);
    REQUIRE_FALSE(p.ok());
    CHECK(p.error().message ==
          "visibility pass: threads = -1 is out of range: it must be >= 0 (0 = all hardware threads)");
}
