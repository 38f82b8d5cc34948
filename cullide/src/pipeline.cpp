#include "cullide/pipeline.h"

#include <chrono>
#include <memory>

#include "spatialhash/broad_phase.h"

namespace cullide {
namespace {

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
                                                       {"qcullide-gl", Method::QCullideGL}};
constexpr std::pair<const char*, BroadPhase> kBroadPhases[] = {{"none", BroadPhase::None},
                                                               {"spatialhash", BroadPhase::SpatialHash},
                                                               {"sap", BroadPhase::SweepAndPrune},
                                                               {"brute", BroadPhase::BruteForce}};
constexpr std::pair<const char*, raster::DepthFormat> kDepthFormats[] = {
    {"d16", raster::DepthFormat::D16}, {"d24", raster::DepthFormat::D24}, {"d32f", raster::DepthFormat::D32F}};

template <class E, std::size_t N>
const char* name_of(E e, const std::pair<const char*, E> (&table)[N]) {
    for (const auto& [n, v] : table)
        if (v == e) return n;
    return "?";
}

// Objects whose box overlaps another object's box (all objects for BroadPhase::None).
Result<std::vector<std::uint32_t>> broad_phase(std::span<const Mesh> objects, const RunOptions& o, FrameStats& st) {
    std::vector<std::uint32_t> active;
    if (o.broadphase == BroadPhase::None || o.self) {
        // With self-collision a lone object can still collide with itself: nothing is dropped.
        for (std::size_t i = 0; i < objects.size(); ++i) active.push_back(static_cast<std::uint32_t>(i));
        return active;
    }
    std::vector<spatialhash::Box> boxes(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Aabb b = mesh_bounds(objects[i]);
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

}  // namespace

const char* to_string(Method m) { return name_of(m, kMethods); }
const char* to_string(BroadPhase b) { return name_of(b, kBroadPhases); }
const char* to_string(raster::DepthFormat f) { return name_of(f, kDepthFormats); }

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

int default_resolution(Method m) {
    return m == Method::RCullide   ? kDefaultResolutionRCullide
           : m == Method::QCullide ? kDefaultResolutionQCullide
                                   : kDefaultResolutionOthers;
}

Result<FrameResult> process_frame(std::span<const Mesh> objects, const RunOptions& options) {
    if (options.threads < 0) return Error{"threads must be >= 0 (got " + std::to_string(options.threads) + ")"};
    if (options.self && options.method != Method::Exact && options.method != Method::QCullide &&
        options.method != Method::QCullideGL)
        return Error{std::string("self-collision is not supported by method '") + to_string(options.method) +
                     "' (CULLIDE never tests an object against itself); use method 'qcullide', 'qcullide-gl' "
                     "or 'exact'"};
    const auto start = std::chrono::steady_clock::now();
    if (Status s = validate_scene(objects); !s) return s.error();
    // Every method ends in the exact test: the same range as the ground truth, for all of them
    // (pipeline_fuzz found rcullide accepting a subnormal coordinate that exact refused).
    if (Status s = validate_exact_range(objects); !s) return s.error();
    if (objects.size() > UINT32_MAX) return Error{"too many objects (limit 2^32 - 1)"};
    FrameResult result;
    FrameStats& st = result.stats;
    for (const Mesh& m : objects) st.triangles += m.triangles.size();

    const auto bp_start = std::chrono::steady_clock::now();
    Result<std::vector<std::uint32_t>> active = broad_phase(objects, options, st);
    if (!active) return active.error();
    st.broadphase_objects = active.value().size();
    st.broadphase_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - bp_start).count();

    switch (options.method) {
        case Method::Exact: {
            // The exact method on the kept objects only; their indices map back in order, so the
            // list stays sorted.
            std::vector<Mesh> kept_storage;
            std::span<const Mesh> kept = objects;
            const bool all = active.value().size() == objects.size();
            if (!all) {
                for (std::uint32_t i : active.value()) kept_storage.push_back(objects[i]);
                kept = kept_storage;
            }
            const auto t0 = std::chrono::steady_clock::now();
            ExactStats es;
            Result<std::vector<TrianglePair>> pairs = exact_pairs(kept, ExactOptions{options.self, options.threads}, &es);
            if (!pairs) return pairs.error();
            result.pairs = std::move(pairs).value();
            if (!all) {
                for (TrianglePair& p : result.pairs) {
                    p.object_a = active.value()[p.object_a];
                    p.object_b = active.value()[p.object_b];
                }
            }
            st.candidate_triangles = es.candidate_triangles;
            st.exact_tests = es.box_pairs;
            st.adjacent_skipped = es.adjacent_skipped;
            st.exact_ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            break;
        }
        case Method::Cullide:
        case Method::RCullide:
        case Method::RCullideOffset: {
            CullideOptions co;
            co.mode = options.method == Method::Cullide    ? VisibilityMode::GLExact
                      : options.method == Method::RCullide ? VisibilityMode::ExactBounds
                                                           : VisibilityMode::Offset;
            co.resolution = options.resolution == 0 ? default_resolution(options.method) : options.resolution;
            co.depth_format = options.depth_format;
            co.subobject_triangles = options.subobject_triangles;
            co.max_rounds = options.max_rounds;
            co.min_prune = options.min_prune;
            co.object_stage = options.object_stage;
            co.threads = options.threads;
            std::unique_ptr<QueryDevice> own;
            QueryDevice* device = options.device;
            if (device == nullptr) {
                own = make_emulator_device(options.threads);
                device = own.get();
            }
            CullideStats cs;
            Result<std::vector<TrianglePair>> pairs = cullide_pairs(objects, active.value(), co, *device, &cs);
            if (!pairs) return pairs.error();
            result.pairs = std::move(pairs).value();
            st.candidate_triangles = cs.candidate_triangles;
            st.exact_tests = cs.exact_tests;
            st.pcs_boxes = cs.pcs_boxes;
            st.pcs_objects = cs.pcs_objects;
            st.subobjects = cs.subobjects;
            st.pcs_subobjects = cs.pcs_subobjects;
            st.subobject_pairs = cs.subobject_pairs;
            st.queries = cs.queries;
            st.triangles_rasterized = cs.triangles_rasterized;
            st.views = std::move(cs.views);
            st.boxes_ms = cs.boxes_ms;
            st.objects_ms = cs.objects_ms;
            st.subobjects_ms = cs.subobjects_ms;
            st.exact_ms = cs.exact_ms;
            break;
        }
        case Method::QCullide:
        case Method::QCullideGL: {
            QuickOptions qo;
            qo.mode = options.method == Method::QCullide ? VisibilityMode::ExactBounds : VisibilityMode::GLExact;
            qo.self = options.self;
            qo.resolution = options.resolution == 0 ? default_resolution(options.method) : options.resolution;
            qo.depth_format = options.depth_format;
            qo.subobject_triangles = options.subobject_triangles;
            qo.max_rounds = options.max_rounds;
            qo.threads = options.threads;
            std::unique_ptr<QueryDevice> own;
            QueryDevice* device = options.device;
            if (device == nullptr) {
                own = make_emulator_device(options.threads);
                device = own.get();
            }
            QuickStats qs;
            Result<std::vector<TrianglePair>> pairs = quick_cullide_pairs(objects, active.value(), qo, *device, &qs);
            if (!pairs) return pairs.error();
            result.pairs = std::move(pairs).value();
            st.candidate_triangles = qs.candidate_triangles;
            st.exact_tests = qs.exact_tests;
            st.adjacent_skipped = qs.adjacent_skipped;
            // With self-collision no object leaves at object level (it may collide with itself).
            st.pcs_boxes = options.self ? qs.objects_in : qs.pcs_boxes;
            st.pcs_objects = options.self ? qs.objects_in : qs.pcs_objects;
            st.subobjects = qs.subobjects;
            st.pcs_subobjects = qs.pcs_subobjects;
            st.subobject_pairs = qs.item_pairs_kept;
            st.queries = qs.queries;
            st.triangles_rasterized = qs.triangles_rasterized;
            st.views = std::move(qs.views);
            st.boxes_ms = qs.boxes_ms;
            st.objects_ms = qs.objects_ms;
            st.subobjects_ms = qs.subobjects_ms;
            st.exact_ms = qs.exact_ms;
            break;
        }
    }
    result.object_pairs = object_pairs(result.pairs);
    st.objects = objects.size();
    st.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace cullide
