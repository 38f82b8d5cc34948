// driver_compare_test.cpp: the counting of driver_report (driver_compare.h) on made-up results, so
// that a report of "no difference" from a real driver means the comparison can see one.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "driver_compare.h"

TEST_CASE("Equal results are identical: every kind of difference is counted where it belongs") {
    raster_test::DriverRow row;
    row.width = 4;
    const std::vector<std::uint64_t> q = {0, 5, 1, 7};
    const std::uint32_t clear = 0xffffff;
    const std::vector<std::uint32_t> d = {clear, 100, 200, 300, 400, 500, 600, 700};
    raster_test::compare_with_driver(row, q, q, d, d, clear, 1, 0);
    CHECK(row.identical());
    CHECK(row.queries == 4);
    CHECK(row.values == 8);

    std::vector<std::uint64_t> q2 = q;
    q2[1] = 9;  // 4 samples more
    q2[3] = 6;  // 1 fewer
    std::vector<std::uint32_t> d2 = d;
    d2[0] = 123;       // written by the driver only
    d2[1] = 101;       // 1 ulp
    d2[2] = 216;       // 16 ulp
    d2[3] = 317;       // 17 ulp
    d2[5] = clear;     // written by the emulator only
    raster_test::compare_with_driver(row, q, q2, d, d2, clear, 7, 3);
    CHECK_FALSE(row.identical());
    CHECK(row.queries == 8);
    CHECK(row.queries_differ == 2);
    CHECK(row.query_max_diff == 4);
    CHECK(row.values == 16);
    CHECK(row.values_differ == 5);
    CHECK(row.differ_by_1 == 1);
    CHECK(row.differ_by_2_to_16 == 1);
    CHECK(row.differ_by_more == 3);
    CHECK(row.written_one_side == 2);
    CHECK(row.max_diff == clear - 123);
    CHECK(row.first_query == "seed 7 scene 3 query 1: emulator 5, driver 9");
    CHECK(row.first_value == "seed 7 scene 3 pixel (0, 0): emulator 00ffffff, driver 0000007b");
}

TEST_CASE("D32F depth differences count units in the last place through the float bits") {
    raster_test::DriverRow row;
    row.width = 2;
    const float a = 0.5f;
    std::uint32_t bits = 0;
    static_assert(sizeof bits == sizeof a);
    std::memcpy(&bits, &a, sizeof bits);
    const std::vector<std::uint32_t> mine = {bits, bits};
    const std::vector<std::uint32_t> theirs = {bits + 1, bits - 3};  // next float up, three floats down
    const std::vector<std::uint64_t> none;
    raster_test::compare_with_driver(row, none, none, mine, theirs, 0x3f800000u, 0, 0);
    CHECK(row.values_differ == 2);
    CHECK(row.differ_by_1 == 1);
    CHECK(row.differ_by_2_to_16 == 1);
    CHECK(row.max_diff == 3);
    CHECK(row.written_one_side == 0);
}
