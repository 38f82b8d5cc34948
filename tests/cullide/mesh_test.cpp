#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "cullide/mesh.h"

using cullide::Mesh;

namespace {
Mesh unit_triangle() {
    Mesh m;
    m.name = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    return m;
}
}  // namespace

TEST_CASE("a valid mesh passes validation and its bounds are its vertices' extent") {
    Mesh m = unit_triangle();
    CHECK(cullide::validate_mesh(m).ok());
    cullide::Aabb b = cullide::mesh_bounds(m);
    CHECK(b.lo == cullide::Vec3{0, 0, 0});
    CHECK(b.hi == cullide::Vec3{1, 1, 0});
    CHECK(cullide::overlaps(b, cullide::triangle_bounds(m, 0)));
}

TEST_CASE("validation names the bad index and the vertex list size") {
    Mesh m = unit_triangle();
    m.triangles.push_back({0, 1, 7});
    cullide::Status s = cullide::validate_mesh(m);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message == "mesh 'tri': triangle 1 vertex index 7 is beyond the vertex list (size 3)");
}

TEST_CASE("validation rejects NaN and infinite coordinates and names the vertex") {
    Mesh m = unit_triangle();
    m.positions[2].y = std::numeric_limits<double>::quiet_NaN();
    cullide::Status s = cullide::validate_mesh(m);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message.find("vertex 2") != std::string::npos);
    m.positions[2].y = std::numeric_limits<double>::infinity();
    CHECK_FALSE(cullide::validate_mesh(m).ok());
}

TEST_CASE("validation rejects an empty mesh and names the object index in a scene") {
    Mesh empty;
    empty.name = "e";
    std::vector<Mesh> scene = {unit_triangle(), empty};
    cullide::Status s = cullide::validate_scene(scene);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message == "object 1: mesh 'e': has no triangles");
}

TEST_CASE("touching boxes overlap, separated boxes do not") {
    cullide::Aabb a{{0, 0, 0}, {1, 1, 1}};
    cullide::Aabb b{{1, 0, 0}, {2, 1, 1}};
    cullide::Aabb c{{std::nextafter(1.0, 2.0), 0, 0}, {2, 1, 1}};
    CHECK(cullide::overlaps(a, b));
    CHECK_FALSE(cullide::overlaps(a, c));
    CHECK(cullide::Aabb{}.empty());
}

namespace {
// Not inlined, so the compiler must compile the conversion as written, for an unknown argument.
[[gnu::noinline]] cullide::Vec3 round_to_float(const cullide::Vec3& v) {
    return {static_cast<double>(static_cast<float>(v.x)), static_cast<double>(static_cast<float>(v.y)),
            static_cast<double>(static_cast<float>(v.z))};
}
}  // namespace

TEST_CASE("the compiler keeps double -> float -> double rounding in every component (GCC 12 SLP bug guard)") {
    // g++ 12.2 -O2 with SLP vectorization turns this into a copy of x and y (cmake/CullideSettings.cmake).
    volatile double scale = 1.0;  // keeps the inputs unknown at compile time
    const cullide::Vec3 v{0.1 * scale, 0.2 * scale, 0.3 * scale};
    const cullide::Vec3 r = round_to_float(v);
    CHECK(r.x == 0.100000001490116119384765625);
    CHECK(r.y == 0.20000000298023223876953125);
    CHECK(r.z == 0.300000011920928955078125);
}
