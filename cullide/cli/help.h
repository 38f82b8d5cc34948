// cullide/cli/help.h: what the CLI says about itself (usage, each command's --help, the man page,
// the version), generated from the option table (options.h) so that no text lists an option the
// parser lacks or misses one it has. Not installed, not a public API.
#pragma once

#include <string>

#include "options.h"

namespace cullide::cli {

// `cullide help`: the commands, then every option grouped by the commands that take it.
[[nodiscard]] std::string usage_text();

// `cullide <command> --help`: the command's synopsis, what it does, and the options it takes with
// its own defaults.
[[nodiscard]] std::string command_help(Command command);

// `cullide help --man`: the manual page, man(7) roff, for `man -l`.
[[nodiscard]] std::string man_page();

// The project version set by CMake's project(cullide VERSION ...).
[[nodiscard]] const char* version();

// `cullide --version`: "cullide <version>", then a line naming the build's configuration (oneTBB
// threading, whether the AVX2 raster kernel runs here).
[[nodiscard]] std::string version_text();

}  // namespace cullide::cli
