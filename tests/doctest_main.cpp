// The one doctest main shared by every test program.
//
// Each test process works in a temporary folder of its own: ctest runs test cases as separate
// processes in parallel (-j), and several different builds' suites may run at once on one machine,
// while tests write files under std::filesystem::temp_directory_path() with fixed names. TMPDIR
// (which temp_directory_path() reads) is pointed at a fresh mkdtemp folder, removed at exit.
//
// A run asked for test cases by name (--test-case, as ctest runs each case) that matches none fails:
// doctest_discover_tests cuts a test-case name at ';' (a CMake list separator), so a case named
// "a; b" became two ctest tests, "a" and " b", that each ran nothing and passed (found in session
// 13: six cases had never run under ctest).
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <stdlib.h>  // mkdtemp, setenv (POSIX)

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

namespace {

// How many test cases passed the run's filters (-1: no test run ended, e.g. a listing query).
int g_cases_matched = -1;

// A listener that only records the run's count of test cases passing the filters.
struct CountMatchedCases : doctest::IReporter {
    explicit CountMatchedCases(const doctest::ContextOptions&) {}
    void report_query(const doctest::QueryData&) override {}
    void test_run_start() override {}
    void test_run_end(const doctest::TestRunStats& stats) override {
        g_cases_matched = static_cast<int>(stats.numTestCasesPassingFilters);
    }
    void test_case_start(const doctest::TestCaseData&) override {}
    void test_case_reenter(const doctest::TestCaseData&) override {}
    void test_case_end(const doctest::CurrentTestCaseStats&) override {}
    void test_case_exception(const doctest::TestCaseException&) override {}
    void subcase_start(const doctest::SubcaseSignature&) override {}
    void subcase_end() override {}
    void log_assert(const doctest::AssertData&) override {}
    void log_message(const doctest::MessageData&) override {}
    void test_case_skipped(const doctest::TestCaseData&) override {}
};
REGISTER_LISTENER("count_matched_cases", 1, CountMatchedCases);

bool asks_for_cases_by_name(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string_view a(argv[i]);
        if (a.starts_with("--test-case=") || a.starts_with("-tc=") || a.starts_with("--dt-test-case=") ||
            a.starts_with("--dt-tc="))
            return true;
    }
    return false;
}

}  // namespace

int main(int argc, char** argv) {
    std::string dir_template = (std::filesystem::temp_directory_path() / "cullide_test.XXXXXX").string();
    const char* dir = mkdtemp(dir_template.data());
    if (dir != nullptr) setenv("TMPDIR", dir, 1);

    doctest::Context context(argc, argv);
    int status = context.run();
    if (status == 0 && g_cases_matched == 0 && asks_for_cases_by_name(argc, argv)) {
        std::fprintf(stderr, "no test case matches the --test-case filter: nothing ran (a ';' in a test case's name?)\n");
        status = 1;
    }

    if (dir != nullptr) {
        std::error_code ignored;
        std::filesystem::remove_all(dir, ignored);
    }
    return status;
}
