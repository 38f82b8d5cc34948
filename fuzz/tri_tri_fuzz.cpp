// libFuzzer target for the exact triangle-triangle test (cullide/tri_tri.h).
// From the input it decodes two triangles in one of several modes chosen by the first byte: raw
// doubles forced into the predicates' exact range, small integers on a grid, shared vertices and
// edges, coplanar by construction, ulp perturbations of grid triangles, and large offsets.
// Properties: tri_tri_relation equals the GMP rational reference of tests/cullide (a different
// method: constructed rational geometry, not orientation predicates), tri_tri_intersect agrees with
// it, tri_tri_relation_checked accepts the input and agrees, and the relation does not change when
// the two triangles are swapped or the vertices of either are permuted (all 36 permutation pairs).
// Any violation prints the triangles and aborts.
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "cullide/predicates.h"
#include "cullide/tri_tri.h"
#include "rational_tri_tri.h"

namespace {

using cullide::TriRelation;
using cullide::Vec3;
using Tri6 = std::array<Vec3, 6>;  // a0 a1 a2 b0 b1 b2

class Reader {
 public:
    Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
    std::uint8_t byte() { return p_ == end_ ? 0 : *p_++; }
    // A small integer in [-8, 8]: small grids make touching and coplanar cases frequent.
    double grid() { return static_cast<double>(static_cast<int>(byte() % 17U) - 8); }
    // A raw double, forced into the exact range of predicates.h by rewriting its exponent (so the
    // mantissa bits stay fuzzer-controlled). A zero byte selects exact zero.
    double raw() {
        std::uint64_t bits = 0;
        for (int i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(byte()) << (8 * i);
        if (bits == 0) return 0.0;
        const std::uint64_t exp_field = (bits >> 52) & 0x7FFU;
        const std::uint64_t new_exp = (exp_field % 601U) + 1023U - 300U;  // 2^-300 .. 2^300
        bits = (bits & ~(std::uint64_t{0x7FF} << 52)) | (new_exp << 52);
        return std::bit_cast<double>(bits);
    }

 private:
    const std::uint8_t* p_;
    const std::uint8_t* end_;
};

Vec3 grid_point(Reader& r) {
    const double x = r.grid();
    const double y = r.grid();
    const double z = r.grid();
    return {x, y, z};
}

// Moves x by k ulps (k may be negative).
double ulps(double x, int k) {
    for (; k > 0; --k) x = std::nextafter(x, HUGE_VAL);
    for (; k < 0; ++k) x = std::nextafter(x, -HUGE_VAL);
    return x;
}

Tri6 decode(Reader& r, unsigned mode) {
    Tri6 t{};
    switch (mode) {
        case 0:  // raw doubles in the exact range
            for (Vec3& v : t) {
                v.x = r.raw();
                v.y = r.raw();
                v.z = r.raw();
            }
            break;
        case 1:  // small integers on a grid
            for (Vec3& v : t) v = grid_point(r);
            break;
        case 2: {  // B shares vertices (an edge, or one vertex, or all) with A
            for (int i = 0; i < 3; ++i) t[static_cast<std::size_t>(i)] = grid_point(r);
            const std::uint8_t sel = r.byte();
            for (int i = 3; i < 6; ++i) {
                const unsigned s = (sel >> (2 * (i - 3))) & 3U;
                t[static_cast<std::size_t>(i)] = s < 3 ? t[s] : grid_point(r);
            }
            break;
        }
        case 3: {  // both in one plane: o + s u + t v with small integers (exact in doubles)
            const Vec3 o = grid_point(r);
            const Vec3 u = grid_point(r);
            const Vec3 w = grid_point(r);
            for (Vec3& v : t) {
                const double s = static_cast<double>(static_cast<int>(r.byte() % 9U) - 4);
                const double q = static_cast<double>(static_cast<int>(r.byte() % 9U) - 4);
                v = o + s * u + q * w;
            }
            break;
        }
        case 4: {  // grid triangles, then some coordinates moved by a few ulps
            for (Vec3& v : t) v = grid_point(r);
            const int moves = r.byte() % 8U;
            for (int i = 0; i < moves; ++i) {
                const std::uint8_t which = r.byte();
                const int k = static_cast<int>(r.byte() % 7U) - 3;
                Vec3& v = t[(which % 18U) / 3U];
                v[static_cast<int>(which % 3U)] = ulps(v[static_cast<int>(which % 3U)], k);
            }
            break;
        }
        default: {  // a large common offset (coordinates round), plus a grid or fractional part
            const int e = 10 + r.byte() % 280U;
            const Vec3 off{std::ldexp(static_cast<double>(r.byte() % 5U) - 2.0, e),
                           std::ldexp(static_cast<double>(r.byte() % 5U) - 2.0, e),
                           std::ldexp(static_cast<double>(r.byte() % 5U) - 2.0, e)};
            const int scale = static_cast<int>(r.byte() % 64U) - 8;
            for (Vec3& v : t) {
                const Vec3 g = grid_point(r);
                v = off + std::ldexp(1.0, e - scale) * g;
            }
            break;
        }
    }
    return t;
}

void print(const Tri6& t) {
    for (std::size_t i = 0; i < 6; ++i)
        std::fprintf(stderr, "  %c%zu = (%a, %a, %a)\n", i < 3 ? 'a' : 'b', i % 3, t[i].x, t[i].y, t[i].z);
}

[[noreturn]] void fail(const Tri6& t, const char* what, TriRelation got, TriRelation want) {
    std::fprintf(stderr, "tri_tri_fuzz: property violated: %s: got %s, reference %s\n", what,
                 cullide::to_string(got), cullide::to_string(want));
    print(t);
    std::abort();
}

constexpr std::array<std::array<std::size_t, 3>, 6> kPerms{
    {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}}};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Reader r(data, size);
    const unsigned mode = r.byte() % 6U;
    const Tri6 t = decode(r, mode);
    for (const Vec3& v : t)
        for (int k = 0; k < 3; ++k)
            if (!cullide::predicate_coordinate_ok(v[k])) return 0;  // rounding left the range: skip

    const TriRelation want = cullide::test::rational_tri_tri_relation(t[0], t[1], t[2], t[3], t[4], t[5]);
    const TriRelation got = cullide::tri_tri_relation(t[0], t[1], t[2], t[3], t[4], t[5]);
    if (got != want) fail(t, "tri_tri_relation differs from the rational reference", got, want);
    const bool hit = cullide::tri_tri_intersect(t[0], t[1], t[2], t[3], t[4], t[5]);
    if (hit != (want != TriRelation::Disjoint))
        fail(t, hit ? "tri_tri_intersect true for disjoint triangles" : "tri_tri_intersect false", want, want);
    const cullide::Result<TriRelation> checked =
        cullide::tri_tri_relation_checked(t[0], t[1], t[2], t[3], t[4], t[5]);
    if (!checked) {
        std::fprintf(stderr, "tri_tri_fuzz: checked rejected in-range input: %s\n", checked.error().message.c_str());
        print(t);
        std::abort();
    }
    if (checked.value() != want) fail(t, "tri_tri_relation_checked differs", checked.value(), want);

    for (const auto& pa : kPerms) {
        for (const auto& pb : kPerms) {
            const Vec3 a0 = t[pa[0]], a1 = t[pa[1]], a2 = t[pa[2]];
            const Vec3 b0 = t[3 + pb[0]], b1 = t[3 + pb[1]], b2 = t[3 + pb[2]];
            const TriRelation ab = cullide::tri_tri_relation(a0, a1, a2, b0, b1, b2);
            if (ab != want) fail(t, "relation changes under a vertex permutation", ab, want);
            const TriRelation ba = cullide::tri_tri_relation(b0, b1, b2, a0, a1, a2);
            if (ba != want) fail(t, "relation changes when the triangles are swapped", ba, want);
            if (cullide::tri_tri_intersect(b0, b1, b2, a0, a1, a2) != (want != TriRelation::Disjoint))
                fail(t, "tri_tri_intersect changes when the triangles are swapped", ba, want);
        }
    }
    return 0;
}
