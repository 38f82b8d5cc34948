// raster_bench.cpp: depth-only triangle and occlusion-query throughput of cullide::raster against
// Mesa llvmpipe (OSMesa) on identical workloads. Every benchmark first checks that both produce the
// same query results (a digest of the workload) and refuses to report a time otherwise.
//
//   build-raster/bin/raster_bench --benchmark_min_time=0.2
//
// Workloads (clip-space floats, built with splitmix64):
//   Cullide/<size>/<threads>: 2000 objects (12-triangle closed boxes, ~10-40 px across), each a
//     GEQUAL query with the mask off followed by a LEQUAL draw with the mask on: CULLIDE's pattern.
//   SmallTris/<size>/<threads>: 20000 triangles of ~8 px^2, LESS, writes on.
//   LargeTris/<size>/<threads>: 200 triangles covering ~1/8 of the target each, LESS, writes on.
//   CullideAny/<size>/<threads>: Cullide with any-samples queries (what cullide.cpp issues): the
//     executor stops a query at its first passing sample.
//   Each run of ours starts with ExecuteOptions::clear_depth = 1 (OSMesa's with glClear). On
//   SmallTris, LargeTris, Cullide and CullideAny that clear is the target's fast clear (only the
//   8 x 8 blocks the previous run wrote are filled: DepthTarget's record).
//   SmallTrisRestore, LargeTrisRestore: the same with the caller's list of those blocks
//     (ExecuteOptions::written_blocks, as CULLIDE's emulator device clears).
//   SmallTrisFullClear: every run fills the whole buffer, as llvmpipe does (the record is dropped
//     before each run).
//   Checked after timing for every clear of ours: the buffer equals a full clear's.
// threads = 0 means the OSMesa oracle (llvmpipe with its default thread count). A third argument
// simd: 1 = default kernel choice (AVX2 8-wide when the CPU has it), 0 = the portable kernel.
//   Reliable/<size>/<mode>: the Cullide workload's 2000 boxes (world = clip: a [-1, 1]^3 view along
//     z), one thread, CPU time, in the three ways CULLIDE can run: mode 0 GL-exact (float, pixel
//     centres), 1 exact-bounds (double, conservative), 2 R-CULLIDE offset boxes per triangle (12
//     boxes per object, far faces queried, near faces written), 3 R-CULLIDE one oriented offset box
//     per object (UOBB). Checked first: the 2-thread run gives the same query results; the number of
//     objects each mode calls fully visible is reported (counter "visible").
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "raster/raster.h"
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
#include "osmesa_device.h"
#endif

namespace {

struct Rng {
    std::uint64_t s;
    std::uint64_t next() {
        std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    float uniform(float lo, float hi) {
        return lo + (hi - lo) * (static_cast<float>(next() >> 40) * (1.0f / 16777216.0f));
    }
};

struct Workload {
    std::vector<raster::Float4> vertices;
    std::vector<std::vector<std::uint32_t>> indices;  // one index list per draw
    raster::CommandBatch batch{1, 1};
    std::size_t triangles = 0;
    std::size_t queries = 0;
};

enum class Kind { Cullide, SmallTris, LargeTris, CullideAny };

std::unique_ptr<Workload> make_workload(Kind kind, int size) {
    auto w = std::make_unique<Workload>();
    w->batch = raster::CommandBatch(size, size);
    Rng rng{static_cast<std::uint64_t>(size) * 31 + static_cast<std::uint64_t>(kind)};
    const float px = 2.0f / static_cast<float>(size);  // one pixel in NDC
    if (kind == Kind::Cullide || kind == Kind::CullideAny) {
        const int objects = 2000;
        w->indices.resize(1);
        // A box: 8 corners, 12 triangles (shared vertex list per object, indices rebased).
        static const std::uint32_t box[36] = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
                                              2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
        for (int o = 0; o < objects; ++o) {
            const float cx = rng.uniform(-0.95f, 0.95f), cy = rng.uniform(-0.95f, 0.95f);
            const float cz = rng.uniform(-0.9f, 0.9f);
            const float e = rng.uniform(5.0f, 20.0f) * px, ez = rng.uniform(0.01f, 0.05f);
            const auto base = static_cast<std::uint32_t>(w->vertices.size());
            for (int k = 0; k < 8; ++k)
                w->vertices.push_back({cx + ((k & 1) ? e : -e), cy + ((k & 2) ? e : -e), cz + ((k & 4) ? ez : -ez), 1.0f});
            w->indices.emplace_back();
            for (auto i : box) w->indices.back().push_back(base + i);
        }
        for (int o = 0; o < objects; ++o) {
            const raster::MeshView m{w->vertices, w->indices[static_cast<std::size_t>(o) + 1]};
            raster::DrawState q;
            q.depth_func = raster::DepthFunc::GEqual;
            q.depth_write = false;
            w->batch.begin_query(kind == Kind::CullideAny ? raster::QueryKind::AnySamplesPassed
                                                          : raster::QueryKind::SamplesPassed);
            w->batch.draw(m, q);
            w->batch.end_query();
            raster::DrawState d;
            d.depth_func = raster::DepthFunc::LEqual;
            w->batch.draw(m, d);
            w->triangles += 24;
            w->queries += 1;
        }
        return w;
    }
    const int count = kind == Kind::SmallTris ? 20000 : 200;
    const float r = kind == Kind::SmallTris ? 2.0f * px : 0.7f;
    w->indices.emplace_back();
    for (int t = 0; t < count; ++t) {
        const float cx = rng.uniform(-1.0f, 1.0f), cy = rng.uniform(-1.0f, 1.0f);
        const auto base = static_cast<std::uint32_t>(w->vertices.size());
        for (int k = 0; k < 3; ++k)
            w->vertices.push_back({cx + rng.uniform(-r, r), cy + rng.uniform(-r, r), rng.uniform(-0.9f, 0.9f), 1.0f});
        for (int k = 0; k < 3; ++k) w->indices[0].push_back(base + static_cast<std::uint32_t>(k));
    }
    // One query around the whole draw so the digest covers it.
    w->batch.begin_query(raster::QueryKind::SamplesPassed);
    w->batch.draw({w->vertices, w->indices[0]}, {});
    w->batch.end_query();
    w->triangles = static_cast<std::size_t>(count);
    w->queries = 1;
    return w;
}

std::uint64_t digest(const raster::QueryResults& r) {
    std::uint64_t h = 1469598103934665603ull;
    for (auto v : r) h = (h ^ v) * 0x100000001b3ull;
    return h;
}

// How each timed run of ours clears (the buffer and results are those of a full clear every time):
// Fast: the target's own record of the blocks written since its last clear (DepthTarget's fast
// clear); Written: the caller's ExecuteOptions::written_blocks kept from one run to the next (how
// CULLIDE's emulator device clears between passes); Full: every pixel, as llvmpipe does.
enum class Clear { Fast, Written, Full };

void run(benchmark::State& state, Kind kind, Clear clear) {
    const bool restore_written = clear == Clear::Written;
    const int size = static_cast<int>(state.range(0));
    const int threads = static_cast<int>(state.range(1));
    const bool simd = state.range(2) != 0;
    const auto w = make_workload(kind, size);
    auto target = raster::DepthTarget::create(size, size, raster::DepthFormat::D24);
    if (!target.ok()) {
        state.SkipWithError(target.error().message.c_str());
        return;
    }
    auto ours = raster::execute(target.value(), w->batch, raster::ExecuteOptions{threads > 0 ? threads : 1, simd});
    if (!ours.ok()) {
        state.SkipWithError(ours.error().message.c_str());
        return;
    }
    const std::uint64_t want = digest(ours.value());
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
    std::unique_ptr<cullide_oracle::OsmesaDevice> dev;
    if (threads == 0 || size <= 1024) {  // the digest check against real GL
        auto d = cullide_oracle::OsmesaDevice::create(size, size, raster::DepthFormat::D24);
        if (!d.ok()) {
            state.SkipWithError(d.error().message.c_str());
            return;
        }
        dev = std::move(d.value());
        auto gl = dev->run(w->batch);
        if (!gl.ok() || digest(gl.value()) != want) {
            state.SkipWithError("query results differ from OSMesa: not timing");
            return;
        }
    }
    if (threads == 0) {
        for (auto _ : state) {
            dev->clear(1.0);
            auto r = dev->run(w->batch);  // issues everything, then reads every query
            benchmark::DoNotOptimize(r);
        }
    }
#else
    if (threads == 0) {
        state.SkipWithError("OSMesa oracle not built");
        return;
    }
#endif
    if (threads > 0) {
        // The clear is part of the timed work on both sides: OSMesa's glClear goes into llvmpipe's
        // scene and its threads clear tile by tile; ours is ExecuteOptions::clear_depth, each
        // tile's task filling its tile first (a separate DepthTarget::clear is one serial pass).
        raster::ExecuteOptions options{threads, simd};
        options.clear_depth = 1.0;
        std::vector<std::uint64_t> written;  // empty: the first run fills every block
        if (restore_written) options.written_blocks = &written;
        for (auto _ : state) {
            if (clear == Clear::Full) (void)target.value().mutable_values();  // forgets the record
            auto r = raster::execute(target.value(), w->batch, options);
            benchmark::DoNotOptimize(r);
        }
        {  // the buffer after the last run is the one a fully cleared target gives
            auto full = raster::DepthTarget::create(size, size, raster::DepthFormat::D24);
            auto r = raster::execute(full.value(), w->batch, raster::ExecuteOptions{threads, simd});
            const auto a = target.value().values(), b = full.value().values();
            if (!r.ok() || digest(r.value()) != want || !std::equal(a.begin(), a.end(), b.begin(), b.end()))
                state.SkipWithError("the clear of the timed runs gave another buffer than a full clear");
        }
    }
    state.counters["tris/s"] = benchmark::Counter(static_cast<double>(w->triangles), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["queries/s"] = benchmark::Counter(static_cast<double>(w->queries), benchmark::Counter::kIsIterationInvariantRate);
    state.SetLabel(threads == 0 ? "osmesa-llvmpipe"
                                : std::string(simd ? "cullide-raster" : "cullide-raster-portable") +
                                      (restore_written        ? "+written-blocks"
                                       : clear == Clear::Full ? "+full-clear"
                                                              : ""));
}

void args(benchmark::internal::Benchmark* b) {
    for (const int size : {256, 1024, 4096})
        for (const int threads : {0, 1, 2}) {
            b->Args({size, threads, 1});
            if (threads == 1) b->Args({size, threads, 0});  // the portable (scalar) kernel, SIMD off
        }
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

// The emulator alone (the OSMesa rows are the plain workload's), AVX2 kernel.
void args_emulator(benchmark::internal::Benchmark* b) {
    for (const int size : {256, 1024, 4096})
        for (const int threads : {1, 2}) b->Args({size, threads, 1});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

// The reliable-mode workloads own their geometry (offset meshes, double vertices).
struct ReliableWorkload {
    std::vector<raster::Float4> fvertices;
    std::vector<raster::Double4> dvertices;
    std::vector<std::vector<std::uint32_t>> indices;
    std::vector<raster::OffsetMesh> offsets;
    raster::CommandBatch batch{1, 1};
};

std::unique_ptr<ReliableWorkload> make_reliable(int size, int mode) {
    auto base = make_workload(Kind::Cullide, size);
    auto w = std::make_unique<ReliableWorkload>();
    w->batch = raster::CommandBatch(size, size);
    w->fvertices = base->vertices;
    for (const auto& v : base->vertices)
        w->dvertices.push_back({static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z), 1.0});
    w->indices.assign(base->indices.begin() + 1, base->indices.end());
    auto view = raster::make_ortho_view(raster::Axis::Z, {-1, -1, -1}, {1, 1, 1}, size, size, raster::DepthFormat::D24);
    std::vector<raster::Double3> world;
    for (const auto& v : w->dvertices) world.push_back({v.x, v.y, v.z});
    if (mode >= 2) {
        for (const auto& idx : w->indices) {
            auto m = mode == 2 ? raster::triangle_offset_boxes(view.value(), world, idx)
                               : raster::object_offset_obbs(view.value(), world, idx, 12);
            w->offsets.push_back(std::move(m.value()));
        }
    }
    for (std::size_t o = 0; o < w->indices.size(); ++o) {
        raster::DrawState q, d;
        q.depth_func = raster::DepthFunc::GEqual;
        q.depth_write = false;
        d.depth_func = raster::DepthFunc::LEqual;
        w->batch.begin_query(raster::QueryKind::SamplesPassed);
        if (mode == 0) {
            w->batch.draw(raster::MeshView{w->fvertices, w->indices[o]}, q);
            w->batch.end_query();
            w->batch.draw(raster::MeshView{w->fvertices, w->indices[o]}, d);
        } else if (mode == 1) {
            q.mode = d.mode = raster::RasterMode::ExactBounds;
            w->batch.draw(raster::MeshViewD{w->dvertices, w->indices[o]}, q);
            w->batch.end_query();
            w->batch.draw(raster::MeshViewD{w->dvertices, w->indices[o]}, d);
        } else {
            q.cull_face = raster::CullFace::Front;
            d.cull_face = raster::CullFace::Back;
            w->batch.draw(w->offsets[o].view(), q);
            w->batch.end_query();
            w->batch.draw(w->offsets[o].view(), d);
        }
    }
    return w;
}

void run_reliable(benchmark::State& state) {
    const int size = static_cast<int>(state.range(0));
    const int mode = static_cast<int>(state.range(1));
    const auto w = make_reliable(size, mode);
    auto target = raster::DepthTarget::create(size, size, raster::DepthFormat::D24);
    auto one = raster::execute(target.value(), w->batch, raster::ExecuteOptions{1});
    (void)target.value().clear(1.0);
    auto two = raster::execute(target.value(), w->batch, raster::ExecuteOptions{2});
    if (!one.ok() || !two.ok() || digest(one.value()) != digest(two.value())) {
        state.SkipWithError("reliable workload: 1- and 2-thread results differ: not timing");
        return;
    }
    double visible = 0;
    for (auto v : one.value()) visible += v == 0 ? 1.0 : 0.0;
    for (auto _ : state) {
        (void)target.value().clear(1.0);
        auto r = raster::execute(target.value(), w->batch, raster::ExecuteOptions{1});
        benchmark::DoNotOptimize(r);
    }
    state.counters["visible"] = visible;
    static const char* kNames[] = {"gl-exact", "exact-bounds", "offset-per-triangle", "offset-uobb"};
    state.SetLabel(kNames[mode]);
}

}  // namespace

BENCHMARK(run_reliable)->ArgsProduct({{256, 1024}, {0, 1, 2, 3}})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, Cullide, Kind::Cullide, Clear::Fast)->Apply(args);
BENCHMARK_CAPTURE(run, SmallTris, Kind::SmallTris, Clear::Fast)->Apply(args);
BENCHMARK_CAPTURE(run, LargeTris, Kind::LargeTris, Clear::Fast)->Apply(args);
BENCHMARK_CAPTURE(run, SmallTrisRestore, Kind::SmallTris, Clear::Written)->Apply(args_emulator);
BENCHMARK_CAPTURE(run, LargeTrisRestore, Kind::LargeTris, Clear::Written)->Apply(args_emulator);
BENCHMARK_CAPTURE(run, SmallTrisFullClear, Kind::SmallTris, Clear::Full)->Apply(args_emulator);
BENCHMARK_CAPTURE(run, CullideAny, Kind::CullideAny, Clear::Fast)->Apply(args);

namespace {

// raster_bench --once <Cullide|CullideAny|SmallTris|LargeTris> <size> <simd 0|1> [threads]: one
// execute() of a workload and its query digest, no timing: for instruction counts, e.g.
//   valgrind --tool=callgrind --collect-atstart=no --toggle-collect='raster::execute(raster::DepthTarget&,
//     raster::CommandBatch const&, raster::ExecuteOptions const&)' raster_bench --once LargeTris 1024 1
int run_once(int argc, char** argv) {
    const std::string name = argv[2];
    Kind kind;
    if (name == "Cullide") kind = Kind::Cullide;
    else if (name == "CullideAny") kind = Kind::CullideAny;
    else if (name == "SmallTris") kind = Kind::SmallTris;
    else if (name == "LargeTris") kind = Kind::LargeTris;
    else {
        std::fprintf(stderr, "raster_bench --once: unknown workload '%s'\n", argv[2]);
        return 2;
    }
    const int size = std::atoi(argv[3]);
    const bool simd = std::atoi(argv[4]) != 0;
    const int threads = argc > 5 ? std::atoi(argv[5]) : 1;
    if (size < 1 || size > 16384 || threads < 1) {
        std::fprintf(stderr, "raster_bench --once: size must be 1..16384 and threads >= 1\n");
        return 2;
    }
    const auto w = make_workload(kind, size);
    auto target = raster::DepthTarget::create(size, size, raster::DepthFormat::D24);
    if (!target.ok()) return 1;
    auto r = raster::execute(target.value(), w->batch, raster::ExecuteOptions{threads, simd});
    if (!r.ok()) {
        std::fprintf(stderr, "%s\n", r.error().message.c_str());
        return 1;
    }
    std::printf("%s %d simd=%d threads=%d digest=%016llx\n", argv[2], size, simd ? 1 : 0, threads,
                static_cast<unsigned long long>(digest(r.value())));
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc >= 5 && std::string(argv[1]) == "--once") return run_once(argc, argv);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
