// The option table of the CLI (cli/options.h): every option is documented in `cullide help`, in each
// taking command's --help and in the man page; options a command does not take are refused naming
// the commands that do; the version is CMake's; the printed ranges are the library's constants.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli.h"
#include "cullide/cullide.h"
#include "cullide/scenes.h"
#include "options.h"
#include "raster/types.h"

namespace {

using cullide::cli::Command;
using cullide::cli::OptionSpec;

struct Outcome {
    int status;
    std::string out, err;
};

Outcome run(std::vector<std::string> args) {
    std::ostringstream out, err;
    const int status = cullide::cli::run(args, out, err);
    return {status, out.str(), err.str()};
}

bool has(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

// Runs of spaces and line breaks as one space, so wrapped help compares with the table's text.
std::string one_line(const std::string& s) { return std::regex_replace(s, std::regex("[ \n]+"), " "); }

std::string roff_name(std::string name) { return std::regex_replace(name, std::regex("-"), "\\-"); }

const std::vector<Command> kCommands{Command::Run, Command::Bench, Command::Sweep, Command::Hunt};

}  // namespace

TEST_CASE(
    "every option of the table is in cullide help, in each taking command's --help and in the man page") {
    const Outcome help = run({"help"});
    REQUIRE(help.status == 0);
    const Outcome man = run({"help", "--man"});
    REQUIRE(man.status == 0);
    REQUIRE_FALSE(cullide::cli::option_table().empty());
    for (const OptionSpec& o : cullide::cli::option_table()) {
        CAPTURE(o.name);
        const std::string synopsis = o.value.empty() ? o.name : o.name + " " + o.value;
        CHECK(has(help.out, "  " + synopsis));
        CHECK(has(one_line(help.out), one_line(o.help)));  // the text is the table's, not a copy
        CHECK(has(man.out, "\\fB" + roff_name(o.name) + "\\fR"));
        for (Command c : kCommands) {
            if (!cullide::cli::takes(o.commands, c)) continue;
            const Outcome h = run({cullide::cli::command_name(c), "--help"});
            CHECK(h.status == 0);
            CHECK(has(h.out, "  " + synopsis + " "));
            CHECK(has(one_line(h.out), one_line(o.help)));
        }
    }
}

TEST_CASE("each command refuses the options it does not take, naming the commands that do") {
    for (const OptionSpec& o : cullide::cli::option_table()) {
        for (Command c : kCommands) {
            bool taken = false;  // a same-named option of c (run's --threads T, bench's --threads LIST)
            cullide::cli::CommandSet takers = 0;  // every command taking an option of this name
            for (const OptionSpec& other : cullide::cli::option_table()) {
                taken = taken || (other.name == o.name && cullide::cli::takes(other.commands, c));
                if (other.name == o.name) takers |= other.commands;
            }
            if (taken) continue;
            const std::string command = cullide::cli::command_name(c);
            CAPTURE(command);
            CAPTURE(o.name);
            const Outcome r = run({command, o.name, "1"});
            CHECK(r.status == 2);
            CHECK(has(r.err, "option " + o.name + " is taken by " + cullide::cli::command_list(takers) +
                                 ", not by " + command));
            CHECK(has(r.err, "cullide " + command + " --help"));
            CHECK(r.out.empty());
        }
    }
    CHECK(has(run({"run", "--csv", "x.csv"}).err, "option --csv is taken by bench, sweep and hunt, not by run"));
    CHECK(has(run({"sweep", "--pairs", "p.csv"}).err, "option --pairs is taken by run, not by sweep"));
    CHECK(has(run({"scenes", "--frames", "2"}).err, "scenes takes no options"));
}

TEST_CASE("--version and version print the version of CMake's project() and the build's configuration") {
    std::ifstream cmake(std::filesystem::path(CULLIDE_SOURCE_DIR) / "CMakeLists.txt");
    std::stringstream text;
    text << cmake.rdbuf();
    std::smatch m;
    const std::string source = text.str();
    REQUIRE(std::regex_search(source, m, std::regex(R"(project\(cullide VERSION ([0-9.]+))")));
    const std::string expected = "cullide " + m[1].str() + "\n";
    for (const char* arg : {"--version", "version"}) {
        CAPTURE(arg);
        const Outcome v = run({arg});
        CHECK(v.status == 0);
        CHECK(v.out.rfind(expected, 0) == 0);
        CHECK(has(v.out, "\nconfiguration: oneTBB "));
        CHECK((has(v.out, ", raster kernel AVX-512\n") || has(v.out, ", raster kernel AVX2\n") ||
               has(v.out, ", raster kernel portable\n")));
        CHECK(v.err.empty());
    }
    CHECK(has(run({"help", "--man"}).out, ".TH CULLIDE 1 \"\" \"cullide " + m[1].str() + "\""));
    CHECK(run({"version", "--json"}).status == 2);
}

TEST_CASE("the ranges printed and checked are the library's limits") {
    const std::string run_help = one_line(run({"run", "--help"}).out);
    CHECK(has(run_help,
              "view resolution of visibility methods (16.." + std::to_string(raster::kMaxTargetSize)));
    CHECK(has(run_help, "(1.." + std::to_string(cullide::kMaxRounds) + "; default 4)"));
    CHECK(has(run_help, "scene size factor ((0, 100]; default 1)"));
    CHECK(cullide::kMaxSceneScale == 100.0);
    const std::string too_big = std::to_string(raster::kMaxTargetSize + 1);
    CHECK(has(run({"run", "--resolution", too_big}).err, "--resolution must be an integer in 16.." +
                                                             std::to_string(raster::kMaxTargetSize) +
                                                             " (got '" + too_big + "')"));
    CHECK(has(run({"sweep", "--rounds", "1001"}).err, "--rounds must be an integer in 1..1000 (got '1001')"));
}

TEST_CASE("help is generated per command: sweep prints its own defaults, help COMMAND is COMMAND --help") {
    const std::string sweep = one_line(run({"sweep", "--help"}).out);
    const std::string bench = one_line(run({"bench", "--help"}).out);
    CHECK(has(sweep, "usage: cullide sweep [options]"));
    CHECK(has(sweep, "(1..1000; default 1)"));  // --reps
    CHECK(has(bench, "(1..1000; default 5)"));
    CHECK(has(sweep, "default cullide,rcullide,rcullide-offset"));
    CHECK(has(bench, "default exact,cullide,rcullide"));
    CHECK_FALSE(has(bench, "--pairs"));
    CHECK_FALSE(has(run({"run", "--help"}).out, "--csv"));
    for (const char* c : {"run", "bench", "sweep", "hunt"}) {
        CAPTURE(c);
        CHECK(run({"help", c}).out == run({c, "--help"}).out);
    }
    const Outcome bad = run({"help", "frobnicate"});
    CHECK(bad.status == 2);
    CHECK(has(bad.err, "help takes one command name (run, bench, sweep, hunt) or --man (got 'frobnicate')"));
}

TEST_CASE("the man page is man(7) roff: a title, the sections, and no line a formatter would misread") {
    const std::string man = run({"help", "--man"}).out;
    for (const char* section : {".SH NAME", ".SH SYNOPSIS", ".SH DESCRIPTION", ".SH COMMANDS", ".SH OPTIONS",
                                ".SS \"Options of run\"",
                                ".SS \"Options of bench and sweep\"", ".SS \"Options of run and hunt\"",
                                ".SS \"Options of run, bench, sweep and hunt\"", ".SS \"Options of hunt\"", ".SH \"EXIT STATUS\""}) {
        CAPTURE(section);
        CHECK(has(man, std::string("\n") + section + "\n"));
    }
    std::istringstream lines(man);
    std::string line;
    while (std::getline(lines, line)) {
        CAPTURE(line);
        CHECK_FALSE(line.empty());                    // a blank line is a paragraph break in roff
        CHECK(line.rfind("'", 0) != 0);               // a control line with the other control character
        CHECK(line.find("--") == std::string::npos);  // hyphens are escaped as \-
    }
}
