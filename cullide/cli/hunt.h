// cullide/cli/hunt.h: `cullide hunt`, the search for frames a method gets wrong (docs/hunt.md).
//
// The engine (generators, check, shrink, classify) is the library's (cullide/hunt.h); this command
// adds the options, the time and case budgets, Ctrl-C, the progress line and the output files.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace cullide::cli {

// `cullide hunt ...` (args[0] is "hunt"). Returns the exit status: 0 the search ran (findings or not,
// for a method that may miss), 1 a method that never misses had a finding or a file could not be
// read or written, 2 bad usage.
int hunt_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace cullide::cli
