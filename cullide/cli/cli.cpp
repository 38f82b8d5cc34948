#include "cli.h"

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "bench.h"
#include "help.h"
#include "hunt.h"
#include "options.h"
#include "cullide/mesh_io.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"

namespace cullide::cli {

std::string json_escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '"' || c == '\\') {
            o += '\\';
            o += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
            o += buf;
        } else {
            o += c;
        }
    }
    return o;
}

namespace {

struct RunArgs {
    std::vector<std::string> scene;
    RunOptions options;
    std::optional<int> frames;
    std::string pairs_file;
    bool json = false;
    SceneOptions scene_options;
};

// run's own defaults, after the table's: a method without --resolution runs at its
// default_resolution (printed, so the text and JSON show the real figure). --self without --method
// runs the default, auto, which runs exact then (it used to run qcullide, measured slower than exact
// with self-collision: docs/quick-cullide.md).
RunArgs run_args_of(const Settings& s) {
    RunOptions p = s.pipeline;
    if (p.resolution == 0) p.resolution = default_resolution(p.method);
    return RunArgs{s.inputs, p, s.frames, s.pairs_file, s.json, s.scene};
}

bool is_builtin(const std::string& name) {
    for (const std::string& s : scene_names()) {
        if (s == name) return true;
    }
    return false;
}

int run_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
    const Settings settings = parse_options(Command::Run, args);
    if (settings.help) {
        out << command_help(Command::Run);
        return 0;
    }
    RunArgs r = run_args_of(settings);
    if (r.scene.empty()) r.scene.push_back("cylinders");

    // The frame source: a built-in generator, or the objects of the given files (static).
    std::unique_ptr<SceneGenerator> generator;
    std::vector<Mesh> file_objects;
    std::vector<MeshReadInfo> file_infos;  // one per file argument: what its reader skipped (--json)
    std::string scene_label;
    if (r.scene.size() == 1 && is_builtin(r.scene[0])) {
        Result<std::unique_ptr<SceneGenerator>> g = make_scene(r.scene[0], r.scene_options);
        if (!g) {
            err << "cullide: error: " << g.error().message << "\n";
            return 1;
        }
        generator = std::move(g).value();
        scene_label = generator->name();
    } else {
        for (const std::string& path : r.scene) {
            if (is_builtin(path)) throw UsageError{"give one built-in scene or mesh files, not both ('" + path + "')"};
            MeshReadInfo info;
            Result<std::vector<Mesh>> meshes = read_mesh_file(path, &info);
            if (!meshes) {
                err << "cullide: error: " << meshes.error().message << "\n";
                return 1;
            }
            file_infos.push_back(info);
            for (Mesh& m : meshes.value()) file_objects.push_back(std::move(m));
            scene_label += (scene_label.empty() ? "" : " ") + path;
        }
    }
    const int frames = r.frames.value_or(generator ? 10 : 1);

    std::ofstream pairs_out;
    if (!r.pairs_file.empty()) {
        pairs_out.open(r.pairs_file, std::ios::out | std::ios::trunc);
        if (!pairs_out) {
            err << "cullide: error: cannot open '" << r.pairs_file << "' for writing\n";
            return 1;
        }
        pairs_out << "frame,object_a,triangle_a,object_b,triangle_b\n";
    }

    const bool visibility = r.options.method != Method::Exact;
    if (r.json) {
        out << "{\"scene\": \"" << json_escape(scene_label) << "\", \"method\": \"" << to_string(r.options.method)
            << "\", \"self\": " << (r.options.self ? "true" : "false") << ", \"resolution\": "
            << r.options.resolution << ", \"depth_format\": \"" << to_string(r.options.depth_format)
            << "\", \"subobject\": " << r.options.subobject_triangles << ", \"rounds\": " << r.options.max_rounds
            << ", \"broadphase\": \"" << to_string(r.options.broadphase) << "\", \"inputs\": [";
        // Per mesh file (none for a built-in scene): the statements its reader read and dropped.
        for (std::size_t i = 0; i < file_infos.size(); ++i) {
            out << (i ? ", " : "") << "{\"file\": \"" << json_escape(r.scene[i]) << "\", \"skipped\": {";
            bool first_key = true;
            for (const auto& [keyword, count] : file_infos[i].skipped()) {
                out << (first_key ? "" : ", ") << '"' << keyword << "\": " << count;
                first_key = false;
            }
            out << "}}";
        }
        out << "], \"frames\": [";
    } else {
        out << "cullide run: scene " << scene_label << ", method " << to_string(r.options.method)
            << (r.options.self ? ", self-collision on" : "");
        if (visibility) {
            out << ", resolution " << r.options.resolution << ", depth " << to_string(r.options.depth_format)
                << ", sub-object " << r.options.subobject_triangles << " triangles";
            if (r.options.gpu_rules != raster::RasterRules::GlLlvmpipe)
                out << ", gpu rules " << to_string(r.options.gpu_rules);
        }
        if (r.options.broadphase != BroadPhase::None) out << ", broad phase " << to_string(r.options.broadphase);
        out << ", " << frames << " frame" << (frames == 1 ? "" : "s") << "\n";
    }
    double total_ms = 0;
    std::uint64_t total_pairs = 0;
    FrameContext context;  // kept from frame to frame (pipeline.h): the same results, less set-up
    for (int f = 0; f < frames; ++f) {
        Frame frame_objects;
        if (generator) frame_objects = generator->frame(f);
        std::span<const Mesh> objects = generator ? std::span<const Mesh>(frame_objects) : file_objects;
        Result<FrameResult> fr = process_frame(objects, r.options, context);
        if (!fr) {
            if (r.json) out << "]}\n";
            err << "cullide: error: frame " << f << ": " << fr.error().message << "\n";
            return 1;
        }
        const FrameResult& res = fr.value();
        const FrameStats& s = res.stats;
        total_ms += s.time_ms;
        total_pairs += res.pairs.size();
        if (r.json) {
            out << (f ? ", " : "") << "{\"frame\": " << f << ", \"objects\": " << s.objects
                << ", \"triangles\": " << s.triangles << ", \"triangle_pairs\": " << res.pairs.size()
                << ", \"object_pairs\": " << res.object_pairs.size()
                << ", \"candidate_triangles\": " << s.candidate_triangles << ", \"exact_tests\": " << s.exact_tests
                << ", \"adjacent_skipped\": " << s.adjacent_skipped << ", \"broadphase_objects\": "
                << s.broadphase_objects << ", \"broadphase_pairs\": " << s.broadphase_pairs
                << ", \"pcs_boxes\": " << s.pcs_boxes << ", \"pcs_objects\": " << s.pcs_objects
                << ", \"subobjects\": " << s.subobjects << ", \"pcs_subobjects\": " << s.pcs_subobjects
                << ", \"subobject_pairs\": " << s.subobject_pairs << ", \"queries\": " << s.queries
                << ", \"triangles_rasterized\": " << s.triangles_rasterized;
            if (r.options.method == Method::Auto) {
                const AutoPlan& ap = s.auto_plan;
                out << ", \"auto\": {\"views\": " << (ap.views ? "true" : "false")
                    << ", \"task_triangles\": " << static_cast<std::uint64_t>(ap.task_triangles)
                    << ", \"paired_triangles\": " << ap.paired_triangles << ", \"object_pairs\": " << ap.object_pairs
                    << "}";
            }
            out << ", \"views\": [";
            for (std::size_t v = 0; v < s.views.size(); ++v) {
                const ViewStats& vs = s.views[v];
                out << (v ? ", " : "") << "{\"stage\": \"" << to_string(vs.stage) << "\", \"axis\": \""
                    << "xyz"[vs.axis] << "\", \"before\": " << vs.items_before << ", \"after\": " << vs.items_after
                    << ", \"queries\": " << vs.queries << ", \"triangles_rasterized\": " << vs.triangles_rasterized
                    << "}";
            }
            out << "], " << std::fixed << std::setprecision(3) << "\"broadphase_ms\": " << s.broadphase_ms
                << ", \"boxes_ms\": " << s.boxes_ms << ", \"objects_ms\": " << s.objects_ms
                << ", \"subobjects_ms\": " << s.subobjects_ms << ", \"exact_ms\": " << s.exact_ms
                << ", \"time_ms\": " << s.time_ms << std::defaultfloat << "}";
        } else {
            out << "frame " << f << ": " << s.objects << " objects, " << s.triangles << " triangles -> "
                << res.pairs.size() << " colliding triangle pairs, " << res.object_pairs.size()
                << " object pairs (" << s.candidate_triangles << " candidate triangles, " << s.exact_tests
                << " exact tests) " << std::fixed << std::setprecision(2) << s.time_ms << " ms"
                << std::defaultfloat << "\n";
            if (r.options.broadphase != BroadPhase::None) {
                out << "  broad phase: " << s.broadphase_objects << " of " << s.objects << " objects kept, "
                    << s.broadphase_pairs << " box pairs, " << std::fixed << std::setprecision(2) << s.broadphase_ms
                    << " ms" << std::defaultfloat << "\n";
            }
            const bool is_auto = r.options.method == Method::Auto;
            if (is_auto) {
                const AutoPlan& ap = s.auto_plan;
                out << "  auto: " << (ap.views ? "rcullide's views" : "straight to the exact stage") << " (estimated "
                    << static_cast<std::uint64_t>(ap.task_triangles) << " task triangles for " << ap.paired_triangles
                    << " paired triangles in " << ap.object_pairs << " object pairs)\n";
            }
            if (visibility && (!is_auto || s.auto_plan.views)) {
                const bool object_views = std::any_of(s.views.begin(), s.views.end(),
                                                      [](const ViewStats& v) { return v.stage == CullStage::Objects; });
                out << "  pcs: boxes " << s.broadphase_objects << " -> " << s.pcs_boxes << " objects, triangles -> "
                    << s.pcs_objects << " objects" << (object_views ? "" : " (stage skipped)") << ", sub-objects " << s.subobjects << " -> " << s.pcs_subobjects
                    << "; " << s.subobject_pairs << " sub-object pairs; " << s.queries << " queries, "
                    << s.triangles_rasterized << " triangles rasterized, " << s.views.size() << " views\n"
                    << "  ms: boxes " << std::fixed << std::setprecision(2) << s.boxes_ms << ", objects "
                    << s.objects_ms << ", sub-objects " << s.subobjects_ms << ", exact " << s.exact_ms
                    << std::defaultfloat << "\n";
            }
        }
        if (pairs_out.is_open()) {
            for (const TrianglePair& p : res.pairs) {
                pairs_out << f << ',' << p.object_a << ',' << p.triangle_a << ',' << p.object_b << ','
                          << p.triangle_b << '\n';
            }
        }
    }
    if (r.json) {
        out << "]}\n";
    } else {
        out << "total: " << total_pairs << " colliding triangle pairs in " << frames << " frame"
            << (frames == 1 ? "" : "s") << ", " << std::fixed << std::setprecision(2)
            << total_ms / frames << " ms per frame" << std::defaultfloat << "\n";
    }
    if (pairs_out.is_open()) {
        pairs_out.close();
        if (!pairs_out) {
            err << "cullide: error: writing '" << r.pairs_file << "' failed\n";
            return 1;
        }
    }
    return 0;
}

// `cullide help [COMMAND] [--man]`.
int help_command(const std::vector<std::string>& args, std::ostream& out) {
    if (args.size() == 1) {
        out << usage_text();
        return 0;
    }
    if (args.size() == 2 && args[1] == "--man") {
        out << man_page();
        return 0;
    }
    if (args.size() == 2) {
        for (Command c : kCommandList) {
            if (args[1] == command_name(c)) {
                out << command_help(c);
                return 0;
            }
        }
    }
    throw UsageError{"help takes one command name (run, bench, sweep, hunt) or --man (got '" + args[1] + "')"};
}

int scenes_command(const std::vector<std::string>& args, std::ostream& out) {
    if (args.size() > 1) throw UsageError{"scenes takes no options or operands (got '" + args[1] + "')"};
    SceneOptions defaults;
    for (const std::string& name : scene_names()) {
        Result<std::unique_ptr<SceneGenerator>> g = make_scene(name, defaults);
        out << name << ": " << (g ? g.value()->description() : g.error().message) << "\n";
    }
    return 0;
}

int version_command(const std::vector<std::string>& args, std::ostream& out) {
    if (args.size() > 1) throw UsageError{"version takes no options (got '" + args[1] + "')"};
    out << version_text();
    return 0;
}

}  // namespace

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
    if (args.empty()) {
        err << usage_text();
        return 2;
    }
    const std::string& command = args[0];
    try {
        if (command == "help" || command == "--help" || command == "-h") return help_command(args, out);
        if (command == "version" || command == "--version") return version_command(args, out);
        if (command == "scenes") return scenes_command(args, out);
        if (command == "bench" || command == "sweep") return bench_command(args, out, err);
        if (command == "hunt") return hunt_command(args, out, err);
        if (command == "run") {
            try {
                return run_command(args, out, err);
            } catch (const UsageError& e) {
                err << "cullide run: " << e.message << "\n(run 'cullide run --help' for usage)\n";
                return 2;
            }
        }
        throw UsageError{"unknown command '" + command + "'"};
    } catch (const UsageError& e) {
        err << "cullide: " << e.message << "\n(run 'cullide help' for usage)\n";
        return 2;
    }
}

}  // namespace cullide::cli
