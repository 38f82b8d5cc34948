// find_pairs: validation, then one of the three methods. The grid lives in grid_stages.cpp; the two
// twins (brute force and sweep-and-prune) are here, with the same output contract.
#include "spatialhash/broad_phase.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <charconv>
#include <string>
#include <vector>

#include "spatialhash/detail/executor.h"
#include "spatialhash/detail/grid_stages.h"

namespace spatialhash {

bool overlaps(const Box& x, const Box& y) {
    // Closed boxes: touching faces, edges or corners count.
    return x.lo[0] <= y.hi[0] && y.lo[0] <= x.hi[0] && x.lo[1] <= y.hi[1] && y.lo[1] <= x.hi[1] &&
           x.lo[2] <= y.hi[2] && y.lo[2] <= x.hi[2];
}

bool overlaps(const Sphere& x, const Sphere& y) {
    // Evaluated exactly like this in every method (no contraction: -ffp-contract=off), so the three
    // methods agree bit for bit even where rounding decides a near-touching pair.
    double dx = x.centre[0] - y.centre[0];
    double dy = x.centre[1] - y.centre[1];
    double dz = x.centre[2] - y.centre[2];
    double r = x.radius + y.radius;
    // Tiny magnitudes would square to zero and make distinct points "touch" (found by the fuzzer);
    // scaling by a power of two is exact and keeps the squares normal.
    const double m = std::max({std::fabs(dx), std::fabs(dy), std::fabs(dz), r});
    if (m < 0x1.0p-500) {
        dx *= 0x1.0p600;
        dy *= 0x1.0p600;
        dz *= 0x1.0p600;
        r *= 0x1.0p600;
    }
    return dx * dx + dy * dy + dz * dz <= r * r;
}

namespace {

using detail::chunk_count;
using detail::Executor;
using detail::kChunk;
using detail::Objects;

std::string num(double v) {
    // Shortest text that reads back to the same double.
    char buf[64];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, res.ptr);
}

Result<bool> validate_common(std::size_t n, const Options& options) {
    if (n > kMaxObjects) {
        return Error{"too many objects: " + std::to_string(n) + " (limit " + std::to_string(kMaxObjects) + ")"};
    }
    if (!(options.cell_size == 0.0 || (std::isfinite(options.cell_size) && options.cell_size > 0.0))) {
        return Error{"Options::cell_size = " + num(options.cell_size) +
                     " must be 0 (automatic) or finite and positive"};
    }
    return true;
}

Result<bool> validate(std::span<const Box> boxes) {
    static const char* const kAxis[3] = {"[0]", "[1]", "[2]"};
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        const Box& b = boxes[i];
        for (int k = 0; k < 3; ++k) {
            if (!std::isfinite(b.lo[k])) {
                return Error{"box " + std::to_string(i) + ": lo" + kAxis[k] + " = " + num(b.lo[k]) + " is not finite"};
            }
            if (!std::isfinite(b.hi[k])) {
                return Error{"box " + std::to_string(i) + ": hi" + kAxis[k] + " = " + num(b.hi[k]) + " is not finite"};
            }
            if (b.lo[k] > b.hi[k]) {
                return Error{"box " + std::to_string(i) + ": lo" + kAxis[k] + " = " + num(b.lo[k]) + " > hi" +
                             kAxis[k] + " = " + num(b.hi[k])};
            }
        }
    }
    return true;
}

Result<bool> validate(std::span<const Sphere> spheres) {
    for (std::size_t i = 0; i < spheres.size(); ++i) {
        const Sphere& s = spheres[i];
        for (int k = 0; k < 3; ++k) {
            const std::string what = "sphere " + std::to_string(i) + ": centre[" + std::to_string(k) + "] = ";
            if (!std::isfinite(s.centre[k])) return Error{what + num(s.centre[k]) + " is not finite"};
            if (std::fabs(s.centre[k]) > kMaxSphereMagnitude) {
                return Error{what + num(s.centre[k]) + " exceeds the limit " + num(kMaxSphereMagnitude) + " in magnitude"};
            }
        }
        const std::string what = "sphere " + std::to_string(i) + ": radius = ";
        if (!std::isfinite(s.radius)) return Error{what + num(s.radius) + " is not finite"};
        if (s.radius < 0.0) return Error{what + num(s.radius) + " is negative"};
        if (s.radius > kMaxSphereMagnitude) {
            return Error{what + num(s.radius) + " exceeds the limit " + num(kMaxSphereMagnitude)};
        }
    }
    return true;
}

// Brute force: every pair once, rows in fixed chunks; the output is sorted by construction.
PairSet brute_force(const Objects& objects, Executor& ex) {
    const std::size_t n = objects.size();
    constexpr std::size_t kRows = 64;
    const std::size_t items = chunk_count(n, kRows);
    std::vector<std::size_t> offsets(items + 1, 0);
    const auto row_range = [&](std::size_t c) { return std::pair{c * kRows, std::min(n, (c + 1) * kRows)}; };
    ex.for_each(items, [&](std::size_t c) {
        std::size_t k = 0;
        const auto [begin, end] = row_range(c);
        for (std::size_t i = begin; i < end; ++i) {
            for (std::size_t j = i + 1; j < n; ++j) {
                k += objects.overlap(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)) ? 1 : 0;
            }
        }
        offsets[c + 1] = k;
    });
    for (std::size_t c = 0; c < items; ++c) offsets[c + 1] += offsets[c];
    PairSet out;
    out.pairs.resize(offsets[items]);
    ex.for_each(items, [&](std::size_t c) {
        Pair* dst = out.pairs.data() + offsets[c];
        const auto [begin, end] = row_range(c);
        for (std::size_t i = begin; i < end; ++i) {
            for (std::size_t j = i + 1; j < n; ++j) {
                const auto a = static_cast<std::uint32_t>(i);
                const auto b = static_cast<std::uint32_t>(j);
                if (objects.overlap(a, b)) *dst++ = Pair{a, b};
            }
        }
    });
    out.stats.candidate_tests = n < 2 ? 0 : static_cast<std::uint64_t>(n) * (n - 1) / 2;
    return out;
}

// An order-preserving map of doubles to unsigned keys (negative values flipped entirely, positive
// ones get the sign bit), so the radix sort orders by value. -0 lands just below +0, which keeps the
// order non-decreasing.
std::uint64_t order_key(double v) {
    const auto bits = std::bit_cast<std::uint64_t>(v);
    return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}

struct Interval {
    double lo[3];
    double hi[3];
};

// Sweep-and-prune (Baraff 1992; Ericson 7.5.2): sort the intervals on the axis of greatest spread
// of the centres, then for each interval scan forward while the next one starts before it ends.
PairSet sweep_and_prune(const Objects& objects, std::span<const Interval> boxes, Executor& ex) {
    const std::size_t n = boxes.size();
    PairSet out;
    if (n < 2) return out;
    const std::size_t chunks = chunk_count(n);
    // Variance of centres per axis, on centres divided by their largest magnitude (no overflow);
    // partial sums are merged in chunk order, so the axis does not depend on the thread count.
    double scale[3] = {0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            scale[k] = std::max(scale[k], std::fabs(0.5 * boxes[i].lo[k] + 0.5 * boxes[i].hi[k]));
        }
    }
    struct Sums {
        double s[3];
        double s2[3];
    };
    std::vector<Sums> part(chunks, Sums{{0, 0, 0}, {0, 0, 0}});
    ex.for_each(chunks, [&](std::size_t c) {
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            for (int k = 0; k < 3; ++k) {
                const double v = scale[k] > 0 ? (0.5 * boxes[i].lo[k] + 0.5 * boxes[i].hi[k]) / scale[k] : 0.0;
                part[c].s[k] += v;
                part[c].s2[k] += v * v;
            }
        }
    });
    int axis = 0;
    double best = -1.0;
    for (int k = 0; k < 3; ++k) {
        double s = 0, s2 = 0;
        for (const Sums& p : part) {
            s += p.s[k];
            s2 += p.s2[k];
        }
        const double mean = s / static_cast<double>(n);
        const double var = (s2 / static_cast<double>(n) - mean * mean) * scale[k] * scale[k];
        if (var > best) {
            best = var;
            axis = k;
        }
    }
    out.stats.sweep_axis = axis;

    std::vector<std::uint64_t> keys(n);
    std::vector<std::uint32_t> order(n);
    for (std::size_t i = 0; i < n; ++i) {
        keys[i] = order_key(boxes[i].lo[axis]);
        order[i] = static_cast<std::uint32_t>(i);
    }
    detail::radix_sort(keys, order, 64, ex);  // stable: equal starts stay in index order
    std::vector<double> lo_sorted(n);
    for (std::size_t p = 0; p < n; ++p) lo_sorted[p] = boxes[order[p]].lo[axis];

    const int o1 = (axis + 1) % 3;
    const int o2 = (axis + 2) % 3;
    std::vector<std::uint64_t> tests(chunks, 0);
    const auto visit = [&](std::size_t c, auto&& emit) {
        std::uint64_t t = 0;
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t p = c * kChunk; p < end; ++p) {
            const std::uint32_t i = order[p];
            const Interval& bi = boxes[i];
            const double reach = bi.hi[axis];
            for (std::size_t q = p + 1; q < n && lo_sorted[q] <= reach; ++q) {
                const std::uint32_t j = order[q];
                const Interval& bj = boxes[j];
                if (bi.lo[o1] > bj.hi[o1] || bj.lo[o1] > bi.hi[o1] || bi.lo[o2] > bj.hi[o2] || bj.lo[o2] > bi.hi[o2]) {
                    continue;
                }
                ++t;
                if (objects.overlap(i, j)) emit(std::min(i, j), std::max(i, j));
            }
        }
        return t;
    };
    std::vector<std::size_t> offsets(chunks + 1, 0);
    ex.for_each(chunks, [&](std::size_t c) {
        std::size_t k = 0;
        tests[c] = visit(c, [&](std::uint32_t, std::uint32_t) { ++k; });
        offsets[c + 1] = k;
    });
    for (std::size_t c = 0; c < chunks; ++c) offsets[c + 1] += offsets[c];
    out.pairs.resize(offsets[chunks]);
    ex.for_each(chunks, [&](std::size_t c) {
        Pair* dst = out.pairs.data() + offsets[c];
        (void)visit(c, [&](std::uint32_t a, std::uint32_t b) { *dst++ = Pair{a, b}; });
    });
    for (std::uint64_t t : tests) out.stats.candidate_tests += t;
    detail::sort_pairs(out.pairs, n, ex);
    return out;
}

}  // namespace

namespace detail {
struct WorkspaceState {
    GridWorkspace grid;
    std::unique_ptr<Executor> executor;
    unsigned executor_threads = 0;
    Executor& executor_for(unsigned threads) {
        if (!executor || executor_threads != threads) {
            executor = std::make_unique<Executor>(threads);
            executor_threads = threads;
        }
        return *executor;
    }
};
struct WorkspaceAccess {
    static WorkspaceState& state(Workspace& w) {
        if (!w.state_) w.state_ = std::make_unique<WorkspaceState>();  // a moved-from workspace
        return *w.state_;
    }
};
}  // namespace detail

Workspace::Workspace() : state_(std::make_unique<detail::WorkspaceState>()) {}
Workspace::~Workspace() = default;
Workspace::Workspace(Workspace&&) noexcept = default;
Workspace& Workspace::operator=(Workspace&&) noexcept = default;

std::size_t Workspace::capacity_bytes() const {
    if (!state_) return 0;
    const detail::GridWorkspace& g = state_->grid;
    const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
    std::size_t total = bytes(g.bounds) + bytes(g.plan.huge) + bytes(g.plan.huge_ids) + bytes(g.plan_scratch.diameters) +
                        bytes(g.plan_scratch.sorted) + bytes(g.ids.cell_ids) + bytes(g.ids.objects) +
                        bytes(g.ids.control) + bytes(g.entry_offsets) + bytes(g.radix.keys) + bytes(g.radix.values) +
                        bytes(g.radix.hist) + bytes(g.radix_pairs.keys) + bytes(g.radix_pairs.values) + bytes(g.radix_pairs.hist) + bytes(g.cells.cells) + bytes(g.cell_starts) + bytes(g.filter) +
                        bytes(g.collide.items) + bytes(g.collide.item_counts) + bytes(g.collide.offsets) +
                        bytes(g.pair_keys);
    for (const auto& per_item : g.collide.found) {
        for (const auto& v : per_item) total += bytes(v);
    }
    return total;
}

namespace {

template <class Shape>
Result<Stats> run_into(std::span<const Shape> shapes, const Options& options, detail::WorkspaceState& ws,
                       std::vector<Pair>& pairs) {
    // (No pairs.clear() up front: the grid resizes `pairs` and overwrites every element, so a warm
    // vector is not zero-filled again each frame.)
    if (Result<bool> v = validate_common(shapes.size(), options); !v) {
        pairs.clear();
        return v.error();
    }
    if (Result<bool> v = validate(shapes); !v) {
        pairs.clear();
        return v.error();
    }
    Executor& ex = ws.executor_for(options.threads);
    Objects objects;
    if constexpr (std::is_same_v<Shape, Box>) {
        objects.boxes = shapes;
    } else {
        objects.spheres = shapes;
    }
    PairSet other;
    switch (options.method) {
        case Method::BruteForce:
            other = brute_force(objects, ex);
            break;
        case Method::SweepAndPrune: {
            std::vector<Interval> intervals(shapes.size());
            if constexpr (std::is_same_v<Shape, Box>) {
                for (std::size_t i = 0; i < shapes.size(); ++i) {
                    std::memcpy(&intervals[i], &shapes[i], sizeof(Interval));
                }
            } else {
                // The padded bounding spheres' boxes: conservative for the rounded predicate.
                const std::vector<detail::BoundingSphere> bs = detail::bounding_spheres(shapes, ex);
                for (std::size_t i = 0; i < shapes.size(); ++i) {
                    for (int k = 0; k < 3; ++k) {
                        intervals[i].lo[k] = bs[i].centre[k] - bs[i].radius;
                        intervals[i].hi[k] = bs[i].centre[k] + bs[i].radius;
                    }
                }
            }
            other = sweep_and_prune(objects, intervals, ex);
            break;
        }
        case Method::SpatialHash: {
            Result<Stats> r = [&]() -> Result<Stats> {
                if constexpr (std::is_same_v<Shape, Box>) {
                    // Boxes through their bounding cubes (smaller cells than the circumscribed
                    // sphere's; docs/spatialhash.md, "Sizing: boxes").
                    detail::bounding_cubes(shapes, ex, ws.grid.bounds);
                    return detail::grid_find_pairs(objects, options.cell_size, ex, detail::kCubeKnobs, ws.grid, pairs);
                } else {
                    detail::bounding_spheres(shapes, ex, ws.grid.bounds);
                    return detail::grid_find_pairs(objects, options.cell_size, ex, detail::PlanKnobs{}, ws.grid, pairs);
                }
            }();
            if (!r) pairs.clear();
            return r;
        }
        default:
            pairs.clear();
            return Error{"unknown Method " + std::to_string(static_cast<int>(options.method))};
    }
    pairs.swap(other.pairs);
    return other.stats;
}

template <class Shape>
Result<PairSet> run(std::span<const Shape> shapes, const Options& options) {
    detail::WorkspaceState ws;
    PairSet out;
    Result<Stats> stats = run_into(shapes, options, ws, out.pairs);
    if (!stats) return stats.error();
    out.stats = stats.value();
    return out;
}

}  // namespace

Result<PairSet> find_pairs(std::span<const Box> boxes, const Options& options) { return run(boxes, options); }

Result<PairSet> find_pairs(std::span<const Sphere> spheres, const Options& options) { return run(spheres, options); }

Result<Stats> find_pairs(std::span<const Box> boxes, const Options& options, Workspace& workspace,
                         std::vector<Pair>& pairs) {
    return run_into(boxes, options, detail::WorkspaceAccess::state(workspace), pairs);
}

Result<Stats> find_pairs(std::span<const Sphere> spheres, const Options& options, Workspace& workspace,
                         std::vector<Pair>& pairs) {
    return run_into(spheres, options, detail::WorkspaceAccess::state(workspace), pairs);
}

}  // namespace spatialhash
