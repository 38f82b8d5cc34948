// Exact orientation predicates: a floating-point filter, then exact expansion arithmetic.
//
// Expansion arithmetic after Shewchuk (1997): a real number is held exactly as a sum of doubles
// (an "expansion"), components nonoverlapping and ordered by increasing magnitude, zero components
// removed. The sign of a nonoverlapping expansion is the sign of its largest component. The building
// blocks are Knuth's two-sum and Dekker's two-product (Veltkamp splitting; no FMA, so the bits do not
// depend on the compiler or the CPU). The code here is ours; only the algorithms come from the papers.
//
// Exactness of the fallback on the *original* coordinates: a difference of two doubles is not a
// double in general, so each difference is kept as a 2-component expansion (two-diff), and the
// determinant is evaluated as a polynomial in these expansions with exact products and sums. With
// the input range of predicates.h every product stays a multiple of 2^-1056 (no lost low bits) and
// below 2^910 (no overflow).
#include "cullide/predicates.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

#include "orient_plane.h"

namespace cullide {
namespace {

thread_local PredicateStats g_stats;

constexpr double kEps = 0x1p-53;  // unit roundoff u of round-to-nearest doubles

// ---- error-free transformations ------------------------------------------------------------

// a + b = s + e exactly (Knuth). Valid for any finite a, b without overflow; underflow cannot lose
// bits in a sum of doubles (gradual underflow makes every sum of two doubles' error representable).
inline void two_sum(double a, double b, double& s, double& e) {
    s = a + b;
    const double bv = s - a;
    const double av = s - bv;
    e = (a - av) + (b - bv);
}

// |a| >= |b| (or a == 0): a + b = s + e exactly, in three operations (Dekker).
inline void fast_two_sum(double a, double b, double& s, double& e) {
    s = a + b;
    e = b - (s - a);
}

inline void two_diff(double a, double b, double& s, double& e) {
    s = a - b;
    const double bv = a - s;
    const double av = s + bv;
    e = (a - av) + (bv - b);
}

// Veltkamp split: a = hi + lo, each with at most 26 significant bits, so the four partial products
// of two split numbers are exact.
inline void split(double a, double& hi, double& lo) {
    constexpr double kSplitter = 134217729.0;  // 2^27 + 1
    const double c = kSplitter * a;
    const double big = c - a;
    hi = c - big;
    lo = a - hi;
}

// a * b = p + e exactly (Dekker), provided the product's low bits do not underflow (input range).
inline void two_product(double a, double b, double& p, double& e) {
    p = a * b;
    double ahi = 0, alo = 0, bhi = 0, blo = 0;
    split(a, ahi, alo);
    split(b, bhi, blo);
    const double err1 = p - ahi * bhi;
    const double err2 = err1 - alo * bhi;
    const double err3 = err2 - ahi * blo;
    e = alo * blo - err3;
}

// ---- expansions ------------------------------------------------------------------------------

// A fixed-capacity expansion on the stack. N bounds the number of nonzero components that the
// operation producing it can create (sizes are derived at each use below). Only c[0, n) is ever
// read or copied, so the rest is left unset: zeroing every capacity cost about 6 KB of stores per
// exact orient3d (its 64-, 128- and 192-component sums), most of that call's time on the coplanar
// inputs that reach it.
template <int N>
struct Expansion {
    std::array<double, N> c;  // NOLINT(cppcoreguidelines-pro-type-member-init): c[n, N) unused
    int n = 0;

    Expansion() = default;
    Expansion(const Expansion& e) : n(e.n) { copy_from(e); }
    Expansion& operator=(const Expansion& e) {
        n = e.n;
        copy_from(e);
        return *this;
    }

    void push(double x) {
        if (x != 0) c[static_cast<std::size_t>(n++)] = x;
    }
    [[nodiscard]] int sign() const {
        // Components increase in magnitude and do not overlap: the last one decides.
        if (n == 0) return 0;
        return c[static_cast<std::size_t>(n - 1)] > 0 ? 1 : -1;
    }

   private:
    void copy_from(const Expansion& e) {
        for (int k = 0; k < e.n; ++k) c[static_cast<std::size_t>(k)] = e.c[static_cast<std::size_t>(k)];
    }
};

// x - y as an expansion of at most 2 components.
inline Expansion<2> diff_expansion(double x, double y) {
    double s = 0, e = 0;
    two_diff(x, y, s, e);
    Expansion<2> r;
    r.push(e);
    r.push(s);
    return r;
}

// h = e + f. Shewchuk's fast expansion sum with zero elimination: merge the components by
// magnitude and carry one running sum through two-sums. Correct (the output is nonoverlapping and
// ordered) for strongly nonoverlapping inputs under round-to-nearest-even, which IEEE 754 default
// rounding is and which every expansion built here is (outputs of two-diff, two-product, scale and
// sum are strongly nonoverlapping; Shewchuk 1997, Theorems 13 and 19).
template <int N, int A, int B>
Expansion<N> sum(const Expansion<A>& e, const Expansion<B>& f) {
    static_assert(N >= A + B);
    Expansion<N> h;
    if (e.n == 0 && f.n == 0) return h;
    int i = 0, j = 0;
    // Next component in magnitude order. Ties pick f first; either is fine.
    auto next = [&]() -> double {
        if (i < e.n && (j >= f.n || std::fabs(e.c[static_cast<std::size_t>(i)]) <
                                         std::fabs(f.c[static_cast<std::size_t>(j)]))) {
            return e.c[static_cast<std::size_t>(i++)];
        }
        return f.c[static_cast<std::size_t>(j++)];
    };
    double q = next();
    const int total = e.n + f.n;
    for (int k = 1; k < total; ++k) {
        const double g = next();
        double s = 0, err = 0;
        if (k == 1) {
            fast_two_sum(g, q, s, err);  // |g| >= |q|: g was merged after q
        } else {
            two_sum(q, g, s, err);
        }
        h.push(err);
        q = s;
    }
    if (q != 0 || h.n == 0) h.push(q);
    return h;
}

template <int A>
Expansion<A> negate(const Expansion<A>& e) {
    Expansion<A> r = e;
    for (int k = 0; k < r.n; ++k) r.c[static_cast<std::size_t>(k)] = -r.c[static_cast<std::size_t>(k)];
    return r;
}

// h = e * b (Shewchuk's scale-expansion with zero elimination); at most 2 * A components.
template <int A>
Expansion<2 * A> scale(const Expansion<A>& e, double b) {
    Expansion<2 * A> h;
    if (e.n == 0 || b == 0) return h;
    double q = 0, lo = 0;
    two_product(e.c[0], b, q, lo);
    h.push(lo);
    for (int k = 1; k < e.n; ++k) {
        double p1 = 0, p0 = 0;
        two_product(e.c[static_cast<std::size_t>(k)], b, p1, p0);
        double s = 0, err = 0;
        two_sum(q, p0, s, err);
        h.push(err);
        fast_two_sum(p1, s, q, err);
        h.push(err);
    }
    if (q != 0 || h.n == 0) h.push(q);
    return h;
}

// e * f where f has at most 2 components (every multiplier here is a two-diff).
template <int A>
Expansion<4 * A> mul2(const Expansion<A>& e, const Expansion<2>& f) {
    Expansion<4 * A> r;
    if (f.n == 0) return r;
    if (f.n == 1) {
        const Expansion<2 * A> s = scale(e, f.c[0]);
        r.n = s.n;
        for (int k = 0; k < s.n; ++k) r.c[static_cast<std::size_t>(k)] = s.c[static_cast<std::size_t>(k)];
        return r;
    }
    return sum<4 * A>(scale(e, f.c[0]), scale(e, f.c[1]));
}

// ---- exact determinants ------------------------------------------------------------------------

int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
    ++g_stats.orient2d_exact;
    const Expansion<2> bax = diff_expansion(bx, ax);
    const Expansion<2> bay = diff_expansion(by, ay);
    const Expansion<2> cax = diff_expansion(cx, ax);
    const Expansion<2> cay = diff_expansion(cy, ay);
    const Expansion<8> left = mul2(bax, cay);   // <= 8 components
    const Expansion<8> right = mul2(bay, cax);  // <= 8 components
    return sum<16>(left, negate(right)).sign();
}

// Sign of the 2x2 minor u1 * v2 - u2 * v1 of four two-diff expansions (<= 16 components).
Expansion<16> minor2(const Expansion<2>& u1, const Expansion<2>& v2, const Expansion<2>& u2,
                     const Expansion<2>& v1) {
    return sum<16>(mul2(u1, v2), negate(mul2(u2, v1)));
}

int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    ++g_stats.orient3d_exact;
    // Rows u = b - a, v = c - a, w = d - a; det = u . (v x w).
    const Expansion<2> ux = diff_expansion(b.x, a.x), uy = diff_expansion(b.y, a.y),
                       uz = diff_expansion(b.z, a.z);
    const Expansion<2> vx = diff_expansion(c.x, a.x), vy = diff_expansion(c.y, a.y),
                       vz = diff_expansion(c.z, a.z);
    const Expansion<2> wx = diff_expansion(d.x, a.x), wy = diff_expansion(d.y, a.y),
                       wz = diff_expansion(d.z, a.z);
    const Expansion<16> mx = minor2(vy, wz, vz, wy);  // (v x w).x
    const Expansion<16> my = minor2(vz, wx, vx, wz);  // (v x w).y
    const Expansion<16> mz = minor2(vx, wy, vy, wx);  // (v x w).z
    // Products of a 16-component minor and a 2-component difference have <= 64 components.
    const Expansion<64> tx = sum<64>(scale(mx, ux.n > 0 ? ux.c[0] : 0.0),
                                     scale(mx, ux.n > 1 ? ux.c[1] : 0.0));
    const Expansion<64> ty = sum<64>(scale(my, uy.n > 0 ? uy.c[0] : 0.0),
                                     scale(my, uy.n > 1 ? uy.c[1] : 0.0));
    const Expansion<64> tz = sum<64>(scale(mz, uz.n > 0 ? uz.c[0] : 0.0),
                                     scale(mz, uz.n > 1 ? uz.c[1] : 0.0));
    return sum<192>(sum<128>(tx, ty), tz).sign();
}

// ---- filters -------------------------------------------------------------------------------------
//
// Error bound (our derivation, in the standard model fl(x op y) = (x op y)(1 + d), |d| <= u, u =
// 2^-53, while no result is subnormal). Write the determinant as a signed sum of monomials m_k,
// each a product of input differences, and P = sum |m_k| (the "permanent"). Follow one monomial
// through the evaluation: orient2d rounds it at most 4 times (2 differences, 1 product, 1
// subtraction); orient3d at most 8 times (3 differences, 2 products, the minor's subtraction, 2
// additions). Hence |det_computed - det| <= gamma_k * P with gamma_k = k u / (1 - k u), k = 4 or 8.
// The permanent is computed in floating point from the same rounded differences with every term
// non-negative, so each of its monomials is rounded at most k times as well and P_computed >=
// (1 - u)^k P; the final multiplication by the constant costs one more (1 - u). If |det_computed| >
// C * P_computed (rounded), the computed sign is right as soon as C (1 - u)^(k+1) >= gamma_k:
//   orient2d: C = 5u (5 (1 - u)^5 > 4 / (1 - 4u));  orient3d: C = 9u (9 (1 - u)^9 > 8 / (1 - 8u)).
// The constants 5 * 2^-53 and 9 * 2^-53 are exact doubles. (Shewchuk's tighter 3u and 7u bounds come
// from a finer count; ours leave a slack of about u * P.)
// Subnormals: below 2^-1022 the model gains an absolute error of at most 2^-1075 per operation. We
// only trust the filter when P_computed >= 2^-600; then those absolute errors (a few dozen times
// 2^-1075) are far below the slack u * P, and the bound still holds. Otherwise: exact path.
constexpr double kOrient2dBound = 5.0 * kEps;
using detail::kOrient3dBound;       // 9 * kEps (orient_plane.h, which filters with it too)
using detail::kFilterMinPermanent;  // 2^-600
static_assert(kOrient3dBound == 9.0 * kEps);

// ---- exact small-span stage (orient3d) ------------------------------------------------------------
//
// When the filter fails on points of a coarse grid (coplanar quarter-grid points, the common case of
// a degenerate input), its own evaluation was often exact already. Suppose the nine differences were
// computed exactly and are all integer multiples of 2^lo below 2^(lo + B) in magnitude. Then, in units
// of 2^(2 lo), each product of two differences is an integer below 2^(2B) and each minor one below
// 2^(2B + 1); in units of 2^(3 lo) each of the three terms u_i * minor_i is below 2^(3B + 1), the sum
// of the first two below 2^(3B + 2) and the whole sum below 2^(3B + 3). With B <= 16 every one of
// these integers is below 2^53, so every operation of orient3d's evaluation is exact (a double holds
// any integer multiple of 2^q below 2^53 units, for q >= -1074: here lo >= -352 by the input range,
// so 3 lo >= -1056), and the computed determinant is the exact one.
constexpr int kExactSpanBits = 16;

// Bit positions of a finite nonzero double: it is an integer multiple of 2^low below 2^high in
// magnitude.
struct BitRange {
    int low;
    int high;
};
BitRange bit_range(double x) {
    const auto bits = std::bit_cast<std::uint64_t>(x);
    const auto biased = static_cast<int>((bits >> 52) & 0x7ffU);
    std::uint64_t mantissa = bits & ((std::uint64_t{1} << 52) - 1);
    int unit = -1074;  // subnormal: value = mantissa * 2^-1074
    if (biased != 0) {
        mantissa |= std::uint64_t{1} << 52;
        unit = biased - 1075;  // normal: value = mantissa * 2^(biased - 1075)
    }
    return {unit + std::countr_zero(mantissa), unit + 64 - std::countl_zero(mantissa)};
}

// Whether the differences q - p of the three pairs were computed exactly (their two-diff error is
// zero) and all nine differences span at most kExactSpanBits bits together (see above).
bool exact_small_span(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    int low = 1 << 20, high = -(1 << 20);
    for (const Vec3* q : {&b, &c, &d}) {
        for (int k = 0; k < 3; ++k) {
            double diff = 0, err = 0;
            two_diff((*q)[k], a[k], diff, err);
            if (err != 0) return false;
            if (diff == 0) continue;
            const BitRange r = bit_range(diff);
            low = std::min(low, r.low);
            high = std::max(high, r.high);
        }
    }
    return high - low <= kExactSpanBits;  // also when every difference is 0 (det = 0)
}

}  // namespace

int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const double l = (bx - ax) * (cy - ay);
    const double r = (by - ay) * (cx - ax);
    const double det = l - r;
    const double permanent = std::fabs(l) + std::fabs(r);
    if (permanent >= kFilterMinPermanent) {
        const double bound = kOrient2dBound * permanent;
        if (det > bound) return 1;
        if (-det > bound) return -1;
    } else if (permanent == 0) {
        // Both rounded products are 0, so in each product one rounded difference is 0, which for
        // doubles means that difference is exactly 0 (x - y == 0 only when x == y): det == 0.
        // (Underflow of a nonzero product to 0 is excluded by the input range.)
        return 0;
    }
    return orient2d_exact(ax, ay, bx, by, cx, cy);
}

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
    const double p1 = vy * wz, p2 = vz * wy;
    const double p3 = vz * wx, p4 = vx * wz;
    const double p5 = vx * wy, p6 = vy * wx;
    const double det = ux * (p1 - p2) + uy * (p3 - p4) + uz * (p5 - p6);
    const double permanent = std::fabs(ux) * (std::fabs(p1) + std::fabs(p2)) +
                             std::fabs(uy) * (std::fabs(p3) + std::fabs(p4)) +
                             std::fabs(uz) * (std::fabs(p5) + std::fabs(p6));
    if (permanent >= kFilterMinPermanent) {
        const double bound = kOrient3dBound * permanent;
        if (det > bound) return 1;
        if (-det > bound) return -1;
    }
    // The evaluation above is exact for exact differences of a small bit span (the stage's comment).
    if (exact_small_span(a, b, c, d)) return det > 0 ? 1 : det < 0 ? -1 : 0;
    return orient3d_exact(a, b, c, d);
}

int orient2d_drop(const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
    const int i = (drop + 1) % 3;
    const int j = (drop + 2) % 3;
    return orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

PredicateStats predicate_stats() { return g_stats; }

}  // namespace cullide
