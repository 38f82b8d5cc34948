// cullide/cli/bench.cpp: the engine of `cullide bench` and `cullide sweep` (bench.h) and their output
// (CSV, JSON, a table on stdout). Their options are rows of the option table (options.cpp).
#include "bench.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <unistd.h>

#include "bench_internal.h"
#include "help.h"
#include "options.h"
#include "cullide/scenes.h"

namespace cullide::cli {

using namespace bench_detail;

namespace {

// bench's and sweep's settings, after the table filled in their defaults.
BenchArgs bench_args_of(Command command, const Settings& s) {
    if (s.csv_path == "-" && s.json_path == "-") throw UsageError{"--csv - and --json - cannot both go to stdout"};
    BenchArgs a;
    a.sweep = command == Command::Sweep;
    a.scenes = s.scenes;
    a.scales = s.scales;
    a.methods = s.methods;
    a.resolutions = s.resolutions;  // empty: each visibility method at its own default_resolution
    a.depth_formats = s.depth_formats;
    a.threads = s.thread_counts;
    a.frames = s.frames.value();  // every one of these has a default in the option table
    a.first_frame = s.first_frame;
    a.frame_step = s.frame_step;
    a.warmup = s.warmup.value();
    a.reps = s.reps.value();
    a.base = s.pipeline;
    a.scene_options = s.scene;
    a.csv_path = s.csv_path;
    a.json_path = s.json_path;
    a.progress = s.progress;
    return a;
}

double quantile(std::vector<double> v, double q) {  // linear interpolation between order statistics
    std::sort(v.begin(), v.end());
    if (v.empty()) return 0;
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(pos));
    const std::size_t hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double load_average() {
    std::ifstream f("/proc/loadavg");
    double l = -1;
    if (!(f >> l)) return -1;
    return l;
}

std::uint64_t fnv_bytes(std::uint64_t h, std::uint64_t v, int bytes) {
    for (int b = 0; b < bytes; ++b) {
        h ^= (v >> (8 * b)) & 0xffu;
        h *= 0x100000001b3ull;
    }
    return h;
}

std::string hex64(std::uint64_t v) {
    char buf[20];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

// One row: a combination, its figures over the frames.
struct CaseResult {
    std::string scene;
    double scale = 1;
    Method method = Method::Exact;
    int resolution = 0;
    raster::DepthFormat depth_format = raster::DepthFormat::D24;
    int threads = 0;
    double objects = 0, triangles = 0;  // per frame (mean)
    std::vector<double> frame_ms;       // per frame: median of the repetitions
    std::vector<double> samples;        // every timed run
    std::uint64_t pairs = 0, truth_pairs = 0, false_negatives = 0, missed_object_pairs = 0, true_objects = 0;
    std::uint64_t exact_tests = 0, broadphase_objects = 0, pcs_boxes = 0, pcs_objects = 0, subobjects = 0,
                  pcs_subobjects = 0, subobject_pairs = 0, queries = 0, triangles_rasterized = 0;
    std::uint64_t digest = 0xcbf29ce484222325ull;
    std::string check;  // exact | misses | MISMATCH
    double load = -1;
};

const char* const kCsvHeader =
    "command,scene,scale,objects,triangles,method,resolution,depth_format,threads,self,frames,warmup,reps,"
    "ms_mean,ms_median,ms_q1,ms_q3,ms_min,ms_max,fps,pairs,truth_pairs,false_negatives,missed_object_pairs,"
    "false_positives,exact_tests,broadphase_objects,pcs_boxes,pcs_objects,true_objects,subobjects,"
    "pcs_subobjects,subobject_pairs,queries,triangles_rasterized,digest,check,load";

struct Times {
    double mean, median, q1, q3, min, max;
};
Times times_of(const CaseResult& c) {
    Times t{};
    double sum = 0;
    for (double x : c.frame_ms) sum += x;
    t.mean = c.frame_ms.empty() ? 0 : sum / static_cast<double>(c.frame_ms.size());
    t.median = quantile(c.frame_ms, 0.5);
    t.q1 = quantile(c.samples, 0.25);
    t.q3 = quantile(c.samples, 0.75);
    t.min = c.samples.empty() ? 0 : *std::min_element(c.samples.begin(), c.samples.end());
    t.max = c.samples.empty() ? 0 : *std::max_element(c.samples.begin(), c.samples.end());
    return t;
}

bool visibility_method(Method m) { return m != Method::Exact; }

void write_csv_row(std::ostream& o, const BenchArgs& a, const CaseResult& c) {
    const Times t = times_of(c);
    const bool vis = visibility_method(c.method);
    o << std::defaultfloat << std::setprecision(10);  // the stream's precision is sticky: reset it per row
    o << (a.sweep ? "sweep" : "bench") << ',' << c.scene << ',' << c.scale << ',' << c.objects << ',' << c.triangles
      << ',' << to_string(c.method) << ',' << (vis ? std::to_string(c.resolution) : "") << ','
      << (vis ? to_string(c.depth_format) : "") << ',' << c.threads << ',' << (a.base.self ? 1 : 0) << ','
      << c.frame_ms.size() << ',' << a.warmup
      << ',' << a.reps << std::fixed << std::setprecision(4) << ',' << t.mean << ',' << t.median << ',' << t.q1 << ','
      << t.q3 << ',' << t.min << ',' << t.max << ',' << std::setprecision(2) << (t.mean > 0 ? 1000.0 / t.mean : 0)
      << std::defaultfloat << ',' << c.pairs << ',' << c.truth_pairs << ',' << c.false_negatives << ','
      << c.missed_object_pairs << ',' << (c.exact_tests - c.pairs) << ',' << c.exact_tests << ','
      << c.broadphase_objects << ',' << c.pcs_boxes << ',' << c.pcs_objects << ',' << c.true_objects << ','
      << c.subobjects << ',' << c.pcs_subobjects << ',' << c.subobject_pairs << ',' << c.queries << ','
      << c.triangles_rasterized << ',' << hex64(c.digest) << ',' << c.check << ',' << std::fixed
      << std::setprecision(2) << c.load << std::defaultfloat << '\n';
}

void write_json(std::ostream& o, const BenchArgs& a, const std::vector<CaseResult>& cases, double load_start,
                double load_end) {
    o << "{\"command\": \"" << (a.sweep ? "sweep" : "bench") << "\", \"hardware_threads\": "
      << std::thread::hardware_concurrency() << ", \"load_start\": " << load_start << ", \"load_end\": " << load_end
      << ", \"frames\": " << a.frames << ", \"first_frame\": " << a.first_frame << ", \"frame_step\": "
      << a.frame_step << ", \"warmup\": " << a.warmup << ", \"reps\": " << a.reps << ", \"seed\": "
      << a.scene_options.seed << ", \"subobject\": " << a.base.subobject_triangles << ", \"rounds\": "
      << a.base.max_rounds << ", \"min_prune\": " << a.base.min_prune << ", \"object_stage\": \""
      << (a.base.object_stage == ObjectStage::Auto ? "auto" : a.base.object_stage == ObjectStage::On ? "on" : "off")
      << "\", \"broadphase\": \"" << to_string(a.base.broadphase) << "\", \"self\": " << (a.base.self ? "true" : "false")
      << ", \"cases\": [";
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const CaseResult& c = cases[i];
        const Times t = times_of(c);
        o << std::defaultfloat << std::setprecision(10);
        o << (i ? ",\n  " : "\n  ") << "{\"scene\": \"" << c.scene << "\", \"scale\": " << c.scale
          << ", \"objects\": " << c.objects << ", \"triangles\": " << c.triangles << ", \"method\": \""
          << to_string(c.method) << "\", \"resolution\": " << c.resolution << ", \"depth_format\": \""
          << to_string(c.depth_format) << "\", \"threads\": " << c.threads << std::fixed << std::setprecision(4)
          << ", \"ms_mean\": " << t.mean << ", \"ms_median\": " << t.median << ", \"ms_q1\": " << t.q1
          << ", \"ms_q3\": " << t.q3 << ", \"ms_min\": " << t.min << ", \"ms_max\": " << t.max << ", \"frame_ms\": [";
        for (std::size_t f = 0; f < c.frame_ms.size(); ++f) o << (f ? ", " : "") << c.frame_ms[f];
        o << std::defaultfloat << "], \"pairs\": " << c.pairs << ", \"truth_pairs\": " << c.truth_pairs
          << ", \"false_negatives\": " << c.false_negatives << ", \"missed_object_pairs\": " << c.missed_object_pairs
          << ", \"false_positives\": " << (c.exact_tests - c.pairs) << ", \"exact_tests\": " << c.exact_tests
          << ", \"broadphase_objects\": " << c.broadphase_objects << ", \"pcs_boxes\": " << c.pcs_boxes
          << ", \"pcs_objects\": " << c.pcs_objects << ", \"true_objects\": " << c.true_objects
          << ", \"subobjects\": " << c.subobjects << ", \"pcs_subobjects\": " << c.pcs_subobjects
          << ", \"subobject_pairs\": " << c.subobject_pairs << ", \"queries\": " << c.queries
          << ", \"triangles_rasterized\": " << c.triangles_rasterized << ", \"digest\": \"" << hex64(c.digest)
          << "\", \"check\": \"" << c.check << "\", \"load\": " << c.load << "}";
    }
    o << "\n]}\n";
}

class Progress {
   public:
    Progress(bool on, std::size_t total) : on_(on && isatty(STDERR_FILENO) == 1), total_(total) {}
    void step(std::size_t done, const std::string& what) {
        if (!on_) return;
        const int width = 30;
        const auto filled = static_cast<int>(total_ ? (done * width) / total_ : width);
        std::fprintf(stderr, "\r[%-*s] %zu/%zu %-40.40s", width, std::string(static_cast<std::size_t>(filled), '#').c_str(),
                     done, total_, what.c_str());
        std::fflush(stderr);
    }
    // Erases the bar, so a table row written to the same terminal starts on a clean line.
    void clear() {
        if (!on_) return;
        std::fprintf(stderr, "\r\033[K");
        std::fflush(stderr);
    }
    ~Progress() {
        if (on_) std::fprintf(stderr, "\n");
    }

   private:
    bool on_;
    std::size_t total_;
};

struct CheckFailure {
    std::string message;
};

// A run that cannot go on (a scene that cannot be made, a frame the method rejects, a file that
// cannot be written): exit status 1, the rows printed so far stay.
struct RunFailure {
    std::string message;
};

// One row's coordinates besides scene and scale.
struct Combination {
    Method method;
    int resolution;  // 0 for exact
    raster::DepthFormat depth_format;
    int threads;
};

// Method x resolution x depth format x threads, in output order. Resolution and depth format do not
// apply to exact: one row for it, not one per grid point.
std::vector<Combination> combinations(const BenchArgs& a) {
    std::vector<Combination> v;
    for (Method m : a.methods) {
        const std::vector<int> res = !visibility_method(m)   ? std::vector<int>{0}
                                     : a.resolutions.empty() ? std::vector<int>{default_resolution(m)}
                                                             : a.resolutions;
        const std::vector<raster::DepthFormat> dfs =
            visibility_method(m) ? a.depth_formats : std::vector<raster::DepthFormat>{a.depth_formats[0]};
        for (int resolution : res) {
            for (raster::DepthFormat df : dfs) {
                for (int threads : a.threads) v.push_back({m, resolution, df, threads});
            }
        }
    }
    return v;
}

// The frames of one scene at one scale and the ground truth of each, computed once for all methods.
struct SceneFrames {
    std::vector<Frame> frames;
    std::vector<int> index;  // frame numbers
    std::vector<std::vector<TrianglePair>> truth;
};

SceneFrames scene_frames(const BenchArgs& a, const std::string& scene, double scale) {
    SceneOptions so = a.scene_options;
    so.scale = scale;
    Result<std::unique_ptr<SceneGenerator>> g = make_scene(scene, so);
    if (!g) throw RunFailure{g.error().message};
    SceneFrames sf;
    for (int k = 0; k < a.frames; ++k) {
        sf.index.push_back(a.first_frame + k * a.frame_step);
        sf.frames.push_back(g.value()->frame(sf.index.back()));
    }
    RunOptions exact = a.base;
    exact.method = Method::Exact;
    for (std::size_t f = 0; f < sf.frames.size(); ++f) {
        Result<FrameResult> r = process_frame(sf.frames[f], exact);
        if (!r) {
            throw RunFailure{"scene " + scene + " frame " + std::to_string(sf.index[f]) +
                             ": ground truth: " + r.error().message};
        }
        sf.truth.push_back(std::move(r.value().pairs));
    }
    return sf;
}

// One frame of one combination: the warm-up and timed runs, which must all give the same pairs.
struct FrameRun {
    FrameResult kept;  // the first run's
    std::uint64_t digest = 0;
    std::vector<double> reps_ms;  // the timed runs
};

FrameRun run_frame(const BenchArgs& a, const FrameRunner& runner, const Frame& frame, const RunOptions& o,
                   const std::string& where) {
    FrameRun fr;
    for (int rep = 0; rep < a.warmup + a.reps; ++rep) {
        const auto t0 = std::chrono::steady_clock::now();
        Result<FrameResult> r = runner(frame, o);
        const auto t1 = std::chrono::steady_clock::now();
        if (!r) throw RunFailure{where + ": " + r.error().message};
        const std::uint64_t d = pairs_digest(r.value().pairs);
        if (rep > 0 && fr.digest != d) {
            throw CheckFailure{where + ": repeated runs gave different pairs (digest " + hex64(fr.digest) +
                               " then " + hex64(d) + "): the method is not deterministic"};
        }
        fr.digest = d;
        if (rep >= a.warmup) fr.reps_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        if (rep == 0) fr.kept = std::move(r.value());
    }
    return fr;
}

// Adds one frame's figures to its row (objects and triangles as means over `frames`).
void accumulate(CaseResult& c, const FrameRun& fr, const Comparison& cmp, std::size_t truth_pairs,
                std::size_t frames) {
    const FrameStats& s = fr.kept.stats;
    c.objects += static_cast<double>(s.objects) / static_cast<double>(frames);
    c.triangles += static_cast<double>(s.triangles) / static_cast<double>(frames);
    c.frame_ms.push_back(quantile(fr.reps_ms, 0.5));
    c.samples.insert(c.samples.end(), fr.reps_ms.begin(), fr.reps_ms.end());
    c.pairs += fr.kept.pairs.size();
    c.truth_pairs += truth_pairs;
    c.false_negatives += cmp.false_negatives;
    c.missed_object_pairs += cmp.missed_object_pairs;
    c.true_objects += cmp.true_objects;
    c.exact_tests += s.exact_tests;
    c.broadphase_objects += s.broadphase_objects;
    c.pcs_boxes += s.pcs_boxes;
    c.pcs_objects += s.pcs_objects;
    c.subobjects += s.subobjects;
    c.pcs_subobjects += s.pcs_subobjects;
    c.subobject_pairs += s.subobject_pairs;
    c.queries += s.queries;
    c.triangles_rasterized += s.triangles_rasterized;
    c.digest = fnv_bytes(c.digest, fr.digest, 8);
}

// One combination over the scene's frames, every answer checked against the ground truth. A
// reported pair that does not collide fails the command; so does a miss by a method that never
// misses in bench, while sweep records it as MISMATCH (stderr and `mismatch`) and goes on.
CaseResult run_case(const BenchArgs& a, const FrameRunner& runner, const SceneFrames& sf, CaseResult c,
                    std::ostream& err, bool& mismatch) {
    RunOptions o = a.base;
    o.method = c.method;
    o.resolution = c.resolution;
    o.depth_format = c.depth_format;
    o.threads = c.threads;
    bool misses = false;
    for (std::size_t f = 0; f < sf.frames.size(); ++f) {
        const std::string where = "scene " + c.scene + " (scale " + std::to_string(c.scale) + "), method " +
                                  to_string(c.method) + ", frame " + std::to_string(sf.index[f]);
        const FrameRun fr = run_frame(a, runner, sf.frames[f], o, where);
        const Comparison cmp = compare_with_truth(sf.truth[f], fr.kept.pairs);
        if (cmp.extra_pairs != 0) {
            throw CheckFailure{where + ": " + std::to_string(cmp.extra_pairs) +
                               " reported pair(s) are not colliding pairs of the ground truth"};
        }
        if (cmp.false_negatives != 0) {
            misses = true;
            if (never_misses(c.method)) {
                const std::string msg = where + ": digest mismatch: " + hex64(fr.digest) +
                                        " vs ground truth " + hex64(pairs_digest(sf.truth[f])) + ", " +
                                        std::to_string(cmp.false_negatives) +
                                        " colliding pair(s) missed by a method that never misses";
                if (!a.sweep) throw CheckFailure{msg};
                err << "cullide: MISMATCH: " << msg << "\n";
                mismatch = true;
            }
        }
        accumulate(c, fr, cmp, sf.truth[f].size(), sf.frames.size());
    }
    c.check = !misses ? "exact" : never_misses(c.method) ? "MISMATCH" : "misses";
    c.load = load_average();
    return c;
}

// The CSV sink: stdout for '-', else the file (opened here), else none.
std::ostream* open_csv(const BenchArgs& a, std::ostream& out, std::ofstream& file) {
    if (a.csv_path.empty()) return nullptr;
    if (a.csv_path == "-") return &out;
    file.open(a.csv_path, std::ios::out | std::ios::trunc);
    if (!file) throw RunFailure{"cannot open '" + a.csv_path + "' for writing"};
    return &file;
}

void print_table_header(std::ostream& out, const BenchArgs& a, double load_start) {
    out << "cullide " << (a.sweep ? "sweep" : "bench") << ": " << a.frames << " frame(s) from "
        << a.first_frame << " step " << a.frame_step << ", warm-up " << a.warmup << ", " << a.reps
        << " rep(s); load " << std::fixed << std::setprecision(2) << load_start << std::defaultfloat << " on "
        << std::thread::hardware_concurrency() << " hardware threads";
    // Said only when not the default, so the usual header stays as it was.
    if (a.base.gpu_rules != raster::RasterRules::GlLlvmpipe) out << "; gpu rules " << to_string(a.base.gpu_rules);
    out << "\n";
    out << std::left << std::setw(13) << "scene" << std::setw(6) << "scale" << std::setw(16) << "method"
        << std::setw(6) << "res" << std::setw(5) << "dep" << std::setw(4) << "thr" << std::right
        << std::setw(10) << "ms/frame" << std::setw(10) << "median" << std::setw(22) << "[min, max]"
        << std::setw(9) << "pairs" << std::setw(8) << "misses" << std::setw(10) << "false+"
        << "  check\n";
}

void print_table_row(std::ostream& out, const CaseResult& c) {
    out << std::defaultfloat << std::setprecision(6);
    const Times t = times_of(c);
    const bool vis = visibility_method(c.method);
    std::ostringstream spread;
    spread << std::fixed << std::setprecision(2) << "[" << t.min << ", " << t.max << "]";
    out << std::left << std::setw(13) << c.scene << std::setw(6) << c.scale << std::setw(16)
        << to_string(c.method) << std::setw(6) << (vis ? std::to_string(c.resolution) : "-") << std::setw(5)
        << (vis ? to_string(c.depth_format) : "-") << std::setw(4) << c.threads << std::right << std::fixed
        << std::setprecision(2) << std::setw(10) << t.mean << std::setw(10) << t.median << std::setw(22)
        << spread.str() << std::defaultfloat << std::setw(9) << c.pairs << std::setw(8) << c.false_negatives
        << std::setw(10) << (c.exact_tests - c.pairs) << "  " << c.check << "\n";
    out.flush();
}

void write_json_to(const BenchArgs& a, const std::vector<CaseResult>& cases, double load_start,
                   std::ostream& out) {
    if (a.json_path == "-") {
        write_json(out, a, cases, load_start, load_average());
        return;
    }
    std::ofstream j(a.json_path, std::ios::out | std::ios::trunc);
    if (j) write_json(j, a, cases, load_start, load_average());
    if (j) j.close();
    if (!j) throw RunFailure{"cannot write '" + a.json_path + "'"};
}

// The grid: every scene x scale x combination, a row each, to the CSV, the table and the JSON.
int run_grid(const BenchArgs& a, std::ostream& out, std::ostream& err, const FrameRunner& runner) {
    const double load_start = load_average();
    std::ofstream csv_file;
    std::ostream* csv = open_csv(a, out, csv_file);
    if (csv) *csv << kCsvHeader << '\n';
    const bool table = a.csv_path != "-" && a.json_path != "-";
    if (table) print_table_header(out, a, load_start);
    const std::vector<Combination> combos = combinations(a);
    Progress progress(a.progress, a.scenes.size() * a.scales.size() * combos.size());
    std::vector<CaseResult> cases;
    bool mismatch = false;
    for (const std::string& scene : a.scenes) {
        for (double scale : a.scales) {
            const SceneFrames sf = scene_frames(a, scene, scale);
            for (const Combination& k : combos) {
                CaseResult c;
                c.scene = scene;
                c.scale = scale;
                c.method = k.method;
                c.resolution = k.resolution;
                c.depth_format = k.depth_format;
                c.threads = k.threads;
                progress.step(cases.size(), scene + " " + to_string(k.method) + " " +
                                                std::to_string(k.resolution) + " " +
                                                to_string(k.depth_format));
                c = run_case(a, runner, sf, std::move(c), err, mismatch);
                if (csv) {
                    write_csv_row(*csv, a, c);
                    csv->flush();
                }
                if (table) {
                    progress.clear();
                    print_table_row(out, c);
                }
                cases.push_back(std::move(c));
            }
        }
    }
    progress.step(cases.size(), "done");
    if (csv_file.is_open()) {
        csv_file.close();
        if (!csv_file) throw RunFailure{"writing '" + a.csv_path + "' failed"};
    }
    if (!a.json_path.empty()) write_json_to(a, cases, load_start, out);
    return mismatch ? 1 : 0;
}

int run_bench(const BenchArgs& a, std::ostream& out, std::ostream& err, const FrameRunner& runner) {
    try {
        return run_grid(a, out, err, runner);
    } catch (const RunFailure& f) {
        err << "cullide: error: " << f.message << "\n";
        return 1;
    }
}

}  // namespace

std::uint64_t pairs_digest(std::span<const TrianglePair> pairs) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const TrianglePair& p : pairs) {
        h = fnv_bytes(h, p.object_a, 4);
        h = fnv_bytes(h, p.triangle_a, 4);
        h = fnv_bytes(h, p.object_b, 4);
        h = fnv_bytes(h, p.triangle_b, 4);
    }
    return h;
}

bool never_misses(Method m) {
    // By name, so methods added to pipeline.h later default to "may miss" until listed here.
    const std::string_view n = to_string(m);
    return n == "exact" || n == "rcullide" || n == "rcullide-offset" || n == "qcullide" || n == "auto";
}

int bench_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                  const FrameRunner* runner) {
    const Command command = !args.empty() && args[0] == "sweep" ? Command::Sweep : Command::Bench;
    const char* name = command_name(command);
    try {
        const Settings settings = parse_options(command, args);
        if (settings.help) {
            out << command_help(command);
            return 0;
        }
        const BenchArgs a = bench_args_of(command, settings);
        // One FrameContext for the whole command, as a simulation loop holds one across its frames:
        // what it keeps (the emulator device, qcullide --self's triangle orders) changes no result
        // (every repeated run is still checked for the same pairs), only the set-up each frame pays.
        FrameContext context;
        const FrameRunner process = [&context](std::span<const Mesh> objects, const RunOptions& o) {
            return process_frame(objects, o, context);
        };
        return run_bench(a, out, err, runner ? *runner : process);
    } catch (const UsageError& e) {
        err << "cullide " << name << ": " << e.message << "\n(run 'cullide " << name << " --help' for usage)\n";
        return 2;
    } catch (const CheckFailure& e) {
        err << "cullide " << name << ": check failed, no time reported: " << e.message << "\n";
        return 1;
    }
}

}  // namespace cullide::cli
