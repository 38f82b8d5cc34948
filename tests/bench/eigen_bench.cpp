// The one copy of the Eigen front door (cullide/eigen.h), against the frame it feeds: per built-in
// scene (default scale, frame 3), the time to copy libigl-style V/F matrices into Meshes (to_meshes),
// next to process_frame with the default method (rcullide) on those Meshes. Row-major and
// column-major V (F int, column-major, as libigl holds it). Each benchmark first checks that collide
// returns process_frame's pairs.
//
//   build/bin/eigen_bench --benchmark_min_time=1
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench_frames.h"
#include "cullide/eigen.h"
#include "cullide/scenes.h"

namespace {

using cullide::Mesh;
using RowV = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using ColV = Eigen::MatrixXd;

// The benchmarked frame of every scene.
const std::vector<Mesh>& frame_of(const std::string& scene) { return cullide_bench::scene_frame(scene, 3); }

template <class VMatrix>
struct Matrices {
    std::vector<VMatrix> v;
    std::vector<Eigen::MatrixXi> f;
    std::vector<cullide::EigenMeshRef> refs;

    explicit Matrices(const std::vector<Mesh>& objects) {
        v.reserve(objects.size());
        f.reserve(objects.size());
        for (const Mesh& m : objects) {
            VMatrix vm(static_cast<Eigen::Index>(m.positions.size()), 3);
            for (std::size_t i = 0; i < m.positions.size(); ++i)
                for (int k = 0; k < 3; ++k) vm(static_cast<Eigen::Index>(i), k) = m.positions[i][k];
            Eigen::MatrixXi fm(static_cast<Eigen::Index>(m.triangles.size()), 3);
            for (std::size_t i = 0; i < m.triangles.size(); ++i)
                for (int k = 0; k < 3; ++k) fm(static_cast<Eigen::Index>(i), k) = static_cast<int>(m.triangles[i][k]);
            v.push_back(std::move(vm));
            f.push_back(std::move(fm));
        }
        for (std::size_t i = 0; i < objects.size(); ++i) refs.emplace_back(v[i], f[i]);
    }
};

cullide::RunOptions frame_options(benchmark::State& state) {
    cullide::RunOptions o;  // rcullide, the default method
    o.threads = static_cast<int>(state.range(0));
    return o;
}

template <class VMatrix>
void BM_Copy(benchmark::State& state, const std::string& scene) {
    const std::vector<Mesh>& objects = frame_of(scene);
    const Matrices<VMatrix> m(objects);
    auto direct = cullide::process_frame(objects, frame_options(state));
    auto front = cullide::collide(m.refs, frame_options(state));
    if (!direct || !front || front.value().frame.pairs != direct.value().pairs) {
        state.SkipWithError("collide and process_frame disagree");
        return;
    }
    std::uint64_t triangles = 0;
    for (const Mesh& mesh : objects) triangles += mesh.triangles.size();
    for (auto _ : state) {
        auto meshes = cullide::to_meshes(m.refs);
        benchmark::DoNotOptimize(meshes);
    }
    state.counters["triangles"] = static_cast<double>(triangles);
    state.counters["pairs"] = static_cast<double>(direct.value().pairs.size());
}

void BM_Frame(benchmark::State& state, const std::string& scene) {
    const std::vector<Mesh>& objects = frame_of(scene);
    const cullide::RunOptions o = frame_options(state);
    for (auto _ : state) {
        auto r = cullide::process_frame(objects, o);
        benchmark::DoNotOptimize(r);
    }
}

void register_all() {
    for (const std::string& scene : cullide::scene_names()) {
        benchmark::RegisterBenchmark(("copy_row_major/" + scene).c_str(), BM_Copy<RowV>, scene)
            ->Arg(1)->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("copy_col_major/" + scene).c_str(), BM_Copy<ColV>, scene)
            ->Arg(1)->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("frame_rcullide/" + scene).c_str(), BM_Frame, scene)
            ->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
    }
}

}  // namespace

int main(int argc, char** argv) {
    register_all();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
