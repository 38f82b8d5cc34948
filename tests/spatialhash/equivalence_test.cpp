// The three methods against an independent brute-force reference on many random scenes: the pair
// lists must be equal exactly (same pairs, same order), for boxes and spheres, for every family.
#include <doctest/doctest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "scene_gen.h"
#include "spatialhash/broad_phase.h"

using namespace sh_test;
using spatialhash::Method;
using spatialhash::Options;

namespace {

// Scene counts: the default run stays short; SPATIALHASH_SCENES raises it for long sweeps.
std::size_t scenes_per_family(std::size_t fallback) {
    if (const char* env = std::getenv("SPATIALHASH_SCENES")) return std::strtoull(env, nullptr, 10);
    return fallback;
}

template <class Shape>
void check_all_methods(const std::vector<Shape>& scene, double cell, unsigned threads) {
    const std::vector<Pair> expected = reference_pairs(scene);
    const Method methods[] = {Method::SpatialHash, Method::SweepAndPrune, Method::BruteForce};
    for (Method m : methods) {
        Options o;
        o.method = m;
        o.threads = threads;
        o.cell_size = m == Method::SpatialHash ? cell : 0.0;
        CAPTURE(static_cast<int>(m));
        auto r = spatialhash::find_pairs(std::span<const Shape>(scene), o);
        REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
        CHECK(r.value().pairs == expected);
    }
}

}  // namespace

TEST_CASE("every method returns exactly the reference pairs on random box scenes of every family") {
    const std::size_t per_family = scenes_per_family(1000);
    std::size_t scenes = 0;
    std::size_t pairs_seen = 0;
    for (int f = 0; f < static_cast<int>(Family::kCount); ++f) {
        Rng rng(0x5eed0000ULL + static_cast<std::uint64_t>(f));
        for (std::size_t s = 0; s < per_family; ++s) {
            const std::size_t n = s < 3 ? s : 3 + rng.below(60);  // n = 0, 1, 2 first
            double cell = 0.0;
            const std::vector<Box> scene = box_scene(static_cast<Family>(f), n, rng, &cell);
            CAPTURE(family_name(static_cast<Family>(f)));
            CAPTURE(s);
            check_all_methods(scene, cell, 1 + static_cast<unsigned>(s % 3));
            pairs_seen += reference_pairs(scene).size();
            ++scenes;
        }
    }
    MESSAGE("box scenes checked: " << scenes << ", reference pairs: " << pairs_seen);
    CHECK(pairs_seen > 0);
}

TEST_CASE("every method returns exactly the reference pairs on random sphere scenes") {
    const std::size_t per_kind = scenes_per_family(250);
    std::size_t pairs_seen = 0;
    for (int kind = 0; kind < 4; ++kind) {
        Rng rng(0xb0b0ULL + static_cast<std::uint64_t>(kind));
        for (std::size_t s = 0; s < per_kind; ++s) {
            const std::size_t n = s < 3 ? s : 3 + rng.below(60);
            const std::vector<Sphere> scene = sphere_scene(kind, n, rng);
            CAPTURE(kind);
            CAPTURE(s);
            check_all_methods(scene, 0.0, 1 + static_cast<unsigned>(s % 3));
            pairs_seen += reference_pairs(scene).size();
        }
    }
    CHECK(pairs_seen > 0);
}

TEST_CASE("a given cell size smaller than some objects still finds every pair") {
    // Objects too large for the requested cell are tested apart, never dropped.
    Rng rng(77);
    for (int s = 0; s < 300; ++s) {
        double unused = 0.0;
        const std::vector<Box> scene = box_scene(Family::Uniform, 3 + rng.below(50), rng, &unused);
        const double cell = rng.range(0.05, 3.0);
        CAPTURE(s);
        CAPTURE(cell);
        check_all_methods(scene, cell, 2);
    }
}

TEST_CASE("touching boxes overlap: faces, edges and corners in contact count") {
    const std::vector<Box> scene = {
        Box{{0, 0, 0}, {1, 1, 1}},  // 0
        Box{{1, 0, 0}, {2, 1, 1}},  // 1: shares a face with 0
        Box{{1, 1, 0}, {2, 2, 1}},  // 2: shares an edge with 0, a face with 1
        Box{{1, 1, 1}, {2, 2, 2}},  // 3: shares a corner with 0
        Box{{2.5, 0, 0}, {3, 1, 1}},  // 4: apart from all
    };
    const std::vector<Pair> expected = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    CHECK(reference_pairs(scene) == expected);
    check_all_methods(scene, 0.0, 1);
    check_all_methods(scene, 1.0, 2);
}
