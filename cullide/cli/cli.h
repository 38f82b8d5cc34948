// The `cullide` command line, as a function so tests can drive it without a process.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace cullide::cli {

// Runs the command line `args` (without the program name). Results go to `out`, errors to `err`.
// Returns the exit status: 0 success, 1 bad input or failed run, 2 bad usage.
int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// `s` as the inside of a JSON string: quotes and backslashes escaped, control characters as \u00XX.
// Shared by run --json and hunt's summary.
std::string json_escape(const std::string& s);

}  // namespace cullide::cli
