// cullide/cli/options.cpp: the option table of run, bench, sweep and hunt, and the parser that reads it.
#include "options.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string_view>

#include "cullide/hunt.h"
#include "raster/types.h"

namespace cullide::cli {
namespace {

// The command line's smallest view: the library accepts 1 pixel, but the CLI has always refused
// views below 16 (none was ever measured; docs/cullide.md starts at 16). The largest is the
// rasterizer's own limit.
constexpr int kMinCliResolution = 16;
constexpr int kMaxThreads = 1024;

template <class T>
std::optional<T> parse_integer(std::string_view s) {
    T v{};
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
    return v;
}

std::optional<double> parse_real(std::string_view s) {
    double v = 0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v))
        return std::nullopt;
    return v;
}

Range integers(long long lo, long long hi) {
    return Range{Range::Kind::Integer, static_cast<double>(lo), static_cast<double>(hi), false, false};
}
Range reals(double lo, bool lo_open, double hi, bool hi_open) {
    return Range{Range::Kind::Real, lo, hi, lo_open, hi_open};
}

// The value of an integer option (or of one item of a list), checked against spec.range.
int int_value(const OptionSpec& spec, const std::string& v) {
    const auto n = parse_integer<int>(v);
    if (!n || *n < spec.range.lo || *n > spec.range.hi) {
        throw UsageError{spec.name + " must be an integer in " + range_text(spec.range) + " (got '" + v +
                         "')"};
    }
    return *n;
}

bool in_range(const Range& r, double x) {
    return (r.lo_open ? x > r.lo : x >= r.lo) && (r.hi_open ? x < r.hi : x <= r.hi);
}

// The value of a real option; a list item's message says "each" (the wording tests pin).
double real_value(const OptionSpec& spec, const std::string& v, bool list_item) {
    const auto x = parse_real(v);
    if (!x || !in_range(spec.range, *x)) {
        throw UsageError{spec.name + (list_item ? ": each" : "") + " must be a number in " +
                         range_text(spec.range) + " (got '" + v + "')"};
    }
    return *x;
}

std::vector<std::string> list_items(const OptionSpec& spec, const std::string& v) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = v.find(',', start);
        std::string item = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        if (item.empty()) throw UsageError{spec.name + ": empty item in list '" + v + "'"};
        parts.push_back(std::move(item));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return parts;
}

template <class T>
T checked(const OptionSpec& spec, Result<T> r) {
    if (!r) throw UsageError{spec.name + ": " + r.error().message};
    return std::move(r).value();
}

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

ObjectStage object_stage_value(const OptionSpec& spec, const std::string& v) {
    if (v == "auto") return ObjectStage::Auto;
    if (v == "on") return ObjectStage::On;
    if (v == "off") return ObjectStage::Off;
    throw UsageError{spec.name + " must be auto, on or off (got '" + v + "')"};
}

std::string resolution_default() {
    return std::to_string(default_resolution(Method::RCullide)) + " for auto, rcullide and qcullide (exact bounds), " +
           std::to_string(default_resolution(Method::Cullide)) + " for the others";
}

std::string min_prune_default() {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, kDefaultMinPruneExactBounds);
    return std::string(buf, r.ptr) +
           " for rcullide, 0 for cullide and rcullide-offset: stop when nothing more is pruned";
}

// Options every command reads the same way: the pipeline's knobs and the scene's seed and meshes.
void add_shared_options(std::vector<OptionSpec>& t) {
    const RunOptions d;
    t.push_back({"--subobject", "N", kAllCommands, "triangles per sub-object of visibility methods",
                 integers(1, 65536), std::to_string(d.subobject_triangles), "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.subobject_triangles = int_value(o, v);
                 }});
    t.push_back({"--rounds", "N", kAllCommands, "rounds of x, y, z views per visibility stage",
                 integers(1, kMaxRounds), std::to_string(d.max_rounds), "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.max_rounds = int_value(o, v);
                 }});
    t.push_back({"--min-prune", "F", kAllCommands,
                 "a stage stops after three views in a row that each prune less than F of its live triangles",
                 reals(0, false, 1, true), min_prune_default(), "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.min_prune = real_value(o, v, false);
                 }});
    t.push_back(
        {"--object-stage",
         "S",
         kAllCommands,
         "the object-level triangle stage: auto (off for rcullide, whose sub-object views prune every object "
         "an object view would; on for cullide and rcullide-offset), on, off",
         {},
         "auto",
         "",
         [](const OptionSpec& o, const std::string& v, Settings& s) {
             s.pipeline.object_stage = object_stage_value(o, v);
         }});
    t.push_back(
        {"--broadphase",
         "B",
         kAllCommands,
         "first stage on object boxes: none, spatialhash, sap, brute; objects overlapping no other box are "
         "dropped at once",
         {},
         to_string(d.broadphase),
         "",
         [](const OptionSpec& o, const std::string& v, Settings& s) {
             s.pipeline.broadphase = checked(o, parse_broadphase(v));
         }});
    t.push_back(
        {"--self",
         "",
         kAllCommands,
         "also report pairs inside one object (adjacent triangles excluded); methods exact, qcullide, "
         "qcullide-gl, auto (which runs exact then)",
         {},
         "",
         "",
         [](const OptionSpec&, const std::string&, Settings& s) { s.pipeline.self = true; }});
    t.push_back({"--gpu-rules",
                 "R",
                 kAllCommands,
                 "rasterization rules of the GL-exact views (cullide, qcullide-gl): gl (OpenGL on llvmpipe) or "
                 "vulkan (Vulkan as lavapipe: top-left rule on y-down, depth in [0, 1], first provoking vertex); "
                 "rcullide-offset needs gl",
                 {},
                 to_string(d.gpu_rules),
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.gpu_rules = checked(o, parse_gpu_rules(v));
                 }});
    t.push_back({"--seed",
                 "S",
                 kAllCommands,
                 "scene seed, an unsigned 64-bit integer (hunt: the seed of the whole search)",
                 {},
                 std::to_string(SceneOptions{}.seed),
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     const auto n = parse_integer<std::uint64_t>(v);
                     if (!n)
                         throw UsageError{o.name + " must be an unsigned 64-bit integer (got '" + v + "')"};
                     s.scene.seed = *n;
                 }});
    t.push_back({"--mesh-dir",
                 "DIR",
                 kAllCommands,
                 "where real meshes (bunny, dragon) are read from",
                 {},
                 SceneOptions{}.mesh_dir,
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.scene.mesh_dir = v; }});
}

void add_run_options(std::vector<OptionSpec>& t) {
    const RunOptions d;
    t.push_back(
        {"--method",
         "M",
         kRunHunt,
         "rcullide (R-CULLIDE, exact-bounds conservative raster: never misses), exact (the ground truth), "
         "cullide (GL-exact visibility culling, may miss collisions like the GPU original), rcullide-offset "
         "(R-CULLIDE with the paper's offset solids: never misses), qcullide (Quick-CULLIDE, exact-bounds: "
         "never misses), qcullide-gl (Quick-CULLIDE, GL-exact), auto (never misses: rcullide's views where a "
         "count-based estimate says they pay, else straight to the exact test)",
         {},
         std::string(to_string(d.method)) + "; with --self it runs exact",
         "",
         [](const OptionSpec& o, const std::string& v, Settings& s) {
             s.pipeline.method = checked(o, parse_method(v));
         }});
    t.push_back({"--frames", "N", kRunOnly, "frames to run", integers(1, 1000000),
                 "10 for built-in scenes, 1 for files", "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) { s.frames = int_value(o, v); }});
    t.push_back({"--threads", "T", kRunHunt, "worker threads, 0 = all cores; results do not depend on it",
                 integers(0, kMaxThreads), std::to_string(d.threads), "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.threads = int_value(o, v);
                 }});
    t.push_back({"--resolution", "R", kRunHunt, "view resolution of visibility methods",
                 integers(kMinCliResolution, kMaxViewResolution), resolution_default(), "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.resolution = int_value(o, v);
                 }});
    t.push_back({"--depth-format",
                 "F",
                 kRunHunt,
                 "depth buffer of visibility methods: d16, d24, d32f",
                 {},
                 to_string(d.depth_format),
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.pipeline.depth_format = checked(o, parse_depth_format(v));
                 }});
    t.push_back({"--scale", "X", kRunHunt, "scene size factor", reals(0, true, kMaxSceneScale, false), "1",
                 "", [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.scene.scale = real_value(o, v, false);
                 }});
    t.push_back({"--pairs",
                 "FILE",
                 kRunOnly,
                 "write every colliding triangle pair as CSV: frame,object_a,triangle_a,object_b,triangle_b",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.pairs_file = v; }});
    t.push_back({"--json",
                 "",
                 kRunOnly,
                 "print the per-frame results as one JSON document instead of text",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string&, Settings& s) { s.json = true; }});
}

void add_bench_options(std::vector<OptionSpec>& t) {
    t.push_back({"--scenes",
                 "LIST",
                 kBenchSweep,
                 "built-in scenes; 'all' = every scene",
                 {},
                 "cylinders",
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.scenes.clear();  // a repeated option replaces the list
                     const std::vector<std::string> names = scene_names();
                     for (const std::string& item : list_items(o, v)) {
                         if (item == "all") {
                             s.scenes.insert(s.scenes.end(), names.begin(), names.end());
                         } else if (std::find(names.begin(), names.end(), item) == names.end()) {
                             throw UsageError{o.name + ": unknown scene '" + item +
                                              "' (valid: " + joined(names) + ", all)"};
                         } else {
                             s.scenes.push_back(item);
                         }
                     }
                 },
                 true});
    t.push_back({"--scales", "LIST", kBenchSweep, "scene size factors", reals(0, true, kMaxSceneScale, false),
                 "1", "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.scales.clear();
                     for (const std::string& item : list_items(o, v))
                         s.scales.push_back(real_value(o, item, true));
                 },
                 true});
    t.push_back({"--methods",
                 "LIST",
                 kBenchSweep,
                 "methods (as run's --method); 'all' = every method",
                 {},
                 "exact,cullide,rcullide",
                 "cullide,rcullide,rcullide-offset",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.methods.clear();
                     for (const std::string& item : list_items(o, v)) {
                         if (item == "all") {
                             for (const std::string& n : method_names())
                                 s.methods.push_back(parse_method(n).value());
                         } else {
                             s.methods.push_back(checked(o, parse_method(item)));
                         }
                     }
                 },
                 true});
    t.push_back({"--resolutions", "LIST", kBenchSweep,
                 "view resolutions; bench without it runs each method at its own: " + resolution_default(),
                 integers(kMinCliResolution, kMaxViewResolution), "", "32,64,128,256,512,1024",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.resolutions.clear();
                     for (const std::string& item : list_items(o, v))
                         s.resolutions.push_back(int_value(o, item));
                 },
                 true});
    t.push_back({"--depth-formats",
                 "LIST",
                 kBenchSweep,
                 "depth buffers: d16, d24, d32f",
                 {},
                 to_string(RunOptions{}.depth_format),
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.depth_formats.clear();
                     for (const std::string& item : list_items(o, v)) {
                         s.depth_formats.push_back(checked(o, parse_depth_format(item)));
                     }
                 },
                 true});
    t.push_back({"--threads", "LIST", kBenchSweep, "worker threads, 0 = all cores", integers(0, kMaxThreads),
                 "0", "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.thread_counts.clear();
                     for (const std::string& item : list_items(o, v))
                         s.thread_counts.push_back(int_value(o, item));
                 },
                 true});
    t.push_back({"--frames", "N", kBenchSweep, "frames per scene", integers(1, 100000), "5", "2",
                 [](const OptionSpec& o, const std::string& v, Settings& s) { s.frames = int_value(o, v); },
                 true});
    t.push_back(
        {"--first-frame", "F", kBenchSweep, "first frame index", integers(-1000000, 1000000), "0", "",
         [](const OptionSpec& o, const std::string& v, Settings& s) { s.first_frame = int_value(o, v); },
         true});
    t.push_back(
        {"--frame-step", "K", kBenchSweep, "frame index step", integers(1, 100000), "1", "",
         [](const OptionSpec& o, const std::string& v, Settings& s) { s.frame_step = int_value(o, v); },
         true});
    t.push_back({"--warmup", "N", kBenchSweep, "untimed runs per frame", integers(0, 1000), "1", "0",
                 [](const OptionSpec& o, const std::string& v, Settings& s) { s.warmup = int_value(o, v); },
                 true});
    t.push_back({"--reps", "N", kBenchSweep, "timed runs per frame", integers(1, 1000), "5", "1",
                 [](const OptionSpec& o, const std::string& v, Settings& s) { s.reps = int_value(o, v); },
                 true});
    t.push_back({"--csv",
                 "FILE",
                 kBenchSweep,
                 "write one CSV row per combination ('-' = stdout)",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.csv_path = v; }});
    t.push_back({"--json",
                 "FILE",
                 kBenchSweep,
                 "write a JSON document ('-' = stdout)",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.json_path = v; }});
    t.push_back({"--no-progress",
                 "",
                 kBenchSweep | kHuntOnly,
                 "no progress bar (it is drawn on stderr only when stderr is a terminal)",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string&, Settings& s) { s.progress = false; }});
}

void add_hunt_options(std::vector<OptionSpec>& t) {
    t.push_back({"--generators",
                 "LIST",
                 kHuntOnly,
                 "frame generators: " + joined(hunt::generator_names()) +
                     "; 'all' = every one (docs/hunt.md says what each makes)",
                 {},
                 "all, or none when --mesh or --scene is given",
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.generators.clear();
                     for (const std::string& item : list_items(o, v)) {
                         if (item == "all") {
                             const std::vector<std::string> all = hunt::generator_names();
                             s.generators.insert(s.generators.end(), all.begin(), all.end());
                         } else {
                             (void)checked(o, hunt::parse_generator(item));
                             s.generators.push_back(item);
                         }
                     }
                 }});
    t.push_back({"--mesh",
                 "FILE",
                 kHuntOnly,
                 "also hunt perturbations of the frame made of these mesh files (.obj .ply .stl); repeat for "
                 "more files",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.mesh_files.push_back(v); }});
    t.push_back({"--scene",
                 "NAME",
                 kHuntOnly,
                 "also hunt perturbations of frames of this built-in scene; repeat for more scenes",
                 {},
                 "",
                 "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     const std::vector<std::string> names = scene_names();
                     if (std::find(names.begin(), names.end(), v) == names.end())
                         throw UsageError{o.name + ": unknown scene '" + v + "' (valid: " + joined(names) +
                                          ")"};
                     s.hunt_scenes.push_back(v);
                 }});
    t.push_back({"--budget-s", "S", kHuntOnly,
                 "stop after S seconds of searching (Ctrl-C also stops, keeping what was found)",
                 reals(0, true, 604800, false), "30 when --cases is not given", "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.budget_s = real_value(o, v, false);
                 }});
    t.push_back({"--cases", "N", kHuntOnly, "stop after N generated frames", integers(1, 1000000000),
                 "no limit", "", [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.cases = static_cast<std::uint64_t>(int_value(o, v));
                 }});
    t.push_back({"--max-findings", "N", kHuntOnly,
                 "shrink and write the first N findings; later failing frames are only counted",
                 integers(1, 100000), "10", "", [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.max_findings = int_value(o, v);
                 }});
    t.push_back({"--shrink-checks", "N", kHuntOnly, "at most N frames run to shrink one finding",
                 integers(0, 100000000), "2000", "",
                 [](const OptionSpec& o, const std::string& v, Settings& s) {
                     s.shrink_checks = static_cast<std::uint64_t>(int_value(o, v));
                 }});
    t.push_back(
        {"--out",
         "DIR",
         kHuntOnly,
         "where findings are written, one folder each (OBJ files, the run command, the missed pairs), "
         "with summary.csv and summary.json",
         {},
         "hunt-out",
         "",
         [](const OptionSpec&, const std::string& v, Settings& s) {
             if (v.empty()) throw UsageError{"--out needs a folder name"};
             s.out_dir = v;
         }});
    t.push_back({"--csv",
                 "FILE",
                 kHuntOnly,
                 "also write the summary, one CSV row per finding ('-' = stdout)",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.csv_path = v; }});
    t.push_back({"--json",
                 "FILE",
                 kHuntOnly,
                 "also write the summary as a JSON document ('-' = stdout)",
                 {},
                 "",
                 "",
                 [](const OptionSpec&, const std::string& v, Settings& s) { s.json_path = v; }});
}

std::vector<OptionSpec> make_table() {
    std::vector<OptionSpec> t;
    add_run_options(t);
    add_shared_options(t);
    add_bench_options(t);
    add_hunt_options(t);
    return t;
}

// Why `name` is refused by `command`: taken by other commands only, or by none.
std::string refusal(const std::string& name, Command command) {
    CommandSet others = 0;
    for (const OptionSpec& o : option_table()) {
        if (o.name == name) others |= o.commands;
    }
    if (others == 0) return "unknown option '" + name + "'";
    return "option " + name + " is taken by " + command_list(others) + ", not by " + command_name(command);
}

}  // namespace

const char* command_name(Command c) {
    switch (c) {
        case Command::Run:
            return "run";
        case Command::Bench:
            return "bench";
        case Command::Sweep:
            return "sweep";
        case Command::Hunt:
            return "hunt";
    }
    return "?";
}

std::string command_list(CommandSet set) {
    std::vector<std::string> names;
    for (Command c : kCommandList) {
        if (takes(set, c)) names.emplace_back(command_name(c));
    }
    std::string s;
    for (std::size_t i = 0; i < names.size(); ++i) {
        s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
    }
    return s;
}

const std::vector<OptionSpec>& option_table() {
    static const std::vector<OptionSpec> table = make_table();
    return table;
}

std::string range_text(const Range& r) {
    auto number = [](double x) {
        char buf[32];
        const auto res = std::to_chars(buf, buf + sizeof buf, x);
        return std::string(buf, res.ptr);
    };
    switch (r.kind) {
        case Range::Kind::None:
            return "";
        case Range::Kind::Integer:  // digits, never 1e+06
            return std::to_string(static_cast<long long>(r.lo)) + ".." +
                   std::to_string(static_cast<long long>(r.hi));
        case Range::Kind::Real:
            // GCC 12 at -O3 reports a false -Wrestrict inside libstdc++ for `"literal" + std::string&&`
            // (GCC bug 105329); silenced for this statement only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wrestrict"
#endif
            return (r.lo_open ? "(" : "[") + number(r.lo) + ", " + number(r.hi) + (r.hi_open ? ")" : "]");
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
    }
    return "";
}

Settings parse_options(Command command, const std::vector<std::string>& args) {
    Settings s;
    for (std::size_t i = 1; i < args.size(); ++i) {
        if (args[i] == "--help" || args[i] == "-h") {
            s.help = true;
            return s;
        }
    }
    const std::vector<OptionSpec>& table = option_table();
    std::vector<const OptionSpec*> given;
    for (std::size_t i = 1; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a.size() < 2 || a[0] != '-') {
            // Only run takes operands (a scene or mesh files); "-" alone is an operand too.
            if (command == Command::Run) {
                s.inputs.push_back(a);
                continue;
            }
            const char* where = command == Command::Hunt
                                    ? " (mesh files are given with --mesh, scenes with --scene)"
                                    : " (scenes are given with --scenes)";
            throw UsageError{"unknown option '" + a + "'" + where};
        }
        const auto spec = std::find_if(table.begin(), table.end(), [&](const OptionSpec& o) {
            return o.name == a && takes(o.commands, command);
        });
        if (spec == table.end()) throw UsageError{refusal(a, command)};
        std::string value;
        if (!spec->value.empty()) {
            if (i + 1 >= args.size()) throw UsageError{"option " + a + " needs a value"};
            value = args[++i];
        }
        spec->apply(*spec, value, s);
        given.push_back(&*spec);
    }
    for (const OptionSpec& o : table) {
        if (!o.default_is_value || !takes(o.commands, command)) continue;
        if (std::find(given.begin(), given.end(), &o) != given.end()) continue;
        const std::string& d =
            command == Command::Sweep && !o.sweep_default.empty() ? o.sweep_default : o.default_text;
        if (!d.empty()) o.apply(o, d, s);
    }
    return s;
}

}  // namespace cullide::cli
