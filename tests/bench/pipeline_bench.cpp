// pipeline_bench.cpp: time per frame of every collision method on every built-in scene, on the
// emulator device and on the OSMesa device (Mesa llvmpipe) running the very same visibility passes
// (issue #5). Side by side in one run: the ground truth (`exact`), cullide, rcullide-offset and
// qcullide-gl (GL-exact passes: emulator and OSMesa), rcullide and qcullide (exact-bounds passes:
// emulator only, real GL has no such raster mode; they are not registered on OSMesa).
//
//   build/bin/pipeline_bench [--scenes=LIST|all] [--scale=S[,scene=S...]] [--frames=N]
//       [--reps=N] [--methods=LIST] [--gl-chunk=N] [benchmark flags]
//   e.g. pipeline_bench --scale=0.1,cylinders=1,leaves=1,cloth=1 --frames=2 --reps=2
//
// Defaults: every scene at scale 1, 3 frames per scene (the first frame with collisions, then every
// 5th: bunny-dragon 25, breaking 26, cloth 20, the others 0; as scripts/results.sh), 2 timed runs.
// Every method runs at its own default resolution (cullide::default_resolution: rcullide 32, the
// others 1024), D24, 4 triangles per sub-object, 4 rounds, no broad phase, no self-collision.
//
// One benchmark = scene x method x device x threads. Emulator: 1 and 2 worker threads. OSMesa: the
// visibility passes run on llvmpipe's own threads (LP_NUM_THREADS, else one per core: printed in the
// context), the host stages (PCS bookkeeping, exact test) on 2 workers.
// Before timing, every benchmark runs its frames once (untimed, also the warm-up) and refuses to
// time (SkipWithError naming scene, method and frame) unless
//   - every reported pair is in the ground truth (every method ends in the exact test);
//   - a method that never misses (exact, rcullide, rcullide-offset, qcullide) gives exactly the
//     ground truth's pairs;
//   - its pairs, queries, triangles rasterized, PCS sizes (boxes, objects, sub-objects) and every
//     view's surviving items equal the emulator's at 1 thread for the same method (so OSMesa and
//     the emulator's thread counts are checked against it). On OSMesa the message also names the
//     first query whose answers differ (TeeDevice). A refused benchmark makes the exit status 1.
// OSMesa gets each batch whole (--gl-chunk=0, the default), or in pieces of at most N queries
// (--gl-chunk=N, ChunkedDevice). Whole batches agree since the OSMesa device bounds llvmpipe's
// scenes (issue #17, docs/raster-known-differences.md "Whole batches").
// Time: wall clock per frame (manual time: each iteration runs all frames; mean over iterations).
// Counters are per frame (means over the frames): pairs, misses (ground-truth pairs not found),
// pcs_boxes, pcs_objects, pcs_subobjects, queries; res = the view resolution used.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "raster/raster.h"
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
#include "osmesa_query_device.h"
#endif

namespace {

using cullide::FrameResult;
using cullide::Method;
using cullide::TrianglePair;

struct Config {
    std::vector<std::string> scenes;
    double default_scale = 1.0;
    std::map<std::string, double> scale_of;  // per-scene overrides
    int frames = 3;
    // > 0: OSMesa gets each batch in pieces of at most this many queries (ChunkedDevice); 0: whole.
    int gl_chunk = 0;
    int reps = 2;
    std::vector<Method> methods{Method::Exact,   Method::Cullide,  Method::RCullideOffset,
                                Method::QCullideGL, Method::RCullide, Method::QCullide};
    double scale(const std::string& s) const {
        auto it = scale_of.find(s);
        return it == scale_of.end() ? default_scale : it->second;
    }
};

Config& config() {
    static Config c;
    return c;
}

// Frames where each scene has collisions (docs/scenes.md, scripts/results.sh).
int first_frame(const std::string& scene) {
    if (scene == "bunny-dragon") return 25;
    if (scene == "breaking") return 26;
    if (scene == "cloth") return 20;
    return 0;
}
constexpr int kFrameStep = 5;

bool never_misses(Method m) {
    return m == Method::Exact || m == Method::RCullide || m == Method::RCullideOffset || m == Method::QCullide;
}
bool exact_bounds(Method m) { return m == Method::RCullide || m == Method::QCullide; }

struct SceneData {
    std::vector<int> frame_ids;
    std::vector<cullide::Frame> frames;
    std::vector<std::vector<TrianglePair>> truth;  // exact_pairs per frame
    std::string description;
};

// Scenes, ground truth and the emulator references are computed once, on first use (a benchmark
// that is filtered out costs nothing).
const SceneData& scene_data(const std::string& name) {
    static std::map<std::string, SceneData> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second;
    SceneData d;
    cullide::SceneOptions so;
    so.scale = config().scale(name);
    so.mesh_dir = CULLIDE_SHARED_MESH_DIR;
    auto g = cullide::make_scene(name, so);
    if (!g.ok()) {
        std::fprintf(stderr, "pipeline_bench: scene %s: %s\n", name.c_str(), g.error().message.c_str());
        std::fflush(nullptr);
        std::_Exit(1);  // not std::exit: see g_osmesa
    }
    d.description = g.value()->description();
    for (int k = 0; k < config().frames; ++k) {
        const int f = first_frame(name) + k * kFrameStep;
        d.frame_ids.push_back(f);
        d.frames.push_back(g.value()->frame(f));
        auto t = cullide::exact_pairs(d.frames.back(), cullide::ExactOptions{false, 0});
        if (!t.ok()) {
            std::fprintf(stderr, "pipeline_bench: ground truth of %s frame %d: %s\n", name.c_str(), f,
                         t.error().message.c_str());
            std::fflush(nullptr);
            std::_Exit(1);  // not std::exit: see g_osmesa
        }
        d.truth.push_back(std::move(t.value()));
    }
    return cache[name] = std::move(d);
}

cullide::RunOptions options_for(Method m, int threads, cullide::QueryDevice* device) {
    cullide::RunOptions o;
    o.method = m;
    o.threads = threads;
    o.resolution = 0;  // the method's own default
    o.device = device;
    return o;
}

// The emulator at 1 thread: what every other run of the same scene and method must reproduce.
// Empty (with `error` set) when a frame fails.
const std::vector<FrameResult>& reference(const std::string& scene, Method m, std::string& error) {
    static std::map<std::pair<std::string, Method>, std::vector<FrameResult>> cache;
    auto key = std::make_pair(scene, m);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    const SceneData& d = scene_data(scene);
    std::vector<FrameResult> out;
    for (std::size_t k = 0; k < d.frames.size(); ++k) {
        auto r = cullide::process_frame(d.frames[k], options_for(m, 1, nullptr));
        if (!r.ok()) {
            error = "emulator reference frame " + std::to_string(d.frame_ids[k]) + ": " + r.error().message;
            static const std::vector<FrameResult> kNone;
            return kNone;
        }
        out.push_back(std::move(r.value()));
    }
    return cache[key] = std::move(out);
}

// Empty when the two runs agree on pairs and every count of the visibility passes.
std::string compare(const FrameResult& got, const FrameResult& want) {
    if (got.pairs != want.pairs) return "pairs differ (" + std::to_string(got.pairs.size()) + " vs " + std::to_string(want.pairs.size()) + ")";
    const cullide::FrameStats &a = got.stats, &b = want.stats;
    auto differ = [](const char* what, std::uint64_t x, std::uint64_t y) {
        return std::string(what) + " differ (" + std::to_string(x) + " vs " + std::to_string(y) + ")";
    };
    if (a.pcs_boxes != b.pcs_boxes) return differ("PCS boxes", a.pcs_boxes, b.pcs_boxes);
    if (a.pcs_objects != b.pcs_objects) return differ("PCS objects", a.pcs_objects, b.pcs_objects);
    if (a.pcs_subobjects != b.pcs_subobjects) return differ("PCS sub-objects", a.pcs_subobjects, b.pcs_subobjects);
    if (a.views.size() != b.views.size()) return differ("view counts", a.views.size(), b.views.size());
    for (std::size_t v = 0; v < a.views.size(); ++v) {
        if (a.views[v].items_after != b.views[v].items_after)
            return differ(("items after view " + std::to_string(v)).c_str(), a.views[v].items_after, b.views[v].items_after);
        if (a.views[v].queries != b.views[v].queries)
            return differ(("queries of view " + std::to_string(v)).c_str(), a.views[v].queries, b.views[v].queries);
    }
    if (a.queries != b.queries) return differ("queries", a.queries, b.queries);
    if (a.triangles_rasterized != b.triangles_rasterized)
        return differ("triangles rasterized", a.triangles_rasterized, b.triangles_rasterized);
    return {};
}

int g_refused = 0;  // benchmarks that refused to time: the exit status says so

void refuse(benchmark::State& state, const std::string& why) {
    ++g_refused;
    state.SkipWithError(why.c_str());
}

#if defined(CULLIDE_BENCH_HAVE_OSMESA)
// Destroyed explicitly at the end of main: an OSMesa context destroyed by a static destructor, after
// Mesa's own teardown, crashes in OSMesaDestroyContext.
std::unique_ptr<cullide::QueryDevice> g_osmesa;

cullide::QueryDevice* osmesa_device(std::string& error) {
    std::unique_ptr<cullide::QueryDevice>& dev = g_osmesa;
    static std::string err;
    static bool tried = false;
    if (!tried) {
        tried = true;
        auto d = cullide_oracle::make_osmesa_query_device();
        if (d.ok()) dev = std::move(d.value());
        else err = d.error().message;
    }
    error = err;
    return dev.get();
}
#endif

#if defined(CULLIDE_BENCH_HAVE_OSMESA)
// For the report when OSMesa and the emulator disagree: runs every batch on both (the emulator as
// raster::execute on its own target, as make_emulator_device does) and records the first query whose
// results differ (batch number in the frame, query index, both answers, and the scalar
// raster::execute_reference's answer on the same depth buffer: which side the emulator's own
// reference takes).
class TeeDevice final : public cullide::QueryDevice {
   public:
    explicit TeeDevice(cullide::QueryDevice& gl) : gl_(gl) {}
    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        auto t = raster::DepthTarget::create(width, height, format);
        if (!t.ok()) return t.error();
        target_ = std::make_unique<raster::DepthTarget>(std::move(t.value()));
        size_ = std::to_string(width) + "x" + std::to_string(height);
        return gl_.clear(width, height, format);
    }
    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        if (!target_) return cullide::Error{"tee device: execute before clear"};
        const raster::DepthTarget before = *target_;
        auto e = raster::execute(*target_, batch, raster::ExecuteOptions{1});
        auto g = gl_.execute(batch);
        ++batches_;
        if (!e.ok()) return cullide::Error{e.error().message};
        if (!g.ok()) {
            if (first_.empty()) first_ = "batch " + std::to_string(batches_) + ": GL failed: " + g.error().message;
            return e.value();
        }
        for (std::size_t q = 0; first_.empty() && q < e.value().size() && q < g.value().size(); ++q) {
            const bool any = batch.query_kinds()[q] == raster::QueryKind::AnySamplesPassed;
            if (any ? (e.value()[q] > 0) == (g.value()[q] > 0) : e.value()[q] == g.value()[q]) continue;
            raster::DepthTarget copy = before;
            auto r = raster::execute_reference(copy, batch, raster::ExecuteOptions{1, false});
            first_ = "first differing query: batch " + std::to_string(batches_) + " (" + size_ + ", " +
                     std::to_string(batch.commands().size()) + " commands), query " + std::to_string(q) + " of " +
                     std::to_string(e.value().size()) + ": emulator " + std::to_string(e.value()[q]) + ", osmesa " +
                     std::to_string(g.value()[q]) + ", scalar reference " +
                     (r.ok() ? std::to_string(r.value()[q]) : "failed: " + r.error().message);
        }
        return e.value();
    }
    std::string name() const override { return "tee"; }
    const std::string& first_difference() const { return first_; }

   private:
    cullide::QueryDevice& gl_;
    std::unique_ptr<raster::DepthTarget> target_;
    std::string size_;
    std::uint64_t batches_ = 0;
    std::string first_;
};
#endif

// Hands each batch to the GL device in pieces of at most N queries (--gl-chunk=N; the depth
// buffer carries over between execute() calls). Before issue #17 was understood this was how the
// OSMesa rows agreed at all (whole batches of thousands of queries met llvmpipe's over-count);
// the OSMesa device now bounds llvmpipe's scenes itself, and this stays for comparing timings.
class ChunkedDevice final : public cullide::QueryDevice {
   public:
    ChunkedDevice(cullide::QueryDevice& gl, int chunk) : gl_(gl), chunk_(chunk) {}
    cullide::Status clear(int width, int height, raster::DepthFormat format) override { return gl_.clear(width, height, format); }
    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        raster::QueryResults out;
        raster::CommandBatch part(batch.target_width(), batch.target_height());
        int in_part = 0;
        auto flush = [&]() -> cullide::Status {
            auto r = gl_.execute(part);
            if (!r.ok()) return r.error();
            out.insert(out.end(), r.value().begin(), r.value().end());
            part = raster::CommandBatch(batch.target_width(), batch.target_height());
            in_part = 0;
            return {};
        };
        for (const raster::Command& c : batch.commands()) {
            if (c.kind == raster::Command::Kind::BeginQuery) {
                if (in_part >= chunk_)
                    if (cullide::Status st = flush(); !st) return st.error();
                (void)part.begin_query(batch.query_kinds()[c.query]);
                ++in_part;
            } else if (c.kind == raster::Command::Kind::EndQuery) {
                part.end_query();
            } else {
                part.draw(c.mesh, c.state);
            }
        }
        if (cullide::Status st = flush(); !st) return st.error();
        return out;
    }
    std::string name() const override { return "chunked " + gl_.name(); }

   private:
    cullide::QueryDevice& gl_;
    int chunk_;
};

// Where OSMesa and the emulator part (empty when not on OSMesa or nothing found).
std::string locate_difference([[maybe_unused]] const cullide::Frame& objects, [[maybe_unused]] cullide::RunOptions opts) {
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
    if (opts.device == nullptr) return {};
    TeeDevice tee(*opts.device);
    opts.device = &tee;
    (void)cullide::process_frame(objects, opts);
    return tee.first_difference().empty() ? std::string() : "; " + tee.first_difference();
#else
    return {};
#endif
}

void bm_pipeline(benchmark::State& state, const std::string& scene, Method m, bool on_osmesa, int threads) {
    const std::string where = scene + " / " + cullide::to_string(m) + (on_osmesa ? " / osmesa" : " / emulator");
    cullide::QueryDevice* device = nullptr;
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
    if (on_osmesa) {
        std::string err;
        device = osmesa_device(err);
        if (device == nullptr) {
            refuse(state, "OSMesa device: " + err);
            return;
        }
        static std::unique_ptr<ChunkedDevice> chunked;
        if (config().gl_chunk > 0) {
            if (!chunked) chunked = std::make_unique<ChunkedDevice>(*device, config().gl_chunk);
            device = chunked.get();
        }
    }
#else
    if (on_osmesa) {
        refuse(state, "OSMesa oracle not built");
        return;
    }
#endif
    const SceneData& d = scene_data(scene);
    std::string err;
    const std::vector<FrameResult>& ref = reference(scene, m, err);
    if (ref.size() != d.frames.size()) {
        refuse(state, where + ": " + err + ": not timing");
        return;
    }
    const cullide::RunOptions opts = options_for(m, threads, device);

    // The check (untimed; it also warms caches and the GL context).
    double pairs = 0, misses = 0, pcs_boxes = 0, pcs_objects = 0, pcs_sub = 0, queries = 0;
    for (std::size_t k = 0; k < d.frames.size(); ++k) {
        const std::string at = where + " frame " + std::to_string(d.frame_ids[k]);
        auto r = cullide::process_frame(d.frames[k], opts);
        if (!r.ok()) {
            refuse(state, at + ": " + r.error().message + locate_difference(d.frames[k], opts) + ": not timing");
            return;
        }
        const FrameResult& fr = r.value();
        const std::vector<TrianglePair>& truth = d.truth[k];
        std::vector<TrianglePair> extra, missing;
        std::set_difference(fr.pairs.begin(), fr.pairs.end(), truth.begin(), truth.end(), std::back_inserter(extra));
        std::set_difference(truth.begin(), truth.end(), fr.pairs.begin(), fr.pairs.end(), std::back_inserter(missing));
        if (!extra.empty()) {
            refuse(state, at + ": " + std::to_string(extra.size()) + " pairs not in the ground truth: not timing");
            return;
        }
        if (never_misses(m) && !missing.empty()) {
            refuse(state, at + ": misses " + std::to_string(missing.size()) + " ground-truth pairs: not timing");
            return;
        }
        if (std::string diff = compare(fr, ref[k]); !diff.empty()) {
            refuse(state, at + ": " + diff + " from the emulator at 1 thread" + locate_difference(d.frames[k], opts) +
                              ": not timing");
            return;
        }
        pairs += static_cast<double>(fr.pairs.size());
        misses += static_cast<double>(missing.size());
        pcs_boxes += static_cast<double>(fr.stats.pcs_boxes);
        pcs_objects += static_cast<double>(fr.stats.pcs_objects);
        pcs_sub += static_cast<double>(fr.stats.pcs_subobjects);
        queries += static_cast<double>(fr.stats.queries);
    }

    for (auto _ : state) {
        double seconds = 0;
        for (const cullide::Frame& objects : d.frames) {
            const auto t0 = std::chrono::steady_clock::now();
            auto r = cullide::process_frame(objects, opts);
            const auto t1 = std::chrono::steady_clock::now();
            benchmark::DoNotOptimize(r);
            seconds += std::chrono::duration<double>(t1 - t0).count();
        }
        state.SetIterationTime(seconds / static_cast<double>(d.frames.size()));
    }
    const double n = static_cast<double>(d.frames.size());
    state.counters["pairs"] = pairs / n;
    state.counters["misses"] = misses / n;
    state.counters["pcs_boxes"] = pcs_boxes / n;
    state.counters["pcs_objects"] = pcs_objects / n;
    state.counters["pcs_subobj"] = pcs_sub / n;
    state.counters["queries"] = queries / n;
    state.counters["res"] = m == Method::Exact ? 0 : cullide::default_resolution(m);
    state.SetLabel(on_osmesa ? "osmesa-llvmpipe" : (m == Method::Exact ? "cpu" : "emulator"));
}

std::vector<std::string> split(const std::string& v) {
    std::vector<std::string> out;
    std::stringstream ss(v);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(item);
    return out;
}

[[noreturn]] void usage_error(const std::string& msg) {
    std::fprintf(stderr, "pipeline_bench: %s\n", msg.c_str());
    std::exit(2);
}

double parse_scale(const std::string& what, const std::string& s) {
    char* end = nullptr;
    const double x = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !(x > 0) || x > 100)
        usage_error(what + ": scale must be a number in (0, 100] (got '" + s + "')");
    return x;
}

int parse_count(const std::string& what, const std::string& s, int hi) {
    char* end = nullptr;
    const long x = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || end != s.c_str() + s.size() || x < 1 || x > hi)
        usage_error(what + " must be an integer in 1.." + std::to_string(hi) + " (got '" + s + "')");
    return static_cast<int>(x);
}

// Takes this program's own flags out of argv (Google Benchmark rejects unknown ones).
void parse_own_flags(int& argc, char** argv) {
    Config& c = config();
    c.scenes = cullide::scene_names();
    const std::vector<std::string> names = cullide::scene_names();
    auto known = [&](const std::string& s) { return std::find(names.begin(), names.end(), s) != names.end(); };
    int out = 1;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&](const char* flag) -> std::string { return a.substr(std::string(flag).size()); };
        if (a.rfind("--scenes=", 0) == 0) {
            c.scenes.clear();
            for (const std::string& s : split(value("--scenes="))) {
                if (s == "all") c.scenes = names;
                else if (!known(s)) usage_error("--scenes: unknown scene '" + s + "'");
                else c.scenes.push_back(s);
            }
        } else if (a.rfind("--scale=", 0) == 0) {
            for (const std::string& s : split(value("--scale="))) {
                const auto eq = s.find('=');
                if (eq == std::string::npos) {
                    c.default_scale = parse_scale("--scale", s);
                } else {
                    const std::string scene = s.substr(0, eq);
                    if (!known(scene)) usage_error("--scale: unknown scene '" + scene + "'");
                    c.scale_of[scene] = parse_scale("--scale " + scene, s.substr(eq + 1));
                }
            }
        } else if (a.rfind("--frames=", 0) == 0) {
            c.frames = parse_count("--frames", value("--frames="), 1000);
        } else if (a.rfind("--gl-chunk=", 0) == 0) {
            c.gl_chunk = value("--gl-chunk=") == "0" ? 0 : parse_count("--gl-chunk", value("--gl-chunk="), 1000000);
        } else if (a.rfind("--reps=", 0) == 0) {
            c.reps = parse_count("--reps", value("--reps="), 1000);
        } else if (a.rfind("--methods=", 0) == 0) {
            c.methods.clear();
            for (const std::string& s : split(value("--methods="))) {
                auto m = cullide::parse_method(s);
                if (!m.ok()) usage_error("--methods: " + m.error().message);
                c.methods.push_back(m.value());
            }
        } else {
            argv[out++] = argv[i];
        }
    }
    argc = out;
    argv[argc] = nullptr;
}

std::string fmt_scale(double s) {
    std::ostringstream os;
    os << s;
    return os.str();
}

}  // namespace

int main(int argc, char** argv) {
    // As the cullide command does (cullide/pipeline.h); OSMesa runs in this process too.
    const bool retained = cullide::retain_freed_memory();
    parse_own_flags(argc, argv);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    const Config& c = config();

    const char* lp = std::getenv("LP_NUM_THREADS");
    benchmark::AddCustomContext("retain_freed_memory", retained ? "yes" : "no");
    benchmark::AddCustomContext("llvmpipe_threads",
                                lp != nullptr ? std::string("LP_NUM_THREADS=") + lp
                                              : "default: one per core (" + std::to_string(std::thread::hardware_concurrency()) + ")");
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
    {
        std::string err;
        cullide::QueryDevice* dev = osmesa_device(err);
        // The GL context (and so the renderer string) exists once a target was cleared.
        if (dev != nullptr && !dev->clear(16, 16, raster::DepthFormat::D24).ok()) err = "clear failed";
        benchmark::AddCustomContext("osmesa_device", dev != nullptr ? dev->name() : "unavailable: " + err);
    }
#else
    benchmark::AddCustomContext("osmesa_device", "not built (CULLIDE_HAVE_OSMESA off)");
#endif
    benchmark::AddCustomContext("not_on_osmesa", "rcullide, qcullide (exact-bounds raster mode: emulator only)");
    benchmark::AddCustomContext("resolutions", "rcullide " + std::to_string(cullide::default_resolution(Method::RCullide)) +
                                                   ", cullide / rcullide-offset / qcullide / qcullide-gl " +
                                                   std::to_string(cullide::default_resolution(Method::Cullide)) + ", D24");
    benchmark::AddCustomContext("osmesa_batches", c.gl_chunk > 0 ? "in pieces of at most " + std::to_string(c.gl_chunk) + " queries"
                                                                 : "whole");
    benchmark::AddCustomContext("frames", std::to_string(c.frames) + " per scene, from the scene's first colliding frame, step " +
                                              std::to_string(kFrameStep) + "; " + std::to_string(c.reps) + " timed runs");

    for (const std::string& scene : c.scenes) {
        cullide::SceneOptions so;
        so.scale = c.scale(scene);
        so.mesh_dir = CULLIDE_SHARED_MESH_DIR;
        auto g = cullide::make_scene(scene, so);
        benchmark::AddCustomContext("scene " + scene, g.ok() ? g.value()->description() : g.error().message);
    }
    for (const std::string& scene : c.scenes) {
        const std::string sname = scene + "@" + fmt_scale(c.scale(scene));
        for (Method m : c.methods) {
            std::vector<bool> devices{false};
            if (m != Method::Exact && !exact_bounds(m)) devices.push_back(true);
            for (bool gl : devices) {
                for (int threads : {1, 2}) {
                    if (gl && threads == 1) continue;  // llvmpipe has its own threads; host stages at 2
                    const std::string name = "pipeline/" + sname + "/" + cullide::to_string(m) + "/" +
                                             (gl ? "osmesa" : (m == Method::Exact ? "cpu" : "emulator")) +
                                             "/threads:" + std::to_string(threads);
                    benchmark::RegisterBenchmark(name.c_str(), [scene, m, gl, threads](benchmark::State& st) {
                        bm_pipeline(st, scene, m, gl, threads);
                    })
                        ->Iterations(c.reps)
                        ->UseManualTime()
                        ->Unit(benchmark::kMillisecond);
                }
            }
        }
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
#if defined(CULLIDE_BENCH_HAVE_OSMESA)
    g_osmesa.reset();
#endif
    if (g_refused > 0) {
        std::fprintf(stderr, "pipeline_bench: %d benchmark(s) refused to time (ERROR rows above)\n", g_refused);
        return 1;
    }
    return 0;
}
