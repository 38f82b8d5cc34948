// The uniform-grid broad phase of GPU Gems 3 ch. 32 (S. Le Grand, "Broad-Phase Collision Detection
// with CUDA", 2007), stage by stage, on CPU threads. Each stage is a function with its own tests;
// docs/spatialhash.md gives the argument for the sizing constants and the duplicate-avoidance rule.
#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <charconv>
#include <vector>

#include "spatialhash/detail/grid_stages.h"

namespace spatialhash::detail {

namespace {

// Relative padding of bounding spheres. Rounding in the centre, the radius, the predicates and the
// cell arithmetic is a few units of 2^-53 relative to the largest magnitude involved (|centre| or
// the radius); 2^-46 covers it with a margin of 8 or more, and adds nothing measurable to the
// candidates of a scene near the origin.
constexpr double kPad = 0x1.0p-46;

double padded_radius(double r, const double c[3]) {
    const double cmax = std::max({std::fabs(c[0]), std::fabs(c[1]), std::fabs(c[2])});
    // Near zero, rounding is absolute (subnormal spacing), not relative: add a few of those too.
    constexpr double kAbsolutePad = 4.0 * std::numeric_limits<double>::denorm_min();
    return r + (r + cmax) * kPad + kAbsolutePad;
}

// Half the diagonal of a box with edges e[0..2], without underflow or overflow in the squares
// (found by the fuzzer: edges near 1e-300 squared to 0 and gave a zero radius).
double half_diagonal(const double e[3]) {
    const double m = std::max({e[0], e[1], e[2]});
    if (!(m > 0.0) || !std::isfinite(m)) return 0.5 * m;
    const double x = e[0] / m, y = e[1] / m, z = e[2] / m;
    // Rounding here is a few units of 2^-53, far inside the 2^-46 padding.
    return 0.5 * m * std::sqrt(x * x + y * y + z * z);
}

// The "count -> scan -> fill" pattern over fixed items: count(i) returns item i's output size,
// fill(i, out) writes exactly that many elements starting at out.
template <class T, class Count, class Fill>
std::vector<T> count_scan_fill(std::size_t items, Executor& ex, Count&& count, Fill&& fill) {
    std::vector<std::size_t> offsets(items + 1, 0);
    ex.for_each(items, [&](std::size_t i) { offsets[i + 1] = count(i); });
    for (std::size_t i = 0; i < items; ++i) offsets[i + 1] += offsets[i];
    std::vector<T> out(offsets[items]);
    ex.for_each(items, [&](std::size_t i) {
        [[maybe_unused]] const std::size_t written = fill(i, out.data() + offsets[i]);
        assert(written == offsets[i + 1] - offsets[i]);
    });
    return out;
}

std::string format_double(double v) {
    // Shortest text that reads back to the same double.
    char buf[64];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, res.ptr);
}

}  // namespace

std::vector<BoundingSphere> bounding_spheres(std::span<const Box> boxes, Executor& ex) {
    std::vector<BoundingSphere> out(boxes.size());
    ex.for_each(chunk_count(boxes.size()), [&](std::size_t c) {
        const std::size_t end = std::min(boxes.size(), (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            const Box& b = boxes[i];
            BoundingSphere& s = out[i];
            double e[3];
            for (int k = 0; k < 3; ++k) {
                // 0.5 lo + 0.5 hi cannot overflow where (lo + hi) / 2 can.
                s.centre[k] = 0.5 * b.lo[k] + 0.5 * b.hi[k];
                e[k] = b.hi[k] - b.lo[k];  // may overflow to inf: the object is then huge
            }
            s.radius = padded_radius(half_diagonal(e), s.centre);
        }
    });
    return out;
}

std::vector<BoundingSphere> bounding_spheres(std::span<const Sphere> spheres, Executor& ex) {
    std::vector<BoundingSphere> out(spheres.size());
    ex.for_each(chunk_count(spheres.size()), [&](std::size_t c) {
        const std::size_t end = std::min(spheres.size(), (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            BoundingSphere& s = out[i];
            for (int k = 0; k < 3; ++k) s.centre[k] = spheres[i].centre[k];
            s.radius = padded_radius(spheres[i].radius, s.centre);
        }
    });
    return out;
}

Result<GridPlan> plan_grid(std::span<const BoundingSphere> spheres, double requested_cell_size, Executor& ex,
                           const PlanKnobs& knobs) {
    const std::size_t n = spheres.size();
    GridPlan plan;
    plan.coverage_scale = knobs.coverage_scale;
    // Below 1 a coverage box could span three cells per axis, more than the 2^d slots.
    const double min_cell_factor = std::max(1.0, knobs.min_cell_factor);
    plan.huge.assign(n, 0);
    const auto scaled_diameter = [&](std::size_t i) { return 2.0 * (knobs.coverage_scale * spheres[i].radius); };

    double cell = requested_cell_size;
    if (cell > 0.0) {
        for (std::size_t i = 0; i < n; ++i) {
            plan.huge[i] = !(min_cell_factor * scaled_diameter(i) <= cell) ? 1 : 0;
        }
    } else if (n > 0) {
        // Automatic: the chapter's rule (1.5 x the largest scaled sphere) over every object except
        // outliers above kOutlierFactor x the 99th percentile, which are tested apart.
        std::vector<double> d(n);
        for (std::size_t i = 0; i < n; ++i) d[i] = scaled_diameter(i);
        std::vector<double> sorted = d;
        const auto rank = static_cast<std::size_t>(kOutlierQuantile * static_cast<double>(n - 1));
        std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank), sorted.end());
        const double q = sorted[rank];
        const double threshold = q > 0.0 ? kOutlierFactor * q : std::numeric_limits<double>::infinity();
        double largest = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const bool huge = !(d[i] <= threshold) || !std::isfinite(d[i]);
            plan.huge[i] = huge ? 1 : 0;
            if (!huge) largest = std::max(largest, d[i]);
        }
        cell = std::max(kAutoCellFactor, min_cell_factor) * largest;
        if (!(cell > 0.0)) {
            // Only points in the grid: any cell works; take 1/1024 of the scene's extent.
            double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
            bool first = true;
            for (std::size_t i = 0; i < n; ++i) {
                if (plan.huge[i]) continue;
                for (int k = 0; k < 3; ++k) {
                    lo[k] = first ? spheres[i].centre[k] : std::min(lo[k], spheres[i].centre[k]);
                    hi[k] = first ? spheres[i].centre[k] : std::max(hi[k], spheres[i].centre[k]);
                }
                first = false;
            }
            const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
            cell = extent / 1024.0;
            if (!(cell >= std::numeric_limits<double>::min())) cell = 1.0;
        }
    } else {
        cell = 1.0;
    }
    plan.cell_size = cell;
    for (std::size_t i = 0; i < n; ++i) {
        if (plan.huge[i]) plan.huge_ids.push_back(static_cast<std::uint32_t>(i));
    }

    // Origin: the lowest corner of every gridded coverage box, so that cell coordinates are >= 0.
    // min/max are exact, so the chunked reduction gives the same bits for any thread count.
    const std::size_t chunks = chunk_count(n);
    struct Extent {
        double lo[3];
        double hi[3];
    };
    constexpr double kInf = std::numeric_limits<double>::infinity();
    std::vector<Extent> part(chunks, Extent{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}});
    ex.for_each(chunks, [&](std::size_t c) {
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            if (plan.huge[i]) continue;
            const double rho = knobs.coverage_scale * spheres[i].radius;
            for (int k = 0; k < 3; ++k) {
                part[c].lo[k] = std::min(part[c].lo[k], spheres[i].centre[k] - rho);
                part[c].hi[k] = std::max(part[c].hi[k], spheres[i].centre[k] + rho);
            }
        }
    });
    Extent all{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
    for (const Extent& e : part) {
        for (int k = 0; k < 3; ++k) {
            all.lo[k] = std::min(all.lo[k], e.lo[k]);
            all.hi[k] = std::max(all.hi[k], e.hi[k]);
        }
    }
    const bool any_gridded = plan.huge_ids.size() < n;
    for (int k = 0; k < 3; ++k) plan.origin[k] = any_gridded ? all.lo[k] : 0.0;

    // Limit check, naming the object: its top coverage corner decides the largest coordinate.
    double max_q = 0.0;
    if (any_gridded) {
        for (int k = 0; k < 3; ++k) {
            const double q = std::floor((all.hi[k] - plan.origin[k]) / cell);
            if (!(q <= kMaxCellCoordinate)) {
                std::size_t culprit = 0;
                for (std::size_t i = 0; i < n; ++i) {
                    if (!plan.huge[i] && spheres[i].centre[k] + knobs.coverage_scale * spheres[i].radius == all.hi[k]) {
                        culprit = i;
                        break;
                    }
                }
                return Error{"spatial hash: object " + std::to_string(culprit) + " lies " + format_double(q) +
                             " cells from the grid origin on axis " + std::to_string(k) +
                             ", beyond the limit 2^50 (cell size " + format_double(cell) +
                             "); pass a larger Options::cell_size or use Method::SweepAndPrune"};
            }
            max_q = std::max(max_q, q);
        }
    }
    const auto max_coord = static_cast<std::uint64_t>(max_q);
    plan.axis_bits = std::clamp(static_cast<unsigned>(std::bit_width(max_coord)), 1U, kMaxAxisBits);
    plan.sentinel = std::uint64_t{1} << (3 * plan.axis_bits);
    plan.key_bits = 3 * plan.axis_bits + 1;
    return plan;
}

CellIdArray build_cell_ids(std::span<const BoundingSphere> spheres, const GridPlan& plan, Executor& ex) {
    const std::size_t n = spheres.size();
    CellIdArray out;
    out.cell_ids.assign(kSlots * n, plan.sentinel);
    out.objects.resize(kSlots * n);
    out.control.assign(n, 0);
    const unsigned b = plan.axis_bits;
    const std::uint64_t wrap = (std::uint64_t{1} << b) - 1;
    ex.for_each(chunk_count(n), [&](std::size_t c) {
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            const auto id = static_cast<std::uint32_t>(i);
            for (int s = 0; s < kSlots; ++s) out.objects[s * n + i] = (id << 1) | (s == 0 ? 0U : 1U);
            if (plan.huge[i]) continue;
            const BoundingSphere& sp = spheres[i];
            const double rho = plan.coverage_scale * sp.radius;
            std::uint64_t lo[3], home[3], hi[3];
            for (int k = 0; k < 3; ++k) {
                // The same expressions as plan_grid's, so every value is >= 0 and <= 2^50.
                lo[k] = static_cast<std::uint64_t>(std::floor(((sp.centre[k] - rho) - plan.origin[k]) / plan.cell_size));
                home[k] = static_cast<std::uint64_t>(std::floor((sp.centre[k] - plan.origin[k]) / plan.cell_size));
                hi[k] = static_cast<std::uint64_t>(std::floor(((sp.centre[k] + rho) - plan.origin[k]) / plan.cell_size));
                assert(lo[k] <= home[k] && home[k] <= hi[k] && hi[k] - lo[k] <= 1);
            }
            const auto type_of = [](std::uint64_t x, std::uint64_t y, std::uint64_t z) {
                return static_cast<unsigned>((x & 1U) | ((y & 1U) << 1) | ((z & 1U) << 2));
            };
            unsigned mask = 0;
            int slot = 1;
            for (std::uint64_t x = lo[0]; x <= hi[0]; ++x) {
                for (std::uint64_t y = lo[1]; y <= hi[1]; ++y) {
                    for (std::uint64_t z = lo[2]; z <= hi[2]; ++z) {
                        mask |= 1U << type_of(x, y, z);
                        const std::uint64_t key = cell_key(x & wrap, y & wrap, z & wrap, b);
                        if (x == home[0] && y == home[1] && z == home[2]) {
                            out.cell_ids[i] = key;
                        } else {
                            assert(slot < kSlots);
                            out.cell_ids[static_cast<std::size_t>(slot) * n + i] = key;
                            ++slot;
                        }
                    }
                }
            }
            out.control[i] = static_cast<std::uint16_t>(type_of(home[0], home[1], home[2]) | (mask << 3));
        }
    });
    return out;
}

CollisionCells build_collision_cells(std::span<const std::uint64_t> sorted_keys,
                                     std::span<const std::uint32_t> sorted_objects, const GridPlan& plan,
                                     Executor& ex) {
    CollisionCells out;
    // Sentinels sort last: the real entries are the prefix below the first sentinel.
    const auto valid = static_cast<std::size_t>(
        std::lower_bound(sorted_keys.begin(), sorted_keys.end(), plan.sentinel) - sorted_keys.begin());
    out.entries = valid;
    // Scan 1: where the key changes (cell starts).
    const std::size_t chunks = chunk_count(valid);
    const auto is_start = [&](std::size_t i) { return i == 0 || sorted_keys[i] != sorted_keys[i - 1]; };
    const std::vector<std::uint32_t> starts = count_scan_fill<std::uint32_t>(
        chunks, ex,
        [&](std::size_t c) {
            std::size_t k = 0;
            const std::size_t end = std::min(valid, (c + 1) * kChunk);
            for (std::size_t i = c * kChunk; i < end; ++i) k += is_start(i) ? 1 : 0;
            return k;
        },
        [&](std::size_t c, std::uint32_t* dst) {
            std::size_t k = 0;
            const std::size_t end = std::min(valid, (c + 1) * kChunk);
            for (std::size_t i = c * kChunk; i < end; ++i) {
                if (is_start(i)) dst[k++] = static_cast<std::uint32_t>(i);
            }
            return k;
        });
    // Scan 2: occupants per cell (H entries first, by the stable sort), keep >= 1 H and >= 2 in all.
    const std::size_t cells = starts.size();
    const auto describe = [&](std::size_t j) {
        const std::uint32_t start = starts[j];
        const std::size_t end = j + 1 < cells ? starts[j + 1] : valid;
        std::uint32_t homes = 0;
        while (start + homes < end && !entry_is_phantom(sorted_objects[start + homes])) ++homes;
        return CollisionCell{start, homes, static_cast<std::uint32_t>(end - start - homes),
                             cell_type_of_key(sorted_keys[start], plan.axis_bits)};
    };
    const auto keep = [](const CollisionCell& cc) { return cc.homes >= 1 && cc.homes + cc.phantoms >= 2; };
    constexpr std::size_t kCellChunk = 4096;
    out.cells = count_scan_fill<CollisionCell>(
        chunk_count(cells, kCellChunk), ex,
        [&](std::size_t c) {
            std::size_t k = 0;
            const std::size_t end = std::min(cells, (c + 1) * kCellChunk);
            for (std::size_t j = c * kCellChunk; j < end; ++j) k += keep(describe(j)) ? 1 : 0;
            return k;
        },
        [&](std::size_t c, CollisionCell* dst) {
            std::size_t k = 0;
            const std::size_t end = std::min(cells, (c + 1) * kCellChunk);
            for (std::size_t j = c * kCellChunk; j < end; ++j) {
                const CollisionCell cc = describe(j);
                if (keep(cc)) dst[k++] = cc;
            }
            return k;
        });
    return out;
}

std::vector<Pair> collide_cells(const CollisionCells& cells, std::span<const std::uint32_t> sorted_objects,
                                std::span<const std::uint16_t> control, const Objects& objects, Executor& ex,
                                std::uint64_t* candidate_tests) {
    // Cells grouped by type, key order kept inside each group.
    std::array<std::vector<std::uint32_t>, kSlots> by_type;
    for (std::size_t j = 0; j < cells.cells.size(); ++j) {
        by_type[cells.cells[j].type].push_back(static_cast<std::uint32_t>(j));
    }
    // Visits the pairs of one cell in pass t; emit(a, b) gets a < b. Returns the exact tests done.
    const auto visit = [&](const CollisionCell& cc, unsigned t, auto&& emit) {
        std::uint64_t tests = 0;
        const std::uint32_t end = cc.start + cc.homes + cc.phantoms;
        for (std::uint32_t h = cc.start; h < cc.start + cc.homes; ++h) {
            const std::uint32_t a = entry_object(sorted_objects[h]);
            for (std::uint32_t m = h + 1; m < end; ++m) {
                const std::uint32_t b = entry_object(sorted_objects[m]);
                if (tested_in_earlier_pass(control[a], control[b], t)) continue;
                ++tests;
                if (objects.overlap(a, b)) emit(std::min(a, b), std::max(a, b));
            }
        }
        return tests;
    };
    constexpr std::size_t kCellsPerItem = 1024;
    std::vector<Pair> all;
    std::uint64_t total_tests = 0;
    for (unsigned t = 0; t < static_cast<unsigned>(kSlots); ++t) {
        const std::vector<std::uint32_t>& list = by_type[t];
        const std::size_t items = chunk_count(list.size(), kCellsPerItem);
        std::vector<std::uint64_t> tests(items, 0);
        std::vector<Pair> pass = count_scan_fill<Pair>(
            items, ex,
            [&](std::size_t c) {
                std::size_t k = 0;
                const std::size_t end = std::min(list.size(), (c + 1) * kCellsPerItem);
                for (std::size_t j = c * kCellsPerItem; j < end; ++j) {
                    tests[c] += visit(cells.cells[list[j]], t, [&](std::uint32_t, std::uint32_t) { ++k; });
                }
                return k;
            },
            [&](std::size_t c, Pair* dst) {
                std::size_t k = 0;
                const std::size_t end = std::min(list.size(), (c + 1) * kCellsPerItem);
                for (std::size_t j = c * kCellsPerItem; j < end; ++j) {
                    (void)visit(cells.cells[list[j]], t, [&](std::uint32_t a, std::uint32_t b) { dst[k++] = Pair{a, b}; });
                }
                return k;
            });
        for (std::uint64_t v : tests) total_tests += v;
        all.insert(all.end(), pass.begin(), pass.end());
    }
    if (candidate_tests) *candidate_tests = total_tests;
    return all;
}

std::vector<Pair> collide_huge(std::span<const std::uint32_t> huge_ids, std::span<const std::uint8_t> huge,
                               const Objects& objects, Executor& ex, std::uint64_t* candidate_tests) {
    const std::size_t n = objects.size();
    const std::size_t per_huge = chunk_count(n);
    const std::size_t items = huge_ids.size() * per_huge;
    std::vector<std::uint64_t> tests(items, 0);
    const auto visit = [&](std::size_t item, auto&& emit) {
        const std::uint32_t h = huge_ids[item / per_huge];
        const std::size_t c = item % per_huge;
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        std::uint64_t t = 0;
        for (std::size_t jj = c * kChunk; jj < end; ++jj) {
            const auto j = static_cast<std::uint32_t>(jj);
            // Huge-huge pairs belong to the smaller index.
            if (j == h || (huge[j] && j < h)) continue;
            ++t;
            if (objects.overlap(h, j)) emit(std::min(h, j), std::max(h, j));
        }
        return t;
    };
    std::vector<Pair> out = count_scan_fill<Pair>(
        items, ex,
        [&](std::size_t item) {
            std::size_t k = 0;
            tests[item] = visit(item, [&](std::uint32_t, std::uint32_t) { ++k; });
            return k;
        },
        [&](std::size_t item, Pair* dst) {
            std::size_t k = 0;
            (void)visit(item, [&](std::uint32_t a, std::uint32_t b) { dst[k++] = Pair{a, b}; });
            return k;
        });
    if (candidate_tests) {
        *candidate_tests = 0;
        for (std::uint64_t v : tests) *candidate_tests += v;
    }
    return out;
}

void sort_pairs(std::vector<Pair>& pairs, std::size_t object_count, Executor& ex) {
    std::vector<std::uint64_t> keys(pairs.size());
    ex.for_each(chunk_count(pairs.size()), [&](std::size_t c) {
        const std::size_t end = std::min(pairs.size(), (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) keys[i] = (std::uint64_t{pairs[i].a} << 32) | pairs[i].b;
    });
    std::vector<std::uint32_t> no_values;
    const auto top = static_cast<unsigned>(std::bit_width(std::max<std::size_t>(object_count, 1)));
    radix_sort(keys, no_values, 32 + top, ex);
    ex.for_each(chunk_count(pairs.size()), [&](std::size_t c) {
        const std::size_t end = std::min(pairs.size(), (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            pairs[i] = Pair{static_cast<std::uint32_t>(keys[i] >> 32), static_cast<std::uint32_t>(keys[i])};
        }
    });
}

Result<PairSet> grid_find_pairs(const Objects& objects, std::span<const BoundingSphere> spheres,
                                double requested_cell_size, Executor& ex, const PlanKnobs& knobs) {
    Result<GridPlan> planned = plan_grid(spheres, requested_cell_size, ex, knobs);
    if (!planned) return planned.error();
    const GridPlan& plan = planned.value();
    CellIdArray ids = build_cell_ids(spheres, plan, ex);
    radix_sort(ids.cell_ids, ids.objects, plan.key_bits, ex);
    const CollisionCells cells = build_collision_cells(ids.cell_ids, ids.objects, plan, ex);
    PairSet out;
    std::uint64_t grid_tests = 0;
    std::uint64_t huge_tests = 0;
    out.pairs = collide_cells(cells, ids.objects, ids.control, objects, ex, &grid_tests);
    if (!plan.huge_ids.empty()) {
        std::vector<Pair> extra = collide_huge(plan.huge_ids, plan.huge, objects, ex, &huge_tests);
        out.pairs.insert(out.pairs.end(), extra.begin(), extra.end());
    }
    sort_pairs(out.pairs, objects.size(), ex);
    out.stats.cell_size = plan.cell_size;
    out.stats.axis_bits = plan.axis_bits;
    out.stats.huge_objects = static_cast<std::uint32_t>(plan.huge_ids.size());
    out.stats.cell_entries = cells.entries;
    out.stats.collision_cells = cells.cells.size();
    out.stats.candidate_tests = grid_tests + huge_tests;
    return out;
}

}  // namespace spatialhash::detail
