// cullide/cli/options.h: the one table of command-line options of `run`, `bench`, `sweep` and `hunt`.
//
// Each option is one OptionSpec: name, value placeholder, help line, range, default, the commands
// that take it and how it sets Settings. Parsing, range checks and error messages come from the
// table, and so do every command's --help, `cullide help` and the man page (help.h): an option that
// is documented is an option that is parsed, and the reverse. Not installed, not a public API.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cullide/pipeline.h"
#include "cullide/scenes.h"

namespace cullide::cli {

// The commands that take options. Bits, so one option can name every command that takes it.
enum class Command : unsigned { Run = 1u, Bench = 2u, Sweep = 4u, Hunt = 8u };
using CommandSet = unsigned;
inline constexpr CommandSet kRunOnly = static_cast<unsigned>(Command::Run);
inline constexpr CommandSet kHuntOnly = static_cast<unsigned>(Command::Hunt);
// The options that set one frame's pipeline (method, resolution, depth format, threads): run and
// hunt take one value each, bench and sweep lists of their own.
inline constexpr CommandSet kRunHunt = kRunOnly | kHuntOnly;
inline constexpr CommandSet kBenchSweep =
    static_cast<unsigned>(Command::Bench) | static_cast<unsigned>(Command::Sweep);
inline constexpr CommandSet kAllCommands = kRunOnly | kBenchSweep | kHuntOnly;
// Every command, in help order.
inline constexpr Command kCommandList[] = {Command::Run, Command::Bench, Command::Sweep, Command::Hunt};

[[nodiscard]] inline bool takes(CommandSet set, Command c) { return (set & static_cast<unsigned>(c)) != 0; }
[[nodiscard]] const char* command_name(Command c);
// "run", "bench and sweep", "run, bench and sweep": the commands of a set, for messages and headings.
[[nodiscard]] std::string command_list(CommandSet set);

// Bad usage: the caller prints the message with a pointer to the help and exits with status 2.
struct UsageError {
    std::string message;
};

// Everything the options of run, bench and sweep set. Empty lists and unset optionals mean "the
// command's default" (the commands fill them in after parsing).
struct Settings {
    // The pipeline knobs every command shares, straight into the RunOptions that reaches
    // process_frame (no second struct to copy); resolution 0 = the method's default_resolution.
    // Bench and sweep cross the method, resolution, depth format and thread count with their
    // lists, per combination.
    RunOptions pipeline;
    SceneOptions scene;
    bool help = false;  // --help / -h anywhere: print the command's help and nothing else
    std::optional<int> frames;
    // run
    std::vector<std::string> inputs;  // one built-in scene name, or mesh files
    std::string pairs_file;
    bool json = false;
    // bench and sweep: lists are crossed
    std::vector<std::string> scenes;
    std::vector<double> scales;
    std::vector<Method> methods;
    std::vector<int> resolutions;
    std::vector<raster::DepthFormat> depth_formats;
    std::vector<int> thread_counts;
    int first_frame = 0;
    int frame_step = 1;
    std::optional<int> warmup, reps;
    std::string csv_path, json_path;  // also hunt's summary copies
    bool progress = true;
    // hunt (cullide/hunt.h); generator names are checked by the option
    std::vector<std::string> generators;  // empty: every generator, unless --mesh or --scene is given
    std::vector<std::string> mesh_files;  // --mesh, repeatable: one frame of all of them
    std::vector<std::string> hunt_scenes;  // --scene, repeatable
    std::optional<double> budget_s;
    std::optional<std::uint64_t> cases;
    int max_findings = 10;
    std::uint64_t shrink_checks = 2000;
    std::string out_dir = "hunt-out";
};

struct OptionSpec;
using ApplyOption = void (*)(const OptionSpec& spec, const std::string& value, Settings& s);

// The accepted values of a numeric option. Integers: lo..hi, both included. Reals: an interval
// whose ends are open or closed as flagged. None: the option checks its value itself (names).
struct Range {
    enum class Kind { None, Integer, Real } kind = Kind::None;
    double lo = 0, hi = 0;
    bool lo_open = false, hi_open = false;
};

struct OptionSpec {
    std::string name;   // "--resolution"
    std::string value;  // placeholder in help ("R", "LIST"); empty for a flag, which takes no value
    CommandSet commands = 0;
    std::string help;  // what it does; range and default are appended by the help generator
    Range range;
    std::string default_text;   // empty: no default worth printing
    std::string sweep_default;  // sweep's default where it differs from bench's; else empty
    ApplyOption apply = nullptr;
    // The default is a value: parse_options applies it when the option is absent, so the default
    // printed is the default used. Otherwise the default is prose, and the command or the library
    // supplies it.
    bool default_is_value = false;
};

// Every option, in help order. Two entries may share a name when the commands that take them read
// the value differently (run's --threads T, bench's --threads LIST).
[[nodiscard]] const std::vector<OptionSpec>& option_table();

// "16..16384", "(0, 100]"; empty for Kind::None.
[[nodiscard]] std::string range_text(const Range& r);

// Parses args[1..] (args[0] is the command's name) for `command`. Throws UsageError naming the
// option: unknown, taken by other commands only, missing its value, or a value out of range.
// --help or -h anywhere returns at once with help set and nothing else parsed. Options absent whose
// default is a value get it (sweep's where it has its own).
[[nodiscard]] Settings parse_options(Command command, const std::vector<std::string>& args);

}  // namespace cullide::cli
