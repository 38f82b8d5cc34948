// Test helpers for spatialhash: a seeded generator (splitmix64; never std::uniform_*), scene
// families, and an independent reference (a plain double loop written here, not the library's).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "spatialhash/broad_phase.h"
#include "spatialhash/detail/executor.h"

namespace sh_test {

using SpreadScope = spatialhash::detail::SpreadScheduleScope;

// Thread counts of the thread tests: oneTBB's schedule, then 2 and 3 on the spread schedule
// (spatialhash/detail/executor.h).
struct ThreadRun {
    unsigned threads;
    bool spread;
};
inline constexpr ThreadRun kThreadRuns[] = {{1, false}, {2, false}, {3, false},
                                            {8, false}, {2, true},  {3, true}};

using spatialhash::Box;
using spatialhash::Pair;
using spatialhash::Sphere;

// splitmix64 (Steele, Lea, Flood 2014): the same numbers on every platform.
class Rng {
   public:
    explicit Rng(std::uint64_t seed) : s_(seed) {}
    std::uint64_t next() {
        std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        return z ^ (z >> 31);
    }
    double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
    double range(double lo, double hi) { return lo + (hi - lo) * unit(); }
    std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(next() % n); }

   private:
    std::uint64_t s_;
};

inline Box box_at(double cx, double cy, double cz, double hx, double hy, double hz) {
    return Box{{cx - hx, cy - hy, cz - hz}, {cx + hx, cy + hy, cz + hz}};
}

// The reference: closed boxes overlap when every axis interval meets (written independently of
// spatialhash::overlaps).
inline bool ref_overlap(const Box& p, const Box& q) {
    for (int k = 0; k < 3; ++k) {
        if (p.hi[k] < q.lo[k] || q.hi[k] < p.lo[k]) return false;
    }
    return true;
}
// The documented sphere predicate, spelled out again here.
inline bool ref_overlap(const Sphere& p, const Sphere& q) {
    double d[3];
    double m = p.radius + q.radius;
    for (int k = 0; k < 3; ++k) {
        d[k] = p.centre[k] - q.centre[k];
        m = std::fmax(m, std::fabs(d[k]));
    }
    double r = p.radius + q.radius;
    const double scale = m < 0x1.0p-500 ? 0x1.0p600 : 1.0;  // keep tiny squares from underflowing
    double d2 = 0.0;
    for (double v : d) d2 = d2 + (v * scale) * (v * scale);
    r = r * scale;
    return d2 <= r * r;
}

template <class Shape>
std::vector<Pair> reference_pairs(const std::vector<Shape>& s) {
    std::vector<Pair> out;
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        for (std::uint32_t j = i + 1; j < s.size(); ++j) {
            if (ref_overlap(s[i], s[j])) out.push_back(Pair{i, j});
        }
    }
    return out;
}

inline std::uint64_t digest(const std::vector<Pair>& pairs) {
    std::uint64_t h = 1469598103934665603ULL;  // FNV-1a over the pair words
    for (const Pair& p : pairs) {
        for (std::uint32_t w : {p.a, p.b}) {
            for (int k = 0; k < 4; ++k) {
                h ^= (w >> (8 * k)) & 0xFFU;
                h *= 1099511628211ULL;
            }
        }
    }
    return h;
}

enum class Family {
    Uniform,
    Clustered,
    AllOverlapping,
    Touching,
    EqualCentroids,
    OnCellBoundaries,
    OneGiant,
    Degenerate,
    FarOffset,
    kCount
};
inline const char* family_name(Family f) {
    static const char* const kNames[] = {"uniform",     "clustered",          "all-overlapping",
                                         "touching",    "equal-centroids",    "on-cell-boundaries",
                                         "one-giant",   "degenerate",         "far-offset"};
    return kNames[static_cast<int>(f)];
}

// A random box scene of family f with n objects. For OnCellBoundaries the matching cell size is
// written to *cell (else 0).
inline std::vector<Box> box_scene(Family f, std::size_t n, Rng& rng, double* cell) {
    std::vector<Box> s;
    s.reserve(n);
    *cell = 0.0;
    switch (f) {
        case Family::Uniform: {
            const double side = rng.range(2.0, 20.0);
            for (std::size_t i = 0; i < n; ++i) {
                s.push_back(box_at(rng.range(0, side), rng.range(0, side), rng.range(0, side), rng.range(0.05, 1.0),
                                   rng.range(0.05, 1.0), rng.range(0.05, 1.0)));
            }
            break;
        }
        case Family::Clustered: {
            const std::uint32_t clusters = 1 + rng.below(4);
            std::vector<double> cx(clusters), cy(clusters), cz(clusters);
            for (std::uint32_t c = 0; c < clusters; ++c) {
                cx[c] = rng.range(-50, 50);
                cy[c] = rng.range(-50, 50);
                cz[c] = rng.range(-50, 50);
            }
            for (std::size_t i = 0; i < n; ++i) {
                const std::uint32_t c = rng.below(clusters);
                s.push_back(box_at(cx[c] + rng.range(-2, 2), cy[c] + rng.range(-2, 2), cz[c] + rng.range(-2, 2),
                                   rng.range(0.01, 0.6), rng.range(0.01, 0.6), rng.range(0.01, 0.6)));
            }
            break;
        }
        case Family::AllOverlapping: {
            // Every box contains the point (1, 2, 3).
            for (std::size_t i = 0; i < n; ++i) {
                s.push_back(Box{{1 - rng.range(0, 2), 2 - rng.range(0, 2), 3 - rng.range(0, 2)},
                                {1 + rng.range(0, 2), 2 + rng.range(0, 2), 3 + rng.range(0, 2)}});
            }
            break;
        }
        case Family::Touching: {
            // Integer lattice boxes with integer sizes: faces, edges and corners touch exactly.
            for (std::size_t i = 0; i < n; ++i) {
                double lo[3], hi[3];
                for (int k = 0; k < 3; ++k) {
                    lo[k] = static_cast<double>(rng.below(6));
                    hi[k] = lo[k] + static_cast<double>(rng.below(3));
                }
                s.push_back(Box{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}});
            }
            break;
        }
        case Family::EqualCentroids: {
            const double c[2][3] = {{0.5, 0.5, 0.5}, {rng.range(0, 3), rng.range(0, 3), rng.range(0, 3)}};
            for (std::size_t i = 0; i < n; ++i) {
                const double* p = c[rng.below(2)];
                const double h = rng.range(0.0, 1.0);
                s.push_back(box_at(p[0], p[1], p[2], h, h * rng.range(0.5, 1.0), h * rng.range(0.5, 1.0)));
            }
            break;
        }
        case Family::OnCellBoundaries: {
            // Cell edge 1 given; centres and faces on multiples of 1/4, so many lie exactly on cell
            // boundaries, and sizes up to what a cell of edge 1 admits.
            *cell = 1.0;
            const double max_half = 1.0 / (2.0 * 1.25 * 1.4142135623730951 * 1.7320508075688772);
            for (std::size_t i = 0; i < n; ++i) {
                const double h = std::floor(rng.range(0, max_half) * 8.0) / 8.0;
                s.push_back(box_at(static_cast<double>(rng.below(16)) * 0.25, static_cast<double>(rng.below(16)) * 0.25,
                                   static_cast<double>(rng.below(16)) * 0.25, h, h, h));
            }
            break;
        }
        case Family::OneGiant: {
            for (std::size_t i = 0; i < n; ++i) {
                s.push_back(box_at(rng.range(0, 30), rng.range(0, 30), rng.range(0, 30), rng.range(0.05, 0.5),
                                   rng.range(0.05, 0.5), rng.range(0.05, 0.5)));
            }
            if (n > 0) s[rng.below(static_cast<std::uint32_t>(n))] = box_at(15, 15, 15, 8, 8, 20);
            break;
        }
        case Family::Degenerate: {
            // Points and flat boxes on a coarse lattice, so that some coincide exactly.
            for (std::size_t i = 0; i < n; ++i) {
                double lo[3], hi[3];
                for (int k = 0; k < 3; ++k) {
                    lo[k] = static_cast<double>(rng.below(4)) * 0.5;
                    hi[k] = lo[k] + (rng.below(3) == 0 ? 0.5 : 0.0);
                }
                s.push_back(Box{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}});
            }
            break;
        }
        case Family::FarOffset: {
            // Far from the origin, sizes spread over three decades.
            const double off = rng.range(-1e7, 1e7);
            for (std::size_t i = 0; i < n; ++i) {
                const double h = std::pow(10.0, rng.range(-3, 0));
                s.push_back(box_at(off + rng.range(0, 5), off + rng.range(0, 5), off + rng.range(0, 5), h, h, h));
            }
            break;
        }
        case Family::kCount:
            break;
    }
    return s;
}

// A random sphere scene: 0 uniform, 1 clustered, 2 tangent lattice (exact touching), 3 equal centres.
inline std::vector<Sphere> sphere_scene(int kind, std::size_t n, Rng& rng) {
    std::vector<Sphere> s;
    for (std::size_t i = 0; i < n; ++i) {
        switch (kind) {
            case 0:
                s.push_back(Sphere{{rng.range(0, 8), rng.range(0, 8), rng.range(0, 8)}, rng.range(0.05, 1.0)});
                break;
            case 1:
                s.push_back(Sphere{{rng.range(0, 1.5), rng.range(0, 1.5), rng.range(-100, -98.5)}, rng.range(0.01, 0.4)});
                break;
            case 2:
                s.push_back(Sphere{{static_cast<double>(rng.below(5)), static_cast<double>(rng.below(5)),
                                    static_cast<double>(rng.below(5))},
                                   0.5});
                break;
            default:
                s.push_back(Sphere{{1.0, 1.0, 1.0}, rng.range(0.0, 2.0)});
                break;
        }
    }
    return s;
}

}  // namespace sh_test
