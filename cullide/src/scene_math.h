// scene_math.h: deterministic elementary functions and random numbers for the scene generators.
//
// Why: std::sin/cos/exp/pow and the std distributions are not specified bit for bit; glibc, musl,
// Apple's libm and MSVC give different last bits, and so would our scenes. Everything here uses only
// operations IEEE 754 defines exactly (+ - * / sqrt, floor, integer arithmetic) in a fixed order, so
// with -ffp-contract=off (cullide::fp) the results are the same bits on x86-64 and aarch64.
//
// Accuracy: det_sin/det_cos are within a few ulps of 1 (|error| < 1e-15) for |x| <= 2^20; beyond
// that the three-part reduction loses bits but stays deterministic. Non-finite input gives NaN.
#pragma once

#include <cmath>
#include <cstdint>

namespace cullide::det {

inline constexpr double kPi = 3.141592653589793;      // nearest double to pi
inline constexpr double kTwoPi = 6.283185307179586;   // nearest double to 2 pi
inline constexpr double kTwoOverPi = 0.6366197723675814;
// pi/2 split as p1 + p2 + p3: p1 and p2 have 33 significant bits, so k * p1 and k * p2 are exact for
// |k| < 2^20 and the reduction x - k*p1 - k*p2 - k*p3 keeps ~100 bits of pi/2 (Cody & Waite's
// scheme). Computed from 100 digits of pi with exact rationals.
inline constexpr double kPiOver2Part1 = 1.5707963267341256;
inline constexpr double kPiOver2Part2 = 6.077100506303966e-11;
inline constexpr double kPiOver2Part3 = 2.0222662487959506e-21;

namespace detail {

// Taylor coefficients 1/n! (n! < 2^53 up to 18!, so each is the correctly rounded quotient).
inline constexpr double inv_factorial(int n) {
    double f = 1.0;
    for (int i = 2; i <= n; ++i) f *= static_cast<double>(i);
    return 1.0 / f;
}

// sin on |r| <= pi/4 (+ rounding): Taylor to r^17; the r^19 term is below 1e-19.
inline double sin_kernel(double r) {
    const double r2 = r * r;
    double p = inv_factorial(17);
    p = -inv_factorial(15) + r2 * p;
    p = inv_factorial(13) + r2 * p;
    p = -inv_factorial(11) + r2 * p;
    p = inv_factorial(9) + r2 * p;
    p = -inv_factorial(7) + r2 * p;
    p = inv_factorial(5) + r2 * p;
    p = -inv_factorial(3) + r2 * p;
    return r + (r * r2) * p;
}

// cos on |r| <= pi/4: Taylor to r^18; the r^20 term is below 1e-20.
inline double cos_kernel(double r) {
    const double r2 = r * r;
    double p = -inv_factorial(18);
    p = inv_factorial(16) + r2 * p;
    p = -inv_factorial(14) + r2 * p;
    p = inv_factorial(12) + r2 * p;
    p = -inv_factorial(10) + r2 * p;
    p = inv_factorial(8) + r2 * p;
    p = -inv_factorial(6) + r2 * p;
    p = inv_factorial(4) + r2 * p;
    // 1 - r^2/2 + r^4 * p, with the large terms added last to keep the small ones' bits.
    return 1.0 + (-0.5 * r2 + (r2 * r2) * p);
}

}  // namespace detail

// sin(x) and cos(x) together: reduce once to r in [-pi/4, pi/4] and quadrant k mod 4.
inline void det_sincos(double x, double& s, double& c) {
    if (!std::isfinite(x)) {
        s = c = x - x;  // NaN for +-inf and NaN
        return;
    }
    const double k = std::floor(x * kTwoOverPi + 0.5);
    const double r = ((x - k * kPiOver2Part1) - k * kPiOver2Part2) - k * kPiOver2Part3;
    const double sr = detail::sin_kernel(r);
    const double cr = detail::cos_kernel(r);
    // Quadrant from the integer k; fmod-free so huge k stays defined (wraps but deterministic).
    const double k_mod = k - 4.0 * std::floor(k * 0.25);  // exact: 0, 1, 2 or 3
    const int q = static_cast<int>(k_mod);
    switch (q) {
        case 0: s = sr; c = cr; break;
        case 1: s = cr; c = -sr; break;
        case 2: s = -sr; c = -cr; break;
        default: s = -cr; c = sr; break;
    }
}

inline double det_sin(double x) {
    double s = 0, c = 0;
    det_sincos(x, s, c);
    return s;
}

inline double det_cos(double x) {
    double s = 0, c = 0;
    det_sincos(x, s, c);
    return c;
}

// sin(2 pi * num / den) for integers, reducing num mod den exactly first: periodic motions of the
// scenes use it so that an argument never grows with the frame number.
inline double det_sin_cycle(std::int64_t num, std::int64_t den, double phase) {
    std::int64_t m = num % den;
    if (m < 0) m += den;
    return det_sin(kTwoPi * (static_cast<double>(m) / static_cast<double>(den)) + phase);
}

inline double det_cos_cycle(std::int64_t num, std::int64_t den, double phase) {
    std::int64_t m = num % den;
    if (m < 0) m += den;
    return det_cos(kTwoPi * (static_cast<double>(m) / static_cast<double>(den)) + phase);
}

// Cube root of x > 0 by Newton's method from above (y >= cbrt(x) stays so), a fixed number of
// steps so the operation sequence never depends on the platform. Exact enough (a few ulps) for
// sizing rooms; x outside (0, 1e6] is not used by the scenes.
inline double det_cbrt(double x) {
    double y = x > 1.0 ? x : 1.0;
    for (int i = 0; i < 80; ++i) y = (2.0 * y + x / (y * y)) / 3.0;
    return y;
}

// Steele, Lea & Flood's SplitMix64 (OOPSLA 2014): a 64-bit counter passed through a mixing
// function. Pure integer arithmetic, so identical everywhere.
inline std::uint64_t splitmix64_mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

class SplitMix64 {
   public:
    explicit SplitMix64(std::uint64_t seed) : state_(seed) {}

    std::uint64_t next() {
        state_ += 0x9E3779B97F4A7C15ULL;
        return splitmix64_mix(state_);
    }
    // Uniform in [0, 1): the top 53 bits as an integer times 2^-53 (both steps exact).
    double uniform01() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    // Uniform in [lo, hi).
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }
    // Integer in [0, n), n > 0 (modulo bias below 2^-40 for the n the scenes use; irrelevant here).
    std::uint64_t below(std::uint64_t n) { return next() % n; }
    // Integer in [lo, hi].
    std::int64_t between(std::int64_t lo, std::int64_t hi) {
        return lo + static_cast<std::int64_t>(below(static_cast<std::uint64_t>(hi - lo + 1)));
    }

   private:
    std::uint64_t state_;
};

// A stream seed for one (seed, part, index) triple, so each object draws its own numbers and frame
// f never depends on what was drawn for other objects or frames.
inline std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t part, std::uint64_t index) {
    std::uint64_t h = splitmix64_mix(seed + 0x9E3779B97F4A7C15ULL);
    h = splitmix64_mix(h ^ (part * 0xD6E8FEB86659FD93ULL + 1));
    return splitmix64_mix(h ^ (index * 0xA0761D6478BD642FULL + 7));
}

}  // namespace cullide::det
