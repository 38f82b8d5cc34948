// `cullide bench` and `cullide sweep`: the result checks (a wrong, nondeterministic or extra answer
// is caught before any time is reported), the CSV / JSON layout, the sweep grid and the errors.
// Wrong answers are injected through the FrameRunner hook of cli/bench.h; the ground truth is always
// the real exact_pairs.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench.h"
#include "cli.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"

namespace {

using cullide::cli::FrameRunner;

struct Outcome {
    int status;
    std::string out, err;
};

Outcome bench(std::vector<std::string> args, const FrameRunner* runner = nullptr) {
    std::ostringstream out, err;
    const int status = runner ? cullide::cli::bench_command(args, out, err, runner) : cullide::cli::run(args, out, err);
    return {status, out.str(), err.str()};
}

bool has(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

std::vector<std::string> lines(const std::string& s) {
    std::vector<std::string> v;
    std::stringstream ss(s);
    std::string l;
    while (std::getline(ss, l)) v.push_back(l);
    return v;
}

std::vector<std::string> fields(const std::string& line) {
    std::vector<std::string> v;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) v.push_back(f);
    if (!line.empty() && line.back() == ',') v.emplace_back();
    return v;
}

// Column `name` of CSV row `row` (1-based data row) of `csv`.
std::string column(const std::string& csv, std::size_t row, const std::string& name) {
    const std::vector<std::string> ls = lines(csv);
    REQUIRE(ls.size() > row);
    const std::vector<std::string> head = fields(ls[0]);
    const std::vector<std::string> r = fields(ls[row]);
    REQUIRE(r.size() == head.size());
    for (std::size_t i = 0; i < head.size(); ++i) {
        if (head[i] == name) return r[i];
    }
    FAIL("no column " << name);
    return {};
}

// Small, fast frames: 5 cylinders (scale 0.05); frames 0..2 have colliding pairs (checked below).
const std::vector<std::string> kSmall{"--scenes", "cylinders", "--scales", "0.05", "--frames", "2",
                                      "--resolutions", "64", "--warmup", "0", "--reps", "2", "--threads", "1"};

std::vector<std::string> with(std::string command, std::vector<std::string> extra) {
    std::vector<std::string> a{std::move(command)};
    a.insert(a.end(), kSmall.begin(), kSmall.end());
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
}

FrameRunner real() {
    return [](std::span<const cullide::Mesh> o, const cullide::RunOptions& r) { return cullide::process_frame(o, r); };
}

// The real runner, but `method` loses its last pair (a miss), or gains a non-colliding pair.
FrameRunner tampered(cullide::Method method, bool drop) {
    return [method, drop](std::span<const cullide::Mesh> o, const cullide::RunOptions& r) {
        cullide::Result<cullide::FrameResult> fr = cullide::process_frame(o, r);
        if (fr && r.method == method) {
            std::vector<cullide::TrianglePair>& p = fr.value().pairs;
            if (drop && !p.empty()) p.pop_back();
            if (!drop) {  // the smallest pair between objects 0 and 1 keeps the list sorted
                std::vector<cullide::TrianglePair> q(1, cullide::TrianglePair{0, 0, 1, 0});
                for (const cullide::TrianglePair& x : p) q.push_back(x);
                p.swap(q);
            }
        }
        return fr;
    };
}

}  // namespace

TEST_CASE("the small scene used here has colliding pairs in the frames benchmarked") {
    auto g = cullide::make_scene("cylinders", cullide::SceneOptions{1, "", 0.05});
    REQUIRE(g);
    for (int f = 0; f < 2; ++f) {
        auto fr = cullide::process_frame(g.value()->frame(f), cullide::RunOptions{});
        REQUIRE(fr);
        CHECK(!fr.value().pairs.empty());
        // The pair injected by tampered(..., false) must not be a real one.
        CHECK(!std::binary_search(fr.value().pairs.begin(), fr.value().pairs.end(), cullide::TrianglePair{0, 0, 1, 0}));
    }
}

TEST_CASE("bench: CSV has the documented columns and one row per method and the checks pass") {
    const Outcome o = bench(with("bench", {"--methods", "exact,cullide,rcullide", "--csv", "-"}));
    REQUIRE(o.status == 0);
    const std::vector<std::string> ls = lines(o.out);
    REQUIRE(ls.size() == 4);
    CHECK(ls[0] ==
          "command,scene,scale,objects,triangles,method,resolution,depth_format,threads,self,frames,warmup,reps,"
          "ms_mean,ms_median,ms_q1,ms_q3,ms_min,ms_max,fps,pairs,truth_pairs,false_negatives,missed_object_pairs,"
          "false_positives,exact_tests,broadphase_objects,pcs_boxes,pcs_objects,true_objects,subobjects,"
          "pcs_subobjects,subobject_pairs,queries,triangles_rasterized,digest,check,load");
    CHECK(column(o.out, 1, "method") == "exact");
    CHECK(column(o.out, 1, "resolution").empty());  // not a visibility method
    CHECK(column(o.out, 2, "method") == "cullide");
    CHECK(column(o.out, 3, "method") == "rcullide");
    CHECK(column(o.out, 3, "resolution") == "64");
    for (std::size_t r = 1; r <= 3; ++r) {
        CHECK(column(o.out, r, "command") == "bench");
        CHECK(column(o.out, r, "frames") == "2");
        CHECK(column(o.out, r, "self") == "0");
        CHECK(column(o.out, r, "reps") == "2");
        CHECK(column(o.out, r, "objects") == "5");
        CHECK(column(o.out, r, "triangles") == "1000");  // plain digits in every row, never 1e+03
        CHECK(std::stod(column(o.out, r, "ms_min")) <= std::stod(column(o.out, r, "ms_median")));
        CHECK(std::stod(column(o.out, r, "ms_median")) <= std::stod(column(o.out, r, "ms_max")));
        CHECK(std::stoull(column(o.out, r, "truth_pairs")) > 0);
    }
    // Methods that never miss equal the ground truth, digest included.
    CHECK(column(o.out, 1, "check") == "exact");
    CHECK(column(o.out, 3, "check") == "exact");
    CHECK(column(o.out, 1, "digest") == column(o.out, 3, "digest"));
    CHECK(column(o.out, 3, "pairs") == column(o.out, 3, "truth_pairs"));
    CHECK(column(o.out, 3, "false_negatives") == "0");
    // cullide's check is consistent with its misses.
    const bool cullide_missed = column(o.out, 2, "false_negatives") != "0";
    CHECK(column(o.out, 2, "check") == (cullide_missed ? "misses" : "exact"));
    CHECK(std::stoull(column(o.out, 2, "pairs")) + std::stoull(column(o.out, 2, "false_negatives")) ==
          std::stoull(column(o.out, 2, "truth_pairs")));
}

TEST_CASE("bench: a method that never misses but misses a pair fails with a digest mismatch and no time") {
    const FrameRunner r = tampered(cullide::Method::RCullide, true);
    const Outcome o = bench(with("bench", {"--methods", "exact,rcullide", "--csv", "-"}), &r);
    CHECK(o.status == 1);
    CHECK(has(o.err, "digest mismatch"));
    CHECK(has(o.err, "method rcullide"));
    CHECK(has(o.err, "frame 0"));
    CHECK(has(o.err, "1 colliding pair(s) missed"));
    CHECK(!has(o.out, ",rcullide,"));  // no row, so no time, for it
    CHECK(has(o.out, ",exact,"));      // the method before it was reported
}

TEST_CASE("bench: a reported pair that does not collide fails whatever the method") {
    const FrameRunner r = tampered(cullide::Method::Cullide, false);
    const Outcome o = bench(with("bench", {"--methods", "cullide", "--csv", "-"}), &r);
    CHECK(o.status == 1);
    CHECK(has(o.err, "not colliding pairs of the ground truth"));
    CHECK(lines(o.out).size() == 1);  // header only
}

TEST_CASE("bench: repetitions that disagree are reported as nondeterminism") {
    int calls = 0;
    const FrameRunner r = [&calls](std::span<const cullide::Mesh> o, const cullide::RunOptions& ro) {
        cullide::Result<cullide::FrameResult> fr = cullide::process_frame(o, ro);
        if (fr && (calls++ % 2) == 1 && !fr.value().pairs.empty()) fr.value().pairs.pop_back();
        return fr;
    };
    const Outcome o = bench(with("bench", {"--methods", "exact", "--csv", "-"}), &r);
    CHECK(o.status == 1);
    CHECK(has(o.err, "not deterministic"));
}

TEST_CASE("bench: a method that may miss is reported with its misses") {
    const FrameRunner r = tampered(cullide::Method::Cullide, true);
    const Outcome o = bench(with("bench", {"--methods", "cullide", "--csv", "-"}), &r);
    REQUIRE(o.status == 0);
    CHECK(column(o.out, 1, "check") == "misses");
    CHECK(std::stoull(column(o.out, 1, "false_negatives")) >= 2);  // one per frame at least
    CHECK(std::stoull(column(o.out, 1, "missed_object_pairs")) <= std::stoull(column(o.out, 1, "false_negatives")));
}

TEST_CASE("sweep: one row per grid point with exact once and MISMATCH recorded with exit status 1") {
    const FrameRunner ok = real();
    const Outcome o = bench(with("sweep", {"--methods", "exact,cullide,rcullide", "--resolutions", "32,64",
                                           "--depth-formats", "d16,d24", "--csv", "-"}),
                            &ok);
    REQUIRE(o.status == 0);
    const std::vector<std::string> ls = lines(o.out);
    REQUIRE(ls.size() == 1 + 1 + 2 * 2 * 2);  // exact once, then 2 methods x 2 resolutions x 2 formats
    CHECK(column(o.out, 1, "method") == "exact");
    CHECK(column(o.out, 2, "method") == "cullide");
    CHECK(column(o.out, 2, "resolution") == "32");
    CHECK(column(o.out, 2, "depth_format") == "d16");
    CHECK(column(o.out, 3, "depth_format") == "d24");
    CHECK(column(o.out, 4, "resolution") == "64");
    for (std::size_t r = 1; r < ls.size(); ++r) {
        CHECK(column(o.out, r, "command") == "sweep");
        CHECK(column(o.out, r, "reps") == "2");  // given; the sweep's default is checked below
        // PCS sizes shrink stage by stage; false positives are the exact stage's rejected candidates.
        if (column(o.out, r, "method") != "exact") {
            CHECK(std::stoull(column(o.out, r, "pcs_boxes")) <= std::stoull(column(o.out, r, "broadphase_objects")));
            CHECK(std::stoull(column(o.out, r, "pcs_objects")) <= std::stoull(column(o.out, r, "pcs_boxes")));
        }
        CHECK(std::stoull(column(o.out, r, "false_positives")) + std::stoull(column(o.out, r, "pairs")) ==
              std::stoull(column(o.out, r, "exact_tests")));
    }
    const Outcome d = bench({"sweep", "--scenes", "cylinders", "--scales", "0.05", "--frames", "1", "--methods",
                             "cullide", "--resolutions", "32", "--csv", "-"});
    REQUIRE(d.status == 0);
    CHECK(column(d.out, 1, "reps") == "1");
    CHECK(column(d.out, 1, "warmup") == "0");
    const FrameRunner bad = tampered(cullide::Method::RCullide, true);
    const Outcome m = bench(with("sweep", {"--methods", "rcullide", "--resolutions", "32", "--csv", "-"}), &bad);
    CHECK(m.status == 1);
    CHECK(has(m.err, "MISMATCH"));
    CHECK(column(m.out, 1, "check") == "MISMATCH");
    CHECK(std::stoull(column(m.out, 1, "false_negatives")) >= 1);
}

TEST_CASE("bench --self: the ground truth with self pairs is the reference and the CSV says so") {
    // Cloth frames 58-59: the flap dips through the base (self pairs) at every scale.
    const Outcome o = bench({"bench", "--scenes", "cloth", "--scales", "0.05", "--self", "--methods", "exact",
                             "--first-frame", "58", "--frames", "2", "--warmup", "0", "--reps", "1", "--csv", "-"});
    REQUIRE(o.status == 0);
    CHECK(column(o.out, 1, "self") == "1");
    CHECK(column(o.out, 1, "check") == "exact");
    // Dropping a self pair is caught like any other miss.
    const FrameRunner r = tampered(cullide::Method::Exact, true);
    const Outcome m = bench({"bench", "--scenes", "cloth", "--scales", "0.05", "--self", "--methods", "exact",
                             "--first-frame", "58", "--frames", "1", "--warmup", "0", "--reps", "1", "--csv", "-"},
                            &r);
    CHECK(m.status == 1);
    CHECK(has(m.err, "digest mismatch"));
}

TEST_CASE("bench: without --resolutions each visibility method runs at its own default resolution") {
    const Outcome o = bench({"bench", "--scenes", "cylinders", "--scales", "0.05", "--frames", "1", "--warmup", "0",
                             "--reps", "1", "--methods", "rcullide,cullide", "--csv", "-"});
    REQUIRE(o.status == 0);
    CHECK(column(o.out, 1, "resolution") == std::to_string(cullide::default_resolution(cullide::Method::RCullide)));
    CHECK(column(o.out, 2, "resolution") == std::to_string(cullide::default_resolution(cullide::Method::Cullide)));
}

TEST_CASE("bench: JSON document and files") {
    const auto dir = std::filesystem::temp_directory_path();
    const auto csv = dir / "cullide_bench_cli_test.csv";
    const auto json = dir / "cullide_bench_cli_test.json";
    const Outcome o = bench(with("bench", {"--methods", "exact,rcullide-offset", "--csv", csv.string(), "--json",
                                           json.string()}));
    REQUIRE(o.status == 0);
    CHECK(has(o.out, "rcullide-offset"));  // the table on stdout
    std::ifstream jin(json);
    std::stringstream js;
    js << jin.rdbuf();
    const std::string j = js.str();
    CHECK(j.rfind("{\"command\": \"bench\"", 0) == 0);
    CHECK(has(j, "\"method\": \"exact\""));
    CHECK(has(j, "\"method\": \"rcullide-offset\""));
    CHECK(has(j, "\"frame_ms\": ["));
    CHECK(has(j, "\"check\": \"exact\""));
    std::ifstream cin(csv);
    std::stringstream cs;
    cs << cin.rdbuf();
    CHECK(lines(cs.str()).size() == 3);
    std::filesystem::remove(csv);
    std::filesystem::remove(json);
}

TEST_CASE("pairs_digest: FNV-1a offset basis when empty and sensitive to order and content") {
    using cullide::TrianglePair;
    CHECK(cullide::cli::pairs_digest({}) == 0xcbf29ce484222325ull);
    const std::vector<TrianglePair> a{{0, 1, 2, 3}, {0, 2, 2, 3}}, b{{0, 2, 2, 3}, {0, 1, 2, 3}}, c{{0, 1, 2, 4}, {0, 2, 2, 3}};
    CHECK(cullide::cli::pairs_digest(a) != cullide::cli::pairs_digest(b));
    CHECK(cullide::cli::pairs_digest(a) != cullide::cli::pairs_digest(c));
    CHECK(cullide::cli::pairs_digest(a) == cullide::cli::pairs_digest(std::vector<TrianglePair>(a)));
    CHECK(cullide::cli::never_misses(cullide::Method::Exact));
    CHECK(cullide::cli::never_misses(cullide::Method::RCullideOffset));
    CHECK(cullide::cli::never_misses(cullide::Method::QCullide));
    CHECK(!cullide::cli::never_misses(cullide::Method::QCullideGL));
    CHECK(!cullide::cli::never_misses(cullide::Method::Cullide));
}

TEST_CASE("bench and sweep: bad options give clear errors and exit status 2") {
    struct Case {
        std::vector<std::string> args;
        std::string message;
    };
    const std::vector<Case> cases{
        {{"bench", "--frobnicate"}, "unknown option '--frobnicate'"},
        {{"bench", "cylinders"}, "scenes are given with --scenes"},
        {{"bench", "--scenes", "cylinders,teapot"}, "unknown scene 'teapot'"},
        {{"bench", "--methods", "exact,fastest"}, "--methods:"},
        {{"sweep", "--resolutions", "64,8"}, "--resolutions must be an integer in 16..16384 (got '8')"},
        {{"sweep", "--resolutions", "64,,128"}, "empty item"},
        {{"bench", "--depth-formats", "d12"}, "--depth-formats:"},
        {{"bench", "--reps", "0"}, "--reps must be an integer in 1..1000"},
        {{"bench", "--scales", "0"}, "--scales: each must be a number in (0, 100]"},
        {{"bench", "--frames"}, "option --frames needs a value"},
        {{"bench", "--csv", "-", "--json", "-"}, "cannot both go to stdout"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.message);
        const Outcome o = bench(c.args);
        CHECK(o.status == 2);
        CHECK(has(o.err, c.message));
        CHECK(has(o.err, "--help"));
        CHECK(o.out.empty());
    }
    const Outcome h = bench({"sweep", "--help"});
    CHECK(h.status == 0);
    CHECK(has(h.out, "usage: cullide sweep"));
    const Outcome top = bench({"help"});
    CHECK(has(top.out, "bench"));
    CHECK(has(top.out, "sweep"));
    // A method without self-collision fails the run (1) with the pipeline's message.
    const Outcome self = bench(with("bench", {"--self", "--methods", "cullide"}));
    CHECK(self.status == 1);
    CHECK(has(self.err, "self-collision is not supported by method 'cullide'"));
    // A file that cannot be written is a run error (1), not a usage error.
    const Outcome w = bench(with("bench", {"--methods", "exact", "--csv", "/nonexistent-dir/x.csv"}));
    CHECK(w.status == 1);
    CHECK(has(w.err, "cannot open '/nonexistent-dir/x.csv'"));
}
