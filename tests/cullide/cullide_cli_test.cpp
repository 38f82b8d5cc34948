// The CLI's visibility-method options and figures: --method cullide|rcullide|rcullide-offset,
// --depth-format, --subobject, --rounds, --broadphase, and the PCS statistics in text and JSON.
#include <doctest/doctest.h>

#include <sstream>
#include <string>
#include <vector>

#include "cli.h"

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

bool has(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

}  // namespace

TEST_CASE("bad visibility options are usage errors naming the option and the valid values") {
    Outcome o = run({"run", "--depth-format", "d8"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--depth-format: unknown depth format 'd8' (valid: d16, d24, d32f)"));
    o = run({"run", "--broadphase", "grid"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "(valid: none, spatialhash, sap, brute)"));
    o = run({"run", "--subobject", "0"});
    CHECK(o.status == 2);
    CHECK(has(o.err, "--subobject must be an integer in 1..65536 (got '0')"));
    o = run({"run", "--rounds", "x"});
    CHECK(o.status == 2);
    o = run({"run", "--method", "magic"});
    CHECK(has(o.err, "(valid: exact, cullide, rcullide, rcullide-offset)"));
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

    Outcome json = with({"--method", "cullide", "--json"});
    REQUIRE(json.status == 0);
    CHECK(has(json.out, "\"method\": \"cullide\", \"self\": false, \"resolution\": 64, \"depth_format\": \"d24\""));
    CHECK(has(json.out, "\"views\": [{\"stage\": \"boxes\", \"axis\": \"x\", \"before\": "));
    CHECK(has(json.out, "\"pcs_subobjects\": "));
    CHECK(has(json.out, "\"exact_ms\": "));
    CHECK(json.out.substr(json.out.size() - 3) == "]}\n");
}
