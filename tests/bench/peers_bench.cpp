// tests/bench/peers_bench.cpp: cullide's methods and other collision libraries side by side, in one
// run, on the same frames of the built-in scenes (issue #8, ../shared/docs/peers.md).
//
// For every scene and frame k (frame index f = first + k * step) and every peer:
//   build(f)  timed: every structure from scratch, then query() timed: the rigid case (prebuilt tree);
//   build(f - step) untimed, refit(f) timed, query() timed: the deforming case with refit.
// Every answer is sorted, deduplicated and compared with the ground truth (exact_pairs) of the frame:
// peers that are not exact are labelled so, with their misses and extra pairs. cullide's own methods
// (process_frame) run on the same frames; their time is the whole frame (no tree survives a frame).
// Output: a table on stdout and, with --csv FILE, one CSV row per (scene, peer); times are medians
// over the frames (queries: of --reps repetitions each), wall-clock milliseconds; the load average is
// recorded. Peers are compiled in only when their library was found (tests/bench/CMakeLists.txt).
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "peers/peer.h"

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double load_average() {
    std::ifstream f("/proc/loadavg");
    double l = -1;
    f >> l;
    return l;
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

[[noreturn]] void usage_error(const std::string& msg) {
    std::cerr << "peers_bench: " << msg << "\n"
              << "usage: peers_bench [--scenes LIST] [--scales LIST] [--frames N] [--first-frame F]\n"
              << "       [--frame-step K] [--reps N] [--threads T] [--peers LIST] [--methods LIST]\n"
              << "       [--resolution R] [--mesh-dir DIR] [--csv FILE]\n"
              << "peers: fcl-obbrss, fcl-aabb, bullet-gimpact, bullet-gimpact-exact, embree-collide, cgal-box-d (default: all built)\n";
    std::exit(2);
}

int int_arg(const std::string& opt, const std::string& v, int lo, int hi) {
    int n = 0;
    auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (v.empty() || ec != std::errc() || p != v.data() + v.size() || n < lo || n > hi) {
        usage_error(opt + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + " (got '" + v + "')");
    }
    return n;
}

struct Row {
    std::string scene;
    double scale = 1;
    double objects = 0, triangles = 0;
    std::string peer, narrow;
    std::vector<double> build, refit, query, query_refit, total;
    std::uint64_t pairs = 0, truth = 0, misses = 0, extra = 0;
    std::uint64_t refit_misses = 0, refit_extra = 0;  // of the refitted tree's answers
    bool refit_is_rebuild = false;
    bool ours = false;
};

void compare(const std::vector<cullide::TrianglePair>& truth, std::vector<cullide::TrianglePair> got, Row& r) {
    std::sort(got.begin(), got.end());
    got.erase(std::unique(got.begin(), got.end()), got.end());
    std::vector<cullide::TrianglePair> miss, extra;
    std::set_difference(truth.begin(), truth.end(), got.begin(), got.end(), std::back_inserter(miss));
    std::set_difference(got.begin(), got.end(), truth.begin(), truth.end(), std::back_inserter(extra));
    r.pairs += got.size();
    r.truth += truth.size();
    r.misses += miss.size();
    r.extra += extra.size();
}

}  // namespace

int main(int argc, char** argv) {
    // As the cullide command does (cullide/pipeline.h); the peers run in this process too.
    const bool retained = cullide::retain_freed_memory();
    std::vector<std::string> scenes{"cylinders"}, peer_names, methods{"exact", "cullide", "rcullide"};
    std::vector<double> scales{1.0};
    int frames = 3, first = 0, step = 5, reps = 3, threads = 0, resolution = 0;  // 0: each method's default
    std::string csv_path;
    cullide::SceneOptions scene_options;
#ifdef CULLIDE_SHARED_MESH_DIR
    scene_options.mesh_dir = CULLIDE_SHARED_MESH_DIR;
#endif
    for (int i = 1; i < argc; ++i) {
        const std::string o = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage_error("option " + o + " needs a value");
            return argv[++i];
        };
        if (o == "--scenes") scenes = split(value());
        else if (o == "--scales") {
            scales.clear();
            for (const std::string& s : split(value())) {
                char* end = nullptr;
                const double x = std::strtod(s.c_str(), &end);
                if (*end != '\0' || !(x > 0) || x > 100) usage_error("--scales: each must be in (0, 100] (got '" + s + "')");
                scales.push_back(x);
            }
        } else if (o == "--frames") frames = int_arg(o, value(), 1, 10000);
        else if (o == "--first-frame") first = int_arg(o, value(), -1000000, 1000000);
        else if (o == "--frame-step") step = int_arg(o, value(), 1, 100000);
        else if (o == "--reps") reps = int_arg(o, value(), 1, 1000);
        else if (o == "--threads") threads = int_arg(o, value(), 0, 1024);
        else if (o == "--resolution") resolution = int_arg(o, value(), 16, 16384);  // all visibility methods
        else if (o == "--peers") peer_names = split(value());
        else if (o == "--methods") methods = split(value());
        else if (o == "--mesh-dir") scene_options.mesh_dir = value();
        else if (o == "--csv") csv_path = value();
        else usage_error("unknown option '" + o + "'");
    }

    // The peers built into this binary.
    std::vector<std::function<std::unique_ptr<peers::Peer>()>> factories;
    std::vector<std::string> built;
#ifdef PEERS_HAVE_FCL
    factories.push_back([&] { return peers::make_fcl(true, threads); });
    built.push_back("fcl-obbrss");
    factories.push_back([&] { return peers::make_fcl(false, threads); });
    built.push_back("fcl-aabb");
#endif
#ifdef PEERS_HAVE_BULLET
    factories.push_back([&] { return peers::make_bullet(false, threads); });
    built.push_back("bullet-gimpact");
    factories.push_back([&] { return peers::make_bullet(true, threads); });
    built.push_back("bullet-gimpact-exact");
#endif
#ifdef PEERS_HAVE_EMBREE
    factories.push_back([&] { return peers::make_embree(threads); });
    built.push_back("embree-collide");
#endif
#ifdef PEERS_HAVE_CGAL
    factories.push_back([&] { return peers::make_cgal(threads); });
    built.push_back("cgal-box-d");
#endif
    std::vector<bool> enabled(built.size(), peer_names.empty());
    for (const std::string& p : peer_names) {
        auto it = std::find(built.begin(), built.end(), p);
        if (it == built.end()) usage_error("peer '" + p + "' is unknown or was not built in");
        enabled[static_cast<std::size_t>(it - built.begin())] = true;
    }
    std::vector<cullide::Method> our;
    for (const std::string& m : methods) {
        cullide::Result<cullide::Method> pm = cullide::parse_method(m);
        if (!pm) usage_error("--methods: " + pm.error().message);
        our.push_back(pm.value());
    }

    std::ofstream csv;
    if (!csv_path.empty()) {
        csv.open(csv_path, std::ios::out | std::ios::trunc);
        if (!csv) usage_error("cannot open '" + csv_path + "' for writing");
        csv << "scene,scale,objects,triangles,frames,threads,peer,narrow_phase,build_ms,refit_ms,refit_is_rebuild,"
               "query_ms,query_after_refit_ms,rigid_ms,deform_rebuild_ms,deform_refit_ms,frame_ms,pairs,truth_pairs,"
               "misses,extra,refit_misses,refit_extra,exact,load\n";
    }
    std::cout << "peers_bench: " << frames << " frame(s) from " << first << " step " << step << ", " << reps
              << " query rep(s), threads " << threads << ", load " << std::fixed << std::setprecision(2)
              << load_average() << std::defaultfloat << ", freed memory retained: " << (retained ? "yes" : "no") << "\n";
    int status = 0;
    for (const std::string& scene : scenes) {
        for (double scale : scales) {
            cullide::SceneOptions so = scene_options;
            so.scale = scale;
            auto gen = cullide::make_scene(scene, so);
            if (!gen) {
                std::cerr << "peers_bench: " << gen.error().message << "\n";
                return 1;
            }
            std::vector<cullide::Frame> cur, prev;
            std::vector<std::vector<cullide::TrianglePair>> truth;
            std::vector<double> truth_ms;
            double objects = 0, triangles = 0;
            for (int k = 0; k < frames; ++k) {
                const int f = first + k * step;
                cur.push_back(gen.value()->frame(f));
                prev.push_back(gen.value()->frame(f - step));
                cullide::ExactOptions eo;
                eo.threads = threads;
                const auto t0 = Clock::now();
                auto t = cullide::exact_pairs(cur.back(), eo);
                truth_ms.push_back(ms_since(t0));
                if (!t) {
                    std::cerr << "peers_bench: " << scene << " frame " << f << ": " << t.error().message << "\n";
                    return 1;
                }
                truth.push_back(std::move(t).value());
                objects += static_cast<double>(cur.back().size()) / frames;
                std::size_t tris = 0;
                for (const cullide::Mesh& m : cur.back()) tris += m.triangles.size();
                triangles += static_cast<double>(tris) / frames;
            }
            std::vector<Row> rows;
            // cullide's methods (the ground truth included), through process_frame.
            for (cullide::Method m : our) {
                Row r;
                r.peer = cullide::to_string(m);
                if (m != cullide::Method::Exact) {
                    r.peer += "@" + std::to_string(resolution > 0 ? resolution : cullide::default_resolution(m));
                }
                r.narrow = m == cullide::Method::Exact ? "ground truth" : "cullide pipeline";
                r.ours = true;
                for (int k = 0; k < frames; ++k) {
                    cullide::RunOptions ro;
                    ro.method = m;
                    ro.threads = threads;
                    ro.resolution = resolution > 0 ? resolution : cullide::default_resolution(m);
                    std::vector<double> t;
                    std::vector<cullide::TrianglePair> got;
                    for (int rep = 0; rep < reps; ++rep) {
                        const auto t0 = Clock::now();
                        auto fr = cullide::process_frame(cur[static_cast<std::size_t>(k)], ro);
                        t.push_back(ms_since(t0));
                        if (!fr) {
                            std::cerr << "peers_bench: " << scene << " " << r.peer << ": " << fr.error().message << "\n";
                            return 1;
                        }
                        got = std::move(fr.value().pairs);
                    }
                    r.total.push_back(median(t));
                    compare(truth[static_cast<std::size_t>(k)], std::move(got), r);
                }
                rows.push_back(std::move(r));
            }
            for (std::size_t p = 0; p < factories.size(); ++p) {
                if (!enabled[p]) continue;
                std::unique_ptr<peers::Peer> peer = factories[p]();
                Row r;
                r.peer = peer->name();
                r.narrow = peer->narrow_phase();
                r.refit_is_rebuild = peer->refit_is_rebuild();
                for (int k = 0; k < frames; ++k) {
                    const auto ks = static_cast<std::size_t>(k);
                    // Deforming with refit: prebuilt on the previous frame, refitted to this one.
                    peer->build(prev[ks]);
                    auto t0 = Clock::now();
                    peer->refit(cur[ks]);
                    r.refit.push_back(ms_since(t0));
                    std::vector<double> q;
                    std::vector<cullide::TrianglePair> got;
                    for (int rep = 0; rep < reps; ++rep) {
                        t0 = Clock::now();
                        got = peer->query();
                        q.push_back(ms_since(t0));
                    }
                    r.query_refit.push_back(median(q));
                    Row refit_check;
                    compare(truth[ks], got, refit_check);
                    r.refit_misses += refit_check.misses;
                    r.refit_extra += refit_check.extra;
                    // Rigid / rebuilt: built on this frame.
                    t0 = Clock::now();
                    peer->build(cur[ks]);
                    r.build.push_back(ms_since(t0));
                    q.clear();
                    for (int rep = 0; rep < reps; ++rep) {
                        t0 = Clock::now();
                        got = peer->query();
                        q.push_back(ms_since(t0));
                    }
                    r.query.push_back(median(q));
                    compare(truth[ks], std::move(got), r);
                }
                rows.push_back(std::move(r));
            }
            for (Row& r : rows) {
                r.scene = scene;
                r.scale = scale;
                r.objects = objects;
                r.triangles = triangles;
                const double build = median(r.build), refit = median(r.refit), query = median(r.query),
                             qr = median(r.query_refit);
                const double frame_ms = r.ours ? median(r.total) : std::min(build + query, refit + qr);
                const bool exact = r.misses == 0 && r.extra == 0 && r.refit_misses == 0 && r.refit_extra == 0;
                if (!exact && (r.peer == "exact" || r.peer.rfind("rcullide@", 0) == 0 ||
                               r.peer.rfind("rcullide-offset@", 0) == 0 || r.peer.rfind("qcullide@", 0) == 0 ||
                               r.peer.rfind("auto@", 0) == 0)) {
                    status = 1;  // a method that never misses did
                }
                std::ostringstream label;
                label << (exact ? "exact" : "NOT exact (" + std::to_string(r.misses) + " missed, " +
                                                std::to_string(r.extra) + " extra" +
                                                (r.ours ? std::string(")") : "; after refit " +
                                                std::to_string(r.refit_misses) + " missed, " +
                                                std::to_string(r.refit_extra) + " extra)"));
                std::cout << std::defaultfloat << std::setprecision(6);
                std::cout << std::left << std::setw(11) << scene << std::setw(6) << scale << std::setw(21) << r.peer
                          << std::right << std::fixed << std::setprecision(2);
                if (r.ours) {
                    std::cout << "  frame " << std::setw(9) << frame_ms << " ms" << std::setw(42) << "";
                } else {
                    std::cout << "  build " << std::setw(9) << build << "  refit " << std::setw(9) << refit
                              << (r.refit_is_rebuild ? "*" : " ") << " query " << std::setw(8) << query
                              << "  deform " << std::setw(9) << frame_ms;
                }
                std::cout << std::defaultfloat << "  pairs " << r.pairs << "/" << r.truth << "  " << label.str() << "\n";
                if (csv) {
                    csv << std::defaultfloat << std::setprecision(10);  // sticky: reset per row
                    csv << scene << ',' << scale << ',' << objects << ',' << triangles << ',' << frames << ',' << threads
                        << ',' << r.peer << ',' << r.narrow << ',' << std::fixed << std::setprecision(4);
                    if (r.ours) {
                        csv << ",,,,,,,," << frame_ms;
                    } else {
                        csv << build << ',' << refit << ',' << (r.refit_is_rebuild ? 1 : 0) << ',' << query << ','
                            << qr << ',' << query << ',' << build + query << ',' << refit + qr << ',' << frame_ms;
                    }
                    csv << std::defaultfloat << ',' << r.pairs << ',' << r.truth << ',' << r.misses << ',' << r.extra
                        << ',' << r.refit_misses << ',' << r.refit_extra << ',' << (exact ? "yes" : "no") << ',' << std::fixed << std::setprecision(2) << load_average()
                        << std::defaultfloat << '\n';
                    csv.flush();
                }
            }
        }
    }
    return status;
}
