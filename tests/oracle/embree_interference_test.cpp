// The Embree edge-ray oracle against the exact reference (cullide::exact_pairs): every pair either
// method reports alone is classified with the exact relation, on the double coordinates and on the
// float-rounded ones Embree saw (docs/embree-oracle.md).
#include "embree_interference.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh_io.h"
#include "cullide/scenes.h"
#include "cullide/tri_tri.h"

using cullide::Mesh;
using cullide::TrianglePair;
using cullide::TriRelation;
using cullide::Vec3;
using cullide_oracle::EmbreeOptions;
using cullide_oracle::round_to_float;

namespace {

Mesh triangle_mesh(const std::string& name, const std::vector<Vec3>& vertices) {
    Mesh m;
    m.name = name;
    m.positions = vertices;
    for (std::uint32_t i = 0; i + 2 < vertices.size(); i += 3) m.triangles.push_back({i, i + 1, i + 2});
    return m;
}

std::vector<TrianglePair> embree(const std::vector<Mesh>& objects, bool self, int threads = 0) {
    auto r = cullide_oracle::embree_pairs(objects, EmbreeOptions{self, threads});
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
    return r.value();
}

std::vector<TrianglePair> exact(const std::vector<Mesh>& objects, bool self, int threads = 0) {
    auto r = cullide::exact_pairs(objects, {self, threads});
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
    return r.value();
}

// The six vertices of a pair: a[0..2] from triangle_a, a[3..5] from triangle_b.
std::array<Vec3, 6> vertices(const std::vector<Mesh>& objects, const TrianglePair& p) {
    std::array<Vec3, 6> v;
    for (std::size_t k = 0; k < 3; ++k) {
        v[k] = objects[p.object_a].positions[objects[p.object_a].triangles[p.triangle_a][k]];
        v[3 + k] = objects[p.object_b].positions[objects[p.object_b].triangles[p.triangle_b][k]];
    }
    return v;
}

TriRelation relation_of(const std::array<Vec3, 6>& v) {
    return cullide::tri_tri_relation(v[0], v[1], v[2], v[3], v[4], v[5]);
}

// Embree decides in float arithmetic, on coordinates of the size of the pair's own coordinates, so
// a pair within a few float ulps (2^-24 * M, M: the pair's largest coordinate magnitude) of changing
// its relation can go either way. The tolerance of the classification, in those units:
constexpr double kNearUlps = 16;

double largest_magnitude(const std::array<Vec3, 6>& v);

// For a Crossing pair: the smallest k in {1, 2, 4, 8, 16} such that translating triangle b by
// k * 2^-24 * M along one of the candidate directions (the axes, both normals, the nine edge-edge
// cross products: the directions that open a vertex-face or edge-edge contact) makes it not
// Crossing; 0 when none does. (Crossing is an open condition and so is Disjoint, so overshooting a
// Touching configuration still lands on a non-Crossing one.)
int ulps_to_uncross(const std::array<Vec3, 6>& v) {
    const double m = largest_magnitude(v);
    std::vector<Vec3> directions{{1, 0, 0},
                                 {0, 1, 0},
                                 {0, 0, 1},
                                 cullide::cross(v[1] - v[0], v[2] - v[0]),
                                 cullide::cross(v[4] - v[3], v[5] - v[3])};
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = 0; j < 3; ++j) {
            directions.push_back(cullide::cross(v[(i + 1) % 3] - v[i], v[3 + (j + 1) % 3] - v[3 + j]));
        }
    }
    for (int k : {1, 2, 4, 8, 16}) {
        const double tol = k * 0x1p-24 * m;
        for (const Vec3& d : directions) {
            const double len = std::sqrt(cullide::dot(d, d));
            if (!(len > 0)) continue;
            for (double sign : {-1.0, 1.0}) {
                std::array<Vec3, 6> moved = v;
                for (std::size_t b = 3; b < 6; ++b) moved[b] = v[b] + (sign * tol / len) * d;
                if (relation_of(moved) != TriRelation::Crossing) return k;
            }
        }
    }
    return 0;
}

// Distance from p to the closed triangle (a, b, c), in double: the closest point is found by the
// Voronoi-region case analysis of Ericson, "Real-Time Collision Detection" (2005), 5.1.5.
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    using cullide::dot;
    auto dist = [&](const Vec3& q) { return std::sqrt(dot(p - q, p - q)); };
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return dist(a);
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return dist(b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return dist(a + (d1 / (d1 - d3)) * ab);
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return dist(c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return dist(a + (d2 / (d2 - d6)) * ac);
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return dist(b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b));
    const double denom = va + vb + vc;
    if (!(denom > 0)) return std::min({dist(a), dist(b), dist(c)});  // degenerate triangle
    return dist(a + (vb / denom) * ab + (vc / denom) * ac);
}

// Distance between segments p0p1 and q0q1 (Ericson 5.1.9: clamp the parameters of the closest
// points of the two lines to [0, 1], re-projecting once).
double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
    using cullide::dot;
    const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0, t = 0;
    if (a <= 0 && e <= 0) return std::sqrt(dot(r, r));
    if (a <= 0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = dot(d1, r);
        if (e <= 0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = dot(d1, d2), denom = a * e - b * b;
            s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    const Vec3 gap = (p0 + s * d1) - (q0 + t * d2);
    return std::sqrt(dot(gap, gap));
}

// Distance between two disjoint triangles: it is reached at a vertex of one, or between two edges.
double triangle_distance(const std::array<Vec3, 6>& v) {
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < 3; ++k) {
        d = std::min(d, point_triangle_distance(v[k], v[3], v[4], v[5]));
        d = std::min(d, point_triangle_distance(v[3 + k], v[0], v[1], v[2]));
        for (std::size_t j = 0; j < 3; ++j) {
            d = std::min(d, segment_distance(v[k], v[(k + 1) % 3], v[3 + j], v[3 + (j + 1) % 3]));
        }
    }
    return d;
}

double largest_magnitude(const std::array<Vec3, 6>& v) {
    double m = 0;
    for (const Vec3& p : v) m = std::max({m, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    return m;
}

// One comparison of the two methods on one frame, with every disagreement classified.
struct Agreement {
    std::size_t exact = 0, embree = 0, both = 0;
    // Exact-only pairs by exact relation; Crossing ones split by why Embree may miss them.
    std::size_t missed_touching = 0, missed_coplanar = 0;
    std::size_t missed_crossing_float_flipped = 0;  // not Crossing once rounded to float
    std::size_t missed_crossing_near = 0;           // within a few float ulps of not crossing
    std::size_t missed_crossing_unexplained = 0;    // a real miss
    // Embree-only pairs (exact: Disjoint).
    std::size_t extra_float_explained = 0;  // they do meet once rounded to float
    std::size_t extra_near = 0;             // within a few float ulps of meeting
    std::size_t extra_unexplained = 0;
    double worst_ulps = 0;  // largest distance or move, in float ulps of M, that explained a pair
    double exact_seconds = 0, embree_seconds = 0;
    std::vector<TrianglePair> unexplained;  // first few, for the failure message

    void add(const Agreement& o) {
        exact += o.exact;
        embree += o.embree;
        both += o.both;
        missed_touching += o.missed_touching;
        missed_coplanar += o.missed_coplanar;
        missed_crossing_float_flipped += o.missed_crossing_float_flipped;
        missed_crossing_near += o.missed_crossing_near;
        missed_crossing_unexplained += o.missed_crossing_unexplained;
        extra_float_explained += o.extra_float_explained;
        extra_near += o.extra_near;
        extra_unexplained += o.extra_unexplained;
        worst_ulps = std::max(worst_ulps, o.worst_ulps);
        exact_seconds += o.exact_seconds;
        embree_seconds += o.embree_seconds;
        unexplained.insert(unexplained.end(), o.unexplained.begin(), o.unexplained.end());
    }
    // A row of docs/embree-oracle.md's table (times are per frame).
    [[nodiscard]] std::string row(const std::string& name, int frames) const {
        std::ostringstream s;
        s.setf(std::ios::fixed);
        s.precision(1);
        s << "| " << name << " | " << exact << " | " << embree << " | " << both << " | " << missed_touching
          << " / " << missed_coplanar << " / " << missed_crossing_float_flipped << " / "
          << missed_crossing_near << " / " << missed_crossing_unexplained << " | " << extra_float_explained
          << " / " << extra_near << " / " << extra_unexplained << " | " << worst_ulps << " | "
          << 1e3 * exact_seconds / frames << " | " << 1e3 * embree_seconds / frames << " |";
        return s.str();
    }
};

Agreement compare(const std::vector<Mesh>& objects, bool self) {
    Agreement a;
    // One thread each and process CPU time: the machine's cores are shared, so wall time is noise.
    const std::clock_t t0 = std::clock();
    const std::vector<TrianglePair> ex = exact(objects, self, 1);
    const std::clock_t t1 = std::clock();
    const std::vector<TrianglePair> em = embree(objects, self, 1);
    const std::clock_t t2 = std::clock();
    a.exact_seconds = static_cast<double>(t1 - t0) / CLOCKS_PER_SEC;
    a.embree_seconds = static_cast<double>(t2 - t1) / CLOCKS_PER_SEC;
    a.exact = ex.size();
    a.embree = em.size();
    std::vector<TrianglePair> both, exact_only, embree_only;
    std::set_intersection(ex.begin(), ex.end(), em.begin(), em.end(), std::back_inserter(both));
    std::set_difference(ex.begin(), ex.end(), em.begin(), em.end(), std::back_inserter(exact_only));
    std::set_difference(em.begin(), em.end(), ex.begin(), ex.end(), std::back_inserter(embree_only));
    a.both = both.size();
    auto unexplained = [&](const TrianglePair& p) {
        if (a.unexplained.size() < 8) a.unexplained.push_back(p);
    };
    for (const TrianglePair& p : exact_only) {
        const std::array<Vec3, 6> v = vertices(objects, p);
        switch (relation_of(v)) {
            case TriRelation::Touching:
                ++a.missed_touching;
                break;
            case TriRelation::CoplanarOverlap:
                ++a.missed_coplanar;
                break;
            case TriRelation::Crossing: {
                std::array<Vec3, 6> rounded = v;
                for (Vec3& x : rounded) x = round_to_float(x);
                if (relation_of(rounded) != TriRelation::Crossing) {
                    ++a.missed_crossing_float_flipped;
                } else if (const int k = ulps_to_uncross(v)) {
                    ++a.missed_crossing_near;
                    a.worst_ulps = std::max(a.worst_ulps, static_cast<double>(k));
                } else {
                    ++a.missed_crossing_unexplained;
                    unexplained(p);
                }
                break;
            }
            case TriRelation::Disjoint:
                FAIL("exact_pairs reported a Disjoint pair");
                break;
        }
    }
    for (const TrianglePair& p : embree_only) {
        const std::array<Vec3, 6> v = vertices(objects, p);
        REQUIRE(relation_of(v) == TriRelation::Disjoint);  // exact_pairs is complete
        std::array<Vec3, 6> rounded = v;
        for (Vec3& x : rounded) x = round_to_float(x);
        if (relation_of(rounded) != TriRelation::Disjoint) {
            ++a.extra_float_explained;
        } else if (const double ulps = triangle_distance(v) / (0x1p-24 * largest_magnitude(v));
                   ulps <= kNearUlps) {
            ++a.extra_near;
            a.worst_ulps = std::max(a.worst_ulps, ulps);
        } else {
            ++a.extra_unexplained;
            unexplained(p);
        }
    }
    return a;
}

std::string describe(const std::vector<TrianglePair>& pairs) {
    std::ostringstream s;
    for (const TrianglePair& p : pairs) {
        s << " (" << p.object_a << ":" << p.triangle_a << ", " << p.object_b << ":" << p.triangle_b << ")";
    }
    return s.str();
}

void check_agreement(const Agreement& a, const std::string& what) {
    INFO(what, " unexplained:", describe(a.unexplained));
    CHECK(a.missed_crossing_unexplained == 0);
    CHECK(a.extra_unexplained == 0);
    // Every crossing pair is in both lists, so the shared part is the bulk of the exact list
    // whenever something crosses.
    CHECK(a.both + a.missed_touching + a.missed_coplanar + a.missed_crossing_float_flipped +
              a.missed_crossing_near + a.missed_crossing_unexplained ==
          a.exact);
    CHECK(a.both + a.extra_float_explained + a.extra_near + a.extra_unexplained == a.embree);
}

Agreement compare_scene(const std::string& name, double scale, const std::vector<int>& frames, bool self,
                        const std::string& mesh_dir = "") {
    cullide::SceneOptions o;
    o.scale = scale;
    o.mesh_dir = mesh_dir;
    auto gen = cullide::make_scene(name, o);
    REQUIRE_MESSAGE(gen.ok(), (gen.ok() ? std::string() : gen.error().message));
    Agreement total;
    for (int f : frames) {
        const cullide::Frame frame = gen.value()->frame(f);
        const Agreement a = compare(frame, self);
        check_agreement(a, name + " frame " + std::to_string(f));
        total.add(a);
    }
    std::ostringstream label;
    label << name << " (scale " << scale << (self ? ", self" : "") << ", frames";
    for (int f : frames) label << " " << f;
    label << ")";
    MESSAGE(total.row(label.str(), static_cast<int>(frames.size())));
    return total;
}

}  // namespace

TEST_CASE("round_to_float rounds every coordinate to the nearest float") {
    // 0.1 as a float is 0x1.99999ap-4 (rounded up); 1 + 2^-30 rounds to 1; 2^-149 is float's
    // smallest subnormal and stays. Each axis is checked, since a miscompile once dropped x and y.
    const Vec3 r = round_to_float({0.1, 1 + 0x1p-30, 0x1p-149});
    CHECK(r.x == 0x1.99999ap-4);
    CHECK(r.y == 1.0);
    CHECK(r.z == 0x1p-149);
    const Vec3 s = round_to_float({0x1p-149, 0.1, 1 + 0x1p-30});
    CHECK(s.x == 0x1p-149);
    CHECK(s.y == 0x1.99999ap-4);
    CHECK(s.z == 1.0);
}

TEST_CASE("the classification's distance helper measures known gaps") {
    // Parallel triangles 0.5 apart (vertex-face), skew edges 0.25 apart (edge-edge), and a vertex
    // beyond an edge (distance to the edge, not to the plane).
    const std::array<Vec3, 6> stacked{Vec3{0, 0, 0},   {1, 0, 0},       {0, 1, 0},
                                      {0.1, 0.1, 0.5}, {0.6, 0.1, 0.5}, {0.1, 0.6, 0.5}};
    CHECK(triangle_distance(stacked) == doctest::Approx(0.5).epsilon(1e-15));
    const std::array<Vec3, 6> skew{Vec3{-1, 0, 0}, {1, 0, 0},    {0, 0, -1},
                                   {0, -1, 0.25},  {0, 1, 0.25}, {0, 0, 1}};
    CHECK(triangle_distance(skew) == doctest::Approx(0.25).epsilon(1e-15));
    const std::array<Vec3, 6> beyond{Vec3{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, -1, 0}, {3, -1, 0}, {3, -2, 0}};
    CHECK(triangle_distance(beyond) == doctest::Approx(std::sqrt(2.0)).epsilon(1e-15));
    CHECK(relation_of(stacked) == TriRelation::Disjoint);
}

TEST_CASE("two crossing triangles are found and two separate ones are not") {
    const Mesh a = triangle_mesh("a", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const Mesh crossing = triangle_mesh("b", {{0.25, 0.25, -0.5}, {0.25, 0.25, 0.5}, {0.75, -0.5, 0.1}});
    const Mesh apart = triangle_mesh("c", {{0.25, 0.25, 0.1}, {0.25, 0.25, 0.5}, {0.75, -0.5, 0.3}});
    CHECK(cullide::tri_tri_relation(a.positions[0], a.positions[1], a.positions[2], crossing.positions[0],
                                    crossing.positions[1], crossing.positions[2]) == TriRelation::Crossing);
    CHECK(embree({a, crossing}, false) == std::vector<TrianglePair>{{0, 0, 1, 0}});
    CHECK(embree({a, apart}, false).empty());
    // Object order does not matter: the pair is canonical.
    CHECK(embree({crossing, a}, false) == std::vector<TrianglePair>{{0, 0, 1, 0}});
}

TEST_CASE("every triangle a segment passes through is found, not only the nearest") {
    // A needle through a stack of 5 parallel triangles, each its own object, and one triangle of
    // the needle's own object that it also passes (not reported without self).
    std::vector<Mesh> scene;
    scene.push_back(triangle_mesh("needle", {{0.2, 0.2, -1}, {0.2, 0.2, 5}, {0.3, 0.21, 2}}));
    for (int k = 0; k < 5; ++k) {
        const double z = k;
        scene.push_back(triangle_mesh("plate" + std::to_string(k), {{0, 0, z}, {1, 0, z}, {0, 1, z}}));
    }
    std::vector<TrianglePair> expected;
    for (std::uint32_t k = 1; k <= 5; ++k) expected.push_back({0, 0, k, 0});
    CHECK(embree(scene, false) == expected);
    CHECK(exact(scene, false) == expected);
}

TEST_CASE("a coplanar overlap is invisible to edge rays: the documented blind spot") {
    const Mesh a = triangle_mesh("a", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const Mesh b = triangle_mesh("b", {{0.1, 0.1, 0}, {0.6, 0.1, 0}, {0.1, 0.6, 0}});  // inside a, same plane
    CHECK(exact({a, b}, false) == std::vector<TrianglePair>{{0, 0, 1, 0}});
    CHECK(embree({a, b}, false).empty());
}

TEST_CASE("self pairs follow exact_pairs' welded adjacency rule") {
    // Triangle 0 and 1 share an index; triangle 2 has a vertex at the same position as one of
    // triangle 0's (a welded seam); triangle 3 crosses triangle 0 and shares nothing with it.
    Mesh m;
    m.name = "strip";
    m.positions = {{0, 0, 0},    {1, 0, 0},     {0, 1, 0},          {1, 1, 0.5},       {0, 0, 0},
                   {-1, 0, 0.3}, {-1, -1, 0.2}, {0.25, 0.25, -0.5}, {0.25, 0.25, 0.5}, {0.75, -0.5, 0.1}};
    m.triangles = {{0, 1, 2}, {1, 3, 2}, {4, 5, 6}, {7, 8, 9}};
    const std::vector<Mesh> scene{m};
    const std::vector<TrianglePair> expected{{0, 0, 0, 3}};
    CHECK(exact(scene, true) == expected);
    CHECK(embree(scene, true) == expected);
    CHECK(embree(scene, false).empty());
}

TEST_CASE("the result does not depend on the thread count") {
    cullide::SceneOptions o;
    o.scale = 0.05;
    auto gen = cullide::make_scene("tori", o);
    REQUIRE(gen.ok());
    const cullide::Frame frame = gen.value()->frame(0);
    const std::vector<TrianglePair> one = embree(frame, false, 1);
    CHECK(!one.empty());
    for (int threads : {2, 3, 0}) {
        CAPTURE(threads);
        CHECK(embree(frame, false, threads) == one);
    }
}

TEST_CASE("bad input is refused with the object, vertex and limit named") {
    Mesh a = triangle_mesh("a", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    // Embree aborts on rays beyond 1.844e18: coordinates are limited to 2^59 (edge vectors to 2^60).
    Mesh b = triangle_mesh("big", {{0, 0, 0}, {1, 0, 0}, {0, 0x1p60, 0}});
    auto r = cullide_oracle::embree_pairs(std::vector<Mesh>{a, b});
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message ==
          "object 1: mesh 'big': vertex 2 coordinate y = 1.152921504606847e+18 is outside Embree's range "
          "(|x| <= 2^59 = 576460752303423488)");
    b.positions[2].y = -0x1p59;  // the limit itself is inside, and the edges cast without an abort
    b.positions[1].x = 0x1p59;
    CHECK(cullide_oracle::embree_pairs(std::vector<Mesh>{a, b}).ok());
    b.positions[2].y = 1;
    b.triangles[0][1] = 7;
    r = cullide_oracle::embree_pairs(std::vector<Mesh>{a, b});
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("object 1") != std::string::npos);
    r = cullide_oracle::embree_pairs(std::vector<Mesh>{a}, EmbreeOptions{false, -1});
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "threads = -1 is out of range: it must be >= 0");
}

TEST_CASE(
    "on the built-in scenes every crossing pair is found and every extra pair is explained by float "
    "precision") {
    compare_scene("cylinders", 0.3, {0, 40, 80, 120}, false);
    compare_scene("tori", 0.05, {0, 30, 60, 200}, false);
    compare_scene("breaking", 0.05, {0}, false);  // at rest: the pieces touch along their seams
    compare_scene("breaking", 0.05, {30, 40, 50}, false);
    compare_scene("leaves", 0.3, {0, 150, 300}, false);
    compare_scene("cloth", 0.05, {54, 58, 60, 62, 66}, true);
}

TEST_CASE("on the real meshes (bunny through dragon, the teapot's self-intersections) the methods agree") {
    const std::filesystem::path dir(CULLIDE_SHARED_MESH_DIR);
    if (!std::filesystem::exists(dir / "stanford-bunny.obj") ||
        !std::filesystem::exists(dir / "dragon.obj") || !std::filesystem::exists(dir / "teapot.obj")) {
        MESSAGE("skipped: stanford-bunny.obj, dragon.obj or teapot.obj not found in " << dir.string());
        return;
    }
    const Agreement bd = compare_scene("bunny-dragon", 1.0, {30}, false, dir.string());
    CHECK(bd.exact > 1000);  // the bunny really is inside the dragon at frame 30 (docs/scenes.md)
    {
        cullide::SceneOptions o;
        o.mesh_dir = dir.string();
        const cullide::Frame frame = cullide::make_scene("bunny-dragon", o).value()->frame(30);
        for (int threads : {1, 2}) {
            cullide_oracle::EmbreeStats st;
            auto r = cullide_oracle::embree_pairs(frame, EmbreeOptions{false, threads}, &st);
            REQUIRE(r.ok());
            CHECK(r.value().size() == bd.embree);
            CHECK(st.rays + st.zero_length_edges ==
                  3 * (frame[0].triangles.size() + frame[1].triangles.size()));
            MESSAGE("bunny-dragon frame 30, " << threads << " thread(s): " << st.rays << " rays, "
                                              << st.hits_recorded << " hits recorded, build "
                                              << 1e3 * st.build_seconds << " ms, cast "
                                              << 1e3 * st.cast_seconds << " ms");
        }
    }

    auto meshes = cullide::read_mesh_file((dir / "teapot.obj").string());
    REQUIRE(meshes.ok());
    const Agreement tp = compare(meshes.value(), true);
    check_agreement(tp, "teapot");
    MESSAGE(tp.row("teapot (self)", 1));
    CHECK(tp.exact > 0);
}
