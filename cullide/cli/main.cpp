#include <iostream>
#include <string>
#include <vector>

#include "cli.h"
#include "cullide/pipeline.h"

int main(int argc, char** argv) {
    // Frames allocate and free megabytes: keep freed memory in the process (cullide/pipeline.h).
    (void)cullide::retain_freed_memory();
    std::vector<std::string> args(argv + 1, argv + argc);
    return cullide::cli::run(args, std::cout, std::cerr);
}
