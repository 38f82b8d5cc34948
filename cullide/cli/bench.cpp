// cullide/cli/bench.cpp: the engine of `cullide bench` and `cullide sweep` (bench.h), and bench's
// options and output (CSV, JSON, a table on stdout).
#include "bench.h"

#include <algorithm>
#include <charconv>
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
#include "cullide/scenes.h"

namespace cullide::cli {

using namespace bench_detail;

namespace {

constexpr const char* kBenchUsage =
    "usage: cullide bench [options]\n"
    "\n"
    "Times methods frame by frame on built-in scenes. Each frame of each combination scene x scale x\n"
    "method x resolution x depth format x threads runs --warmup untimed times, then --reps timed\n"
    "times; the time of a frame is the median of its repetitions. Before any time is reported the\n"
    "pairs are checked: every repetition must give the same pairs (digest), no reported pair may be\n"
    "rejected by the exact test, and a method that never misses (exact, rcullide, rcullide-offset,\n"
    "qcullide)\n"
    "must give exactly the ground truth's pairs; otherwise the command fails (exit 1) naming the\n"
    "scene, method and frame. Methods that may miss (cullide) are reported with their misses.\n"
    "\n"
    "options (LIST = comma-separated values):\n"
    "  --scenes LIST         built-in scenes (default cylinders; 'all' = every scene)\n"
    "  --scales LIST         scene size factors, each in (0, 100] (default 1)\n"
    "  --methods LIST        methods (default exact,cullide,rcullide; 'all' = every method)\n"
    "  --resolutions LIST    view resolutions, each 16..16384 (default: each method's own, 32 for\n"
    "                        rcullide and qcullide, 1024 for the others)\n"
    "  --depth-formats LIST  d16, d24, d32f (default d24)\n"
    "  --threads LIST        worker threads, each 0..1024, 0 = all cores (default 0)\n"
    "  --frames N            frames per scene, 1..100000 (default 5)\n"
    "  --first-frame F       first frame index (default 0)\n"
    "  --frame-step K        frame index step, 1..100000 (default 1)\n"
    "  --warmup N            untimed runs per frame, 0..1000 (default 1)\n"
    "  --reps N              timed runs per frame, 1..1000 (default 5)\n"
    "  --subobject N, --rounds N, --min-prune F, --object-stage S, --broadphase B, --self, --seed S,\n"
    "  --mesh-dir DIR: as 'cullide run'\n"
    "  --csv FILE            write one CSV row per combination ('-' = stdout)\n"
    "  --json FILE           write a JSON document ('-' = stdout)\n"
    "  --no-progress         no progress bar (it is drawn on stderr only when stderr is a terminal)\n"
    "\n"
    "Times are wall-clock milliseconds per frame (frame generation excluded); counts (pairs, false\n"
    "negatives, PCS sizes, queries) are totals over the frames. The load average is recorded.\n";

template <class T>
std::optional<T> parse_int(std::string_view s) {
    T v{};
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
    return v;
}

std::optional<double> parse_real(std::string_view s) {
    double v = 0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

std::vector<std::string> split_list(const std::string& option, const std::string& v) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = v.find(',', start);
        std::string item = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        if (item.empty()) throw BenchUsageError{option + ": empty item in list '" + v + "'"};
        parts.push_back(std::move(item));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return parts;
}

int int_in(const std::string& option, const std::string& v, int lo, int hi) {
    auto n = parse_int<int>(v);
    if (!n || *n < lo || *n > hi) {
        throw BenchUsageError{option + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                              " (got '" + v + "')"};
    }
    return *n;
}

bool is_scene(const std::string& name) {
    const std::vector<std::string> names = scene_names();
    return std::find(names.begin(), names.end(), name) != names.end();
}

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

BenchArgs parse_args(const std::vector<std::string>& args) {
    BenchArgs a;
    a.sweep = args[0] == "sweep";
    a.warmup = -1;
    auto value = [&](std::size_t& i) -> const std::string& {
        if (i + 1 >= args.size()) throw BenchUsageError{"option " + args[i] + " needs a value"};
        return args[++i];
    };
    for (std::size_t i = 1; i < args.size(); ++i) {
        const std::string& o = args[i];
        if (o == "--scenes") {
            a.scenes.clear();  // a repeated option replaces the list
            for (const std::string& s : split_list(o, value(i))) {
                if (s == "all") {
                    for (const std::string& n : scene_names()) a.scenes.push_back(n);
                } else if (!is_scene(s)) {
                    throw BenchUsageError{"--scenes: unknown scene '" + s + "' (valid: " + joined(scene_names()) + ", all)"};
                } else {
                    a.scenes.push_back(s);
                }
            }
        } else if (o == "--scales") {
            a.scales.clear();  // a repeated option replaces the list
            for (const std::string& s : split_list(o, value(i))) {
                auto x = parse_real(s);
                if (!x || !(*x > 0) || *x > 100) throw BenchUsageError{"--scales: each must be a number in (0, 100] (got '" + s + "')"};
                a.scales.push_back(*x);
            }
        } else if (o == "--methods") {
            a.methods.clear();  // a repeated option replaces the list
            for (const std::string& s : split_list(o, value(i))) {
                if (s == "all") {
                    for (const std::string& n : method_names()) a.methods.push_back(parse_method(n).value());
                    continue;
                }
                Result<Method> m = parse_method(s);
                if (!m) throw BenchUsageError{"--methods: " + m.error().message};
                a.methods.push_back(m.value());
            }
        } else if (o == "--resolutions") {
            a.resolutions.clear();  // a repeated option replaces the list
            for (const std::string& s : split_list(o, value(i))) a.resolutions.push_back(int_in(o, s, 16, 16384));
        } else if (o == "--depth-formats") {
            a.depth_formats.clear();  // a repeated option replaces the list
            for (const std::string& s : split_list(o, value(i))) {
                Result<raster::DepthFormat> f = parse_depth_format(s);
                if (!f) throw BenchUsageError{"--depth-formats: " + f.error().message};
                a.depth_formats.push_back(f.value());
            }
        } else if (o == "--threads") {
            a.threads.clear();  // a repeated option replaces the list
            for (const std::string& s : split_list(o, value(i))) a.threads.push_back(int_in(o, s, 0, 1024));
        } else if (o == "--frames") {
            a.frames = int_in(o, value(i), 1, 100000);
        } else if (o == "--first-frame") {
            a.first_frame = int_in(o, value(i), -1000000, 1000000);
        } else if (o == "--frame-step") {
            a.frame_step = int_in(o, value(i), 1, 100000);
        } else if (o == "--warmup") {
            a.warmup = int_in(o, value(i), 0, 1000);
        } else if (o == "--reps") {
            a.reps = int_in(o, value(i), 1, 1000);
        } else if (o == "--subobject") {
            a.base.subobject_triangles = int_in(o, value(i), 1, 65536);
        } else if (o == "--rounds") {
            a.base.max_rounds = int_in(o, value(i), 1, 1000);
        } else if (o == "--min-prune") {
            const std::string& v = value(i);
            auto x = parse_real(v);
            if (!x || !(*x >= 0) || !(*x < 1)) throw BenchUsageError{"--min-prune must be a number in [0, 1) (got '" + v + "')"};
            a.base.min_prune = *x;
        } else if (o == "--object-stage") {
            const std::string& v = value(i);
            if (v == "auto") a.base.object_stage = ObjectStage::Auto;
            else if (v == "on") a.base.object_stage = ObjectStage::On;
            else if (v == "off") a.base.object_stage = ObjectStage::Off;
            else throw BenchUsageError{"--object-stage must be auto, on or off (got '" + v + "')"};
        } else if (o == "--broadphase") {
            Result<BroadPhase> b = parse_broadphase(value(i));
            if (!b) throw BenchUsageError{"--broadphase: " + b.error().message};
            a.base.broadphase = b.value();
        } else if (o == "--self") {
            a.base.self = true;
        } else if (o == "--seed") {
            const std::string& v = value(i);
            auto n = parse_int<std::uint64_t>(v);
            if (!n) throw BenchUsageError{"--seed must be an unsigned 64-bit integer (got '" + v + "')"};
            a.scene_options.seed = *n;
        } else if (o == "--mesh-dir") {
            a.scene_options.mesh_dir = value(i);
        } else if (o == "--csv") {
            a.csv_path = value(i);
        } else if (o == "--json") {
            a.json_path = value(i);
        } else if (o == "--no-progress") {
            a.progress = false;
        } else {
            throw BenchUsageError{"unknown option '" + o + "'" +
                                  (o.empty() || o[0] != '-' ? " (scenes are given with --scenes)" : "")};
        }
    }
    if (a.csv_path == "-" && a.json_path == "-") throw BenchUsageError{"--csv - and --json - cannot both go to stdout"};
    if (a.sweep) apply_sweep_defaults(a);
    if (a.scenes.empty()) a.scenes = {"cylinders"};
    if (a.scales.empty()) a.scales = {1.0};
    if (a.methods.empty()) a.methods = {Method::Exact, Method::Cullide, Method::RCullide};
    // No --resolutions: each visibility method at its own default (pipeline.h default_resolution).
    if (a.depth_formats.empty()) a.depth_formats = {a.base.depth_format};
    if (a.threads.empty()) a.threads = {0};
    if (a.frames == 0) a.frames = 5;
    if (a.warmup < 0) a.warmup = 1;
    if (a.reps == 0) a.reps = 5;
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

int run_bench(const BenchArgs& a, std::ostream& out, std::ostream& err, const FrameRunner& runner) {
    const double load_start = load_average();
    std::vector<CaseResult> cases;
    bool mismatch = false;
    std::ofstream csv_file;
    std::ostream* csv = nullptr;
    if (a.csv_path == "-") {
        csv = &out;
    } else if (!a.csv_path.empty()) {
        csv_file.open(a.csv_path, std::ios::out | std::ios::trunc);
        if (!csv_file) {
            err << "cullide: error: cannot open '" << a.csv_path << "' for writing\n";
            return 1;
        }
        csv = &csv_file;
    }
    if (csv) *csv << kCsvHeader << '\n';
    const bool table = a.csv_path != "-" && a.json_path != "-";
    if (table) {
        out << "cullide " << (a.sweep ? "sweep" : "bench") << ": " << a.frames << " frame(s) from " << a.first_frame
            << " step " << a.frame_step << ", warm-up " << a.warmup << ", " << a.reps << " rep(s); load "
            << std::fixed << std::setprecision(2) << load_start << std::defaultfloat << " on "
            << std::thread::hardware_concurrency() << " hardware threads\n";
        out << std::left << std::setw(13) << "scene" << std::setw(6) << "scale" << std::setw(16) << "method"
            << std::setw(6) << "res" << std::setw(5) << "dep" << std::setw(4) << "thr" << std::right << std::setw(10)
            << "ms/frame" << std::setw(10) << "median" << std::setw(22) << "[min, max]" << std::setw(9) << "pairs"
            << std::setw(8) << "misses" << std::setw(10) << "false+" << "  check\n";
    }
    const std::size_t per_scene =
        a.methods.size() * std::max<std::size_t>(1, a.resolutions.size()) * a.depth_formats.size() * a.threads.size();
    Progress progress(a.progress, a.scenes.size() * a.scales.size() * per_scene);
    std::size_t done = 0;
    for (const std::string& scene : a.scenes) {
        for (double scale : a.scales) {
            SceneOptions so = a.scene_options;
            so.scale = scale;
            Result<std::unique_ptr<SceneGenerator>> g = make_scene(scene, so);
            if (!g) {
                err << "cullide: error: " << g.error().message << "\n";
                return 1;
            }
            std::vector<Frame> frames;
            std::vector<int> frame_index;
            for (int k = 0; k < a.frames; ++k) {
                frame_index.push_back(a.first_frame + k * a.frame_step);
                frames.push_back(g.value()->frame(frame_index.back()));
            }
            // The ground truth of each frame, once per scene and scale.
            std::vector<std::vector<TrianglePair>> truth;
            for (std::size_t f = 0; f < frames.size(); ++f) {
                RunOptions o = a.base;
                o.method = Method::Exact;
                Result<FrameResult> r = process_frame(frames[f], o);
                if (!r) {
                    err << "cullide: error: scene " << scene << " frame " << frame_index[f]
                        << ": ground truth: " << r.error().message << "\n";
                    return 1;
                }
                truth.push_back(std::move(r.value().pairs));
            }
            for (Method m : a.methods) {
                // Resolution and depth format do not apply to exact: one row, not one per grid point.
                const std::vector<int> res = !visibility_method(m)   ? std::vector<int>{0}
                                             : a.resolutions.empty() ? std::vector<int>{default_resolution(m)}
                                                                     : a.resolutions;
                const std::vector<raster::DepthFormat> dfs =
                    visibility_method(m) ? a.depth_formats : std::vector<raster::DepthFormat>{a.depth_formats[0]};
                for (int resolution : res) {
                    for (raster::DepthFormat df : dfs) {
                        for (int threads : a.threads) {
                            CaseResult c;
                            c.scene = scene;
                            c.scale = scale;
                            c.method = m;
                            c.resolution = resolution;
                            c.depth_format = df;
                            c.threads = threads;
                            RunOptions o = a.base;
                            o.method = m;
                            o.resolution = resolution;
                            o.depth_format = df;
                            o.threads = threads;
                            std::ostringstream label;
                            label << scene << " " << to_string(m) << " " << resolution << " " << to_string(df);
                            progress.step(done, label.str());
                            bool misses = false;
                            for (std::size_t f = 0; f < frames.size(); ++f) {
                                const std::string where = "scene " + scene + " (scale " + std::to_string(scale) +
                                                          "), method " + to_string(m) + ", frame " +
                                                          std::to_string(frame_index[f]);
                                std::vector<double> reps;
                                std::optional<std::uint64_t> first_digest;
                                FrameResult kept;
                                for (int rep = 0; rep < a.warmup + a.reps; ++rep) {
                                    const auto t0 = std::chrono::steady_clock::now();
                                    Result<FrameResult> r = runner(frames[f], o);
                                    const auto t1 = std::chrono::steady_clock::now();
                                    if (!r) {
                                        err << "cullide: error: " << where << ": " << r.error().message << "\n";
                                        return 1;
                                    }
                                    const std::uint64_t d = pairs_digest(r.value().pairs);
                                    if (first_digest && *first_digest != d) {
                                        throw CheckFailure{where + ": repeated runs gave different pairs (digest " +
                                                           hex64(*first_digest) + " then " + hex64(d) +
                                                           "): the method is not deterministic"};
                                    }
                                    first_digest = d;
                                    if (rep >= a.warmup) {
                                        reps.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
                                    }
                                    if (rep == 0) kept = std::move(r.value());
                                }
                                const Comparison cmp = compare_with_truth(truth[f], kept.pairs);
                                if (cmp.extra_pairs != 0) {
                                    throw CheckFailure{where + ": " + std::to_string(cmp.extra_pairs) +
                                                       " reported pair(s) are not colliding pairs of the ground truth"};
                                }
                                if (cmp.false_negatives != 0) {
                                    misses = true;
                                    if (never_misses(m)) {
                                        const std::string msg = where + ": digest mismatch: " + hex64(*first_digest) +
                                                                " vs ground truth " + hex64(pairs_digest(truth[f])) +
                                                                ", " + std::to_string(cmp.false_negatives) +
                                                                " colliding pair(s) missed by a method that never misses";
                                        if (!a.sweep) throw CheckFailure{msg};
                                        err << "cullide: MISMATCH: " << msg << "\n";
                                        mismatch = true;
                                    }
                                }
                                const FrameStats& s = kept.stats;
                                c.objects += static_cast<double>(s.objects) / static_cast<double>(frames.size());
                                c.triangles += static_cast<double>(s.triangles) / static_cast<double>(frames.size());
                                c.frame_ms.push_back(quantile(reps, 0.5));
                                c.samples.insert(c.samples.end(), reps.begin(), reps.end());
                                c.pairs += kept.pairs.size();
                                c.truth_pairs += truth[f].size();
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
                                c.digest = fnv_bytes(c.digest, *first_digest, 8);
                            }
                            c.check = !misses ? "exact" : never_misses(m) ? "MISMATCH" : "misses";
                            c.load = load_average();
                            ++done;
                            if (csv) {
                                write_csv_row(*csv, a, c);
                                csv->flush();
                            }
                            if (table) {
                                progress.clear();
                                out << std::defaultfloat << std::setprecision(6);
                                const Times t = times_of(c);
                                std::ostringstream spread;
                                spread << std::fixed << std::setprecision(2) << "[" << t.min << ", " << t.max << "]";
                                out << std::left << std::setw(13) << c.scene << std::setw(6) << c.scale << std::setw(16)
                                    << to_string(c.method) << std::setw(6)
                                    << (visibility_method(m) ? std::to_string(resolution) : "-") << std::setw(5)
                                    << (visibility_method(m) ? to_string(df) : "-") << std::setw(4) << threads
                                    << std::right << std::fixed << std::setprecision(2) << std::setw(10) << t.mean
                                    << std::setw(10) << t.median << std::setw(22) << spread.str() << std::defaultfloat
                                    << std::setw(9) << c.pairs << std::setw(8) << c.false_negatives << std::setw(10)
                                    << (c.exact_tests - c.pairs) << "  " << c.check << "\n";
                                out.flush();
                            }
                            cases.push_back(std::move(c));
                        }
                    }
                }
            }
        }
    }
    progress.step(done, "done");
    if (csv_file.is_open()) {
        csv_file.close();
        if (!csv_file) {
            err << "cullide: error: writing '" << a.csv_path << "' failed\n";
            return 1;
        }
    }
    if (!a.json_path.empty()) {
        if (a.json_path == "-") {
            write_json(out, a, cases, load_start, load_average());
        } else {
            std::ofstream j(a.json_path, std::ios::out | std::ios::trunc);
            if (j) write_json(j, a, cases, load_start, load_average());
            if (j) j.close();
            if (!j) {
                err << "cullide: error: cannot write '" << a.json_path << "'\n";
                return 1;
            }
        }
    }
    return mismatch ? 1 : 0;
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
    return n == "exact" || n == "rcullide" || n == "rcullide-offset" || n == "qcullide";
}

int bench_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                  const FrameRunner* runner) {
    const bool sweep = !args.empty() && args[0] == "sweep";
    const char* name = sweep ? "sweep" : "bench";
    try {
        for (std::size_t i = 1; i < args.size(); ++i) {
            if (args[i] == "--help" || args[i] == "-h") {
                out << (sweep ? kSweepUsage : kBenchUsage);
                return 0;
            }
        }
        const BenchArgs a = parse_args(args);
        const FrameRunner process = [](std::span<const Mesh> objects, const RunOptions& o) {
            return process_frame(objects, o);
        };
        return run_bench(a, out, err, runner ? *runner : process);
    } catch (const BenchUsageError& e) {
        err << "cullide " << name << ": " << e.message << "\n(run 'cullide " << name << " --help' for usage)\n";
        return 2;
    } catch (const CheckFailure& e) {
        err << "cullide " << name << ": check failed, no time reported: " << e.message << "\n";
        return 1;
    }
}

}  // namespace cullide::cli
