#include "embree_interference.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <type_traits>

namespace cullide_oracle {
namespace {

using cullide::Error;
using cullide::Mesh;
using cullide::Result;
using cullide::Tri;
using cullide::TrianglePair;
using cullide::Vec3;

// Triangles per unit of the ray loop: units are fixed ranges, so what a unit computes does not
// depend on the thread count (and the result is sorted anyway).
constexpr std::size_t kTrianglesPerUnit = 4096;

// The first error Embree reports on a device (Embree calls this from whatever thread failed).
struct DeviceErrors {
    std::atomic<bool> failed{false};
    std::string message;
};

void on_device_error(void* user, RTCError code, const char* str) {
    auto* errors = static_cast<DeviceErrors*>(user);
    bool expected = false;
    if (errors->failed.compare_exchange_strong(expected, true)) {
        errors->message = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (str ? str : "");
    }
}

// RAII owners of the Embree handles, released in reverse order of creation.
struct DeviceHandle {
    RTCDevice device = nullptr;
    ~DeviceHandle() {
        if (device) rtcReleaseDevice(device);
    }
};
struct SceneHandle {
    RTCScene scene = nullptr;
    ~SceneHandle() {
        if (scene) rtcReleaseScene(scene);
    }
};

// What the filter needs to know about the edge being cast. Embree hands the filter a pointer to
// the RTCIntersectContext it was given; it is the first member of this standard-layout struct, so
// the filter can recover the rest (the pattern Embree's documentation describes for context data).
struct CastContext {
    RTCIntersectContext rtc;
    std::uint32_t object;
    std::uint32_t triangle;
    bool self;
    const std::uint32_t* welded;  // welded vertex ids of `object` (self only)
    const Tri* triangles;         // triangles of `object`
    std::vector<TrianglePair>* out;
};
static_assert(std::is_standard_layout_v<CastContext>);

bool share_welded_vertex(const std::uint32_t* welded, const Tri& a, const Tri& b) {
    for (std::uint32_t u : a) {
        for (std::uint32_t v : b) {
            if (welded[u] == welded[v]) return true;
        }
    }
    return false;
}

// Records every hit and rejects it, so that Embree keeps traversing and reports all triangles the
// segment meets, not only the nearest.
void record_and_reject(const RTCFilterFunctionNArguments* args) {
    auto* ctx = reinterpret_cast<CastContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        args->valid[i] = 0;
        const std::uint32_t object = RTCHitN_geomID(args->hit, args->N, i);
        const std::uint32_t triangle = RTCHitN_primID(args->hit, args->N, i);
        if (object == ctx->object) {
            if (!ctx->self || triangle == ctx->triangle) continue;
            if (share_welded_vertex(ctx->welded, ctx->triangles[ctx->triangle], ctx->triangles[triangle]))
                continue;
        }
        TrianglePair p{ctx->object, ctx->triangle, object, triangle};
        if (p.object_a > p.object_b || (p.object_a == p.object_b && p.triangle_a > p.triangle_b)) {
            p = {object, triangle, ctx->object, ctx->triangle};
        }
        ctx->out->push_back(p);
    }
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Nearest float, as a double. The float goes through a volatile because g++ 12.2 at -O2 miscompiles
// the plain form: its SLP vectorizer packs two adjacent double->float->double round trips (x and y)
// and folds them into a copy, so x and y came back unrounded (seen in the object code here; the
// test "round_to_float rounds every coordinate" pins it).
double nearest_float(double x) {
    volatile float f = static_cast<float>(x);
    return static_cast<double>(f);
}

}  // namespace

Vec3 round_to_float(const Vec3& p) { return {nearest_float(p.x), nearest_float(p.y), nearest_float(p.z)}; }

Result<std::vector<TrianglePair>> embree_pairs(std::span<const Mesh> objects, const EmbreeOptions& options,
                                               EmbreeStats* stats) {
    if (cullide::Status s = cullide::validate_scene(objects); !s) return s.error();
    if (objects.size() >= RTC_INVALID_GEOMETRY_ID) return Error{"too many objects for Embree geometry ids"};
    if (options.threads < 0) {
        return Error{"threads = " + std::to_string(options.threads) + " is out of range: it must be >= 0"};
    }
    // Embree asserts (and the Debian build keeps assertions: an abort, not an error) that ray origins
    // and directions are within +-1.844e18 (its FLT_LARGE). With every coordinate within 2^59, an
    // origin is within 2^59 and an edge vector within 2^60 (about 1.15e18). The bound also keeps the
    // double->float conversion defined.
    constexpr double kCoordinateLimit = 0x1p59;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Mesh& m = objects[i];
        for (std::size_t v = 0; v < m.positions.size(); ++v) {
            for (int k = 0; k < 3; ++k) {
                const double x = m.positions[v][k];
                if (!(x >= -kCoordinateLimit && x <= kCoordinateLimit)) {
                    char value[32];
                    std::snprintf(value, sizeof value, "%.17g", x);
                    return Error{"object " + std::to_string(i) + ": mesh '" + m.name + "': vertex " +
                                 std::to_string(v) + " coordinate " + "xyz"[k] + " = " + value +
                                 " is outside Embree's range (|x| <= 2^59 = 576460752303423488)"};
                }
            }
        }
    }

    EmbreeStats st;
    const auto build_start = std::chrono::steady_clock::now();
    DeviceErrors errors;
    DeviceHandle device;
    const std::string config = options.threads > 0 ? "threads=" + std::to_string(options.threads) : "";
    device.device = rtcNewDevice(config.c_str());
    if (!device.device) {
        return Error{"rtcNewDevice failed: Embree error " +
                     std::to_string(static_cast<int>(rtcGetDeviceError(nullptr)))};
    }
    rtcSetDeviceErrorFunction(device.device, on_device_error, &errors);
    if (rtcGetDeviceProperty(device.device, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) == 0) {
        return Error{
            "this Embree build has no filter functions (EMBREE_FILTER_FUNCTION=OFF): all hits cannot be "
            "listed"};
    }

    // Without self pairs, an edge's own object is only noise: every ray starts and ends on it, so
    // the triangles around both end points are hit and filtered out (about 12 filter calls a ray
    // on a closed mesh). With at most 32 objects each gets its own ray-mask bit and a ray skips its
    // own object; with more, every object keeps all bits and the filter does the skipping.
    const bool masked = !options.self && objects.size() <= 32 &&
                        rtcGetDeviceProperty(device.device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
    auto object_mask = [masked](std::size_t object) {
        return masked ? 1u << object : std::numeric_limits<unsigned>::max();
    };

    SceneHandle scene;
    scene.scene = rtcNewScene(device.device);
    if (!scene.scene) return Error{errors.message.empty() ? "rtcNewScene failed" : errors.message};
    rtcSetSceneFlags(scene.scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Mesh& m = objects[i];
        RTCGeometry geometry = rtcNewGeometry(device.device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (!geometry) return Error{errors.message.empty() ? "rtcNewGeometry failed" : errors.message};
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
        auto* indices = static_cast<std::uint32_t*>(
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(std::uint32_t), m.triangles.size()));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            return Error{errors.message.empty() ? "rtcSetNewGeometryBuffer failed" : errors.message};
        }
        for (std::size_t v = 0; v < m.positions.size(); ++v) {
            for (int k = 0; k < 3; ++k)
                vertices[3 * v + static_cast<std::size_t>(k)] = static_cast<float>(m.positions[v][k]);
        }
        for (std::size_t t = 0; t < m.triangles.size(); ++t) {
            for (int k = 0; k < 3; ++k)
                indices[3 * t + static_cast<std::size_t>(k)] = m.triangles[t][static_cast<std::size_t>(k)];
        }
        rtcSetGeometryMask(geometry, object_mask(i));
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(scene.scene, geometry, static_cast<unsigned>(i));
        rtcReleaseGeometry(geometry);  // the scene holds its own reference
    }
    rtcCommitScene(scene.scene);
    if (errors.failed.load()) return Error{errors.message};
    st.build_seconds = seconds_since(build_start);

    std::vector<std::vector<std::uint32_t>> welded(objects.size());
    if (options.self) {
        for (std::size_t i = 0; i < objects.size(); ++i) welded[i] = cullide::weld_vertices(objects[i]);
    }

    struct Unit {
        std::uint32_t object;
        std::size_t begin, end;
    };
    std::vector<Unit> units;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        for (std::size_t b = 0; b < objects[i].triangles.size(); b += kTrianglesPerUnit) {
            units.push_back({static_cast<std::uint32_t>(i), b,
                             std::min(objects[i].triangles.size(), b + kTrianglesPerUnit)});
        }
    }
    struct UnitOut {
        std::vector<TrianglePair> pairs;
        std::uint64_t rays = 0, zero_length = 0;
    };
    std::vector<UnitOut> out(units.size());

    const auto cast_start = std::chrono::steady_clock::now();
    auto run_unit = [&](std::size_t u) {
        const Unit& unit = units[u];
        const Mesh& m = objects[unit.object];
        UnitOut& o = out[u];
        CastContext ctx{};
        rtcInitIntersectContext(&ctx.rtc);
        ctx.rtc.filter = record_and_reject;
        ctx.object = unit.object;
        ctx.self = options.self;
        ctx.welded = options.self ? welded[unit.object].data() : nullptr;
        ctx.triangles = m.triangles.data();
        ctx.out = &o.pairs;
        for (std::size_t t = unit.begin; t < unit.end; ++t) {
            ctx.triangle = static_cast<std::uint32_t>(t);
            const Tri& tri = m.triangles[t];
            for (int e = 0; e < 3; ++e) {
                const Vec3 p = round_to_float(m.positions[tri[static_cast<std::size_t>(e)]]);
                const Vec3 q = round_to_float(m.positions[tri[static_cast<std::size_t>((e + 1) % 3)]]);
                // The difference of two floats is exact in double here (|p|, |q| <= FLT_MAX and both
                // on float's grid); rounding it once to float gives the nearest direction.
                const float dx = static_cast<float>(q.x - p.x);
                const float dy = static_cast<float>(q.y - p.y);
                const float dz = static_cast<float>(q.z - p.z);
                if (dx == 0.0f && dy == 0.0f && dz == 0.0f) {
                    ++o.zero_length;
                    continue;
                }
                RTCRay ray{};
                ray.org_x = static_cast<float>(p.x);
                ray.org_y = static_cast<float>(p.y);
                ray.org_z = static_cast<float>(p.z);
                ray.dir_x = dx;
                ray.dir_y = dy;
                ray.dir_z = dz;
                ray.tnear = 0.0f;
                ray.tfar = 1.0f;
                ray.time = 0.0f;
                ray.mask = masked ? ~object_mask(unit.object) : std::numeric_limits<unsigned>::max();
                ray.id = 0;
                ray.flags = 0;
                rtcOccluded1(scene.scene, &ctx.rtc, &ray);
                ++o.rays;
            }
        }
    };

    unsigned workers =
        options.threads > 0 ? static_cast<unsigned>(options.threads) : std::thread::hardware_concurrency();
    workers = std::max(
        1u, std::min<unsigned>(workers, static_cast<unsigned>(std::max<std::size_t>(1, units.size()))));
    std::atomic<std::size_t> next{0};
    auto worker = [&] {
        for (std::size_t u = next.fetch_add(1); u < units.size(); u = next.fetch_add(1)) run_unit(u);
    };
    std::vector<std::thread> pool;
    for (unsigned w = 1; w < workers; ++w) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    if (errors.failed.load()) return Error{errors.message};

    // Merge in unit order, then sort and dedupe: the same pair is found by several edges.
    std::vector<TrianglePair> pairs;
    for (UnitOut& o : out) {
        pairs.insert(pairs.end(), o.pairs.begin(), o.pairs.end());
        st.rays += o.rays;
        st.zero_length_edges += o.zero_length;
    }
    st.hits_recorded = pairs.size();
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    st.cast_seconds = seconds_since(cast_start);
    if (stats) *stats = st;
    return pairs;
}

}  // namespace cullide_oracle
