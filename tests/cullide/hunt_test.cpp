// `cullide hunt` and its engine (cullide/hunt.h): the generators are deterministic and valid; a
// planted miss of GL-exact CULLIDE (a wall seen edge-on, crossed by a box) is found, shrunk to a
// smaller frame that still misses through process_frame and through `cullide run` on the written OBJ
// files, and classified; methods that never miss give no finding in the same budget; the command's
// errors and output files.
#include "cullide/hunt.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli.h"
#include "cullide/ground_truth.h"
#include "cullide/mesh_io.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "box_mesh.h"

namespace {

namespace fs = std::filesystem;
using cullide::Frame;
using cullide::Mesh;
using cullide::Method;
using cullide::RunOptions;
using cullide::TrianglePair;
using cullide::Vec3;
using cullide::detail::box_mesh;
namespace hunt = cullide::hunt;

struct Outcome {
    int status;
    std::string out, err;
};

Outcome cli(std::vector<std::string> args) {
    std::ostringstream out, err;
    const int status = cullide::cli::run(args, out, err);
    return {status, out.str(), err.str()};
}

bool has(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

fs::path temp_dir(const std::string& name) {
    const fs::path p = fs::temp_directory_path() / ("cullide_hunt_test_" + name);
    fs::remove_all(p);
    return p;
}

std::string read_text(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream text;
    text << f.rdbuf();
    return text.str();
}

std::uint64_t triangles(const Frame& f) {
    std::uint64_t n = 0;
    for (const Mesh& m : f) n += m.triangles.size();
    return n;
}

// The planted miss: a wall in the plane x = 0 (two triangles, seen edge-on in the y and z views,
// where it covers no pixel and is pruned as fully visible), crossed by a box, plus a distant box.
Frame planted_wall() {
    Mesh wall;
    wall.name = "wall";
    wall.positions = {{0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1}};
    wall.triangles = {{0, 1, 2}, {0, 2, 3}};
    return {wall, box_mesh("crosser", {-0.25, 0.1, 0.2}, {0.3, 0.45, 0.6}),
            box_mesh("far", {2, 2, 2}, {2.5, 2.5, 2.5})};
}

RunOptions gl_exact_cullide() {
    RunOptions o;
    o.method = Method::Cullide;
    o.resolution = 64;
    o.threads = 1;
    return o;
}

std::vector<std::string> words(const std::string& line) {
    std::istringstream in(line);
    return {std::istream_iterator<std::string>(in), std::istream_iterator<std::string>()};
}

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> v;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
}

}  // namespace

TEST_CASE("every generator is a function of its seed and gives valid frames in the exact range") {
    for (hunt::Generator g : hunt::all_generators()) {
        CAPTURE(hunt::to_string(g));
        CHECK(hunt::parse_generator(hunt::to_string(g)).value() == g);
        std::set<std::uint64_t> digests;
        for (std::uint64_t seed = 0; seed < 25; ++seed) {
            const Frame a = hunt::generate(g, seed), b = hunt::generate(g, seed);
            REQUIRE(cullide::frame_digest(a) == cullide::frame_digest(b));
            CHECK(a.size() >= 2);
            CHECK(cullide::validate_scene(a));
            CHECK(cullide::validate_exact_range(a));
            digests.insert(cullide::frame_digest(a));
            const Frame p = hunt::perturb(a, seed), q = hunt::perturb(a, seed);
            CHECK(cullide::frame_digest(p) == cullide::frame_digest(q));
            CHECK(cullide::validate_scene(p));
            CHECK(cullide::validate_exact_range(p));
        }
        CHECK(digests.size() == 25);  // different seeds, different frames
    }
    CHECK_FALSE(hunt::parse_generator("teapot"));
    CHECK(has(hunt::parse_generator("teapot").error().message,
              "unknown generator 'teapot' (valid: soup, coplanar"));
}

TEST_CASE("the planted edge-on miss is shrunk to a smaller frame that still misses, and classified edge-on") {
    const Frame planted = planted_wall();
    const RunOptions opt = gl_exact_cullide();
    cullide::FrameContext context;
    const hunt::Verdict before = hunt::check(planted, opt, context).value();
    REQUIRE(before.truth_pairs > 0);
    REQUIRE_FALSE(before.missed.empty());  // the wall is pruned in an edge-on view: every wall pair missed
    CHECK(before.extra.empty());

    hunt::ShrinkStats stats;
    const Frame shrunk = hunt::shrink(planted, opt, context, nullptr, 2000, &stats);
    CHECK_FALSE(stats.stopped);
    CHECK(stats.checks > 0);
    CHECK(shrunk.size() < planted.size());
    CHECK(triangles(shrunk) < triangles(planted));
    CHECK(triangles(shrunk) == 2);  // one wall triangle, one box triangle: nothing smaller can miss

    // Still missing, against the independent ground truth, through process_frame directly.
    const cullide::FrameResult got = cullide::process_frame(shrunk, opt).value();
    const std::vector<TrianglePair> truth = cullide::exact_pairs(shrunk).value();
    REQUIRE_FALSE(truth.empty());
    CHECK(got.pairs.size() < truth.size());
    CHECK(std::includes(truth.begin(), truth.end(), got.pairs.begin(), got.pairs.end()));

    const hunt::Verdict after = hunt::check(shrunk, opt, context).value();
    CHECK(hunt::classify(shrunk, after, opt, context).value() == hunt::Reason::EdgeOn);
    CHECK(stats.reason == hunt::Reason::EdgeOn);
    for (const TrianglePair& p : after.missed) {
        bool edge_on = false;
        for (int axis = 0; axis < 3; ++axis)
            edge_on = edge_on || hunt::edge_on(shrunk[p.object_a], p.triangle_a, axis) ||
                      hunt::edge_on(shrunk[p.object_b], p.triangle_b, axis);
        CHECK(edge_on);
    }
    // A stop at once keeps the input, which still fails.
    hunt::ShrinkStats stopped;
    const Frame same = hunt::shrink(
        planted, opt, context, [] { return true; }, 2000, &stopped);
    CHECK(stopped.stopped);
    CHECK(cullide::frame_digest(same) == cullide::frame_digest(planted));
}

TEST_CASE("boxes touching face to face are missed at any setting, and classified touching") {
    const Frame touching{box_mesh("box", {0, 0, 0}, {1, 1, 1}), box_mesh("box", {1, 0.25, 0.25}, {2, 0.75, 0.75})};
    cullide::FrameContext context;
    const RunOptions opt = gl_exact_cullide();
    const hunt::Verdict v = hunt::check(touching, opt, context).value();
    REQUIRE_FALSE(v.missed.empty());
    CHECK(hunt::classify(touching, v, opt, context).value() == hunt::Reason::Touching);
    // "No setting helps": D32F, a finer view and a shifted grid all still miss.
    for (int resolution : {65, 256}) {
        RunOptions o = opt;
        o.resolution = resolution;
        o.depth_format = raster::DepthFormat::D32F;
        CHECK(hunt::check(touching, o, context).value().failed());
    }
}

TEST_CASE("classify names a depth-quantization miss and a sub-pixel miss by re-running") {
    // Two triangles crossing by a sliver: with D16 over a deep scene the crossing is lost in depth
    // quantization only if D32F finds it, so the test asserts only the consistency of the answer:
    // whatever classify says, re-running with the named setting catches every missed pair.
    cullide::FrameContext context;
    int named = 0;
    for (std::uint64_t seed = 0; seed < 60 && named < 8; ++seed) {
        for (hunt::Generator g :
             {hunt::Generator::SubPixel, hunt::Generator::Coplanar, hunt::Generator::Sliver}) {
            RunOptions opt = gl_exact_cullide();
            opt.depth_format = seed % 2 ? raster::DepthFormat::D16 : raster::DepthFormat::D24;
            const Frame f = hunt::generate(g, seed);
            const hunt::Verdict v = hunt::check(f, opt, context).value();
            if (!v.failed()) continue;
            const hunt::Reason r = hunt::classify(f, v, opt, context).value();
            RunOptions again = opt;
            if (r == hunt::Reason::DepthQuantization)
                again.depth_format = raster::DepthFormat::D32F;
            else if (r == hunt::Reason::SubPixel)
                again.resolution = 4 * opt.resolution;
            else
                continue;
            ++named;
            CAPTURE(hunt::to_string(r));
            CHECK_FALSE(hunt::check(f, again, context).value().failed());
        }
    }
    CHECK(named > 0);
}

TEST_CASE("methods that never miss give no finding in the budget where cullide finds many") {
    cullide::FrameContext context;
    const std::uint64_t cases = 24;
    int cullide_failures = 0;
    for (Method m :
         {Method::Exact, Method::RCullide, Method::RCullideOffset, Method::QCullide, Method::Cullide}) {
        RunOptions opt = gl_exact_cullide();
        opt.method = m;
        CAPTURE(cullide::to_string(m));
        for (hunt::Generator g : hunt::all_generators()) {
            for (std::uint64_t seed = 0; seed < cases / 8; ++seed) {
                const hunt::Verdict v = hunt::check(hunt::generate(g, seed), opt, context).value();
                if (m == Method::Cullide) {
                    cullide_failures += v.failed();
                    CHECK(v.extra.empty());
                } else {
                    CHECK_FALSE(v.failed());
                }
            }
        }
    }
    CHECK(cullide_failures > 0);

    // The same through the command: a finding is exit status 1 for a never-miss method.
    const fs::path dir = temp_dir("never");
    const Outcome r =
        cli({"hunt", "--method", "rcullide", "--resolution", "64", "--cases", "24", "--out", dir.string()});
    CHECK(r.status == 0);
    CHECK(has(r.out, "24 cases"));
    CHECK(has(r.out, "0 findings"));
    CHECK(lines(read_text(dir / "summary.csv")).size() == 1);  // the header only
    fs::remove_all(dir);
}

TEST_CASE("cullide hunt writes each finding, and its run command reproduces the miss") {
    const fs::path dir = temp_dir("findings");
    const std::vector<std::string> args{
        "hunt", "--method",       "cullide", "--resolution", "64", "--generators", "edge-on,room", "--cases",
        "6",    "--max-findings", "2",       "--seed",       "7",  "--out",        dir.string()};
    fs::create_directories(dir / "finding-001");
    std::ofstream(dir / "finding-001" / "object_9.obj") << "# left by an earlier hunt\n";
    const Outcome r = cli(args);
    REQUIRE(r.status == 0);
    CHECK_FALSE(fs::exists(dir / "finding-001" / "object_9.obj"));  // not mistaken for part of the finding
    CHECK(has(r.out, "finding 1: case "));
    CHECK(has(r.out, "6 cases"));
    const std::vector<std::string> rows = lines(read_text(dir / "summary.csv"));
    REQUIRE(rows.size() == 3);  // header + 2 findings (the rest is only counted)
    CHECK(rows[0].rfind("finding,case,source,", 0) == 0);
    const std::string json = read_text(dir / "summary.json");
    CHECK(has(json, "\"method\": \"cullide\""));
    CHECK(has(json, "\"name\": \"edge-on\", \"cases\": 3"));
    CHECK(has(json, "\"stopped_by\": \"cases\""));

    const fs::path f1 = dir / "finding-001";
    for (const char* name : {"object_0.obj", "object_1.obj", "command.txt", "pairs.csv", "reason.txt"}) {
        CAPTURE(name);
        CHECK(fs::exists(f1 / name));
    }
    CHECK(has(rows[1], ",yes,"));  // reproduced from the written files
    // The command, run as printed, reports fewer pairs than the ground truth on the same files, and
    // misses exactly the pairs in pairs.csv.
    std::vector<std::string> command = words(read_text(f1 / "command.txt"));
    REQUIRE(command.size() > 3);
    CHECK(command[0] == "cullide");
    command.erase(command.begin());
    const fs::path got_csv = dir / "got.csv", truth_csv = dir / "truth.csv";
    std::vector<std::string> got_args = command, truth_args = command;
    got_args.insert(got_args.end(), {"--pairs", got_csv.string()});
    truth_args.insert(truth_args.end(), {"--method", "exact", "--pairs", truth_csv.string()});
    REQUIRE(cli(got_args).status == 0);
    REQUIRE(cli(truth_args).status == 0);
    std::vector<std::string> got = lines(read_text(got_csv)), truth = lines(read_text(truth_csv)), missed;
    REQUIRE_FALSE(got.empty());
    REQUIRE_FALSE(truth.empty());
    got.erase(got.begin());  // headers
    truth.erase(truth.begin());
    std::sort(got.begin(), got.end());
    std::sort(truth.begin(), truth.end());
    std::set_difference(truth.begin(), truth.end(), got.begin(), got.end(), std::back_inserter(missed));
    REQUIRE_FALSE(missed.empty());
    std::vector<std::string> expected;
    for (const std::string& l : lines(read_text(f1 / "pairs.csv"))) {
        if (l.rfind("missed,", 0) == 0) expected.push_back("0," + l.substr(7));  // frame 0
    }
    std::sort(expected.begin(), expected.end());
    CHECK(missed == expected);

    // Same seed, same findings (the folder names are the same too).
    const std::string first = read_text(dir / "summary.csv");
    REQUIRE(cli(args).status == 0);
    CHECK(read_text(dir / "summary.csv") == first);
    fs::remove_all(dir);
}

TEST_CASE("cullide hunt perturbs mesh files and built-in scenes") {
    const fs::path dir = temp_dir("sources");
    fs::create_directories(dir);
    const Frame planted = planted_wall();
    const fs::path a = dir / "wall.obj", b = dir / "crosser.obj";
    std::ofstream(a) << cullide::write_obj({planted[0]});
    std::ofstream(b) << cullide::write_obj({planted[1]});
    const Outcome r = cli({"hunt", "--method", "cullide", "--resolution", "64", "--mesh", a.string(),
                           "--mesh", b.string(), "--scene", "cylinders", "--scale", "0.05", "--cases", "4",
                           "--out", (dir / "out").string(), "--json", "-"});
    REQUIRE(r.status == 0);
    CHECK(has(r.out, "\"name\": \"mesh:" + a.string() + "+" + b.string() + "\", \"cases\": 2"));
    CHECK(has(r.out, "\"name\": \"scene:cylinders\", \"cases\": 2"));
    CHECK(has(r.err, "cullide hunt: method cullide"));  // the report moves to stderr with --json -
    // The planted miss, given as files, is found within 2 perturbed frames and shrunk below its
    // 14 triangles; a mesh finding comes first (cases 0 and 2 are the mesh frame's).
    CHECK(has(r.err, "finding 1: case 0 (mesh:"));
    CHECK(has(r.out, "\"source\": \"mesh:"));
    const std::string csv = read_text(dir / "out" / "summary.csv");
    const std::vector<std::string> rows = lines(csv);
    REQUIRE(rows.size() >= 2);
    std::vector<std::string> cells;
    std::istringstream row(rows[1]);
    for (std::string c; std::getline(row, c, ',');) cells.push_back(c);
    REQUIRE(cells.size() > 9);
    CHECK(cells[6] == "14");          // triangles_before
    CHECK(std::stoi(cells[8]) < 14);  // triangles after shrinking
    CHECK(std::stoi(cells[9]) > 0);   // missed pairs
    fs::remove_all(dir);
}

extern "C" void ignore_signal(int) {}

TEST_CASE("Ctrl-C stops a hunt at the next frame and still writes the summary") {
    // The test's own handler first, so a signal that came before the hunt installed its own would be
    // harmless (and the elapsed-time check below would catch it).
    const auto previous = std::signal(SIGINT, ignore_signal);
    const fs::path dir = temp_dir("sigint");
    const auto start = std::chrono::steady_clock::now();
    std::thread interrupter([] {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        std::raise(SIGINT);
    });
    const Outcome r = cli({"hunt", "--method", "cullide", "--resolution", "64", "--generators", "room",
                           "--budget-s", "120", "--out", dir.string()});
    interrupter.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::signal(SIGINT, previous);
    CHECK(r.status == 0);
    CHECK(has(r.out, "(stopped by interrupt)"));
    CHECK(seconds < 60);  // far below the budget
    CHECK(has(read_text(dir / "summary.json"), "\"stopped_by\": \"interrupt\""));
    CHECK(fs::exists(dir / "summary.csv"));
    fs::remove_all(dir);
}

TEST_CASE("cullide hunt refuses bad options, naming them") {
    const auto refused = [](const std::vector<std::string>& options, const std::string& message, int status = 2) {
        // Built by push_back, not insert at the front: GCC 12 at -O3 reports a false null dereference
        // (-Wnull-dereference) in the inlined move of vector::insert.
        std::vector<std::string> args{"hunt"};
        for (const std::string& o : options) args.push_back(o);
        const Outcome r = cli(args);
        CAPTURE(args);
        CHECK(r.status == status);
        CHECK(has(r.err, message));
    };
    refused({"--budget-s", "0"}, "--budget-s must be a number in (0, 604800] (got '0')");
    refused({"--cases", "0"}, "--cases must be an integer in 1..1000000000 (got '0')");
    refused({"--generators", "room,teapot"}, "--generators: unknown generator 'teapot'");
    refused({"--scene", "teapot"}, "--scene: unknown scene 'teapot'");
    refused({"--resolution", "8"}, "--resolution must be an integer in 16..");
    refused({"--method", "fast"}, "--method:");
    refused({"--depth-format", "d8"}, "--depth-format:");
    refused({"scene.obj"}, "unknown option 'scene.obj' (mesh files are given with --mesh");
    refused({"--frames", "2"}, "option --frames is taken by run, bench and sweep, not by hunt");
    refused({"--csv", "-", "--json", "-"}, "cannot both go to stdout");
    refused({"--mesh", "/nonexistent/none.obj", "--cases", "1", "--out", temp_dir("bad").string()},
            "none.obj", 1);
    CHECK(has(cli({"hunt", "--help"}).out, "usage: cullide hunt [options]"));
    CHECK(has(cli({"help", "hunt"}).out, "--generators LIST"));
}
