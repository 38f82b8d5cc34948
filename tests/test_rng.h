// Deterministic random numbers for tests: splitmix64, and values built from its integer bits only
// (std::uniform_*_distribution differs between standard libraries, so it is never used).
#pragma once

#include <cstdint>

namespace test {

class Rng {
   public:
    explicit Rng(std::uint64_t seed) : state_(seed) {}

    std::uint64_t next() {
        std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    // Uniform in [0, n) (n > 0); the modulo bias is irrelevant for tests.
    std::uint64_t below(std::uint64_t n) { return next() % n; }
    // Uniform double in [0, 1) with 53 random bits.
    double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    // Uniform double in [-1, 1) (exactly 2 unit() - 1).
    double sym() { return 2.0 * unit() - 1.0; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
    // Integer in [lo, hi].
    int range(int lo, int hi) { return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1)); }
    bool coin() { return (next() & 1u) != 0; }
    // A value on the grid lo + k / steps_per_unit, k integer, within [lo, hi].
    double grid(double lo, double hi, int steps_per_unit) {
        const auto steps = static_cast<std::uint64_t>((hi - lo) * steps_per_unit);
        return lo + static_cast<double>(below(steps + 1)) / steps_per_unit;
    }

   private:
    std::uint64_t state_;
};

}  // namespace test
