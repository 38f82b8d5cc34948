// hard_cases_test.cpp: numerically hard scenes, each checked against the independent GMP rational
// reference (tests/cullide/rational_tri_tri.h) over every triangle pair, against its expected answer
// by construction, and against the spatial hash broad phase (no colliding object pair may be lost).
//
// Every case runs under several transforms of its coordinates: as built, translated by 1e6, scaled by
// 1e-6 and 1e6 (both inexact: each coordinate rounds on its own), and scaled by 2^-200 and 2^200 (exact,
// near the ends of the predicates' range). Contacts are built from equal coordinates (shared corners,
// edges, face planes), which any transform keeps equal, so "touching" stays touching; gaps are between
// axis-aligned boxes, whose answer after rounding is decided independently by comparing the rounded
// extents.
//
// Then every method of cullide::method_names() runs on the same objects (cullide::process_frame) and is
// compared with the ground truth: the reliable ones (R-CULLIDE in both forms) must report exactly the
// exact pairs; the GL-exact ones (CULLIDE) may miss pairs, and their misses are counted and reported,
// not asserted away; no method may report a pair that does not collide, nor refuse valid input.
// CULLIDE_HARD_CASES_TABLE=1 prints the table of docs/reliability.md (one row per case).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "box_mesh.h"
#include "cullide/pipeline.h"
#include "digest.h"
#include "rational_tri_tri.h"
#include "spatialhash/broad_phase.h"

using cullide::Mesh;
using cullide::TrianglePair;
using cullide::Vec3;

namespace {

// ---- Building blocks --------------------------------------------------------------------------

// Boxes: cullide/src/box_mesh.h (two triangles per face; winding does not matter to the exact test).
using cullide::detail::box_mesh;

Mesh triangle_mesh(const std::string& name, Vec3 a, Vec3 b, Vec3 c) {
    return Mesh{name, {a, b, c}, {{0, 1, 2}}};
}

// A tetrahedron with its apex at `apex`, pointing down (-z) onto whatever lies below.
Mesh spike(const std::string& name, Vec3 apex, double height) {
    Mesh m;
    m.name = name;
    m.positions = {apex, {apex.x - 0.25, apex.y - 0.25, apex.z + height}, {apex.x + 0.25, apex.y - 0.25, apex.z + height},
                   {apex.x, apex.y + 0.25, apex.z + height}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
    return m;
}

// ---- Cases ------------------------------------------------------------------------------------

enum class Expect {
    Collide,   // every transform: objects 0 and 1 collide (contact built from equal coordinates)
    Apart,     // every transform: no pair at all
    BoxTest,   // all objects are axis-aligned boxes: pairs are exactly the overlapping closed boxes
    AllPairs,  // every object pair collides
    ApexGap,   // object 1's lowest point is an apex above the interior of object 0's top face: they
               // collide exactly when the apex z is not above the face z (after rounding)
};

struct Case {
    std::string name;
    std::vector<Mesh> objects;
    Expect expect;
};

std::vector<Case> make_cases() {
    std::vector<Case> cases;
    const Vec3 o{0, 0, 0}, one{1, 1, 1};
    cases.push_back({"empty scene", {}, Expect::Apart});
    cases.push_back({"one object", {box_mesh("a", o, one)}, Expect::Apart});
    cases.push_back({"cubes touching at a corner", {box_mesh("a", o, one), box_mesh("b", one, {2, 2, 2})}, Expect::Collide});
    cases.push_back(
        {"cubes touching along an edge", {box_mesh("a", o, one), box_mesh("b", {1, 1, 0}, {2, 2, 1})}, Expect::Collide});
    cases.push_back(
        {"cubes touching face to face", {box_mesh("a", o, one), box_mesh("b", {1, 0, 0}, {2, 1, 1})}, Expect::Collide});
    cases.push_back({"cubes touching on part of a face",
                     {box_mesh("a", o, one), box_mesh("b", {1, 0.5, 0.5}, {2, 1.5, 1.5})},
                     Expect::Collide});
    for (const double gap : {1e-3, 1e-6, 1e-9, 1e-12}) {
        std::ostringstream n;
        n << "cubes with a gap of " << gap;
        cases.push_back(
            {n.str(), {box_mesh("a", o, one), box_mesh("b", {1 + gap, 0, 0}, {2 + gap, 1, 1})}, Expect::BoxTest});
    }
    for (const double gap : {1e-3, 1e-12}) {
        std::ostringstream n;
        n << "spike above a face with a gap of " << gap;
        cases.push_back(
            {n.str(), {box_mesh("a", o, one), spike("b", {0.5, 0.5, 1 + gap}, 0.5)}, Expect::ApexGap});
    }
    cases.push_back({"spike apex on a face", {box_mesh("a", o, one), spike("b", {0.5, 0.5, 1}, 0.5)}, Expect::Collide});
    cases.push_back({"spike piercing a face by 1e-4 (inside one pixel)",
                     {box_mesh("a", o, one), spike("b", {0.3, 0.6, 1 - 1e-4}, 0.5)},
                     Expect::Collide});
    cases.push_back({"cubes overlapping by 1e-4 at a corner (inside one pixel)",
                     {box_mesh("a", o, one), box_mesh("b", {1 - 1e-4, 1 - 1e-4, 1 - 1e-4}, {2, 2, 2})},
                     Expect::BoxTest});
    // Coplanar overlapping faces, not axis-aligned in the plane: two triangles in z = 0.5.
    cases.push_back({"coplanar overlapping triangles",
                     {triangle_mesh("a", {0, 0, 0.5}, {1, 0.2, 0.5}, {0.3, 0.9, 0.5}),
                      triangle_mesh("b", {0.5, 0.1, 0.5}, {1.2, 0.8, 0.5}, {0.1, 0.7, 0.5})},
                     Expect::Collide});
    cases.push_back({"coplanar triangles sharing only an edge",
                     {triangle_mesh("a", {0, 0, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}),
                      triangle_mesh("b", {1, 0, 0.5}, {0, 1, 0.5}, {1, 1, 0.5})},
                     Expect::Collide});
    // Slivers and zero-area triangles (a segment, a point) through or onto a face.
    cases.push_back({"sliver 1e-12 wide crossing a triangle",
                     {triangle_mesh("a", {0, 0, 0}, {1, 0, 0}, {0, 1, 0}),
                      triangle_mesh("b", {0.25, 0.25, -1}, {0.25 + 1e-12, 0.25, -1}, {0.25, 0.25, 1})},
                     Expect::Collide});
    cases.push_back({"zero-area segment triangle piercing a face",
                     {box_mesh("a", o, one), triangle_mesh("b", {0.5, 0.5, 0.5}, {0.5, 0.5, 1.5}, {0.5, 0.5, 2.5})},
                     Expect::Collide});
    cases.push_back({"zero-area point triangle on a face",
                     {box_mesh("a", o, one), triangle_mesh("b", {0.5, 1, 0.25}, {0.5, 1, 0.25}, {0.5, 1, 0.25})},
                     Expect::Collide});
    cases.push_back({"zero-area point triangle 1e-12 off a face",
                     {box_mesh("a", o, one),
                      triangle_mesh("b", {0.5, 1 + 1e-12, 0.25}, {0.5, 1 + 1e-12, 0.25}, {0.5, 1 + 1e-12, 0.25})},
                     Expect::BoxTest});
    // Depth-range extremes: a scene 1e6 deep (a far object at z = 1e6) with a 1e-6 gap near the eye;
    // a 24-bit depth buffer cannot separate the two close faces.
    cases.push_back({"depth range 1e6 with a 1e-6 gap",
                     {box_mesh("a", o, one), box_mesh("b", {0, 0, 1 + 1e-6}, {1, 1, 2}),
                      box_mesh("far", {0, 0, 1e6}, {1, 1, 1e6 + 1})},
                     Expect::BoxTest});
    {
        // A thousand identical one-triangle objects: every one of the 499,500 object pairs collides.
        Case c{"a thousand identical triangles", {}, Expect::AllPairs};
        for (int i = 0; i < 1000; ++i) {
            c.objects.push_back(triangle_mesh(std::string("t").append(std::to_string(i)), {0, 0, 0}, {1, 0, 0.25}, {0, 1, 0.5}));
        }
        cases.push_back(std::move(c));
    }
    {
        Case c{"forty identical cubes", {}, Expect::AllPairs};
        for (int i = 0; i < 40; ++i) c.objects.push_back(box_mesh(std::string("c").append(std::to_string(i)), o, one));
        cases.push_back(std::move(c));
    }
    return cases;
}

struct Transform {
    const char* name;
    std::function<double(double)> apply;
};

std::vector<Transform> transforms() {
    return {
        {"as built", [](double v) { return v; }},
        {"translated by 1e6", [](double v) { return v + 1e6; }},
        {"scaled by 1e-6", [](double v) { return v * 1e-6; }},
        {"scaled by 1e6", [](double v) { return v * 1e6; }},
        {"scaled by 2^-200", [](double v) { return std::ldexp(v, -200); }},
        {"scaled by 2^200", [](double v) { return std::ldexp(v, 200); }},
    };
}

std::vector<Mesh> transformed(const std::vector<Mesh>& objects, const Transform& t) {
    std::vector<Mesh> out = objects;
    for (Mesh& m : out) {
        for (Vec3& p : m.positions) p = {t.apply(p.x), t.apply(p.y), t.apply(p.z)};
    }
    return out;
}

// ---- References -------------------------------------------------------------------------------

// The GMP reference over every triangle pair of distinct objects. Identical pairs of triangles (the
// thousand copies) are decided once: the memo is keyed on all 18 coordinates' bits.
std::vector<TrianglePair> rational_pairs(const std::vector<Mesh>& objects) {
    std::map<std::array<std::uint64_t, 18>, bool> memo;
    std::vector<TrianglePair> out;
    for (std::uint32_t a = 0; a < objects.size(); ++a) {
        for (std::uint32_t b = a + 1; b < objects.size(); ++b) {
            const Mesh& ma = objects[a];
            const Mesh& mb = objects[b];
            for (std::uint32_t i = 0; i < ma.triangles.size(); ++i) {
                for (std::uint32_t j = 0; j < mb.triangles.size(); ++j) {
                    const Vec3 v[6] = {ma.positions[ma.triangles[i][0]], ma.positions[ma.triangles[i][1]],
                                       ma.positions[ma.triangles[i][2]], mb.positions[mb.triangles[j][0]],
                                       mb.positions[mb.triangles[j][1]], mb.positions[mb.triangles[j][2]]};
                    std::array<std::uint64_t, 18> key{};
                    for (int k = 0; k < 18; ++k) key[static_cast<std::size_t>(k)] = std::bit_cast<std::uint64_t>(v[k / 3][k % 3]);
                    auto it = memo.find(key);
                    if (it == memo.end()) {
                        const bool hit = cullide::test::rational_tri_tri_relation(v[0], v[1], v[2], v[3], v[4], v[5]) !=
                                         cullide::TriRelation::Disjoint;
                        it = memo.emplace(key, hit).first;
                    }
                    if (it->second) out.push_back({a, i, b, j});
                }
            }
        }
    }
    std::sort(out.begin(), out.end());  // generated in (a, b, i, j) order; canonical is (a, i, b, j)
    return out;
}

// The object pairs the case's construction predicts, from the (transformed) doubles alone.
std::vector<cullide::ObjectPair> expected_object_pairs(const Case& c, const std::vector<Mesh>& objects) {
    std::vector<cullide::ObjectPair> out;
    const auto n = static_cast<std::uint32_t>(objects.size());
    switch (c.expect) {
        case Expect::Collide: out.push_back({0, 1}); break;
        case Expect::Apart: break;
        case Expect::AllPairs:
            for (std::uint32_t a = 0; a < n; ++a)
                for (std::uint32_t b = a + 1; b < n; ++b) out.push_back({a, b});
            break;
        case Expect::ApexGap:
            if (cullide::mesh_bounds(objects[1]).lo.z <= cullide::mesh_bounds(objects[0]).hi.z) out.push_back({0, 1});
            break;
        case Expect::BoxTest:
            // Axis-aligned boxes (a point is a box too): closed boxes meet exactly when their solids
            // share a point, and then their surfaces do as well unless one is strictly inside the
            // other, which no case builds.
            for (std::uint32_t a = 0; a < n; ++a)
                for (std::uint32_t b = a + 1; b < n; ++b)
                    if (cullide::overlaps(cullide::mesh_bounds(objects[a]), cullide::mesh_bounds(objects[b])))
                        out.push_back({a, b});
            break;
    }
    return out;
}

// Object pairs the broad phase keeps; every method of spatialhash must keep each colliding pair.
std::vector<spatialhash::Pair> broad_phase_pairs(const std::vector<Mesh>& objects, spatialhash::Method method) {
    std::vector<spatialhash::Box> boxes;
    for (const Mesh& m : objects) {
        const cullide::Aabb b = cullide::mesh_bounds(m);
        boxes.push_back({{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}});
    }
    spatialhash::Options o;
    o.method = method;
    o.threads = 2;
    auto r = spatialhash::find_pairs(std::span<const spatialhash::Box>(boxes), o);
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
    return r.value().pairs;
}

// ---- The methods ------------------------------------------------------------------------------

// What the test asserts for a method of cullide::method_names(). A method this table does not know
// is run and reported, but not asserted on (add it here when it lands).
enum class Role {
    Truth,     // the ground truth itself ("exact")
    Reliable,  // must report exactly the ground truth on every case and transform
    Reported,  // may miss pairs (GL-exact sampling and depth precision): misses are counted, not asserted
};

Role role_of(const std::string& method) {
    if (method == "exact") return Role::Truth;
    if (reliability::reliable_method(method)) return Role::Reliable;
    return Role::Reported;  // "cullide", "qcullide-gl", and anything new
}

// Visibility methods run at this resolution (pixels per view side); the many-object cases at a
// lower one (a thousand full-view queries per pass would dominate the test's time). Either way the
// "inside one pixel" cases (1e-4 of the scene) stay well inside one pixel.
constexpr int kResolution = 64;
constexpr int kResolutionManyObjects = 32;

// One method on one case and transform, against the ground truth.
struct MethodRun {
    bool ok = false;
    std::string error;
    std::uint64_t missed_triangle_pairs = 0;  // ground-truth pairs the method did not report
    std::uint64_t missed_object_pairs = 0;
    std::uint64_t extra_triangle_pairs = 0;  // reported pairs that do not collide (must be 0 for all)
    bool equal = false;
};

MethodRun run_method(const std::string& method, const std::vector<Mesh>& objects,
                     const std::vector<TrianglePair>& truth) {
    MethodRun out;
    auto parsed = cullide::parse_method(method);
    REQUIRE_MESSAGE(parsed.ok(), (parsed.ok() ? std::string() : parsed.error().message));
    cullide::RunOptions o;
    o.method = parsed.value();
    o.threads = 2;
    o.resolution = objects.size() > 10 ? kResolutionManyObjects : kResolution;
    auto r = cullide::process_frame(std::span<const Mesh>(objects), o);
    if (!r.ok()) {
        out.error = r.error().message;
        return out;
    }
    out.ok = true;
    const std::vector<TrianglePair>& got = r.value().pairs;
    out.equal = got == truth;
    std::vector<TrianglePair> missed, extra;
    std::set_difference(truth.begin(), truth.end(), got.begin(), got.end(), std::back_inserter(missed));
    std::set_difference(got.begin(), got.end(), truth.begin(), truth.end(), std::back_inserter(extra));
    out.missed_triangle_pairs = missed.size();
    out.extra_triangle_pairs = extra.size();
    const auto want_objects = cullide::object_pairs(truth);
    const auto got_objects = r.value().object_pairs;
    std::vector<cullide::ObjectPair> missed_objects;
    std::set_difference(want_objects.begin(), want_objects.end(), got_objects.begin(), got_objects.end(),
                        std::back_inserter(missed_objects));
    out.missed_object_pairs = missed_objects.size();
    return out;
}

std::string slash_join(const std::vector<std::string>& cells) {
    std::string s;
    for (std::size_t i = 0; i < cells.size(); ++i) s += (i ? " / " : "") + cells[i];
    return s;
}

// A method's table cell for one case: "equal" when it reported the ground truth under every transform
// run; else the ground-truth triangle pairs it missed (and object pairs), once when the same under
// every transform, else per transform ("refused", "-" for not run).
std::string method_cell(const std::vector<std::optional<MethodRun>>& runs) {
    std::vector<std::string> cells;
    for (const auto& r : runs) {
        if (!r) {
            cells.emplace_back("-");
        } else if (!r->ok) {
            cells.emplace_back("refused");
        } else if (r->equal) {
            cells.emplace_back("0");
        } else {
            std::ostringstream c;
            c << r->missed_triangle_pairs << " (" << r->missed_object_pairs << " obj)";
            if (r->extra_triangle_pairs != 0) c << " +" << r->extra_triangle_pairs << " extra";
            cells.push_back(c.str());
        }
    }
    bool same = true, all_equal = true;
    for (const auto& c : cells) {
        same = same && c == cells.front();
        all_equal = all_equal && (c == "0" || c == "-");
    }
    if (all_equal) return "equal";
    if (same) return "**missed " + cells.front() + "**, every transform";
    return "**missed** " + slash_join(cells);
}

}  // namespace

TEST_CASE("hard cases: every method against the GMP reference and the construction, and the broad phase loses nothing") {
    const bool print_table = std::getenv("CULLIDE_HARD_CASES_TABLE") != nullptr;
    std::vector<std::string> methods;  // every method but the ground truth, in method_names() order
    for (const std::string& m : cullide::method_names())
        if (role_of(m) != Role::Truth) methods.push_back(m);
    if (print_table) {
        std::cout << "| Case | Objects | Triangles | Exact triangle pairs (as built / +1e6 / x1e-6 / x1e6 / x2^-200 / "
                     "x2^200) | Object pairs (same order) | GMP reference and construction | Object pairs lost by "
                     "the broad phase |";
        for (const auto& m : methods) std::cout << " " << m << (role_of(m) == Role::Reliable ? " (asserted)" : "") << " |";
        std::cout << "\n|---|---:|---:|---|---|---|---:|";
        for (std::size_t i = 0; i < methods.size(); ++i) std::cout << "---|";
        std::cout << "\n";
    }
    // Under emulation (scripts/cross-aarch64.sh) or a sanitizer, CULLIDE_RELIABILITY_QUICK=1 runs the
    // many-object cases (half a million pairs each) as built only, and the visibility methods on the
    // untransformed cases only; native runs do every transform (the visibility methods on the
    // many-object cases only when printing the table).
    const bool quick = reliability::quick_mode();
    int checked = 0, skipped = 0;
    std::map<std::string, std::uint64_t> misses, missed_objects, method_runs;
    for (const Case& c : make_cases()) {
        std::vector<std::string> tri_cells, obj_cells;
        bool all_reference = true;
        std::uint64_t lost_total = 0, tris = 0;
        std::map<std::string, std::vector<std::optional<MethodRun>>> runs;
        for (const Mesh& m : c.objects) tris += m.triangles.size();
        for (const Transform& t : transforms()) {
            const bool as_built = std::string(t.name) == "as built";
            if (quick && c.objects.size() > 10 && !as_built) {
                ++skipped;
                tri_cells.emplace_back("-");
                obj_cells.emplace_back("-");
                for (const auto& m : methods) runs[m].emplace_back();
                continue;
            }
            CAPTURE(c.name);
            const std::string transform_name = t.name;
            CAPTURE(transform_name);
            const std::vector<Mesh> objects = transformed(c.objects, t);
            auto got = cullide::exact_pairs(objects, cullide::ExactOptions{false, 2});
            REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
            const std::vector<TrianglePair>& pairs = got.value();
            const std::vector<TrianglePair> reference = rational_pairs(objects);
            CHECK(pairs == reference);
            const auto object_pairs = cullide::object_pairs(pairs);
            const auto expected = expected_object_pairs(c, objects);
            CHECK(object_pairs == expected);
            all_reference = all_reference && pairs == reference && object_pairs == expected;
            std::uint64_t lost = 0;
            for (const auto method :
                 {spatialhash::Method::SpatialHash, spatialhash::Method::SweepAndPrune, spatialhash::Method::BruteForce}) {
                CAPTURE(static_cast<int>(method));
                const auto kept = broad_phase_pairs(objects, method);
                for (const auto& p : object_pairs) {
                    if (!std::binary_search(kept.begin(), kept.end(), spatialhash::Pair{p.a, p.b},
                                            [](const spatialhash::Pair& x, const spatialhash::Pair& y) {
                                                return x.a != y.a ? x.a < y.a : x.b < y.b;
                                            })) {
                        ++lost;
                    }
                }
            }
            CHECK(lost == 0);
            lost_total += lost;
            tri_cells.push_back(std::to_string(pairs.size()));
            obj_cells.push_back(std::to_string(object_pairs.size()));
            ++checked;

            // Every visibility method against the ground truth (the exact pairs, just checked).
            for (const std::string& m : methods) {
                // Default runs keep the test fast (a few seconds): the visibility methods skip the
                // many-object cases (6 s of CPU), which the table run (CULLIDE_HARD_CASES_TABLE=1) does
                // under every transform; quick runs do the untransformed small cases only.
                if (c.objects.size() > 10 ? !print_table : (quick && !as_built)) {
                    runs[m].emplace_back();
                    continue;
                }
                CAPTURE(m);
                const MethodRun r = run_method(m, objects, pairs);
                ++method_runs[m];
                // Every method ends in the exact test: none may report a pair that does not collide.
                CHECK_MESSAGE(r.extra_triangle_pairs == 0, r.extra_triangle_pairs << " false pairs");
                if (role_of(m) == Role::Reliable) {
                    CHECK_MESSAGE(r.ok, r.error);
                    CHECK_MESSAGE(r.equal, r.missed_triangle_pairs << " triangle pairs and " << r.missed_object_pairs
                                                                   << " object pairs missed");
                } else if (!r.ok) {
                    // A GL-exact method may miss, but it must not refuse input the ground truth accepts.
                    CHECK_MESSAGE(r.ok, r.error);
                }
                misses[m] += r.missed_triangle_pairs;
                missed_objects[m] += r.missed_object_pairs;
                runs[m].push_back(r);
            }
        }
        if (print_table) {
            std::cout << "| " << c.name << " | " << c.objects.size() << " | " << tris << " | " << slash_join(tri_cells)
                      << " | " << slash_join(obj_cells) << " | " << (all_reference ? "equal" : "DIFFERS") << " | "
                      << lost_total << " |";
            for (const auto& m : methods) std::cout << " " << method_cell(runs[m]) << " |";
            std::cout << "\n";
        }
    }
    if (print_table) {
        std::cout << "\nVisibility methods at " << kResolution << " x " << kResolution << " pixels per view ("
                  << kResolutionManyObjects << " x " << kResolutionManyObjects
                  << " for the many-object cases), D24, 2 threads. Totals over every case and transform:\n\n";
        for (const auto& m : methods)
            std::cout << "- " << m << ": " << method_runs[m] << " runs, " << misses[m] << " ground-truth triangle pairs and "
                      << missed_objects[m] << " object pairs missed"
                      << (role_of(m) == Role::Reliable ? " (asserted to be 0)" : " (reported, not asserted)") << "\n";
    }
    CHECK(checked + skipped == static_cast<int>(make_cases().size() * transforms().size()));
    CHECK(checked >= 100);
    // The reliable methods exist and ran (a renamed method must not silently drop out of the checks).
    for (const char* m : {"rcullide", "rcullide-offset"}) {
        CAPTURE(std::string(m));
        CHECK(method_runs[m] > 0);
    }
}
