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
#include <cstring>
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
// fill(i, out) writes exactly that many elements starting at out. This one writes into a caller's
// vector (its capacity is kept; the small offsets array is per call); count_scan_fill returns a new one.
template <class T, class Count, class Fill>
void count_scan_fill_into(std::vector<T>& out, std::size_t items, Executor& ex, Count&& count, Fill&& fill) {
    std::vector<std::size_t> offsets(items + 1, 0);
    ex.for_each(items, [&](std::size_t i) { offsets[i + 1] = count(i); });
    for (std::size_t i = 0; i < items; ++i) offsets[i + 1] += offsets[i];
    out.resize(offsets[items]);
    ex.for_each(items, [&](std::size_t i) {
        [[maybe_unused]] const std::size_t written = fill(i, out.data() + offsets[i]);
        assert(written == offsets[i + 1] - offsets[i]);
    });
}

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

// (x - origin) / cell, also where x - origin overflows (coordinates of opposite signs near the
// double range's ends; a fuzzer finding): halving x, origin and cell is then exact (they are far
// from the subnormals), and the quotient is the same value.
double cell_coordinate(double x, double origin, double cell) {
    const double d = x - origin;
    if (std::isinf(d)) return (0.5 * x - 0.5 * origin) / (0.5 * cell);
    return d / cell;
}

// Whether an object's coverage box (centre +- rho) is finite. One that reaches beyond the double
// range cannot be placed in cells relative to a finite origin; such objects are tested apart.
bool coverage_finite(const BoundingSphere& s, double coverage_scale) {
    const double rho = coverage_scale * s.radius;
    for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(s.centre[k] - rho) || !std::isfinite(s.centre[k] + rho)) return false;
    }
    return true;
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

std::vector<BoundingSphere> bounding_cubes(std::span<const Box> boxes, Executor& ex) {
    std::vector<BoundingSphere> out;
    bounding_cubes(boxes, ex, out);
    return out;
}

void bounding_cubes(std::span<const Box> boxes, Executor& ex, std::vector<BoundingSphere>& out) {
    out.resize(boxes.size());
    ex.for_each(chunk_count(boxes.size()), [&](std::size_t c) {
        const std::size_t end = std::min(boxes.size(), (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            const Box& b = boxes[i];
            BoundingSphere& s = out[i];
            double e = 0.0;
            for (int k = 0; k < 3; ++k) {
                s.centre[k] = 0.5 * b.lo[k] + 0.5 * b.hi[k];
                // 0.5 hi - 0.5 lo cannot overflow; halving is exact except deep in the subnormals,
                // which the absolute padding term covers.
                e = std::max(e, 0.5 * b.hi[k] - 0.5 * b.lo[k]);
            }
            s.radius = padded_radius(e, s.centre);
        }
    });
}

std::vector<BoundingSphere> bounding_spheres(std::span<const Sphere> spheres, Executor& ex) {
    std::vector<BoundingSphere> out;
    bounding_spheres(spheres, ex, out);
    return out;
}

void bounding_spheres(std::span<const Sphere> spheres, Executor& ex, std::vector<BoundingSphere>& out) {
    out.resize(spheres.size());
    ex.for_each(chunk_count(spheres.size()), [&](std::size_t c) {
        const std::size_t end = std::min(spheres.size(), (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            BoundingSphere& s = out[i];
            for (int k = 0; k < 3; ++k) s.centre[k] = spheres[i].centre[k];
            s.radius = padded_radius(spheres[i].radius, s.centre);
        }
    });
}

Result<GridPlan> plan_grid(std::span<const BoundingSphere> spheres, double requested_cell_size, Executor& ex,
                           const PlanKnobs& knobs) {
    GridPlan plan;
    PlanScratch scratch;
    if (Result<bool> r = plan_grid(spheres, requested_cell_size, ex, knobs, plan, scratch); !r) return r.error();
    return plan;
}

Result<bool> plan_grid(std::span<const BoundingSphere> spheres, double requested_cell_size, Executor& ex,
                       const PlanKnobs& knobs, GridPlan& plan, PlanScratch& scratch) {
    const std::size_t n = spheres.size();
    plan.huge_ids.clear();
    plan.coverage_scale = knobs.coverage_scale;
    // Below 1 a coverage box could span three cells per axis, more than the 2^d slots.
    const double min_cell_factor = std::max(1.0, knobs.min_cell_factor);
    plan.huge.assign(n, 0);
    const auto scaled_diameter = [&](std::size_t i) { return 2.0 * (knobs.coverage_scale * spheres[i].radius); };

    double cell = requested_cell_size;
    if (cell > 0.0) {
        for (std::size_t i = 0; i < n; ++i) {
            plan.huge[i] =
                !(min_cell_factor * scaled_diameter(i) <= cell) || !coverage_finite(spheres[i], knobs.coverage_scale) ? 1 : 0;
        }
    } else if (n > 0) {
        // Automatic: the chapter's rule (knobs.auto_cell_factor x the largest scaled diameter: 1.5
        // for spheres as in the chapter, 1.1 for cubes, docs/spatialhash.md) over every object except
        // outliers above kOutlierFactor x the 99th percentile, which are tested apart.
        std::vector<double>& d = scratch.diameters;
        d.resize(n);
        for (std::size_t i = 0; i < n; ++i) d[i] = scaled_diameter(i);
        std::vector<double>& sorted = scratch.sorted;
        sorted.assign(d.begin(), d.end());
        const auto rank = static_cast<std::size_t>(kOutlierQuantile * static_cast<double>(n - 1));
        std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank), sorted.end());
        const double q = sorted[rank];
        const double threshold = q > 0.0 ? kOutlierFactor * q : std::numeric_limits<double>::infinity();
        double largest = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const bool huge = !(d[i] <= threshold) || !std::isfinite(d[i]) || !coverage_finite(spheres[i], knobs.coverage_scale);
            plan.huge[i] = huge ? 1 : 0;
            if (!huge) largest = std::max(largest, d[i]);
        }
        cell = std::max(knobs.auto_cell_factor, min_cell_factor) * largest;
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
            const double q = std::floor(cell_coordinate(all.hi[k], plan.origin[k], cell));
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
    return true;
}

namespace {

// The cell range [lo, hi] (per axis, at most 2 cells) that an object's coverage box meets, and its
// home cell. The same expressions as plan_grid's, so every value is >= 0 and <= 2^50.
struct CellRange {
    std::uint64_t lo[3];
    std::uint64_t home[3];
    std::uint64_t hi[3];
};
CellRange cell_range(const BoundingSphere& sp, const GridPlan& plan) {
    CellRange r;
    const double rho = plan.coverage_scale * sp.radius;
    // floor(v) for 0 <= v <= 2^50 (plan_grid's origin and limit check guarantee both: the origin is
    // the minimum of the same expression centre - rho): truncation through int64 is the same value
    // without the floor call and the unsigned-conversion branches.
    const auto cell_of = [](double v) {
        assert(v >= 0.0 && v <= kMaxCellCoordinate + 1.0);
        return static_cast<std::uint64_t>(static_cast<std::int64_t>(v));
    };
    for (int k = 0; k < 3; ++k) {
        r.lo[k] = cell_of(cell_coordinate(sp.centre[k] - rho, plan.origin[k], plan.cell_size));
        r.home[k] = cell_of(cell_coordinate(sp.centre[k], plan.origin[k], plan.cell_size));
        r.hi[k] = cell_of(cell_coordinate(sp.centre[k] + rho, plan.origin[k], plan.cell_size));
        assert(r.lo[k] <= r.home[k] && r.home[k] <= r.hi[k] && r.hi[k] - r.lo[k] <= 1);
    }
    return r;
}

// An object's cell keys: keys[0] the home cell, then the phantom cells in (x, y, z) order; returns
// how many, and the control bits.
int object_cells(const CellRange& r, const GridPlan& plan, std::uint64_t keys[kSlots], std::uint16_t* control) {
    const unsigned b = plan.axis_bits;
    const std::uint64_t wrap = (std::uint64_t{1} << b) - 1;
    const auto type_of = [](std::uint64_t x, std::uint64_t y, std::uint64_t z) {
        return static_cast<unsigned>((x & 1U) | ((y & 1U) << 1) | ((z & 1U) << 2));
    };
    unsigned mask = 0;
    int slot = 1;
    for (std::uint64_t x = r.lo[0]; x <= r.hi[0]; ++x) {
        for (std::uint64_t y = r.lo[1]; y <= r.hi[1]; ++y) {
            for (std::uint64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
                mask |= 1U << type_of(x, y, z);
                const std::uint64_t key = cell_key(x & wrap, y & wrap, z & wrap, b);
                if (x == r.home[0] && y == r.home[1] && z == r.home[2]) {
                    keys[0] = key;
                } else {
                    assert(slot < kSlots);
                    keys[slot++] = key;
                }
            }
        }
    }
    *control = static_cast<std::uint16_t>(type_of(r.home[0], r.home[1], r.home[2]) | (mask << 3));
    return slot;
}

}  // namespace

CellIdArray build_cell_ids(std::span<const BoundingSphere> spheres, const GridPlan& plan, Executor& ex) {
    const std::size_t n = spheres.size();
    CellIdArray out;
    out.cell_ids.assign(kSlots * n, plan.sentinel);
    out.objects.resize(kSlots * n);
    out.control.assign(n, 0);
    ex.for_each(chunk_count(n), [&](std::size_t c) {
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            const auto id = static_cast<std::uint32_t>(i);
            for (int s = 0; s < kSlots; ++s) out.objects[s * n + i] = (id << 1) | (s == 0 ? 0U : 1U);
            if (plan.huge[i]) continue;
            std::uint64_t keys[kSlots];
            const int count = object_cells(cell_range(spheres[i], plan), plan, keys, &out.control[i]);
            for (int s = 0; s < count; ++s) out.cell_ids[static_cast<std::size_t>(s) * n + i] = keys[s];
        }
    });
    return out;
}

CellIdArray build_cell_entries(std::span<const BoundingSphere> spheres, const GridPlan& plan, Executor& ex) {
    CellIdArray out;
    std::vector<std::size_t> offset;
    build_cell_entries(spheres, plan, ex, out, offset);
    return out;
}

void build_cell_entries(std::span<const BoundingSphere> spheres, const GridPlan& plan, Executor& ex, CellIdArray& out,
                        std::vector<std::size_t>& offset) {
    const std::size_t n = spheres.size();
    const std::size_t chunks = chunk_count(n);
    // Count: entries per (chunk, slot). An object fills slots [0, cells).
    offset.assign(chunks * kSlots, 0);
    ex.for_each(chunks, [&](std::size_t c) {
        std::size_t* cnt = offset.data() + c * kSlots;
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            if (plan.huge[i]) continue;
            const CellRange r = cell_range(spheres[i], plan);
            const auto cells = static_cast<int>((r.hi[0] - r.lo[0] + 1) * (r.hi[1] - r.lo[1] + 1) * (r.hi[2] - r.lo[2] + 1));
            for (int s = 0; s < cells; ++s) ++cnt[s];
        }
    });
    // Scan in (slot, chunk) order: the slot-major order of the full array, sentinels left out.
    std::size_t running = 0;
    for (std::size_t s = 0; s < kSlots; ++s) {
        for (std::size_t c = 0; c < chunks; ++c) {
            const std::size_t k = offset[c * kSlots + s];
            offset[c * kSlots + s] = running;
            running += k;
        }
    }
    out.cell_ids.resize(running);
    out.objects.resize(running);
    out.control.assign(n, 0);
    // Fill.
    ex.for_each(chunks, [&](std::size_t c) {
        std::size_t* dst = offset.data() + c * kSlots;
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            if (plan.huge[i]) continue;
            std::uint64_t keys[kSlots];
            const int count = object_cells(cell_range(spheres[i], plan), plan, keys, &out.control[i]);
            const auto id = static_cast<std::uint32_t>(i);
            for (int s = 0; s < count; ++s) {
                const std::size_t e = dst[s]++;
                out.cell_ids[e] = keys[s];
                out.objects[e] = (id << 1) | (s == 0 ? 0U : 1U);
            }
        }
    });
}

void drop_sentinels(CellIdArray& ids, const GridPlan& plan, Executor& ex) {
    const std::size_t total = ids.cell_ids.size();
    const std::size_t chunks = chunk_count(total);
    std::vector<std::size_t> offsets(chunks + 1, 0);
    ex.for_each(chunks, [&](std::size_t c) {
        const std::size_t end = std::min(total, (c + 1) * kChunk);
        std::size_t k = 0;
        for (std::size_t i = c * kChunk; i < end; ++i) k += ids.cell_ids[i] != plan.sentinel ? 1 : 0;
        offsets[c + 1] = k;
    });
    for (std::size_t c = 0; c < chunks; ++c) offsets[c + 1] += offsets[c];
    std::vector<std::uint64_t> keys(offsets[chunks]);
    std::vector<std::uint32_t> objects(offsets[chunks]);
    ex.for_each(chunks, [&](std::size_t c) {
        const std::size_t end = std::min(total, (c + 1) * kChunk);
        std::size_t k = offsets[c];
        for (std::size_t i = c * kChunk; i < end; ++i) {
            if (ids.cell_ids[i] == plan.sentinel) continue;
            keys[k] = ids.cell_ids[i];
            objects[k] = ids.objects[i];
            ++k;
        }
    });
    ids.cell_ids.swap(keys);
    ids.objects.swap(objects);
}

CollisionCells build_collision_cells(std::span<const std::uint64_t> sorted_keys,
                                     std::span<const std::uint32_t> sorted_objects, const GridPlan& plan,
                                     Executor& ex) {
    CollisionCells out;
    std::vector<std::uint32_t> starts;
    build_collision_cells(sorted_keys, sorted_objects, plan, ex, out, starts);
    return out;
}

void build_collision_cells(std::span<const std::uint64_t> sorted_keys, std::span<const std::uint32_t> sorted_objects,
                           const GridPlan& plan, Executor& ex, CollisionCells& out, std::vector<std::uint32_t>& starts) {
    // Sentinels sort last: the real entries are the prefix below the first sentinel.
    const auto valid = static_cast<std::size_t>(
        std::lower_bound(sorted_keys.begin(), sorted_keys.end(), plan.sentinel) - sorted_keys.begin());
    out.entries = valid;
    // Scan 1: where the key changes (cell starts).
    const std::size_t chunks = chunk_count(valid);
    const auto is_start = [&](std::size_t i) { return i == 0 || sorted_keys[i] != sorted_keys[i - 1]; };
    count_scan_fill_into<std::uint32_t>(
        starts, chunks, ex,
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
    count_scan_fill_into<CollisionCell>(
        out.cells, chunk_count(cells, kCellChunk), ex,
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
}

namespace {

// Outward rounding to float: the result is <= v (down) or >= v (up), also beyond float range.
float float_down(double v) {
    constexpr auto kMax = static_cast<double>(std::numeric_limits<float>::max());
    if (v > kMax) return std::numeric_limits<float>::max();
    if (v < -kMax) return -std::numeric_limits<float>::infinity();
    float f = static_cast<float>(v);
    if (static_cast<double>(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}
float float_up(double v) {
    constexpr auto kMax = static_cast<double>(std::numeric_limits<float>::max());
    if (v > kMax) return std::numeric_limits<float>::infinity();
    if (v < -kMax) return -std::numeric_limits<float>::max();
    float f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

// One cell's occupants gathered into contiguous arrays (structure of arrays), so that the inner
// loop of the pair test reads memory in order instead of jumping through the object arrays.
// kLanes padding entries at the end keep the 8-wide blocks in bounds; they are masked off.
constexpr std::uint32_t kLanes = 8;
constexpr std::uint32_t kPrefetch = 12;
struct CellScratch {
    std::vector<std::uint32_t> id;
    std::vector<std::uint16_t> control;
    std::vector<float> lo[3];
    std::vector<float> hi[3];
    std::vector<FilterBox> box;  // the whole filter box, for the inner test of the few survivors
    void gather(const CollisionCell& cc, std::span<const std::uint32_t> sorted_objects,
                std::span<const std::uint16_t> object_control, std::span<const FilterBox> filter) {
        const std::uint32_t size = cc.homes + cc.phantoms;
        const std::size_t padded = static_cast<std::size_t>(size) + kLanes;
        if (id.size() < padded) {
            id.resize(padded);
            control.resize(padded);
            box.resize(padded);
            for (int k = 0; k < 3; ++k) {
                lo[k].resize(padded);
                hi[k].resize(padded);
            }
        }
        for (std::uint32_t m = 0; m < size; ++m) {
#if defined(__GNUC__)
            // A cell's objects lie anywhere in memory; at 1M objects most of these loads miss
            // every cache, and asking kPrefetch entries ahead overlaps the misses.
            if (m + kPrefetch < size) {
                const std::uint32_t ahead = entry_object(sorted_objects[cc.start + m + kPrefetch]);
                __builtin_prefetch(&filter[ahead]);
                __builtin_prefetch(&object_control[ahead]);
            }
#endif
            const std::uint32_t obj = entry_object(sorted_objects[cc.start + m]);
            id[m] = obj;
            control[m] = object_control[obj];
            const FilterBox& fb = filter[obj];
            box[m] = fb;
            for (int k = 0; k < 3; ++k) {
                lo[k][m] = fb.lo[k];
                hi[k][m] = fb.hi[k];
            }
        }
    }
};

// The outer float pre-test of the 8 entries [m, m + 8) against box a, as a bit mask. Most blocks
// have no hit, so this answers "none" with a few SIMD compares, and in the dense blocks of
// clustered scenes it hands over the mask without a second, scalar pass (performance log, idea 14).
// GCC and clang vector extensions: SSE/NEON where the target has them, plain code otherwise; other
// compilers take the scalar loop. Both compute the same IEEE comparisons.
#if defined(__GNUC__)
// 4 floats (16 bytes): SSE/NEON width. Vectors are only locals here, never passed or returned, so
// no vector ABI question arises on targets without SIMD.
typedef float Quad __attribute__((vector_size(16)));
typedef std::int32_t QuadMask __attribute__((vector_size(16)));
#endif
// Returns the hit mask of the 8 entries (bit j = entry m + j passes the outer float test).
inline unsigned lanes_hits(std::uint32_t m, const float* lx, const float* ly, const float* lz, const float* hx,
                           const float* hy, const float* hz, float alx, float aly, float alz, float ahx, float ahy,
                           float ahz) {
#if defined(__GNUC__)
    unsigned bits = 0;
    for (std::uint32_t e = m, shift = 0; e < m + kLanes; e += 4, shift += 4) {
        Quad v[6];
        std::memcpy(&v[0], lx + e, sizeof(Quad));
        std::memcpy(&v[1], hx + e, sizeof(Quad));
        std::memcpy(&v[2], ly + e, sizeof(Quad));
        std::memcpy(&v[3], hy + e, sizeof(Quad));
        std::memcpy(&v[4], lz + e, sizeof(Quad));
        std::memcpy(&v[5], hz + e, sizeof(Quad));
        const QuadMask hit =
            (v[0] <= ahx) & (alx <= v[1]) & (v[2] <= ahy) & (aly <= v[3]) & (v[4] <= ahz) & (alz <= v[5]);
        // Lanes are all-ones or zero: keep one distinct bit per lane and fold them.
        const QuadMask lane_bit = {1, 2, 4, 8};
        const QuadMask b = hit & lane_bit;
        bits |= static_cast<unsigned>(b[0] | b[1] | b[2] | b[3]) << shift;
    }
    return bits;
#else
    unsigned bits = 0;
    for (std::uint32_t j = 0; j < kLanes; ++j) {
        const std::uint32_t e = m + j;
        const bool hit = (lx[e] <= ahx) & (alx <= hx[e]) & (ly[e] <= ahy) & (aly <= hy[e]) & (lz[e] <= ahz) & (alz <= hz[e]);
        bits |= static_cast<unsigned>(hit) << j;
    }
    return bits;
#endif
}

}  // namespace

std::vector<FilterBox> filter_boxes(const Objects& objects, std::span<const BoundingSphere> spheres, Executor& ex) {
    std::vector<FilterBox> out;
    filter_boxes(objects, spheres, ex, out);
    return out;
}

void filter_boxes(const Objects& objects, std::span<const BoundingSphere> spheres, Executor& ex,
                  std::vector<FilterBox>& out) {
    const std::size_t n = objects.size();
    out.resize(n);
    ex.for_each(chunk_count(n), [&](std::size_t c) {
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            for (int k = 0; k < 3; ++k) {
                if (!objects.boxes.empty()) {
                    out[i].lo[k] = float_down(objects.boxes[i].lo[k]);
                    out[i].hi[k] = float_up(objects.boxes[i].hi[k]);
                    out[i].inner_lo[k] = float_up(objects.boxes[i].lo[k]);
                    out[i].inner_hi[k] = float_down(objects.boxes[i].hi[k]);
                } else {
                    out[i].lo[k] = float_down(spheres[i].centre[k] - spheres[i].radius);
                    out[i].hi[k] = float_up(spheres[i].centre[k] + spheres[i].radius);
                    // Empty: a sphere pair is always decided by the exact predicate.
                    out[i].inner_lo[k] = std::numeric_limits<float>::infinity();
                    out[i].inner_hi[k] = -std::numeric_limits<float>::infinity();
                }
            }
        }
    });
}

std::vector<Pair> collide_cells(const CollisionCells& cells, std::span<const std::uint32_t> sorted_objects,
                                std::span<const std::uint16_t> control, const Objects& objects,
                                std::span<const FilterBox> filter, Executor& ex, CollideCounts* counts) {
    std::vector<Pair> out;
    CollideScratch scratch;
    const CollideCounts c = collide_cells(cells, sorted_objects, control, objects, filter, ex, out, scratch);
    if (counts) *counts = c;
    return out;
}

CollideCounts collide_cells(const CollisionCells& cells, std::span<const std::uint32_t> sorted_objects,
                            std::span<const std::uint16_t> control, const Objects& objects,
                            std::span<const FilterBox> filter, Executor& ex, std::vector<Pair>& all,
                            CollideScratch& scratch) {
    // Visits the pairs of one cell in pass t, in the chapter's order (each H entry against every
    // later entry); emit(a, b) gets a < b. The outer float test runs 8 entries at a time without
    // branches; only its survivors meet the duplicate-avoidance rule, then the inner float test,
    // then (if that cannot decide) the exact test.
    const auto visit = [&](const CollisionCell& cc, unsigned t, CellScratch& sc, CollideCounts& cnt, auto&& emit) {
        sc.gather(cc, sorted_objects, control, filter);
        const std::uint32_t size = cc.homes + cc.phantoms;
        cnt.cell_pairs += static_cast<std::uint64_t>(cc.homes) * (size - 1) -
                          static_cast<std::uint64_t>(cc.homes) * (cc.homes - 1) / 2;
        const float* lx = sc.lo[0].data();
        const float* ly = sc.lo[1].data();
        const float* lz = sc.lo[2].data();
        const float* hx = sc.hi[0].data();
        const float* hy = sc.hi[1].data();
        const float* hz = sc.hi[2].data();
        for (std::uint32_t h = 0; h < cc.homes; ++h) {
            const std::uint32_t a = sc.id[h];
            const std::uint16_t ca = sc.control[h];
            const float alx = lx[h], aly = ly[h], alz = lz[h], ahx = hx[h], ahy = hy[h], ahz = hz[h];
            for (std::uint32_t m = h + 1; m < size; m += kLanes) {
                unsigned bits = lanes_hits(m, lx, ly, lz, hx, hy, hz, alx, aly, alz, ahx, ahy, ahz);
                if (bits == 0) continue;
                if (size - m < kLanes) bits &= (1U << (size - m)) - 1U;  // padding lanes
                while (bits != 0) {
                    const std::uint32_t e = m + static_cast<std::uint32_t>(std::countr_zero(bits));
                    bits &= bits - 1;
                    const std::uint32_t b = sc.id[e];
                    if (tested_in_earlier_pass(ca, sc.control[e], t)) continue;
                    if (!inner_overlap(sc.box[h], sc.box[e])) {
                        ++cnt.exact_tests;
                        if (!objects.overlap(a, b)) continue;
                    }
                    emit(std::min(a, b), std::max(a, b));
                }
            }
        }
    };
    // Work items: runs of consecutive cells in key order, cut when their proposed pairs pass
    // kItemWork (a fixed budget, so the cut depends on the data only, never on the thread count).
    // Each item keeps one output buffer per cell type, and the buffers are merged in (type, item)
    // order: exactly the output of the chapter's 8 passes run one after the other, each in key
    // order. The CPU needs no barrier between passes (on the GPU they keep two threads from
    // writing the same object; here an item writes only its own buffers), and visiting cells in
    // key order means neighbouring cells, which share objects, are visited close together in time:
    // the objects' filter boxes are still in cache (at 1M objects this halved the stage).
    constexpr std::uint64_t kItemWork = std::uint64_t{1} << 15;
    std::vector<CollideScratch::Item>& items = scratch.items;
    items.clear();
    {
        std::uint64_t work = 0;
        std::uint32_t begin = 0;
        const auto count = static_cast<std::uint32_t>(cells.cells.size());
        for (std::uint32_t j = 0; j < count; ++j) {
            const CollisionCell& cc = cells.cells[j];
            work += static_cast<std::uint64_t>(cc.homes) * (cc.homes + cc.phantoms) + 16;
            if (work >= kItemWork || j + 1 == count) {
                items.push_back(CollideScratch::Item{begin, j + 1});
                begin = j + 1;
                work = 0;
            }
        }
    }
    // One visit per cell: each item collects its pairs in its own buffers (the "count"), the sizes
    // are scanned into offsets and the buffers copied into place (the "fill").
    // The buffers keep their capacity from frame to frame (a Workspace's scratch); clearing them
    // does not free.
    std::vector<std::array<std::vector<Pair>, kSlots>>& found = scratch.found;
    if (found.size() < items.size()) found.resize(items.size());
    std::vector<CollideCounts>& item_counts = scratch.item_counts;
    item_counts.assign(items.size(), CollideCounts{});
    ex.for_each(items.size(), [&](std::size_t c) {
        for (std::vector<Pair>& v : found[c]) v.clear();
        // Gather arrays per thread, kept between calls (their contents never reach the output).
        thread_local CellScratch sc;
        for (std::uint32_t j = items[c].begin; j < items[c].end; ++j) {
            const CollisionCell& cc = cells.cells[j];
            std::vector<Pair>& out = found[c][cc.type];
            visit(cc, cc.type, sc, item_counts[c], [&](std::uint32_t a, std::uint32_t b) { out.push_back(Pair{a, b}); });
        }
    });
    // offsets[t * items + c]: where type t's pairs of item c go.
    std::vector<std::size_t>& offsets = scratch.offsets;
    offsets.assign(kSlots * items.size() + 1, 0);
    for (std::size_t t = 0; t < kSlots; ++t) {
        for (std::size_t c = 0; c < items.size(); ++c) {
            const std::size_t slot = t * items.size() + c;
            offsets[slot + 1] = offsets[slot] + found[c][t].size();
        }
    }
    all.resize(offsets.back());
    ex.for_each(items.size(), [&](std::size_t c) {
        for (std::size_t t = 0; t < kSlots; ++t) {
            std::copy(found[c][t].begin(), found[c][t].end(),
                      all.begin() + static_cast<std::ptrdiff_t>(offsets[t * items.size() + c]));
        }
    });
    CollideCounts total;
    for (const CollideCounts& v : item_counts) {
        total.cell_pairs += v.cell_pairs;
        total.exact_tests += v.exact_tests;
    }
    return total;
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
    std::vector<std::uint64_t> keys;
    RadixScratch scratch;
    sort_pairs(pairs, object_count, ex, keys, scratch);
}

void sort_pairs(std::vector<Pair>& pairs, std::size_t object_count, Executor& ex, std::vector<std::uint64_t>& keys,
                RadixScratch& scratch) {
    const std::size_t m = pairs.size();
    keys.resize(m);
    ex.for_each(chunk_count(m), [&](std::size_t c) {
        const std::size_t end = std::min(m, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) keys[i] = (std::uint64_t{pairs[i].a} << 32) | pairs[i].b;
    });
    // Radix-sort on a only (the bits in use: bit_width(n - 1), 2 passes up to 2^22 objects), then
    // sort each run of equal a by b. A run holds one object's partners, a handful in the benchmark's
    // scenes, so the second step is an insertion sort in cache; long runs (a huge object's) take
    // std::sort. Keys are unique, so the result is the one sorted order whatever the chunking.
    const auto top = static_cast<unsigned>(std::bit_width(std::max<std::size_t>(object_count, 2) - 1));
    std::vector<std::uint32_t> no_values;
    radix_sort_bits(keys, no_values, 32, 32 + top, ex, scratch);
    const auto a_of = [&](std::size_t i) { return keys[i] >> 32; };
    // Each chunk sorts the runs that start in it (a run may reach into the next chunks).
    ex.for_each(chunk_count(m), [&](std::size_t c) {
        const std::size_t end = std::min(m, (c + 1) * kChunk);
        std::size_t i = c * kChunk;
        if (i > 0) {
            while (i < end && a_of(i) == a_of(i - 1)) ++i;  // the previous chunk's run
        }
        while (i < end) {
            std::size_t j = i + 1;
            while (j < m && a_of(j) == a_of(i)) ++j;
            std::uint64_t* run = keys.data() + i;
            const std::size_t len = j - i;
            if (len <= 32) {
                for (std::size_t x = 1; x < len; ++x) {
                    const std::uint64_t v = run[x];
                    std::size_t y = x;
                    for (; y > 0 && run[y - 1] > v; --y) run[y] = run[y - 1];
                    run[y] = v;
                }
            } else {
                std::sort(run, run + len);
            }
            i = j;
        }
    });
    ex.for_each(chunk_count(m), [&](std::size_t c) {
        const std::size_t end = std::min(m, (c + 1) * kChunk);
        for (std::size_t i = c * kChunk; i < end; ++i) {
            pairs[i] = Pair{static_cast<std::uint32_t>(keys[i] >> 32), static_cast<std::uint32_t>(keys[i])};
        }
    });
}

Result<PairSet> grid_find_pairs(const Objects& objects, std::span<const BoundingSphere> spheres,
                                double requested_cell_size, Executor& ex, const PlanKnobs& knobs) {
    GridWorkspace ws;
    ws.bounds.assign(spheres.begin(), spheres.end());
    PairSet out;
    Result<Stats> stats = grid_find_pairs(objects, requested_cell_size, ex, knobs, ws, out.pairs);
    if (!stats) return stats.error();
    out.stats = stats.value();
    return out;
}

Result<Stats> grid_find_pairs(const Objects& objects, double requested_cell_size, Executor& ex, const PlanKnobs& knobs,
                              GridWorkspace& ws, std::vector<Pair>& pairs) {
    const std::span<const BoundingSphere> spheres = ws.bounds;
    if (Result<bool> r = plan_grid(spheres, requested_cell_size, ex, knobs, ws.plan, ws.plan_scratch); !r) {
        return r.error();
    }
    const GridPlan& plan = ws.plan;
    build_cell_entries(spheres, plan, ex, ws.ids, ws.entry_offsets);
    radix_sort_bits(ws.ids.cell_ids, ws.ids.objects, 0, plan.key_bits - 1, ex, ws.radix);
    build_collision_cells(ws.ids.cell_ids, ws.ids.objects, plan, ex, ws.cells, ws.cell_starts);
    std::uint64_t huge_tests = 0;
    filter_boxes(objects, spheres, ex, ws.filter);
    const CollideCounts grid_counts =
        collide_cells(ws.cells, ws.ids.objects, ws.ids.control, objects, ws.filter, ex, pairs, ws.collide);
    if (!plan.huge_ids.empty()) {
        // (Allocates: only scenes with outliers take this path.)
        std::vector<Pair> extra = collide_huge(plan.huge_ids, plan.huge, objects, ex, &huge_tests);
        pairs.insert(pairs.end(), extra.begin(), extra.end());
    }
    sort_pairs(pairs, objects.size(), ex, ws.pair_keys, ws.radix_pairs);
    Stats stats;
    stats.cell_size = plan.cell_size;
    stats.axis_bits = plan.axis_bits;
    stats.huge_objects = static_cast<std::uint32_t>(plan.huge_ids.size());
    stats.cell_entries = ws.cells.entries;
    stats.collision_cells = ws.cells.cells.size();
    stats.cell_pairs = grid_counts.cell_pairs;
    stats.candidate_tests = grid_counts.exact_tests + huge_tests;
    return stats;
}

}  // namespace spatialhash::detail
