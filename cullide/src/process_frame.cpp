// process_frame.cpp: one frame through a method (cullide/pipeline.h), and the names of methods,
// broad phases and depth formats.
#include "cullide/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <memory>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "cullide_detail.h"
#include "emulator_device.h"
#include "exact_stage.h"
#include "parallel.h"
#include "spatialhash/broad_phase.h"

namespace cullide {

// What a FrameContext holds (pipeline.h): the emulator device, made on the first visibility frame
// that runs on it and kept with its depth target.
struct FrameContext::State {
    std::unique_ptr<detail::EmulatorDevice> device;
    detail::QuickSelfCache quick_self;  // used only where the frame's topology equals its entry's
};

bool retain_freed_memory() {
#if defined(__GLIBC__)
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.") != nullptr) return false;
    return mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1 && mallopt(M_TRIM_THRESHOLD, 256 << 20) == 1;
#else
    return false;
#endif
}

FrameContext::FrameContext() : state_(std::make_unique<State>()) {}
FrameContext::~FrameContext() = default;
FrameContext::FrameContext(FrameContext&&) noexcept = default;
FrameContext& FrameContext::operator=(FrameContext&&) noexcept = default;

namespace {

// Frames of at most this many triangles run on the calling thread whatever RunOptions::threads
// says: starting a oneTBB arena for each parallel step costs more than such a frame's whole work
// (a 2-triangle rcullide frame: about 640 us with two workers, 100 us on one; docs/cullide.md,
// "Tiny frames"). Results never depend on the thread count, so this changes times only.
constexpr std::uint64_t kSerialFrameTriangles = 64;

template <class E, std::size_t N>
Result<E> parse_name(std::string_view what, std::string_view name, const std::pair<const char*, E> (&table)[N]) {
    std::string valid;
    for (const auto& [n, e] : table) {
        if (name == n) return e;
        valid += (valid.empty() ? "" : ", ") + std::string(n);
    }
    return Error{"unknown " + std::string(what) + " '" + std::string(name) + "' (valid: " + valid + ")"};
}

constexpr std::pair<const char*, Method> kMethods[] = {{"exact", Method::Exact},
                                                       {"cullide", Method::Cullide},
                                                       {"rcullide", Method::RCullide},
                                                       {"rcullide-offset", Method::RCullideOffset},
                                                       {"qcullide", Method::QCullide},
                                                       {"qcullide-gl", Method::QCullideGL},
                                                       {"auto", Method::Auto}};
constexpr std::pair<const char*, BroadPhase> kBroadPhases[] = {{"none", BroadPhase::None},
                                                               {"spatialhash", BroadPhase::SpatialHash},
                                                               {"sap", BroadPhase::SweepAndPrune},
                                                               {"brute", BroadPhase::BruteForce}};
constexpr std::pair<const char*, raster::DepthFormat> kDepthFormats[] = {
    {"d16", raster::DepthFormat::D16}, {"d24", raster::DepthFormat::D24}, {"d32f", raster::DepthFormat::D32F}};
constexpr std::pair<const char*, raster::RasterRules> kGpuRules[] = {{"gl", raster::RasterRules::GlLlvmpipe},
                                                                     {"vulkan", raster::RasterRules::Vulkan}};

template <class E, std::size_t N>
const char* name_of(E e, const std::pair<const char*, E> (&table)[N]) {
    for (const auto& [n, v] : table)
        if (v == e) return n;
    return "?";
}

// Whether the broad phase drops objects: one is chosen, and self-collision is off (with it a lone
// object can still collide with itself).
bool broad_phase_drops(const RunOptions& o) { return o.broadphase != BroadPhase::None && !o.self; }

// Objects whose box overlaps another object's box (all objects when !broad_phase_drops).
Result<std::vector<std::uint32_t>> broad_phase(std::span<const Mesh> objects, const RunOptions& o, FrameStats& st) {
    std::vector<std::uint32_t> active;
    if (!broad_phase_drops(o)) {
        for (std::size_t i = 0; i < objects.size(); ++i) active.push_back(static_cast<std::uint32_t>(i));
        return active;
    }
    std::vector<std::uint32_t> all(objects.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
    const std::vector<Aabb> bounds = detail::object_bounds(objects, all, o.threads);
    std::vector<spatialhash::Box> boxes(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Aabb& b = bounds[i];
        boxes[i] = {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}};
    }
    spatialhash::Options so;
    so.method = o.broadphase == BroadPhase::SpatialHash     ? spatialhash::Method::SpatialHash
                : o.broadphase == BroadPhase::SweepAndPrune ? spatialhash::Method::SweepAndPrune
                                                            : spatialhash::Method::BruteForce;
    so.threads = static_cast<unsigned>(o.threads);
    spatialhash::Result<spatialhash::PairSet> ps = spatialhash::find_pairs(boxes, so);
    if (!ps) return Error{"broad phase: " + ps.error().message};
    std::vector<char> keep(objects.size(), 0);
    for (const spatialhash::Pair& p : ps.value().pairs) keep[p.a] = keep[p.b] = 1;
    for (std::size_t i = 0; i < objects.size(); ++i)
        if (keep[i]) active.push_back(static_cast<std::uint32_t>(i));
    st.broadphase_pairs = ps.value().pairs.size();
    return active;
}

// The exact method on the kept objects only; their indices map back in order, so the list stays
// sorted.
Status run_exact(std::span<const Mesh> objects, const std::vector<std::uint32_t>& active, const RunOptions& o,
                 FrameResult& result) {
    std::vector<Mesh> kept_storage;
    std::span<const Mesh> kept = objects;
    const bool all = active.size() == objects.size();
    if (!all) {
        for (std::uint32_t i : active) kept_storage.push_back(objects[i]);
        kept = kept_storage;
    }
    const auto t0 = std::chrono::steady_clock::now();
    ExactStats es;
    Result<std::vector<TrianglePair>> pairs = exact_pairs(kept, ExactOptions{o.self, o.threads}, &es);
    if (!pairs) return pairs.error();
    result.pairs = std::move(pairs).value();
    if (!all) {
        for (TrianglePair& p : result.pairs) {
            p.object_a = active[p.object_a];
            p.object_b = active[p.object_b];
        }
    }
    FrameStats& st = result.stats;
    st.candidate_triangles = es.candidate_triangles;
    st.exact_tests = es.box_pairs;
    st.adjacent_skipped = es.adjacent_skipped;
    st.exact_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return Status{};
}

// A visibility method: the run's shared options go to the method as they are (VisibilityOptions,
// visibility.h), its shared statistics come back as they are (VisibilityStats); the resolution is
// checked and defaulted by the method's entry point.
Status run_visibility(std::span<const Mesh> objects, const std::vector<std::uint32_t>& active, const RunOptions& o,
                      FrameContext::State& context, FrameResult& result) {
    QueryDevice* device = o.device;
    if (device == nullptr) {
        if (!context.device)
            context.device = std::make_unique<detail::EmulatorDevice>(o.threads);
        else
            context.device->set_threads(o.threads);
        device = context.device.get();
    }
    FrameStats& st = result.stats;
    Result<std::vector<TrianglePair>> pairs = Error{};
    if (o.method == Method::QCullide || o.method == Method::QCullideGL) {
        QuickOptions qo;
        static_cast<VisibilityOptions&>(qo) = o;
        qo.mode = o.method == Method::QCullide ? VisibilityMode::ExactBounds : VisibilityMode::GLExact;
        qo.self = o.self;
        QuickStats qs;
        pairs = detail::quick_cullide_pairs(objects, active, qo, *device, &qs, true,  // checked by process_frame
                                            &context.quick_self);
        static_cast<VisibilityStats&>(st) = std::move(qs);
        st.subobject_pairs = qs.item_pairs_kept;
        // With self-collision no object leaves at object level (it may collide with itself).
        if (o.self) st.pcs_boxes = st.pcs_objects = st.objects_in;
    } else {
        CullideOptions co;
        static_cast<VisibilityOptions&>(co) = o;
        co.mode = o.method == Method::Cullide    ? VisibilityMode::GLExact
                  : o.method == Method::RCullide ? VisibilityMode::ExactBounds
                                                 : VisibilityMode::Offset;
        co.min_prune = o.min_prune;
        co.object_stage = o.object_stage;
        // After a broad phase every active object's box overlaps another's, and R-CULLIDE's box views
        // (exact bounds) never prune such an object (CullideOptions::box_stage): they would cost
        // 0.6 ms of a 4.3 ms cylinders frame at 1 thread and prune nothing. GL-exact CULLIDE keeps
        // them (its views may prune overlapping boxes: that is how it misses), as does the offset
        // method (not argued here).
        co.box_stage = !(co.mode == VisibilityMode::ExactBounds && broad_phase_drops(o));
        CullideStats cs;
        pairs = detail::cullide_pairs(objects, active, co, *device, &cs, true);  // checked by process_frame
        static_cast<VisibilityStats&>(st) = std::move(cs);
        st.subobject_pairs = cs.subobject_pairs;
    }
    if (!pairs) return pairs.error();
    result.pairs = std::move(pairs).value();
    return Status{};
}

// The share of [lo, hi] along one axis that [ilo, ihi] (inside it) covers; 1 for a flat extent
// (a flat box is covered along that axis by any box meeting it).
double axis_share(double lo, double hi, double ilo, double ihi) {
    const double extent = hi - lo;
    if (!(extent > 0.0)) return 1.0;
    return std::clamp((ihi - ilo) / extent, 0.0, 1.0);
}

// The share of box `b` that `i` (their intersection) covers: the product of the per-axis shares.
double box_share(const Aabb& b, const Aabb& i) {
    return axis_share(b.lo.x, b.hi.x, i.lo.x, i.hi.x) * axis_share(b.lo.y, b.hi.y, i.lo.y, i.hi.y) *
           axis_share(b.lo.z, b.hi.z, i.lo.z, i.hi.z);
}

// The boxes of the kept objects' vertex lists (referenced or not): linear passes over the positions,
// where mesh_bounds follows the triangles' indices (three scattered reads per triangle); an empty box
// for an object without triangles. For the estimate only; the exact stage keeps its own boxes. In
// jobs of kBoundsChunk vertices on `threads` workers, folded in job order: the same bits as one pass
// (std::min and std::max keep the earlier of equal values), where one serial pass over the tree of
// leaves' vertices was about a tenth of the frame on the auto route.
constexpr std::size_t kBoundsChunk = 8192;
std::vector<Aabb> kept_vertex_bounds(std::span<const Mesh> objects, std::span<const std::uint32_t> active, int threads) {
    struct Job {
        std::size_t k, first, last;
    };
    std::vector<Job> jobs;
    for (std::size_t k = 0; k < active.size(); ++k) {
        const Mesh& m = objects[active[k]];
        if (m.triangles.empty()) continue;
        for (std::size_t f = 0; f < m.positions.size(); f += kBoundsChunk)
            jobs.push_back({k, f, std::min(m.positions.size(), f + kBoundsChunk)});
    }
    std::vector<Aabb> job_box(jobs.size());
    detail::parallel_chunks(threads, jobs.size(), [&](std::size_t j) {
        const Vec3* const pos = objects[active[jobs[j].k]].positions.data();
#if defined(__SSE2__)
        // x and y in the two lanes of one register, z alone: std::min(lo, p) is (p < lo ? p : lo),
        // _mm_min_pd(p, lo), which also keeps lo for a NaN p and a NaN lo (MINPD returns its second
        // operand then); std::max likewise. The same bits as the scalar loop in 4 operations a vertex.
        __m128d lo_xy = _mm_loadu_pd(&pos[jobs[j].first].x), lo_z = _mm_load_sd(&pos[jobs[j].first].z);
        __m128d hi_xy = lo_xy, hi_z = lo_z;
        for (std::size_t v = jobs[j].first; v < jobs[j].last; ++v) {
            const __m128d xy = _mm_loadu_pd(&pos[v].x), z = _mm_load_sd(&pos[v].z);
            lo_xy = _mm_min_pd(xy, lo_xy);
            lo_z = _mm_min_sd(z, lo_z);
            hi_xy = _mm_max_pd(xy, hi_xy);
            hi_z = _mm_max_sd(z, hi_z);
        }
        job_box[j] = detail::aabb_sse2(lo_xy, lo_z, hi_xy, hi_z);
#else
        // Six doubles in registers.
        double x0 = pos[jobs[j].first].x, y0 = pos[jobs[j].first].y, z0 = pos[jobs[j].first].z;
        double x1 = x0, y1 = y0, z1 = z0;
        for (std::size_t v = jobs[j].first; v < jobs[j].last; ++v) {
            x0 = std::min(x0, pos[v].x);
            y0 = std::min(y0, pos[v].y);
            z0 = std::min(z0, pos[v].z);
            x1 = std::max(x1, pos[v].x);
            y1 = std::max(y1, pos[v].y);
            z1 = std::max(z1, pos[v].z);
        }
        job_box[j] = {{x0, y0, z0}, {x1, y1, z1}};
#endif
    });
    std::vector<Aabb> boxes(active.size());
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        Aabb& b = boxes[jobs[j].k];
        const Aabb& c = job_box[j];
        if (jobs[j].first == 0) {
            b = c;
            continue;
        }
        b.lo = {std::min(b.lo.x, c.lo.x), std::min(b.lo.y, c.lo.y), std::min(b.lo.z, c.lo.z)};
        b.hi = {std::max(b.hi.x, c.hi.x), std::max(b.hi.y, c.hi.y), std::max(b.hi.z, c.hi.z)};
    }
    return boxes;
}

// The pairs (a < b) of overlapping boxes, sorted: a sweep along x over the boxes sorted by their low
// x (every pair of the 151 objects of leaves was 11 K box tests, serial). Only boxes with lo <= hi on
// every axis take part: an empty box overlaps nothing, nor does one with a NaN (the scene is not yet
// checked here), which would also break the sort's ordering.
std::vector<std::pair<std::size_t, std::size_t>> overlapping_boxes(const std::vector<Aabb>& boxes) {
    std::vector<std::size_t> order;
    for (std::size_t k = 0; k < boxes.size(); ++k) {
        const Aabb& b = boxes[k];
        if (b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z) order.push_back(k);
    }
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return boxes[a].lo.x != boxes[b].lo.x ? boxes[a].lo.x < boxes[b].lo.x : a < b;
    });
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t p = 0; p < order.size(); ++p)
        for (std::size_t q = p + 1; q < order.size() && boxes[order[q]].lo.x <= boxes[order[p]].hi.x; ++q)
            if (overlaps(boxes[order[p]], boxes[order[q]]))
                pairs.emplace_back(std::min(order[p], order[q]), std::max(order[p], order[q]));
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

}  // namespace

AutoPlan plan_auto(std::span<const Mesh> objects, std::span<const std::uint32_t> active) {
    return plan_auto(objects, active, 1);
}

AutoPlan plan_auto(std::span<const Mesh> objects, std::span<const std::uint32_t> active, int threads) {
    AutoPlan plan;
    const std::vector<Aabb> boxes = kept_vertex_bounds(objects, active, threads);
    std::vector<char> paired(active.size(), 0);
    for (std::size_t k = 0; k < active.size(); ++k) plan.triangles += objects[active[k]].triangles.size();
    // Every pair of kept objects whose boxes overlap, as the exact stage's task builder finds them,
    // in (a, b) order (the sum below is the same bits for the same pairs in the same order).
    for (const auto& [a, b] : overlapping_boxes(boxes)) {
        const double na = static_cast<double>(objects[active[a]].triangles.size());
        const Aabb i{{std::max(boxes[a].lo.x, boxes[b].lo.x), std::max(boxes[a].lo.y, boxes[b].lo.y),
                      std::max(boxes[a].lo.z, boxes[b].lo.z)},
                     {std::min(boxes[a].hi.x, boxes[b].hi.x), std::min(boxes[a].hi.y, boxes[b].hi.y),
                      std::min(boxes[a].hi.z, boxes[b].hi.z)}};
        const double nb = static_cast<double>(objects[active[b]].triangles.size());
        plan.task_triangles += na * box_share(boxes[a], i) + nb * box_share(boxes[b], i);
        ++plan.object_pairs;
        paired[a] = paired[b] = 1;
    }
    for (std::size_t k = 0; k < active.size(); ++k)
        if (paired[k]) plan.paired_triangles += objects[active[k]].triangles.size();
    plan.views = plan.paired_triangles >= kAutoMinViewTriangles &&
                 plan.task_triangles >= kAutoViewsPay * static_cast<double>(plan.paired_triangles);
    return plan;
}

const char* to_string(Method m) { return name_of(m, kMethods); }
const char* to_string(BroadPhase b) { return name_of(b, kBroadPhases); }
const char* to_string(raster::DepthFormat f) { return name_of(f, kDepthFormats); }
const char* to_string(raster::RasterRules r) { return name_of(r, kGpuRules); }

std::vector<std::string> method_names() {
    std::vector<std::string> names;
    for (const auto& m : kMethods) names.emplace_back(m.first);
    return names;
}

Result<Method> parse_method(std::string_view name) { return parse_name("method", name, kMethods); }
Result<BroadPhase> parse_broadphase(std::string_view name) { return parse_name("broad phase", name, kBroadPhases); }
Result<raster::DepthFormat> parse_depth_format(std::string_view name) {
    return parse_name("depth format", name, kDepthFormats);
}
Result<raster::RasterRules> parse_gpu_rules(std::string_view name) { return parse_name("gpu rules", name, kGpuRules); }

int default_resolution(Method m) {
    switch (m) {
        case Method::RCullide:
        case Method::QCullide:
        case Method::Auto:
            return default_resolution(VisibilityMode::ExactBounds);
        case Method::Exact:
        case Method::Cullide:
        case Method::RCullideOffset:
        case Method::QCullideGL:
            break;
    }
    return kDefaultResolutionOthers;
}

Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options) {
    FrameContext context;
    return process_frame(objects, options, context);
}

Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options, FrameContext& context) {
    // A moved-from context has no state; give it a fresh one rather than fail.
    if (!context.state_) context.state_ = std::make_unique<FrameContext::State>();
    if (options.threads < 0) return Error{"threads must be >= 0 (got " + std::to_string(options.threads) + ")"};
    if (options.self && options.method != Method::Exact && options.method != Method::QCullide &&
        options.method != Method::QCullideGL && options.method != Method::Auto)
        return Error{std::string("self-collision is not supported by method '") + to_string(options.method) +
                     "' (CULLIDE never tests an object against itself); use method 'qcullide', 'qcullide-gl' "
                     "or 'exact'"};
    const auto start = std::chrono::steady_clock::now();
    // A frame that goes straight to exact_pairs over all its objects (no broad phase drops any) is
    // checked there, in its parallel box scan, with the same messages and the same first problem
    // named; the serial checks cost 3-10% of such a frame. Nothing before exact_pairs on that route
    // reads a triangle's indices (plan_auto reads the positions only).
    const bool all_objects = !broad_phase_drops(options);
    const bool checked_later =
        all_objects && (options.method == Method::Exact || options.method == Method::Auto);
    // The frame's triangles, and its worker count: frames of at most kSerialFrameTriangles
    // triangles run on the calling thread (their parallel loops would cost more than their work).
    std::uint64_t triangles = 0;
    for (const Mesh& m : objects) triangles += m.triangles.size();
    RunOptions run = options;
    if (triangles <= kSerialFrameTriangles) run.threads = 1;
    const auto check = [&]() -> Status {
        // validate_scene, then validate_exact_range (every method ends in the exact test: the same
        // range as the ground truth, for all of them; pipeline_fuzz found rcullide accepting a
        // subnormal coordinate that exact refused), with each object checked in its own parallel
        // job: the same first problem named as the two serial scans (they were 6% of the calling
        // thread's time in a 2-thread rcullide cylinders frame, perf).
        const std::size_t n = objects.size();
        // The common case first: one scan in parts of at most detail::kCheckPart positions or
        // triangles (one job per object left a thread alone with the tree of leaves or the cloth:
        // the checks did not get faster with a second thread); the per-object scans below run only
        // when it finds a problem, to name the first one.
        if (!detail::scene_clean(objects, run.threads)) {
            std::vector<Status> mesh_ok(n), range_ok(n);
            detail::parallel_chunks(run.threads, n, [&](std::size_t i) {
                mesh_ok[i] = validate_mesh(objects[i]);
                range_ok[i] = detail::validate_exact_range_of(objects[i], i);
            });
            for (std::size_t i = 0; i < n; ++i)
                if (!mesh_ok[i]) return Error{"object " + std::to_string(i) + ": " + mesh_ok[i].error().message};
            for (std::size_t i = 0; i < n; ++i)
                if (!range_ok[i]) return range_ok[i];
        }
        if (objects.size() > UINT32_MAX) return Error{"too many objects (limit 2^32 - 1)"};
        return {};
    };
    if (!checked_later)
        if (Status s = check(); !s) return s.error();
    FrameResult result;
    FrameStats& st = result.stats;
    st.triangles = triangles;

    const auto bp_start = std::chrono::steady_clock::now();
    Result<std::vector<std::uint32_t>> active = broad_phase(objects, run, st);
    if (!active) return active.error();
    st.broadphase_objects = active.value().size();
    st.broadphase_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - bp_start).count();

    if (run.method == Method::Auto) {
        // Self-collision runs as exact: R-CULLIDE never tests an object against itself.
        if (!run.self) st.auto_plan = plan_auto(objects, active.value(), run.threads);
        run.method = st.auto_plan.views ? Method::RCullide : Method::Exact;
    }
    if (checked_later && run.method != Method::Exact)
        if (Status s = check(); !s) return s.error();
    Status ran = run.method == Method::Exact
                     ? run_exact(objects, active.value(), run, result)
                     : run_visibility(objects, active.value(), run, *context.state_, result);
    if (!ran) return ran.error();
    result.object_pairs = object_pairs(result.pairs);
    st.objects = objects.size();
    st.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace cullide
