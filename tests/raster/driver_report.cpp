// driver_report.cpp: the conformance suites' random scenes (scene_gen.h) through a real driver,
// compared with the emulator's reference executor, as a report rather than a pass/fail test: how
// many query results and depth values differ, and by how much. It is how the emulator's two rule
// sets are checked against a GPU's driver on a machine that has one (docs/raster-known-differences.md,
// "Real drivers"), and, with --expect-identical, a test of the EGL and Vulkan oracles themselves on
// Mesa (tests/raster/CMakeLists.txt).
//
//   driver_report --api gl|vulkan [--device NAME] [--scale N] [--seed S] [--json FILE] [--expect-identical]
//                 [--frames] [--frame-resolutions LIST] [--scene-scale S]
//
// --api gl: the GL rules (RasterRules::GlLlvmpipe) through EGL (egl_device.h); --api vulkan: the
// Vulkan rules through Vulkan (vulkan_device.h). --device picks the driver by name (GL_RENDERER or
// the Vulkan device name contains it), e.g. NVIDIA or llvmpipe. --scale multiplies the scene counts
// of the default suites (a tenth of the full ones: 10 scenes each of 64x64, 97x61 and 128x96 and
// one of 1024x768, per depth format); --scale 10 is the full suites. --frames adds whole CULLIDE
// frames: every built-in scene (frame 3, --scene-scale, default 0.05) with the methods that a real
// driver can run (gl: cullide, rcullide-offset, qcullide-gl and its self-collision; vulkan: cullide,
// qcullide-gl and its self-collision), D24, at each of --frame-resolutions (default 64,200,1024),
// on the driver and on the emulator: are the pairs and every view's PCS the same, and how many of the
// ground truth's pairs does each side miss. Exit status: 0, or 1 with
// --expect-identical when anything differs, or 2 on a bad option or a device that cannot be made.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "raster/raster.h"
#include "driver_compare.h"
#include "scene_gen.h"
#if CULLIDE_REPORT_EGL
#include "egl_device.h"
#include "egl_query_device.h"
#endif
#if CULLIDE_REPORT_VULKAN
#include "vulkan_device.h"
#include "vulkan_query_device.h"
#endif

namespace {

const char* format_name(raster::DepthFormat f) {
    return f == raster::DepthFormat::D16 ? "D16" : f == raster::DepthFormat::D24 ? "D24" : "D32F";
}

template <typename Device>
bool run_row(raster_test::DriverRow& row, const std::string& device_name, raster::RasterRules rules, raster::DepthFormat format,
             std::uint64_t seed, std::string& renderer, std::string& error) {
    auto dev = Device::create(row.width, row.height, format, device_name);
    if (!dev.ok()) {
        error = dev.error().message;
        return false;
    }
    if (renderer.empty()) renderer = dev.value()->renderer();
    raster_test::SplitMix64 rng(seed);
    raster_test::Scene scene;
    for (int s = 0; s < row.scenes; ++s) {
        raster_test::SceneOptions o;
        o.width = row.width;
        o.height = row.height;
        o.rules = rules;
        raster_test::build_scene(scene, rng, o);
        dev.value()->clear(scene.clear_depth);
        auto theirs = dev.value()->run(scene.batch);
        if (!theirs.ok()) {
            error = theirs.error().message;
            return false;
        }
        const auto their_depth = dev.value()->read_depth();

        auto target = raster::DepthTarget::create(row.width, row.height, format);
        if (!target.ok() || !target.value().clear(scene.clear_depth).ok()) {
            error = "cannot make the emulator's target";
            return false;
        }
        const std::uint32_t cleared = target.value().values()[0];
        auto ours = raster::execute_reference(target.value(), scene.batch);
        if (!ours.ok() || ours.value().size() != theirs.value().size() ||
            their_depth.size() != target.value().values().size()) {
            error = ours.ok() ? "the two sides returned different numbers of results" : ours.error().message;
            return false;
        }
        raster_test::compare_with_driver(row, ours.value(), theirs.value(), target.value().values(), their_depth,
                                         cleared, seed, s);
    }
    return true;
}

// One whole frame on the driver and on the emulator (same options otherwise).
struct FrameRow {
    std::string scene, method;
    bool self = false;
    int resolution = 0;
    std::size_t truth = 0, emulator_pairs = 0, driver_pairs = 0, emulator_missed = 0, driver_missed = 0;
    std::size_t views = 0, views_differ = 0;
    bool same_pairs = false;
};

std::size_t missed(const std::vector<cullide::TrianglePair>& truth, const std::vector<cullide::TrianglePair>& got) {
    std::vector<cullide::TrianglePair> out;
    std::set_difference(truth.begin(), truth.end(), got.begin(), got.end(), std::back_inserter(out));
    return out.size();
}

bool run_frames(cullide::QueryDevice& device, const std::string& api, const std::vector<int>& resolutions,
                double scene_scale, std::vector<FrameRow>& rows, std::string& error) {
    std::vector<std::pair<cullide::Method, bool>> methods = {{cullide::Method::Cullide, false}};
    if (api == "gl") methods.push_back({cullide::Method::RCullideOffset, false});
    methods.push_back({cullide::Method::QCullideGL, false});
    methods.push_back({cullide::Method::QCullideGL, true});
    for (int resolution : resolutions) {
        for (const std::string& name : cullide::scene_names()) {
            cullide::SceneOptions so;
            so.scale = scene_scale;
            so.mesh_dir = "";
            auto scene = cullide::make_scene(name, so);
            if (!scene.ok()) {
                error = scene.error().message;
                return false;
            }
            const cullide::Frame objects = scene.value()->frame(3);
            for (const auto& [method, self] : methods) {
                cullide::RunOptions o;
                o.method = cullide::Method::Exact;
                o.self = self;
                o.threads = 2;
                auto truth = cullide::process_frame(objects, o);
                o.method = method;
                o.resolution = resolution;
                o.depth_format = raster::DepthFormat::D24;
                if (api == "vulkan") o.gpu_rules = raster::RasterRules::Vulkan;
                auto emu = cullide::process_frame(objects, o);
                o.device = &device;
                auto drv = cullide::process_frame(objects, o);
                if (!truth.ok() || !emu.ok() || !drv.ok()) {
                    error = name + " " + cullide::to_string(method) + ": " +
                            (!truth.ok() ? truth.error().message
                             : !emu.ok() ? emu.error().message
                                         : drv.error().message);
                    return false;
                }
                FrameRow r;
                r.scene = name;
                r.method = cullide::to_string(method);
                r.self = self;
                r.resolution = resolution;
                r.truth = truth.value().pairs.size();
                r.emulator_pairs = emu.value().pairs.size();
                r.driver_pairs = drv.value().pairs.size();
                r.emulator_missed = missed(truth.value().pairs, emu.value().pairs);
                r.driver_missed = missed(truth.value().pairs, drv.value().pairs);
                r.same_pairs = emu.value().pairs == drv.value().pairs;
                const auto& ve = emu.value().stats.views;
                const auto& vd = drv.value().stats.views;
                r.views = std::max(ve.size(), vd.size());
                for (std::size_t v = 0; v < r.views; ++v)
                    if (v >= ve.size() || v >= vd.size() || ve[v].items_after != vd[v].items_after) ++r.views_differ;
                rows.push_back(r);
            }
        }
    }
    return true;
}

int usage(const char* why) {
    std::fprintf(stderr,
                 "driver_report: %s\nusage: driver_report --api gl|vulkan [--device NAME] [--scale N] [--seed S] "
                 "[--json FILE] [--expect-identical] [--frames] [--frame-resolutions LIST] [--scene-scale S]\n",
                 why);
    return 2;
}

std::string json_string(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) < 0x20) continue;
        out += c;
    }
    return out + "\"";
}

}  // namespace

int main(int argc, char** argv) {
    std::string api, device, json;
    long scale = 1;
    unsigned long long seed = 20261126;
    bool expect_identical = false, frames = false;
    std::vector<int> frame_resolutions = {64, 200, 1024};
    double scene_scale = 0.05;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
        if (a == "--api") {
            const char* v = value();
            if (v == nullptr) return usage("--api needs gl or vulkan");
            api = v;
        } else if (a == "--device") {
            const char* v = value();
            if (v == nullptr) return usage("--device needs a name");
            device = v;
        } else if (a == "--scale") {
            const char* v = value();
            char* end = nullptr;
            scale = v ? std::strtol(v, &end, 10) : 0;
            if (v == nullptr || *end != '\0' || scale < 1 || scale > 1000)
                return usage("--scale needs an integer in 1..1000");
        } else if (a == "--seed") {
            const char* v = value();
            char* end = nullptr;
            seed = v ? std::strtoull(v, &end, 10) : 0;
            if (v == nullptr || *end != '\0') return usage("--seed needs an unsigned integer");
        } else if (a == "--json") {
            const char* v = value();
            if (v == nullptr) return usage("--json needs a file");
            json = v;
        } else if (a == "--expect-identical") {
            expect_identical = true;
        } else if (a == "--frames") {
            frames = true;
        } else if (a == "--frame-resolutions") {
            const char* v = value();
            if (v == nullptr) return usage("--frame-resolutions needs a list like 64,200,1024");
            frame_resolutions.clear();
            std::string list = v;
            for (std::size_t at = 0; at <= list.size();) {
                const std::size_t comma = std::min(list.find(',', at), list.size());
                const std::string item = list.substr(at, comma - at);
                char* end = nullptr;
                const long r = std::strtol(item.c_str(), &end, 10);
                if (item.empty() || *end != '\0' || r < 8 || r > raster::kMaxTargetSize)
                    return usage("--frame-resolutions needs integers in 8..kMaxTargetSize, comma separated");
                frame_resolutions.push_back(static_cast<int>(r));
                at = comma + 1;
            }
        } else if (a == "--scene-scale") {
            const char* v = value();
            char* end = nullptr;
            scene_scale = v ? std::strtod(v, &end) : 0;
            if (v == nullptr || *end != '\0' || !(scene_scale > 0 && scene_scale <= 1))
                return usage("--scene-scale needs a number in (0, 1]");
        } else {
            return usage(("unknown option '" + a + "'").c_str());
        }
    }
    if (api != "gl" && api != "vulkan") return usage("--api must be gl or vulkan");
#if !CULLIDE_REPORT_EGL
    if (api == "gl") return usage("this build has no EGL oracle (CULLIDE_WITH_EGL, libegl-dev and libopengl-dev)");
#endif
#if !CULLIDE_REPORT_VULKAN
    if (api == "vulkan") return usage("this build has no Vulkan oracle (CULLIDE_WITH_VULKAN)");
#endif

    struct Size {
        int w, h, scenes;
    };
    const Size sizes[] = {{64, 64, 10}, {97, 61, 10}, {128, 96, 10}, {1024, 768, 1}};
    const raster::DepthFormat formats[] = {raster::DepthFormat::D16, raster::DepthFormat::D24,
                                           raster::DepthFormat::D32F};
    const raster::RasterRules rules = api == "gl" ? raster::RasterRules::GlLlvmpipe : raster::RasterRules::Vulkan;
    std::vector<raster_test::DriverRow> rows;
    std::string renderer, error;
    std::uint64_t row_seed = seed;
    for (const auto f : formats) {
        for (const auto& sz : sizes) {
            raster_test::DriverRow row;
            row.format = format_name(f);
            row.width = sz.w;
            row.height = sz.h;
            row.scenes = static_cast<int>(sz.scenes * scale);
            bool ok = false;
#if CULLIDE_REPORT_EGL
            if (api == "gl") ok = run_row<cullide_oracle::EglDevice>(row, device, rules, f, row_seed, renderer, error);
#endif
#if CULLIDE_REPORT_VULKAN
            if (api == "vulkan")
                ok = run_row<cullide_oracle::VulkanDevice>(row, device, rules, f, row_seed, renderer, error);
#endif
            if (!ok) {
                std::fprintf(stderr, "driver_report: %s %s %dx%d: %s\n", api.c_str(), row.format.c_str(), sz.w, sz.h,
                             error.c_str());
                return 2;
            }
            ++row_seed;
            rows.push_back(row);
        }
    }

    std::printf("driver: %s (--api %s, rules %s, seed %llu, scale %ld)\n\n", renderer.c_str(), api.c_str(),
                api == "gl" ? "GL" : "Vulkan", seed, scale);
    std::printf("| format | size | scenes | queries | differ | max diff | depth values | differ | by 1 | 2-16 | more "
                "| one side written | max ulp |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    raster_test::DriverRow total;
    for (const raster_test::DriverRow& r : rows) {
        std::printf("| %s | %dx%d | %d | %zu | %zu | %llu | %zu | %zu | %zu | %zu | %zu | %zu | %llu |\n",
                    r.format.c_str(), r.width, r.height, r.scenes, r.queries, r.queries_differ,
                    static_cast<unsigned long long>(r.query_max_diff), r.values, r.values_differ, r.differ_by_1,
                    r.differ_by_2_to_16, r.differ_by_more, r.written_one_side,
                    static_cast<unsigned long long>(r.max_diff));
        total.queries += r.queries;
        total.queries_differ += r.queries_differ;
        total.values += r.values;
        total.values_differ += r.values_differ;
    }
    std::printf("\ntotal: %zu queries (%zu differ), %zu depth values (%zu differ)\n", total.queries,
                total.queries_differ, total.values, total.values_differ);
    for (const raster_test::DriverRow& r : rows) {
        if (!r.first_query.empty()) std::printf("first query difference, %s %dx%d: %s\n", r.format.c_str(), r.width, r.height, r.first_query.c_str());
        if (!r.first_value.empty()) std::printf("first depth difference, %s %dx%d: %s\n", r.format.c_str(), r.width, r.height, r.first_value.c_str());
    }

    std::vector<FrameRow> frame_rows;
    bool frames_identical = true;
    if (frames) {
        std::unique_ptr<cullide::QueryDevice> qd;
#if CULLIDE_REPORT_EGL
        if (api == "gl") {
            auto d = cullide_oracle::make_egl_query_device(device);
            if (d.ok()) qd = std::move(d).value();
        }
#endif
#if CULLIDE_REPORT_VULKAN
        if (api == "vulkan") {
            auto d = cullide_oracle::make_vulkan_query_device(device);
            if (d.ok()) qd = std::move(d).value();
        }
#endif
        if (!qd || !run_frames(*qd, api, frame_resolutions, scene_scale, frame_rows, error)) {
            std::fprintf(stderr, "driver_report: frames: %s\n", qd ? error.c_str() : "no query device");
            return 2;
        }
        std::printf("\nWhole frames (frame 3 of each built-in scene at scale %g, D24): pairs and every view's PCS\n\n",
                    scene_scale);
        std::printf("| scene | method | px | true pairs | emulator pairs | driver pairs | same pairs | views | views "
                    "differ | emulator missed | driver missed |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
        for (const FrameRow& r : frame_rows) {
            std::printf("| %s | %s%s | %d | %zu | %zu | %zu | %s | %zu | %zu | %zu | %zu |\n", r.scene.c_str(),
                        r.method.c_str(), r.self ? " --self" : "", r.resolution, r.truth, r.emulator_pairs,
                        r.driver_pairs, r.same_pairs ? "yes" : "**no**", r.views, r.views_differ, r.emulator_missed,
                        r.driver_missed);
            if (!r.same_pairs || r.views_differ != 0) frames_identical = false;
        }
    }

    if (!json.empty()) {
        std::ofstream out(json);
        out << "{\"api\": " << json_string(api) << ", \"driver\": " << json_string(renderer) << ", \"seed\": " << seed
            << ", \"scale\": " << scale << ", \"rows\": [";
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const raster_test::DriverRow& r = rows[i];
            out << (i ? ",\n  " : "\n  ") << "{\"format\": \"" << r.format << "\", \"width\": " << r.width
                << ", \"height\": " << r.height << ", \"scenes\": " << r.scenes << ", \"queries\": " << r.queries
                << ", \"queries_differ\": " << r.queries_differ << ", \"query_max_diff\": " << r.query_max_diff
                << ", \"depth_values\": " << r.values << ", \"depth_differ\": " << r.values_differ
                << ", \"differ_by_1\": " << r.differ_by_1 << ", \"differ_by_2_to_16\": " << r.differ_by_2_to_16
                << ", \"differ_by_more\": " << r.differ_by_more << ", \"written_one_side\": " << r.written_one_side
                << ", \"max_ulp\": " << r.max_diff << ", \"first_query\": " << json_string(r.first_query)
                << ", \"first_depth\": " << json_string(r.first_value) << "}";
        }
        out << "\n], \"frames\": [";
        for (std::size_t i = 0; i < frame_rows.size(); ++i) {
            const FrameRow& r = frame_rows[i];
            out << (i ? ",\n  " : "\n  ") << "{\"scene\": " << json_string(r.scene) << ", \"method\": "
                << json_string(r.method) << ", \"self\": " << (r.self ? "true" : "false")
                << ", \"resolution\": " << r.resolution << ", \"true_pairs\": " << r.truth
                << ", \"emulator_pairs\": " << r.emulator_pairs << ", \"driver_pairs\": " << r.driver_pairs
                << ", \"same_pairs\": " << (r.same_pairs ? "true" : "false") << ", \"views\": " << r.views
                << ", \"views_differ\": " << r.views_differ << ", \"emulator_missed\": " << r.emulator_missed
                << ", \"driver_missed\": " << r.driver_missed << "}";
        }
        out << "\n]}\n";
        if (!out) {
            std::fprintf(stderr, "driver_report: cannot write %s\n", json.c_str());
            return 2;
        }
    }
    if (expect_identical && (!total.identical() || !frames_identical)) {
        std::printf("driver_report: differences found (--expect-identical)\n");
        return 1;
    }
    return 0;
}
