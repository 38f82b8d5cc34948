// Ground-truth time per frame on the built-in scenes, against the box-prefiltered all-pairs twin
// (object boxes, then every triangle pair of overlapping objects through a box test and the same
// exact test), side by side in one run. Each benchmark checks that both give the same pairs first.
//
//   build/bin/ground_truth_bench --benchmark_min_time=2
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

}  // namespace

BENCHMARK_CAPTURE(BM_GroundTruth, cylinders, std::string("cylinders"))->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AllPairsTwin, cylinders, std::string("cylinders"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GroundTruth, tori, std::string("tori"))->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AllPairsTwin, tori, std::string("tori"))->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
