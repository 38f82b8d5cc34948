// driver_compare.h: how driver_report.cpp counts the differences between the emulator and a real
// driver on one scene (tests/raster/driver_compare_test.cpp checks the counting).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace raster_test {

// One format x size of the report.
struct DriverRow {
    std::string format;
    int width = 0, height = 0, scenes = 0;
    std::size_t queries = 0, queries_differ = 0;
    std::uint64_t query_max_diff = 0;
    std::size_t values = 0, values_differ = 0;
    std::size_t differ_by_1 = 0, differ_by_2_to_16 = 0, differ_by_more = 0;  // in units of the last place
    std::size_t written_one_side = 0;  // one side still holds the clear value, the other does not
    std::uint64_t max_diff = 0;
    std::string first_query, first_value;  // what reproduces the first difference of each kind

    [[nodiscard]] bool identical() const { return queries_differ == 0 && values_differ == 0; }
};

inline std::uint64_t absdiff(std::uint64_t a, std::uint64_t b) { return a > b ? a - b : b - a; }

// Adds one scene's query results and depth values (row.width wide, `cleared` = the clear value's
// encoding) to the row. D16/D24 values are integers; D32F values are the float bits of numbers in
// [0, 1], whose order is the integers' order, so a difference counts units in the last place.
template <typename QueriesA, typename QueriesB, typename ValuesA, typename ValuesB>
void compare_with_driver(DriverRow& row, const QueriesA& ours, const QueriesB& theirs, const ValuesA& mine,
                         const ValuesB& their_depth, std::uint32_t cleared, std::uint64_t seed, int scene) {
    char where[160];
    for (std::size_t q = 0; q < ours.size() && q < theirs.size(); ++q) {
        ++row.queries;
        const std::uint64_t a = ours[q], b = theirs[q];
        if (a == b) continue;
        ++row.queries_differ;
        row.query_max_diff = std::max(row.query_max_diff, absdiff(a, b));
        if (row.first_query.empty()) {
            std::snprintf(where, sizeof where, "seed %llu scene %d query %zu: emulator %llu, driver %llu",
                          static_cast<unsigned long long>(seed), scene, q, static_cast<unsigned long long>(a),
                          static_cast<unsigned long long>(b));
            row.first_query = where;
        }
    }
    const std::size_t w = static_cast<std::size_t>(row.width < 1 ? 1 : row.width);
    for (std::size_t i = 0; i < mine.size() && i < their_depth.size(); ++i) {
        ++row.values;
        if (mine[i] == their_depth[i]) continue;
        ++row.values_differ;
        const std::uint64_t d = absdiff(mine[i], their_depth[i]);
        row.max_diff = std::max(row.max_diff, d);
        (d == 1 ? row.differ_by_1 : d <= 16 ? row.differ_by_2_to_16 : row.differ_by_more) += 1;
        if ((mine[i] == cleared) != (their_depth[i] == cleared)) ++row.written_one_side;
        if (row.first_value.empty()) {
            std::snprintf(where, sizeof where, "seed %llu scene %d pixel (%zu, %zu): emulator %08x, driver %08x",
                          static_cast<unsigned long long>(seed), scene, i % w, i / w, static_cast<unsigned>(mine[i]),
                          static_cast<unsigned>(their_depth[i]));
            row.first_value = where;
        }
    }
}

}  // namespace raster_test
