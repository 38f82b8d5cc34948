// Triangle-triangle tests per second: tri_tri_intersect, tri_tri_relation and the GMP rational
// reference, on fixed seeded sets of 4096 pairs: random (mostly decided by the filter), near-coplanar
// (integer coplanar pairs moved by one ulp: the exact fallback runs often), touching (integer
// contact configurations: many exact zeros), and the three mixed. Before timing, every benchmark
// checks that its results on the whole set equal the reference's (computed once, independently);
// a mismatch fails the benchmark instead of reporting a time.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "../cullide/rational_tri_tri.h"
#include "cullide/tri_tri.h"
#include "test_rng.h"

using cullide::TriRelation;
using cullide::Vec3;

namespace {

// splitmix64: tests/test_rng.h, plus a vector helper.
struct Rng : test::Rng {
    using test::Rng::Rng;
    Vec3 int3(int lo, int hi) {
        const double x = range(lo, hi);
        const double y = range(lo, hi);
        return {x, y, static_cast<double>(range(lo, hi))};
    }
};

using Pair = std::array<Vec3, 6>;

Pair random_pair(Rng& rng) {
    Pair p;
    for (Vec3& v : p) {
        const double x = rng.sym();
        const double y = rng.sym();
        v = {x, y, rng.sym()};
    }
    return p;
}

Pair near_coplanar_pair(Rng& rng) {
    Vec3 e1{1, 0, 0}, e2{0, 1, 0};
    do {
        e1 = rng.int3(-3, 3);
        e2 = rng.int3(-3, 3);
    } while (cross(e1, e2) == Vec3{0, 0, 0});
    Pair p;
    for (Vec3& v : p) {
        const int u = rng.range(0, 6);
        const int w = rng.range(0, 6);
        v = static_cast<double>(u) * e1 + static_cast<double>(w) * e2;
    }
    double& x = p[static_cast<std::size_t>(rng.range(0, 5))][rng.range(0, 2)];
    if (x != 0) x = std::nextafter(x, (rng.next() & 1u) ? 1e300 : -1e300);
    return p;
}

Pair touching_pair(Rng& rng) {
    Pair p;
    p[0] = rng.int3(-8, 8);
    p[1] = rng.int3(-8, 8);
    p[2] = rng.int3(-8, 8);
    const int w0 = rng.range(0, 16);
    const int w1 = rng.range(0, 16 - w0);
    const Vec3 x = (1.0 / 16.0) * (static_cast<double>(w0) * p[0] + static_cast<double>(w1) * p[1] +
                                   static_cast<double>(16 - w0 - w1) * p[2]);
    p[3] = x;
    p[4] = x + rng.int3(-6, 6);
    p[5] = x + rng.int3(-6, 6);
    return p;
}

constexpr int kPairs = 4096;

const std::vector<Pair>& pairs(int family) {
    static const std::array<std::vector<Pair>, 4> sets = [] {
        std::array<std::vector<Pair>, 4> s;
        Rng rng{2003};
        for (int i = 0; i < kPairs; ++i) {
            s[0].push_back(random_pair(rng));
            s[1].push_back(near_coplanar_pair(rng));
            s[2].push_back(touching_pair(rng));
            const int pick = i % 3;
            s[3].push_back(pick == 0 ? s[0].back() : (pick == 1 ? s[1].back() : s[2].back()));
        }
        return s;
    }();
    return sets[static_cast<std::size_t>(family)];
}

// The reference relations, computed once per set by the rational method.
const std::vector<TriRelation>& expected(int family) {
    static std::array<std::vector<TriRelation>, 4> cache;
    std::vector<TriRelation>& r = cache[static_cast<std::size_t>(family)];
    if (r.empty()) {
        for (const Pair& p : pairs(family)) {
            r.push_back(cullide::test::rational_tri_tri_relation(p[0], p[1], p[2], p[3], p[4], p[5]));
        }
    }
    return r;
}

const char* kFamilyNames[4] = {"random", "near_coplanar", "touching", "mix"};

// check(pair, reference relation) must hold on every pair before the timed loop runs timed(pair).
template <class Check, class Timed>
void run(benchmark::State& state, Check&& check, Timed&& timed) {
    const int family = static_cast<int>(state.range(0));
    state.SetLabel(kFamilyNames[family]);
    const std::vector<Pair>& set = pairs(family);
    const std::vector<TriRelation>& want = expected(family);
    for (std::size_t i = 0; i < set.size(); ++i) {
        if (!check(set[i], want[i])) {
            state.SkipWithError(("result differs from the other method at pair " + std::to_string(i)).c_str());
            return;
        }
    }
    for (auto _ : state) {
        unsigned acc = 0;
        for (const Pair& p : set) acc += static_cast<unsigned>(timed(p));
        benchmark::DoNotOptimize(acc);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(set.size()));
}

bool fast_intersect(const Pair& p) { return cullide::tri_tri_intersect(p[0], p[1], p[2], p[3], p[4], p[5]); }
TriRelation fast_relation(const Pair& p) { return cullide::tri_tri_relation(p[0], p[1], p[2], p[3], p[4], p[5]); }
TriRelation reference(const Pair& p) {
    return cullide::test::rational_tri_tri_relation(p[0], p[1], p[2], p[3], p[4], p[5]);
}

void BM_tri_tri_intersect(benchmark::State& state) {
    run(state, [](const Pair& p, TriRelation want) { return fast_intersect(p) == (want != TriRelation::Disjoint); },
        fast_intersect);
}
void BM_tri_tri_relation(benchmark::State& state) {
    run(state, [](const Pair& p, TriRelation want) { return fast_relation(p) == want; }, fast_relation);
}
void BM_rational_reference(benchmark::State& state) {
    // The reference's own check is agreement with the fast relation (the two share no code).
    run(state, [](const Pair& p, TriRelation) { return reference(p) == fast_relation(p); }, reference);
}

}  // namespace

BENCHMARK(BM_tri_tri_intersect)->DenseRange(0, 3);
BENCHMARK(BM_tri_tri_relation)->DenseRange(0, 3);
BENCHMARK(BM_rational_reference)->DenseRange(0, 3);

BENCHMARK_MAIN();
