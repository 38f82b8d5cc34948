// cullide/cli/help.cpp: usage, per-command help, the man page and the version, from the option table.
#include "help.h"

#include <string_view>
#include <vector>

#include "raster/command_batch.h"

#if !defined(CULLIDE_VERSION)
#error "CULLIDE_VERSION must come from CMake's project(VERSION) (cullide/CMakeLists.txt)"
#endif

namespace cullide::cli {
namespace {

constexpr std::size_t kWidth = 100;        // text help wraps here
constexpr std::size_t kOptionColumn = 24;  // where an option's description starts

// What the help and the man page say about each command, in the order they are listed.
struct CommandDoc {
    const char* name;
    const char* operands;  // after the name in the synopsis
    const char* summary;   // one line, for the command list
    const char* description;
};

constexpr const char* kRunDescription =
    "Detects the colliding triangle pairs of every frame. SCENE is one built-in scene name (default: "
    "cylinders; 'cullide scenes' lists them) or mesh files (.obj .ply .stl); each file is one object, or one "
    "object per OBJ group, in argument order.";

constexpr const char* kBenchDescription =
    "Times methods frame by frame on built-in scenes. Each frame of each combination scene x scale x method "
    "x "
    "resolution x depth format x threads runs --warmup untimed times, then --reps timed times; the time of a "
    "frame is the median of its repetitions. Before any time is reported the pairs are checked: every "
    "repetition must give the same pairs (digest), no reported pair may be rejected by the exact test, and a "
    "method that never misses (exact, rcullide, rcullide-offset, qcullide) must give exactly the ground "
    "truth's pairs; otherwise the command fails (exit 1) naming the scene, method and frame. Methods that "
    "may "
    "miss (cullide) are reported with their misses. Times are wall-clock milliseconds per frame (frame "
    "generation excluded); counts (pairs, false negatives, PCS sizes, queries) are totals over the frames. "
    "The "
    "load average is recorded.";

constexpr const char* kSweepDescription =
    "Runs every combination scene x scale x method x resolution x depth format x threads over the same "
    "frames "
    "and reports, per combination: time per frame, PCS size per stage, false negatives (true colliding "
    "triangle pairs not reported) and false positives (candidate triangle pairs sent to the exact test that "
    "do not collide) against the ground truth. A method that never misses (exact, rcullide, rcullide-offset, "
    "qcullide) but misses is marked MISMATCH and the exit status is 1. The options are those of bench, with "
    "the sweep's own defaults; a progress bar goes to stderr when it is a terminal.";

constexpr const char* kHuntDescription =
    "Searches for frames where a method misses a true colliding pair (for a method that never misses: any "
    "difference from the ground truth) and shrinks each finding to a small reproduction. Frames come from "
    "built-in generators of adversarial triangle soups (--generators), from perturbations of mesh files "
    "(--mesh) and of built-in scene frames (--scene), all deterministic from --seed. A finding is shrunk "
    "by delta debugging over objects, then triangles, then by simplifying coordinates while it still "
    "misses, and its reason is named by re-running it with one setting changed (docs/hunt.md). Each "
    "finding gets a folder in --out: one OBJ file per object, command.txt (a 'cullide run' line that "
    "reproduces it), pairs.csv (the missed pairs) and the reason; summary.csv and summary.json list them "
    "all. The search stops at --budget-s, --cases or Ctrl-C, writing what was found; it prints, per source, how many frames failed and how many true pairs were missed. Exit "
    "status 1 when a method that never misses has a finding.";

const std::vector<CommandDoc>& command_docs() {
    static const std::vector<CommandDoc> docs{
        {"run", "[SCENE...] [options]", "detect colliding triangle pairs, frame by frame", kRunDescription},
        {"scenes", "", "list the built-in scenes", "Lists the built-in scenes, one line each."},
        {"bench", "[options]", "time methods per frame, checked against the ground truth", kBenchDescription},
        {"sweep", "[options]", "resolution x depth format x method x scene: time, PCS, errors",
         kSweepDescription},
        {"hunt", "[options]", "search for frames a method gets wrong, and shrink them", kHuntDescription},
        {"help", "[COMMAND] [--man]", "this text, or one command's; --man: the manual page (roff)",
         "Prints every command and option; 'cullide help COMMAND' is 'cullide COMMAND --help'; 'cullide help "
         "--man' prints this manual page as roff."},
        {"version", "", "the version and the build's configuration (also --version)",
         "Prints the version and the build's configuration (oneTBB threading, the AVX2 raster kernel)."},
    };
    return docs;
}

const CommandDoc& doc_of(Command c) {
    for (const CommandDoc& d : command_docs()) {
        if (std::string_view(d.name) == command_name(c)) return d;
    }
    return command_docs().front();
}

// Appends `text` word by word, breaking before `width`; continuation lines start at `indent`.
// `column` is where the text starts on the current line.
void wrap(std::string& out, std::string_view text, std::size_t column, std::size_t indent) {
    std::size_t at = column;
    bool first = true;
    while (!text.empty()) {
        const std::size_t space = text.find(' ');
        const std::string_view word = text.substr(0, space);
        text = space == std::string_view::npos ? std::string_view() : text.substr(space + 1);
        if (word.empty()) continue;
        if (!first && at + 1 + word.size() > kWidth) {
            out += '\n';
            out.append(indent, ' ');
            at = indent;
        } else if (!first) {
            out += ' ';
            ++at;
        }
        out += word;
        at += word.size();
        first = false;
    }
    out += '\n';
}

enum class Defaults { Bench, Sweep, Both };

// An option's description as printed: its help, then its range and default in parentheses.
std::string description(const OptionSpec& o, Defaults which) {
    std::vector<std::string> notes;
    if (const std::string r = range_text(o.range); !r.empty()) notes.push_back(r);
    if (which == Defaults::Sweep && !o.sweep_default.empty()) {
        notes.push_back("default " + o.sweep_default);
    } else if (!o.default_text.empty()) {
        notes.push_back("default " + o.default_text);
    }
    if (which == Defaults::Both && !o.sweep_default.empty())
        notes.push_back("sweep: default " + o.sweep_default);
    std::string s = o.help;
    for (std::size_t i = 0; i < notes.size(); ++i) s += (i == 0 ? " (" : "; ") + notes[i];
    if (!notes.empty()) s += ")";
    return s;
}

std::string synopsis_of(const OptionSpec& o) { return o.value.empty() ? o.name : o.name + " " + o.value; }

void append_option(std::string& out, const OptionSpec& o, Defaults which) {
    const std::string head = "  " + synopsis_of(o);
    out += head;
    if (head.size() + 2 > kOptionColumn) {
        out += '\n';
        out.append(kOptionColumn, ' ');
    } else {
        out.append(kOptionColumn - head.size(), ' ');
    }
    wrap(out, description(o, which), kOptionColumn, kOptionColumn);
}

// The distinct command sets of the table, in the order they first appear: the help's groups.
std::vector<CommandSet> option_groups() {
    std::vector<CommandSet> groups;
    for (const OptionSpec& o : option_table()) {
        bool seen = false;
        for (CommandSet g : groups) seen = seen || g == o.commands;
        if (!seen) groups.push_back(o.commands);
    }
    return groups;
}

bool has_list_value(CommandSet group) {
    for (const OptionSpec& o : option_table()) {
        if (o.commands == group && o.value == "LIST") return true;
    }
    return false;
}

// man(7) text: backslashes and hyphens escaped (so option names copy and paste as ASCII), and a
// line that would start with a control character guarded.
std::string roff(std::string_view text) {
    std::string s;
    if (!text.empty() && (text[0] == '.' || text[0] == '\'')) s += "\\&";
    for (char c : text) {
        if (c == '\\')
            s += "\\e";
        else if (c == '-')
            s += "\\-";
        else
            s += c;
    }
    return s;
}

void append_man_options(std::string& out) {
    out += ".SH OPTIONS\nLIST is a comma\\-separated list of values; a repeated option replaces the list.\n";
    for (CommandSet group : option_groups()) {
        out += ".SS \"Options of " + command_list(group) + "\"\n";
        for (const OptionSpec& o : option_table()) {
            if (o.commands != group) continue;
            out += ".TP\n\\fB" + roff(o.name) + "\\fR";
            if (!o.value.empty()) out += " \\fI" + roff(o.value) + "\\fR";
            // GCC 12 at -O3 reports a false -Wrestrict inside libstdc++ for `"literal" + std::string&&`
            // (GCC bug 105329); silenced for this statement only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wrestrict"
#endif
            out += "\n" + roff(description(o, Defaults::Both)) + "\n";
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
        }
    }
}

}  // namespace

std::string usage_text() {
    std::string out = "usage: cullide <command> [options]\n\ncommands:\n";
    for (const CommandDoc& d : command_docs()) {
        std::string head = std::string("  ") + d.name;
        if (std::string_view(d.name) == "run") head += " [SCENE...]";
        head.append(head.size() < 19 ? 19 - head.size() : 1, ' ');
        out += head;
        wrap(out, d.summary, head.size(), 19);
    }
    out += '\n';
    wrap(out,
         "SCENE is one built-in scene name (default: cylinders) or mesh files (.obj .ply .stl); each file is "
         "one object, or one object per OBJ group, in argument order.",
         0, 0);
    for (CommandSet group : option_groups()) {
        out += "\noptions of " + command_list(group) +
               (has_list_value(group) ? " (LIST = comma-separated values)" : "") + ":\n";
        for (const OptionSpec& o : option_table()) {
            if (o.commands == group) append_option(out, o, Defaults::Both);
        }
    }
    return out;
}

std::string command_help(Command command) {
    const CommandDoc& d = doc_of(command);
    std::string out = std::string("usage: cullide ") + d.name + " " + d.operands + "\n\n";
    wrap(out, d.description, 0, 0);
    out += "\noptions";
    out += command == Command::Run
               ? ":\n"
               : " (LIST = comma-separated values; a repeated option replaces the list):\n";
    const Defaults which = command == Command::Sweep ? Defaults::Sweep : Defaults::Bench;
    for (const OptionSpec& o : option_table()) {
        if (takes(o.commands, command)) append_option(out, o, which);
    }
    out += "  --help, -h            this text\n";
    return out;
}

std::string man_page() {
    std::string out;
    out += ".\\\" Generated by the cullide CLI from its option table (cullide/cli/options.cpp).\n";
    out += ".TH CULLIDE 1 \"\" \"cullide " + roff(version()) + "\" \"User Commands\"\n";
    out += ".nh\n";  // no hyphenation: option names and method names are words to copy
    out += ".SH NAME\ncullide \\- CULLIDE, R\\-CULLIDE and Quick\\-CULLIDE collision culling on the CPU\n";
    out += ".SH SYNOPSIS\n";
    for (const CommandDoc& d : command_docs()) {
        out += ".B cullide " + roff(d.name) + "\n";
        if (*d.operands) out += roff(d.operands) + "\n";
        out += ".br\n";
    }
    out += ".B cullide \\-\\-version\n";
    out += ".SH DESCRIPTION\n";
    out +=
        "cullide runs the GPU collision\\-culling algorithms CULLIDE, R\\-CULLIDE and Quick\\-CULLIDE on the "
        "CPU "
        "through a software depth rasterizer, and checks them against an exact ground truth. Results do not "
        "depend on the thread count.\n";
    out += ".SH COMMANDS\n";
    for (const CommandDoc& d : command_docs())
        out += ".TP\n.B " + roff(d.name) + "\n" + roff(d.description) + "\n";
    append_man_options(out);
    out += ".SH \"EXIT STATUS\"\n0 success; 1 bad input, a failed run or a failed check; 2 bad usage.\n";
    out +=
        ".SH \"SEE ALSO\"\nREADME.md and docs/ in the source tree: docs/architecture.md, docs/results.md.\n";
    return out;
}

const char* version() { return CULLIDE_VERSION; }

std::string version_text() {
#if defined(CULLIDE_CLI_HAVE_TBB) && CULLIDE_CLI_HAVE_TBB
    const char* tbb = "oneTBB on";
#else
    const char* tbb = "oneTBB off (serial)";
#endif
    return std::string("cullide ") + version() + "\nconfiguration: " + tbb + ", raster kernel " +
           raster::simd_kernel_name() + "\n";
}

}  // namespace cullide::cli
