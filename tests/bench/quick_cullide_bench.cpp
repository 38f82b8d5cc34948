// Self-collision time per frame, side by side in one run: qcullide (Quick-CULLIDE, exact-bounds),
// qcullide-gl, the ground truth (`--method exact --self`), and the box-prefiltered all-pairs self
// test (quick_cullide_pairs with the visibility passes skipped: sweep and prune on triangle boxes,
// adjacency, exact test). Each benchmark first checks that its pairs equal the ground truth's
// (qcullide-gl: a subset), and reports the triangle pairs sent to the exact test as a counter.
//
//   build/bin/quick_cullide_bench --benchmark_min_time=1 --benchmark_filter=cloth
#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/quick_cullide.h"
#include "cullide/scenes.h"

namespace {

using cullide::Mesh;
using cullide::TrianglePair;

const std::vector<Mesh>& frame_of(const std::string& scene, int f) {
    static std::map<std::pair<std::string, int>, std::vector<Mesh>> cache;
    auto key = std::make_pair(scene, f);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    cullide::SceneOptions options;
    options.mesh_dir = "";
    auto g = cullide::make_scene(scene, options);
    if (!g) std::abort();
    return cache[key] = g.value()->frame(f);
}

const std::vector<TrianglePair>& truth_of(const std::string& scene, int f) {
    static std::map<std::pair<std::string, int>, std::vector<TrianglePair>> cache;
    auto key = std::make_pair(scene, f);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    cullide::ExactOptions eo;
    eo.self = true;
    auto r = cullide::exact_pairs(frame_of(scene, f), eo);
    if (!r) std::abort();
    return cache[key] = r.value();
}

// kind: 0 qcullide, 1 qcullide-gl, 2 exact --self, 3 box-prefiltered all-pairs.
void bm_self(benchmark::State& state, const std::string& scene, int frame, int kind, int threads) {
    const std::vector<Mesh>& objects = frame_of(scene, frame);
    const std::vector<TrianglePair>& truth = truth_of(scene, frame);
    std::uint64_t exact_tests = 0;
    cullide::QuickStats st;
    auto once = [&]() -> std::vector<TrianglePair> {
        if (kind != 2) {
            // Quick-CULLIDE directly (process_frame adds only validation), for its statistics.
            auto device = cullide::make_emulator_device(threads);
            cullide::QuickOptions qo;
            qo.mode = kind == 1 ? cullide::VisibilityMode::GLExact : cullide::VisibilityMode::ExactBounds;
            qo.self = true;
            qo.threads = threads;
            qo.resolution = kind == 3 ? 16 : static_cast<int>(state.range(0));
            qo.subobject_triangles = kind == 3 ? 1 : static_cast<int>(state.range(1));
            qo.skip_visibility = kind == 3;
            std::vector<std::uint32_t> active(objects.size());
            for (std::size_t i = 0; i < active.size(); ++i) active[i] = static_cast<std::uint32_t>(i);
            auto r = cullide::quick_cullide_pairs(objects, active, qo, *device, &st);
            if (!r) std::abort();
            exact_tests = st.exact_tests;
            return r.value();
        }
        cullide::RunOptions o;
        o.self = true;
        o.threads = threads;
        o.method = cullide::Method::Exact;
        auto r = cullide::process_frame(objects, o);
        if (!r) std::abort();
        exact_tests = r.value().stats.exact_tests;
        return r.value().pairs;
    };
    const std::vector<TrianglePair> first = once();
    const bool ok = kind == 1 ? std::includes(truth.begin(), truth.end(), first.begin(), first.end()) : first == truth;
    if (!ok) {
        state.SkipWithError("pairs differ from the ground truth");
        return;
    }
    for (auto _ : state) benchmark::DoNotOptimize(once());
    state.counters["exact_tests"] = static_cast<double>(exact_tests);
    state.counters["true_pairs"] = static_cast<double>(truth.size());
    state.counters["found"] = static_cast<double>(first.size());
    if (kind != 2) {
        state.counters["near_tests"] = static_cast<double>(st.near_exact_tests);
        state.counters["far_items"] = static_cast<double>(st.pcs_boxes);  // items the passes had to classify
        state.counters["left"] = static_cast<double>(st.pcs_subobjects);
        state.counters["views"] = static_cast<double>(st.views.size());
        state.counters["window"] = static_cast<double>(st.window_max);
    }
}

void register_all() {
    const char* kinds[] = {"qcullide", "qcullide_gl", "exact_self", "box_all_pairs"};
    for (const auto& [scene, frame] : {std::pair<std::string, int>{"cloth", 0}, {"cloth", 60}, {"breaking", 6}, {"breaking", 40}}) {
        for (int kind = 0; kind < 4; ++kind) {
            const std::string name = std::string("self/") + scene + "/" + std::to_string(frame) + "/" + kinds[kind];
            auto* b = benchmark::RegisterBenchmark(name.c_str(), [scene = scene, frame = frame, kind](benchmark::State& s) {
                bm_self(s, scene, frame, kind, 2);
            });
            b->Unit(benchmark::kMillisecond);
            if (kind <= 1) {
                b->ArgNames({"res", "sub"});
                b->Args({32, 16})->Args({64, 16})->Args({128, 16})->Args({256, 16})->Args({256, 4})->Args({1024, 4});
            } else {
                b->Args({0, 0});
            }
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    register_all();
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
