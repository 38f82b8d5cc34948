// The CLI contract: options, errors, exit codes, the CSV pair file and the JSON document, and the
// visibility methods' options (--depth-format, --subobject, --rounds, --broadphase) and PCS figures.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"

namespace {

struct Outcome {
    int status;
    std::string out, err;
};

Outcome run(std::vector<std::string> args) {
    std::ostringstream out, err;
    int status = cullide::cli::run(args, out, err);
    return {status, out.str(), err.str()};
}

std::string read_file(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

bool has(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

std::filesystem::path temp_path(const std::string& name) {
    return std::filesystem::temp_directory_path() / ("cullide_cli_test_" + name);
}

}  // namespace

TEST_CASE("usage errors exit with status 2 and say what is wrong") {
    Outcome o = run({});
    CHECK(o.status == 2);
    CHECK(o.err.find("usage: cullide") != std::string::npos);

    o = run({"frobnicate"});
    CHECK(o.status == 2);
    CHECK(o.err.find("unknown command 'frobnicate'") != std::string::npos);

    o = run({"run", "--bogus"});
    CHECK(o.status == 2);
    CHECK(o.err.find("unknown option '--bogus'") != std::string::npos);

    o = run({"run", "--frames", "0"});
    CHECK(o.status == 2);
    CHECK(o.err.find("--frames must be an integer in 1..1000000 (got '0')") != std::string::npos);

    o = run({"run", "--frames", "3x"});
    CHECK(o.status == 2);
    o = run({"run", "--threads", "-1"});
    CHECK(o.status == 2);
    o = run({"run", "--resolution", "99999"});
    CHECK(o.status == 2);
    o = run({"run", "--scale", "nan"});
    CHECK(o.status == 2);
    o = run({"run", "--method", "magic"});
    CHECK(o.status == 2);
    CHECK(o.err.find("unknown method 'magic' (valid: exact") != std::string::npos);
    o = run({"run", "--pairs"});
    CHECK(o.status == 2);
    CHECK(o.err.find("option --pairs needs a value") != std::string::npos);
    CHECK(o.out.empty());
}

TEST_CASE("a missing mesh file is an input error naming the file") {
    Outcome o = run({"run", "/nonexistent/dir/x.obj"});
    CHECK(o.status == 1);
    CHECK(o.err.find("/nonexistent/dir/x.obj") != std::string::npos);
}

TEST_CASE("an unwritable pair file is an error before any frame runs") {
    Outcome o = run({"run", "--scale", "0.05", "--frames", "1", "--pairs", "/nonexistent/dir/p.csv"});
    CHECK(o.status == 1);
    CHECK(o.err.find("cannot open '/nonexistent/dir/p.csv' for writing") != std::string::npos);
    CHECK(o.out.empty());
}

TEST_CASE("the pair file holds exactly the library's pairs, frame by frame, sorted, with the header") {
    const auto csv = temp_path("pairs.csv");
    Outcome o = run({"run", "cylinders", "--frames", "3", "--threads", "2", "--pairs", csv.string()});
    REQUIRE(o.status == 0);
    CHECK(o.out.find("frame 2:") != std::string::npos);

    std::ostringstream expected;
    expected << "frame,object_a,triangle_a,object_b,triangle_b\n";
    auto scene = cullide::make_scene("cylinders", {});
    REQUIRE(scene.ok());
    std::size_t rows = 0;
    for (int f = 0; f < 3; ++f) {
        cullide::Frame objects = scene.value()->frame(f);
        auto r = cullide::process_frame(objects, {});
        REQUIRE(r.ok());
        for (const auto& p : r.value().pairs) {
            expected << f << ',' << p.object_a << ',' << p.triangle_a << ',' << p.object_b << ',' << p.triangle_b
                     << '\n';
            ++rows;
        }
    }
    CHECK(rows > 0);  // the default scene must have collisions, or this test proves little
    CHECK(read_file(csv) == expected.str());
    std::filesystem::remove(csv);
}

TEST_CASE("--json prints one document with a record per frame") {
    Outcome o = run({"run", "--method", "exact", "--scale", "0.1", "--frames", "2", "--json"});
    REQUIRE(o.status == 0);
    CHECK(o.out.rfind("{\"scene\": \"cylinders\", \"method\": \"exact\"", 0) == 0);
    CHECK(o.out.find("{\"frame\": 0,") != std::string::npos);
    CHECK(o.out.find("{\"frame\": 1,") != std::string::npos);
    CHECK(o.out.find("{\"frame\": 2,") == std::string::npos);
    CHECK(o.out.substr(o.out.size() - 3) == "]}\n");
}

TEST_CASE("mesh files are objects in argument order and --self reports pairs inside one object") {
    const auto path = temp_path("fold.obj");
    {
        std::ofstream f(path);
        // Two triangles of one object crossing each other, sharing no vertex.
        f << "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0.5 0.5 -1\nv 0.5 0.5 1\nv 3 3 0\nf 1 2 3\nf 4 5 6\n";
    }
    Outcome plain = run({"run", path.string()});
    REQUIRE(plain.status == 0);
    CHECK(plain.out.find("-> 0 colliding triangle pairs") != std::string::npos);
    Outcome self = run({"run", path.string(), "--self"});
    REQUIRE(self.status == 0);
    CHECK(self.out.find("-> 1 colliding triangle pairs, 1 object pairs") != std::string::npos);
    std::filesystem::remove(path);
}

TEST_CASE("--json reports, per input file, the statements its reader skipped") {
    const auto fcl = temp_path("skips_fcl.obj");
    const auto plain = temp_path("skips_plain.obj");
    {
        std::ofstream f(fcl);
        f << "3 1\nmtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nusemtl a\ns off\nf 1/1 2/2 3/1\n";
        std::ofstream g(plain);
        g << "v 0 0 2\nv 1 0 2\nv 0 1 2\nf 1 2 3\n";
    }
    Outcome o = run({"run", fcl.string(), plain.string(), "--method", "exact", "--json"});
    REQUIRE(o.status == 0);
    CHECK(has(o.out, "\"inputs\": [{\"file\": \"" + fcl.string() +
                         "\", \"skipped\": {\"vt\": 2, \"vn\": 0, \"vp\": 0, \"l\": 0, \"p\": 0, \"s\": 1, "
                         "\"usemtl\": 1, \"mtllib\": 1, \"count_line\": 1}}, {\"file\": \"" +
                         plain.string() +
                         "\", \"skipped\": {\"vt\": 0, \"vn\": 0, \"vp\": 0, \"l\": 0, \"p\": 0, \"s\": 0, "
                         "\"usemtl\": 0, \"mtllib\": 0, \"count_line\": 0}}], \"frames\": ["));
    // A built-in scene has no input files.
    Outcome scene = run({"run", "--method", "exact", "--scale", "0.1", "--frames", "1", "--json"});
    REQUIRE(scene.status == 0);
    CHECK(has(scene.out, "\"inputs\": [], \"frames\": ["));
    // A count line that disagrees with the file is an input error naming the file and line.
    {
        std::ofstream f(fcl);
        f << "4 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    }
    Outcome bad = run({"run", fcl.string(), "--json"});
    CHECK(bad.status == 1);
    CHECK(has(bad.err, fcl.string() + ":1: the count line says 4 vertices and 1 face but the file has 3 vertices"));
    std::filesystem::remove(fcl);
    std::filesystem::remove(plain);
}

TEST_CASE("the README's library example is the file the build compiles") {
    const std::string readme = read_file(std::filesystem::path(CULLIDE_SOURCE_DIR) / "README.md");
    const std::string example = read_file(std::filesystem::path(CULLIDE_SOURCE_DIR) / "tests/cullide/readme_example.cpp");
    REQUIRE_FALSE(example.empty());
    CHECK(readme.find(example) != std::string::npos);
}

TEST_CASE("bad visibility options are usage errors naming the option and the valid values") {
    Outcome o = run({"run", "--depth-format", "d8"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--depth-format: unknown depth format 'd8' (valid: d16, d24, d32f)"));
    o = run({"run", "--gpu-rules", "metal"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--gpu-rules: unknown gpu rules 'metal' (valid: gl, vulkan)"));
    o = run({"run", "--broadphase", "grid"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "(valid: none, spatialhash, sap, brute)"));
    o = run({"run", "--subobject", "0"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--subobject must be an integer in 1..65536 (got '0')"));
    o = run({"run", "--rounds", "x"});
    CHECK(o.status == 2);
    o = run({"run", "--min-prune", "1"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--min-prune must be a number in [0, 1) (got '1')"));
    o = run({"run", "--min-prune", "nan"});
    CHECK(o.status == 2);
    o = run({"run", "--object-stage", "maybe"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--object-stage must be auto, on or off (got 'maybe')"));
    o = run({"run", "--method", "magic"});
    CHECK(has(o.err, "(valid: exact, cullide, rcullide, rcullide-offset, qcullide, qcullide-gl, auto)"));
    o = run({"run", "--method", "cullide", "--self", "--scale", "0.05", "--frames", "1"});
    CHECK(o.status == 1);
    CHECK(has(o.err, "self-collision is not supported by method 'cullide'"));
}

TEST_CASE("a visibility method prints its PCS figures in text and in JSON, and finds the exact pairs") {
    const std::vector<std::string> common{"run", "tori", "--scale", "0.05", "--frames", "1", "--resolution", "64"};
    auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> a = common;
        a.insert(a.end(), extra.begin(), extra.end());
        return run(a);
    };
    Outcome exact = with({"--method", "exact"});
    REQUIRE(exact.status == 0);
    const std::size_t at = exact.out.find("-> ");
    REQUIRE(at != std::string::npos);
    const std::string count = exact.out.substr(at, exact.out.find(" colliding", at) - at);

    Outcome text = with({"--method", "rcullide-offset", "--depth-format", "d16", "--subobject", "2", "--rounds", "2",
                         "--broadphase", "sap"});
    REQUIRE(text.status == 0);
    CHECK(has(text.out, "method rcullide-offset, resolution 64, depth d16, sub-object 2 triangles, broad phase sap"));
    CHECK(has(text.out, count + " colliding triangle pairs"));  // reliable: the exact count
    CHECK(has(text.out, "  pcs: boxes "));
    CHECK(has(text.out, " queries, "));
    CHECK(has(text.out, "  broad phase: "));

    // rcullide skips the object stage by default (its sub-object views subsume it) and says so;
    // forced on, the object views run; both with any --min-prune still give the exact pairs.
    Outcome skipped = with({"--method", "rcullide"});
    REQUIRE(skipped.status == 0);
    CHECK(has(skipped.out, count + " colliding triangle pairs"));
    CHECK(has(skipped.out, " objects (stage skipped), sub-objects "));
    Outcome forced = with({"--method", "rcullide", "--object-stage", "on", "--min-prune", "0", "--json"});
    REQUIRE(forced.status == 0);
    CHECK(has(forced.out, "\"stage\": \"objects\""));
    Outcome eager = with({"--method", "rcullide", "--object-stage", "off", "--min-prune", "0.99"});
    REQUIRE(eager.status == 0);
    CHECK(has(eager.out, count + " colliding triangle pairs"));
    CHECK_FALSE(has(text.out, "(stage skipped)"));  // rcullide-offset keeps the object stage

    Outcome json = with({"--method", "cullide", "--json"});
    REQUIRE(json.status == 0);
    CHECK(has(json.out, "\"method\": \"cullide\", \"self\": false, \"resolution\": 64, \"depth_format\": \"d24\""));
    CHECK(has(json.out, "\"views\": [{\"stage\": \"boxes\", \"axis\": \"x\", \"before\": "));
    CHECK(has(json.out, "\"pcs_subobjects\": "));
    CHECK(has(json.out, "\"exact_ms\": "));
    CHECK(json.out.substr(json.out.size() - 3) == "]}\n");
}
