// The one doctest main shared by every test program.
//
// Each test process works in a temporary folder of its own: ctest runs test cases as separate
// processes in parallel (-j), and several different builds' suites may run at once on one machine,
// while tests write files under std::filesystem::temp_directory_path() with fixed names. TMPDIR
// (which temp_directory_path() reads) is pointed at a fresh mkdtemp folder, removed at exit.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <stdlib.h>  // mkdtemp, setenv (POSIX)

#include <filesystem>
#include <string>
#include <system_error>

int main(int argc, char** argv) {
    std::string dir_template = (std::filesystem::temp_directory_path() / "cullide_test.XXXXXX").string();
    const char* dir = mkdtemp(dir_template.data());
    if (dir != nullptr) setenv("TMPDIR", dir, 1);

    doctest::Context context(argc, argv);
    const int status = context.run();

    if (dir != nullptr) {
        std::error_code ignored;
        std::filesystem::remove_all(dir, ignored);
    }
    return status;
}
