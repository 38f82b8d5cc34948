// cullide/cli/hunt.cpp: `cullide hunt` (hunt.h): the search loop over the library's generators,
// check, shrink and classify (cullide/hunt.h), with budgets, Ctrl-C, progress and output files.
#include "hunt.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "bench.h"
#include "cli.h"
#include "cullide/hunt.h"
#include "cullide/mesh_io.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "help.h"
#include "options.h"

namespace cullide::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Set by SIGINT while a hunt runs; the loop and the shrinker ask it between frames. A lock-free
// atomic (allowed in a signal handler), not a volatile flag, because the handler may run on any
// thread (a signal raised by another thread, as in the test) and the loop reads it on this one.
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free);
extern "C" void on_sigint(int) { g_interrupted.store(true, std::memory_order_relaxed); }

// SIGINT handled for the scope of one hunt, the previous handler restored after.
class SigintScope {
 public:
    SigintScope() {
        g_interrupted.store(false);
        previous_ = std::signal(SIGINT, on_sigint);
    }
    ~SigintScope() { std::signal(SIGINT, previous_ == SIG_ERR ? SIG_DFL : previous_); }
    SigintScope(const SigintScope&) = delete;
    SigintScope& operator=(const SigintScope&) = delete;

 private:
    void (*previous_)(int) = SIG_DFL;
};

struct Failure {  // a file that cannot be read or written, a frame the pipeline refuses
    std::string message;
};

// A word for a POSIX shell: as it is when it is plain, else in single quotes.
std::string shell_word(const std::string& s) {
    const bool plain = !s.empty() && s.find_first_not_of(
                                         "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                         "_-+=./,:@%") == std::string::npos;
    if (plain) return s;
    std::string q = "'";
    for (char c : s) {
        if (c == '\'')
            q.append("'\\''");
        else
            q += c;
    }
    q += '\'';
    return q;
}

std::string hex(std::uint64_t x) {
    std::ostringstream o;
    o << "0x" << std::hex << std::setw(16) << std::setfill('0') << x;
    return o.str();
}

std::uint64_t triangle_count(const Frame& f) {
    std::uint64_t n = 0;
    for (const Mesh& m : f) n += m.triangles.size();
    return n;
}

// Where the frames come from: a generator, the frame of the --mesh files, or a built-in scene.
struct Source {
    std::string name;
    std::optional<hunt::Generator> generator;
    const Frame* base = nullptr;            // --mesh: perturbations of this frame
    std::shared_ptr<SceneGenerator> scene;  // --scene: perturbations of its frames
};

// The frame of case `index` and its seed.
std::uint64_t case_seed(std::uint64_t seed, std::uint64_t index) {
    std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (index + 1);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

Frame make_case(const Source& s, std::uint64_t seed, int* scene_frame) {
    if (s.generator) return hunt::generate(*s.generator, seed);
    if (s.base) return hunt::perturb(*s.base, seed);
    // A frame index in 0..599 (20 s of scene time; every scene accepts any index).
    *scene_frame = static_cast<int>(seed % 600);
    return hunt::perturb(s.scene->frame(*scene_frame), seed);
}

struct Finding {
    int number = 0;
    std::uint64_t case_index = 0;
    std::string source;
    int scene_frame = -1;
    std::uint64_t seed = 0;
    std::uint64_t objects_before = 0, triangles_before = 0, objects = 0, triangles = 0;
    std::uint64_t missed = 0, extra = 0, shrink_checks = 0;
    bool shrink_complete = true;
    std::string reason;
    bool reproduced = false;  // the written OBJ files, read back, still give the difference
    std::string dir, command;
};

// The settings a `cullide run` line needs to repeat the pipeline of `o` exactly.
std::string run_settings(const RunOptions& o) {
    std::ostringstream c;
    c << " --method " << to_string(o.method) << " --resolution " << o.resolution << " --depth-format "
      << to_string(o.depth_format) << " --subobject " << o.subobject_triangles << " --rounds "
      << o.max_rounds;
    if (o.min_prune >= 0) c << " --min-prune " << std::setprecision(17) << o.min_prune;
    if (o.object_stage != ObjectStage::Auto)
        c << " --object-stage " << (o.object_stage == ObjectStage::On ? "on" : "off");
    if (o.broadphase != BroadPhase::None) c << " --broadphase " << to_string(o.broadphase);
    if (o.self) c << " --self";
    return c.str();
}

void write_file(const fs::path& p, const std::string& text) {
    std::ofstream f(p, std::ios::out | std::ios::trunc | std::ios::binary);
    f << text;
    f.close();
    if (!f) throw Failure{"cannot write '" + p.string() + "'"};
}

// Writes the finding's folder and fills dir, command and reproduced.
void write_finding(Finding& fd, const Frame& shrunk, const hunt::Verdict& v, const RunOptions& opt,
                   const fs::path& out_dir, FrameContext& context) {
    char name[32];
    std::snprintf(name, sizeof name, "finding-%03d", fd.number);
    const fs::path dir = out_dir / name;
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw Failure{"cannot create '" + dir.string() + "': " + ec.message()};
    // An earlier hunt's object files in the same folder would read as part of this finding.
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
        const std::string n = e.path().filename().string();
        if (n.rfind("object_", 0) == 0 && e.path().extension() == ".obj") fs::remove(e.path(), ec);
    }
    std::string command = "cullide run";
    std::vector<Mesh> read_back;
    for (std::size_t i = 0; i < shrunk.size(); ++i) {
        const fs::path file = dir / ("object_" + std::to_string(i) + ".obj");
        Mesh m = shrunk[i];
        m.name = "object_" + std::to_string(i);
        write_file(file, write_obj({m}));
        command.append(" ").append(shell_word(file.string()));
        Result<std::vector<Mesh>> back = read_mesh_file(file.string());
        if (!back) throw Failure{back.error().message};
        for (Mesh& b : back.value()) read_back.push_back(std::move(b));
    }
    command += run_settings(opt);
    std::ostringstream pairs;
    pairs << "kind,object_a,triangle_a,object_b,triangle_b\n";
    for (const TrianglePair& p : v.missed)
        pairs << "missed," << p.object_a << ',' << p.triangle_a << ',' << p.object_b << ',' << p.triangle_b
              << '\n';
    for (const TrianglePair& p : v.extra)
        pairs << "extra," << p.object_a << ',' << p.triangle_a << ',' << p.object_b << ',' << p.triangle_b
              << '\n';
    write_file(dir / "pairs.csv", pairs.str());
    write_file(dir / "command.txt", command + "\n");
    std::ostringstream about;
    about << "source " << fd.source;
    if (fd.scene_frame >= 0) about << " frame " << fd.scene_frame << " (perturbed)";
    about << ", case " << fd.case_index << ", case seed " << hex(fd.seed) << "\n"
          << "before shrinking: " << fd.objects_before << " objects, " << fd.triangles_before
          << " triangles\n"
          << "after: " << fd.objects << " objects, " << fd.triangles << " triangles (" << fd.shrink_checks
          << " frames run" << (fd.shrink_complete ? "" : ", stopped early") << ")\n"
          << "missed pairs " << fd.missed << ", extra pairs " << fd.extra << "\n"
          << "reason " << fd.reason << "\n";
    write_file(dir / "reason.txt", about.str());
    Result<hunt::Verdict> again = hunt::check(read_back, opt, context);
    fd.reproduced = again && again.value().missed == v.missed && again.value().extra == v.extra;
    fd.dir = dir.string();
    fd.command = command;
}

const char* kCsvHeader =
    "finding,case,source,scene_frame,case_seed,objects_before,triangles_before,objects,triangles,missed_"
    "pairs,"
    "extra_pairs,reason,shrink_checks,shrink_complete,reproduced,dir,command\n";

std::string csv_field(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) {
        if (c == '"') q += '"';
        q += c;
    }
    return q + "\"";
}

std::string csv_row(const Finding& f) {
    std::ostringstream o;
    o << f.number << ',' << f.case_index << ',' << csv_field(f.source) << ',' << f.scene_frame << ','
      << hex(f.seed) << ',' << f.objects_before << ',' << f.triangles_before << ',' << f.objects << ','
      << f.triangles << ',' << f.missed << ',' << f.extra << ',' << f.reason << ',' << f.shrink_checks << ','
      << (f.shrink_complete ? "yes" : "no") << ',' << (f.reproduced ? "yes" : "no") << ',' << csv_field(f.dir)
      << ',' << csv_field(f.command) << '\n';
    return o.str();
}

// Per source, over every case run (before any shrinking): how often and how much the method misses.
struct SourceStats {
    std::string name;
    std::uint64_t cases = 0, failing = 0, true_pairs = 0, missed = 0, extra = 0;
};

struct Summary {
    RunOptions options;
    std::uint64_t seed = 0;
    std::uint64_t cases = 0;
    double seconds = 0;
    std::string stopped_by;
    std::vector<SourceStats> sources;
    std::vector<Finding> findings;
};

std::string summary_json(const Summary& s) {
    std::ostringstream o;
    const RunOptions& p = s.options;
    o << "{\"method\": \"" << to_string(p.method) << "\", \"resolution\": " << p.resolution
      << ", \"depth_format\": \"" << to_string(p.depth_format)
      << "\", \"subobject\": " << p.subobject_triangles << ", \"rounds\": " << p.max_rounds
      << ", \"self\": " << (p.self ? "true" : "false") << ", \"seed\": " << s.seed << ", \"sources\": [";
    for (std::size_t i = 0; i < s.sources.size(); ++i) {
        const SourceStats& x = s.sources[i];
        o << (i ? ", " : "") << "{\"name\": \"" << json_escape(x.name) << "\", \"cases\": " << x.cases
          << ", \"failing_cases\": " << x.failing << ", \"true_pairs\": " << x.true_pairs
          << ", \"missed_pairs\": " << x.missed << ", \"extra_pairs\": " << x.extra << "}";
    }
    o << "], \"cases\": " << s.cases << ", \"seconds\": " << std::fixed << std::setprecision(3) << s.seconds
      << std::defaultfloat << ", \"stopped_by\": \"" << s.stopped_by << "\", \"findings\": [";
    for (std::size_t i = 0; i < s.findings.size(); ++i) {
        const Finding& f = s.findings[i];
        o << (i ? ", " : "") << "{\"finding\": " << f.number << ", \"case\": " << f.case_index
          << ", \"source\": \"" << json_escape(f.source) << "\", \"scene_frame\": " << f.scene_frame
          << ", \"case_seed\": \"" << hex(f.seed) << "\", \"objects_before\": " << f.objects_before
          << ", \"triangles_before\": " << f.triangles_before << ", \"objects\": " << f.objects
          << ", \"triangles\": " << f.triangles << ", \"missed_pairs\": " << f.missed
          << ", \"extra_pairs\": " << f.extra << ", \"reason\": \"" << f.reason
          << "\", \"shrink_checks\": " << f.shrink_checks
          << ", \"shrink_complete\": " << (f.shrink_complete ? "true" : "false")
          << ", \"reproduced\": " << (f.reproduced ? "true" : "false") << ", \"dir\": \""
          << json_escape(f.dir) << "\", \"command\": \"" << json_escape(f.command) << "\"}";
    }
    o << "]}\n";
    return o.str();
}

std::string summary_csv(const Summary& s) {
    std::string t = kCsvHeader;
    for (const Finding& f : s.findings) t += csv_row(f);
    return t;
}

void emit(const std::string& path, const std::string& text, std::ostream& out) {
    if (path.empty()) return;
    if (path == "-") {
        out << text;
        return;
    }
    write_file(path, text);
}

int hunt_main(const Settings& s, std::ostream& stdout_stream, std::ostream& err) {
    if (s.csv_path == "-" && s.json_path == "-")
        throw UsageError{"--csv - and --json - cannot both go to stdout"};
    // The report goes to stderr when a summary takes stdout.
    std::ostream& out = s.csv_path == "-" || s.json_path == "-" ? err : stdout_stream;
    RunOptions opt = s.pipeline;
    if (opt.resolution == 0) opt.resolution = default_resolution(opt.method);

    // Sources, in a fixed order: generators, then the mesh files' frame, then scenes.
    std::vector<std::string> gens = s.generators;
    if (gens.empty() && s.mesh_files.empty() && s.hunt_scenes.empty()) gens = hunt::generator_names();
    std::vector<Source> sources;
    for (const std::string& g : gens)
        sources.push_back({g, hunt::parse_generator(g).value(), nullptr, nullptr});
    Frame mesh_frame;
    if (!s.mesh_files.empty()) {
        std::string label;
        for (const std::string& path : s.mesh_files) {
            Result<std::vector<Mesh>> meshes = read_mesh_file(path);
            if (!meshes) throw Failure{meshes.error().message};
            for (Mesh& m : meshes.value()) mesh_frame.push_back(std::move(m));
            label += (label.empty() ? "mesh:" : "+") + path;
        }
        sources.push_back({label, std::nullopt, &mesh_frame, nullptr});
    }
    for (const std::string& name : s.hunt_scenes) {
        Result<std::unique_ptr<SceneGenerator>> g = make_scene(name, s.scene);
        if (!g) throw Failure{g.error().message};
        sources.push_back(
            {"scene:" + name, std::nullopt, nullptr, std::shared_ptr<SceneGenerator>(std::move(g).value())});
    }

    const std::optional<double> budget =
        s.budget_s ? s.budget_s : (s.cases ? std::nullopt : std::optional<double>(30.0));
    const fs::path out_dir = s.out_dir;
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) throw Failure{"cannot create '" + out_dir.string() + "': " + ec.message()};

    Summary sum;
    sum.options = opt;
    sum.seed = s.scene.seed;
    for (const Source& src : sources) sum.sources.push_back({src.name});

    const bool progress = s.progress && isatty(STDERR_FILENO) == 1;
    const SigintScope sigint;
    const Clock::time_point start = Clock::now();
    const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    const auto interrupted = [] { return g_interrupted.load(std::memory_order_relaxed); };
    const auto out_of_time = [&] { return interrupted() || (budget && elapsed() >= *budget); };
    Clock::time_point last_progress = start;
    FrameContext context;

    out << "cullide hunt: method " << to_string(opt.method) << ", resolution " << opt.resolution << ", depth "
        << to_string(opt.depth_format) << ", sub-object " << opt.subobject_triangles << ", rounds "
        << opt.max_rounds << ", seed " << s.scene.seed << ", " << sources.size() << " source"
        << (sources.size() == 1 ? "" : "s");
    if (budget) out << ", budget " << *budget << " s";
    if (s.cases) out << ", at most " << *s.cases << " cases";
    out << "\n";

    std::uint64_t index = 0;
    for (;; ++index) {
        if (interrupted()) {
            sum.stopped_by = "interrupt";
            break;
        }
        if (s.cases && index >= *s.cases) {
            sum.stopped_by = "cases";
            break;
        }
        if (budget && elapsed() >= *budget) {
            sum.stopped_by = "time";
            break;
        }
        if (progress && Clock::now() - last_progress > std::chrono::milliseconds(200)) {
            last_progress = Clock::now();
            err << "\rhunt: " << index << " cases, " << sum.findings.size() << " findings, " << std::fixed
                << std::setprecision(1) << elapsed() << " s   " << std::defaultfloat << std::flush;
        }
        const Source& src = sources[index % sources.size()];
        SourceStats& stats = sum.sources[index % sources.size()];
        const std::uint64_t seed = case_seed(s.scene.seed, index);
        int scene_frame = -1;
        const Frame frame = make_case(src, seed, &scene_frame);
        Result<hunt::Verdict> v = hunt::check(frame, opt, context);
        if (!v) {
            throw Failure{"case " + std::to_string(index) + " (" + src.name + ", seed " + hex(seed) +
                          "): " + v.error().message};
        }
        ++stats.cases;
        stats.true_pairs += v.value().truth_pairs;
        stats.missed += v.value().missed.size();
        stats.extra += v.value().extra.size();
        if (!v.value().failed()) continue;
        ++stats.failing;
        if (static_cast<int>(sum.findings.size()) >= s.max_findings) continue;  // counted only

        Finding fd;
        fd.number = static_cast<int>(sum.findings.size()) + 1;
        fd.case_index = index;
        fd.source = src.name;
        fd.scene_frame = scene_frame;
        fd.seed = seed;
        fd.objects_before = frame.size();
        fd.triangles_before = triangle_count(frame);
        hunt::ShrinkStats st;
        const Frame shrunk = hunt::shrink(frame, opt, context, out_of_time, s.shrink_checks, &st);
        fd.shrink_checks = st.checks;
        fd.shrink_complete = !st.stopped;
        fd.objects = shrunk.size();
        fd.triangles = triangle_count(shrunk);
        Result<hunt::Verdict> sv = hunt::check(shrunk, opt, context);
        if (!sv) throw Failure{"shrunk case " + std::to_string(index) + ": " + sv.error().message};
        Result<hunt::Reason> reason = hunt::classify(shrunk, sv.value(), opt, context);
        if (!reason)
            throw Failure{"classifying case " + std::to_string(index) + ": " + reason.error().message};
        fd.reason = hunt::to_string(reason.value());
        fd.missed = sv.value().missed.size();
        fd.extra = sv.value().extra.size();
        write_finding(fd, shrunk, sv.value(), opt, out_dir, context);
        if (progress) err << "\r" << std::string(60, ' ') << "\r";
        out << "finding " << fd.number << ": case " << index << " (" << src.name << "): " << fd.objects_before
            << " objects, " << fd.triangles_before << " triangles -> " << fd.objects << " objects, "
            << fd.triangles << " triangles; " << fd.missed << " missed, " << fd.extra
            << " extra pairs; reason " << fd.reason
            << (fd.reproduced ? "" : "; NOT reproduced from the written files") << "\n  " << fd.command
            << "\n";
        sum.findings.push_back(std::move(fd));
    }
    if (progress) err << "\r" << std::string(60, ' ') << "\r";
    sum.cases = index;
    sum.seconds = elapsed();
    out << "hunt: " << sum.cases << " cases in " << std::fixed << std::setprecision(1) << sum.seconds
        << std::defaultfloat << " s, " << sum.findings.size() << " finding"
        << (sum.findings.size() == 1 ? "" : "s") << " (stopped by " << sum.stopped_by << "); written to "
        << out_dir.string() << "\n";
    for (const SourceStats& x : sum.sources) {
        if (x.cases == 0) continue;
        out << "  " << x.name << ": " << x.cases << " cases, " << x.failing << " failing; " << x.missed
            << " of " << x.true_pairs << " true pairs missed";
        if (x.extra) out << ", " << x.extra << " extra pairs";
        out << "\n";
    }
    write_file(out_dir / "summary.csv", summary_csv(sum));
    write_file(out_dir / "summary.json", summary_json(sum));
    emit(s.csv_path, summary_csv(sum), stdout_stream);
    emit(s.json_path, summary_json(sum), stdout_stream);
    return !sum.findings.empty() && never_misses(opt.method) ? 1 : 0;
}

}  // namespace

int hunt_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
    try {
        const Settings s = parse_options(Command::Hunt, args);
        if (s.help) {
            out << command_help(Command::Hunt);
            return 0;
        }
        return hunt_main(s, out, err);
    } catch (const UsageError& e) {
        err << "cullide hunt: " << e.message << "\n(run 'cullide hunt --help' for usage)\n";
        return 2;
    } catch (const Failure& e) {
        err << "cullide hunt: error: " << e.message << "\n";
        return 1;
    }
}

}  // namespace cullide::cli
