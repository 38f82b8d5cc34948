// Ground-truth time per frame on the built-in scenes, against the box-prefiltered all-pairs twin
// (object boxes, then every triangle pair of overlapping objects through a box test and the same
// exact test), side by side in one run. Each benchmark checks that both give the same pairs first.
// BM_SetSweep runs the exact stage's general set sweep (sweep_exact_stage, one set per triangle: the
// ground truth's path before sweep_exact_triangles) on frame 30 of every scene, beside BM_GroundTruth30
// on the same frames; both must give the same pairs and counts. Times: wall clock (real time) and the
// process's CPU time, so a loaded machine shows in the gap between them.
//
//   build/bin/ground_truth_bench --benchmark_min_time=2
//   build/bin/ground_truth_bench --benchmark_filter='30|SetSweep' --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench_frames.h"
#include "cullide/ground_truth.h"
#include "cullide/scenes.h"
#include "cullide/tri_tri.h"
#include "exact_stage.h"

namespace {

using cullide::Mesh;
using cullide::TrianglePair;

std::vector<TrianglePair> all_pairs_twin(const std::vector<Mesh>& objects) {
    std::vector<TrianglePair> out;
    std::vector<cullide::Aabb> ob(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) ob[i] = cullide::mesh_bounds(objects[i]);
    for (std::uint32_t a = 0; a < objects.size(); ++a) {
        for (std::uint32_t b = a + 1; b < objects.size(); ++b) {
            if (!cullide::overlaps(ob[a], ob[b])) continue;
            const Mesh& ma = objects[a];
            const Mesh& mb = objects[b];
            std::vector<cullide::Aabb> bb(mb.triangles.size());
            for (std::size_t j = 0; j < mb.triangles.size(); ++j) bb[j] = cullide::triangle_bounds(mb, j);
            for (std::uint32_t i = 0; i < ma.triangles.size(); ++i) {
                const cullide::Aabb ba = cullide::triangle_bounds(ma, i);
                if (!cullide::overlaps(ba, ob[b])) continue;
                for (std::uint32_t j = 0; j < mb.triangles.size(); ++j) {
                    if (!cullide::overlaps(ba, bb[j])) continue;
                    const auto& ta = ma.triangles[i];
                    const auto& tb = mb.triangles[j];
                    if (cullide::tri_tri_intersect(ma.positions[ta[0]], ma.positions[ta[1]], ma.positions[ta[2]],
                                                   mb.positions[tb[0]], mb.positions[tb[1]], mb.positions[tb[2]])) {
                        out.push_back({a, i, b, j});
                    }
                }
            }
        }
    }
    std::sort(out.begin(), out.end());  // canonical (a, i, b, j) order, as exact_pairs returns
    return out;
}

using cullide_bench::scene_frame;

void check_agreement(benchmark::State& state, const std::vector<Mesh>& objects) {
    auto fast = cullide::exact_pairs(objects, {false, 1});
    if (!fast.ok() || fast.value() != all_pairs_twin(objects)) state.SkipWithError("ground truth and twin disagree");
    state.counters["pairs"] = static_cast<double>(fast.ok() ? fast.value().size() : 0);
}

void BM_GroundTruth(benchmark::State& state, const std::string& scene) {
    const auto& objects = scene_frame(scene, 3);
    check_agreement(state, objects);
    const int threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        auto r = cullide::exact_pairs(objects, {false, threads});
        benchmark::DoNotOptimize(r);
    }
}

void BM_AllPairsTwin(benchmark::State& state, const std::string& scene) {
    const auto& objects = scene_frame(scene, 3);
    check_agreement(state, objects);
    for (auto _ : state) {
        auto r = all_pairs_twin(objects);
        benchmark::DoNotOptimize(r);
    }
}

// The general set sweep with one set per triangle, as exact_pairs called it before
// sweep_exact_triangles (validation and boxes included).
cullide::Result<std::vector<TrianglePair>> set_sweep_pairs(const std::vector<Mesh>& objects, int threads,
                                                           cullide::ExactStats* stats) {
    if (cullide::Status s = cullide::validate_scene(objects); !s) return s.error();
    if (cullide::Status s = cullide::validate_exact_range(objects); !s) return s.error();
    std::vector<cullide::detail::ExactObject> exact(objects.size());
    std::vector<cullide::detail::CandidateSet> sets;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Mesh& m = objects[i];
        const auto object = static_cast<std::uint32_t>(i);
        for (std::size_t t = 0; t < m.triangles.size(); ++t)
            sets.push_back({object, static_cast<std::uint32_t>(t), 1, cullide::triangle_bounds(m, t)});
        exact[i] = {&m, object, cullide::mesh_bounds(m), {}, {}, {}};
    }
    auto r = cullide::detail::sweep_exact_stage(exact, sets, {false, false, threads});
    if (stats) {
        stats->candidate_triangles = r.stats.task_triangles;
        stats->box_pairs = r.stats.tests;
    }
    return std::move(r.pairs);
}

void check_same(benchmark::State& state, const std::vector<Mesh>& objects) {
    cullide::ExactStats a, b;
    auto fast = cullide::exact_pairs(objects, {false, 1}, &a);
    auto sets = set_sweep_pairs(objects, 1, &b);
    if (!fast.ok() || !sets.ok() || fast.value() != sets.value() || a.candidate_triangles != b.candidate_triangles ||
        a.box_pairs != b.box_pairs)
        state.SkipWithError("triangle sweep and set sweep disagree");
    state.counters["pairs"] = static_cast<double>(fast.ok() ? fast.value().size() : 0);
    state.counters["tests"] = static_cast<double>(a.box_pairs);
}

void BM_GroundTruth30(benchmark::State& state, const std::string& scene) {
    const auto& objects = scene_frame(scene, 30);
    check_same(state, objects);
    const int threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        auto r = cullide::exact_pairs(objects, {false, threads});
        benchmark::DoNotOptimize(r);
    }
}

void BM_SetSweep(benchmark::State& state, const std::string& scene) {
    const auto& objects = scene_frame(scene, 30);
    check_same(state, objects);
    const int threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        auto r = set_sweep_pairs(objects, threads, nullptr);
        benchmark::DoNotOptimize(r);
    }
}

}  // namespace

#define SIDE_BY_SIDE(scene)                                                                                   \
    BENCHMARK_CAPTURE(BM_GroundTruth30, scene, std::string(#scene))                                          \
        ->Arg(1)->Arg(2)->UseRealTime()->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);            \
    BENCHMARK_CAPTURE(BM_SetSweep, scene, std::string(#scene))                                               \
        ->Arg(1)->Arg(2)->UseRealTime()->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond)
SIDE_BY_SIDE(cylinders);
SIDE_BY_SIDE(tori);
BENCHMARK_CAPTURE(BM_GroundTruth30, bunny_dragon, std::string("bunny-dragon"))
    ->Arg(1)->Arg(2)->UseRealTime()->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SetSweep, bunny_dragon, std::string("bunny-dragon"))
    ->Arg(1)->Arg(2)->UseRealTime()->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);
SIDE_BY_SIDE(breaking);
SIDE_BY_SIDE(leaves);
SIDE_BY_SIDE(cloth);

BENCHMARK_CAPTURE(BM_GroundTruth, cylinders, std::string("cylinders"))->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AllPairsTwin, cylinders, std::string("cylinders"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GroundTruth, tori, std::string("tori"))->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AllPairsTwin, tori, std::string("tori"))->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
