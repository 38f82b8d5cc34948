#include "cli.h"

#include <charconv>
#include <cmath>
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
#include "cullide/mesh_io.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"

namespace cullide::cli {
namespace {

constexpr const char* kUsage =
    "usage: cullide <command> [options]\n"
    "\n"
    "commands:\n"
    "  run [SCENE...]   detect colliding triangle pairs, frame by frame\n"
    "  scenes           list the built-in scenes\n"
    "  bench            time methods per frame, checked against the ground truth (bench --help)\n"
    "  sweep            resolution x depth format x method x scene: time, PCS, errors (sweep --help)\n"
    "  help             this text\n"
    "\n"
    "SCENE is one built-in scene name (default: cylinders) or mesh files (.obj .ply .stl); each file is\n"
    "one object, or one object per OBJ group, in argument order.\n"
    "\n"
    "run options:\n"
    "  --method M        rcullide (default; R-CULLIDE, exact-bounds conservative raster: never\n"
    "                    misses), exact (the ground truth), cullide (GL-exact visibility culling, may\n"
    "                    miss collisions like the GPU original), rcullide-offset (R-CULLIDE with the\n"
    "                    paper's offset solids: never misses), qcullide (Quick-CULLIDE, exact-bounds:\n"
    "                    never misses; the default with --self), qcullide-gl (Quick-CULLIDE, GL-exact)\n"
    "  --frames N        frames to run (default 10 for built-in scenes, 1 for files; 1..1000000)\n"
    "  --threads T       worker threads, 0 = all cores (default 0); results do not depend on it\n"
    "  --resolution R    view resolution of visibility methods, 16..16384 (default 32 for rcullide\n"
    "                    and qcullide, 1024 for the others)\n"
    "  --depth-format F  depth buffer of visibility methods: d16, d24 (default), d32f\n"
    "  --subobject N     triangles per sub-object of visibility methods, 1..65536 (default 4)\n"
    "  --rounds N        rounds of x, y, z views per visibility stage, 1..1000 (default 4)\n"
    "  --min-prune F     a stage stops after three views in a row that each prune less than F of\n"
    "                    its live triangles, 0 <= F < 1 (default 0.5 for rcullide, 0 for cullide and\n"
    "                    rcullide-offset: stop when nothing more is pruned)\n"
    "  --object-stage S  auto (default: off for rcullide, whose sub-object views prune every object\n"
    "                    an object view would; on for cullide and rcullide-offset), on, off\n"
    "  --broadphase B    first stage on object boxes: none (default), spatialhash, sap, brute;\n"
    "                    objects overlapping no other box are dropped at once\n"
    "  --self            also report pairs inside one object (adjacent triangles excluded); methods\n"
    "                    exact, qcullide, qcullide-gl\n"
    "  --pairs FILE      write every colliding triangle pair as CSV:\n"
    "                    frame,object_a,triangle_a,object_b,triangle_b\n"
    "  --json            print the per-frame results as one JSON document instead of text\n"
    "  --seed S          scene seed, an unsigned 64-bit integer (default 1)\n"
    "  --scale X         scene size factor, 0 < X <= 100 (default 1)\n"
    "  --mesh-dir DIR    where real meshes are read from (default ../shared/data/meshes)\n";

struct UsageError {
    std::string message;
};

template <class T>
std::optional<T> parse_integer(std::string_view s) {
    T v{};
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) return std::nullopt;
    return v;
}

std::optional<double> parse_double(std::string_view s) {
    double v = 0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty() || !std::isfinite(v)) return std::nullopt;
    return v;
}

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

struct RunArgs {
    std::vector<std::string> scene;
    RunOptions options;
    bool method_given = false;  // --self without --method runs qcullide
    bool resolution_given = false;  // else the method's default_resolution
    std::optional<int> frames;
    std::string pairs_file;
    bool json = false;
    SceneOptions scene_options;
};

RunArgs parse_run_args(const std::vector<std::string>& args) {
    RunArgs r;
    auto need_value = [&](std::size_t& i) -> const std::string& {
        if (i + 1 >= args.size()) throw UsageError{"option " + args[i] + " needs a value"};
        return args[++i];
    };
    for (std::size_t i = 1; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--method") {
            const std::string& v = need_value(i);
            Result<Method> m = parse_method(v);
            if (!m) throw UsageError{m.error().message};
            r.options.method = m.value();
            r.method_given = true;
        } else if (a == "--frames") {
            const std::string& v = need_value(i);
            auto n = parse_integer<int>(v);
            if (!n || *n < 1 || *n > 1000000) throw UsageError{"--frames must be an integer in 1..1000000 (got '" + v + "')"};
            r.frames = *n;
        } else if (a == "--threads") {
            const std::string& v = need_value(i);
            auto n = parse_integer<int>(v);
            if (!n || *n < 0 || *n > 1024) throw UsageError{"--threads must be an integer in 0..1024 (got '" + v + "')"};
            r.options.threads = *n;
        } else if (a == "--resolution") {
            const std::string& v = need_value(i);
            auto n = parse_integer<int>(v);
            if (!n || *n < 16 || *n > 16384) {
                throw UsageError{"--resolution must be an integer in 16..16384 (got '" + v + "')"};
            }
            r.options.resolution = *n;
            r.resolution_given = true;
        } else if (a == "--depth-format") {
            Result<raster::DepthFormat> f = parse_depth_format(need_value(i));
            if (!f) throw UsageError{"--depth-format: " + f.error().message};
            r.options.depth_format = f.value();
        } else if (a == "--broadphase") {
            Result<BroadPhase> b = parse_broadphase(need_value(i));
            if (!b) throw UsageError{"--broadphase: " + b.error().message};
            r.options.broadphase = b.value();
        } else if (a == "--subobject") {
            const std::string& v = need_value(i);
            auto n = parse_integer<int>(v);
            if (!n || *n < 1 || *n > 65536) throw UsageError{"--subobject must be an integer in 1..65536 (got '" + v + "')"};
            r.options.subobject_triangles = *n;
        } else if (a == "--rounds") {
            const std::string& v = need_value(i);
            auto n = parse_integer<int>(v);
            if (!n || *n < 1 || *n > 1000) throw UsageError{"--rounds must be an integer in 1..1000 (got '" + v + "')"};
            r.options.max_rounds = *n;
        } else if (a == "--min-prune") {
            const std::string& v = need_value(i);
            auto x = parse_double(v);
            if (!x || !(*x >= 0) || !(*x < 1)) throw UsageError{"--min-prune must be a number in [0, 1) (got '" + v + "')"};
            r.options.min_prune = *x;
        } else if (a == "--object-stage") {
            const std::string& v = need_value(i);
            if (v == "auto") r.options.object_stage = ObjectStage::Auto;
            else if (v == "on") r.options.object_stage = ObjectStage::On;
            else if (v == "off") r.options.object_stage = ObjectStage::Off;
            else throw UsageError{"--object-stage must be auto, on or off (got '" + v + "')"};
        } else if (a == "--self") {
            r.options.self = true;
        } else if (a == "--pairs") {
            r.pairs_file = need_value(i);
        } else if (a == "--json") {
            r.json = true;
        } else if (a == "--seed") {
            const std::string& v = need_value(i);
            auto n = parse_integer<std::uint64_t>(v);
            if (!n) throw UsageError{"--seed must be an unsigned 64-bit integer (got '" + v + "')"};
            r.scene_options.seed = *n;
        } else if (a == "--scale") {
            const std::string& v = need_value(i);
            auto x = parse_double(v);
            if (!x || !(*x > 0) || *x > 100) throw UsageError{"--scale must be a number in (0, 100] (got '" + v + "')"};
            r.scene_options.scale = *x;
        } else if (a == "--mesh-dir") {
            r.scene_options.mesh_dir = need_value(i);
        } else if (a.size() > 1 && a[0] == '-') {
            throw UsageError{"unknown option '" + a + "'"};
        } else {
            r.scene.push_back(a);
        }
    }
    if (r.options.self && !r.method_given) r.options.method = Method::QCullide;
    if (!r.resolution_given) r.options.resolution = default_resolution(r.options.method);
    return r;
}

bool is_builtin(const std::string& name) {
    for (const std::string& s : scene_names()) {
        if (s == name) return true;
    }
    return false;
}

int run_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
    RunArgs r = parse_run_args(args);
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
        }
        if (r.options.broadphase != BroadPhase::None) out << ", broad phase " << to_string(r.options.broadphase);
        out << ", " << frames << " frame" << (frames == 1 ? "" : "s") << "\n";
    }
    double total_ms = 0;
    std::uint64_t total_pairs = 0;
    for (int f = 0; f < frames; ++f) {
        Frame frame_objects;
        if (generator) frame_objects = generator->frame(f);
        std::span<const Mesh> objects = generator ? std::span<const Mesh>(frame_objects) : file_objects;
        Result<FrameResult> fr = process_frame(objects, r.options);
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
                << ", \"triangles_rasterized\": " << s.triangles_rasterized << ", \"views\": [";
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
            if (visibility) {
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

}  // namespace

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
    try {
        if (args.empty() || args[0] == "help" || args[0] == "--help" || args[0] == "-h") {
            (args.empty() ? err : out) << kUsage;
            return args.empty() ? 2 : 0;
        }
        if (args[0] == "scenes") {
            SceneOptions defaults;
            for (const std::string& name : scene_names()) {
                Result<std::unique_ptr<SceneGenerator>> g = make_scene(name, defaults);
                out << name << ": " << (g ? g.value()->description() : g.error().message) << "\n";
            }
            return 0;
        }
        if (args[0] == "run") return run_command(args, out, err);
        if (args[0] == "bench" || args[0] == "sweep") return bench_command(args, out, err);
        throw UsageError{"unknown command '" + args[0] + "'"};
    } catch (const UsageError& e) {
        err << "cullide: " << e.message << "\n(run 'cullide help' for usage)\n";
        return 2;
    }
}

}  // namespace cullide::cli
