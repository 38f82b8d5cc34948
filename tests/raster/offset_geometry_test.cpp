// offset_geometry_test.cpp: R-CULLIDE's offset boxes (raster/offset_geometry.h) and the orthographic
// view helper (raster/transform.h), each against an exact rational check: the boxes contain the
// triangles grown by r (balls of radius r around every vertex, exactly), their winding makes
// CullFace::Back draw the near faces and CullFace::Front the far ones, and ortho_view_to_clip stays
// within its documented error.
#include <doctest/doctest.h>
#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "raster/raster.h"
#include "test_rng.h"

namespace {

using raster::Double3;

double comp(const Double3& p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }

// The view map of transform.h in exact arithmetic: clip = 2 (a - lo) / (hi - lo) - 1 per view axis.
struct ExactView {
    mpq_class lo[3], hi[3];
    explicit ExactView(const raster::OrthoView& v) {
        const Double3 l = raster::view_axes(v, v.box_min), h = raster::view_axes(v, v.box_max);
        for (int k = 0; k < 3; ++k) {
            lo[k] = comp(l, k);
            hi[k] = comp(h, k);
        }
    }
    // view coordinates (u, v, d) of a clip value along axis k
    mpq_class from_clip(int k, double c) const { return (mpq_class(c) + 1) * (hi[k] - lo[k]) / 2 + lo[k]; }
    mpq_class to_clip(int k, const mpq_class& a) const { return 2 * (a - lo[k]) / (hi[k] - lo[k]) - 1; }
};

raster::OrthoView random_view(test::Rng& rng, raster::Axis axis, raster::DepthFormat f) {
    const double s = std::ldexp(1.0, static_cast<int>(rng.below(30)) - 10);
    const Double3 lo{rng.uniform(-5, 5) * s, rng.uniform(-5, 5) * s, rng.uniform(-5, 5) * s};
    const Double3 hi{lo.x + rng.uniform(0.5, 8) * s, lo.y + rng.uniform(0.5, 8) * s,
                     lo.z + rng.uniform(0.5, 8) * s};
    // Sequenced explicitly: the order in which function arguments are evaluated is unspecified
    // (g++ on x86-64 and on aarch64 differ), and the inputs must be the same everywhere.
    const int width = 16 + static_cast<int>(rng.below(300));
    const int height = 16 + static_cast<int>(rng.below(300));
    auto v = raster::make_ortho_view(axis, lo, hi, width, height, f);
    REQUIRE(v.ok());
    return v.value();
}

std::vector<Double3> random_points(test::Rng& rng, const raster::OrthoView& v, int n) {
    std::vector<Double3> p;
    for (int i = 0; i < n; ++i)
        p.push_back({rng.uniform(v.box_min.x, v.box_max.x), rng.uniform(v.box_min.y, v.box_max.y),
                     rng.uniform(v.box_min.z, v.box_max.z)});
    return p;
}

// r^2 >= 3/4 p^2 exactly, with p = max(2 dx, 2 dy, 2 dz) of the view in exact arithmetic.
bool radius_is_enough(const raster::OrthoView& v, double r) {
    const ExactView e(v);
    const mpq_class quantum = v.format == raster::DepthFormat::D16   ? mpq_class(1, 65535)
                              : v.format == raster::DepthFormat::D24 ? mpq_class(1, 16777215)
                                                                     : mpq_class(1, 16777216);
    mpq_class p = 2 * (e.hi[0] - e.lo[0]) / v.width;
    p = std::max(p, mpq_class(2 * (e.hi[1] - e.lo[1]) / v.height));
    p = std::max(p, mpq_class(2 * (e.hi[2] - e.lo[2]) * quantum));
    const mpq_class rq(r);
    return rq * rq * 4 >= 3 * p * p;
}

// Every ball of radius r around a vertex lies inside the box (its 12 triangle planes, exactly),
// in view coordinates; the box's corners are read back from the floats exactly.
bool box_contains_balls(const raster::OrthoView& v, const raster::OffsetMesh& m, std::size_t box,
                        const std::vector<Double3>& pts, double r) {
    const ExactView e(v);
    std::vector<std::array<mpq_class, 3>> c(8);
    for (std::size_t k = 0; k < 8; ++k) {
        const raster::Float4& f = m.vertices[8 * box + k];
        const double cc[3] = {static_cast<double>(f.x), static_cast<double>(f.y), static_cast<double>(f.z)};
        for (int a = 0; a < 3; ++a) c[k][static_cast<std::size_t>(a)] = e.from_clip(a, cc[a]);
    }
    const mpq_class rr = mpq_class(r) * mpq_class(r);
    for (std::size_t t = 0; t < 12; ++t) {
        const auto& a = c[m.indices[36 * box + 3 * t] - 8 * box];
        const auto& b = c[m.indices[36 * box + 3 * t + 1] - 8 * box];
        const auto& d = c[m.indices[36 * box + 3 * t + 2] - 8 * box];
        mpq_class u[3], w[3], n[3];
        for (int k = 0; k < 3; ++k) {
            u[k] = b[static_cast<std::size_t>(k)] - a[static_cast<std::size_t>(k)];
            w[k] = d[static_cast<std::size_t>(k)] - a[static_cast<std::size_t>(k)];
        }
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        const mpq_class nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (nn == 0) continue;  // a flat (zero-thickness) face triangle bounds nothing
        for (const Double3& p : pts) {
            const Double3 q = raster::view_axes(v, p);
            mpq_class s = 0;
            for (int k = 0; k < 3; ++k) s += n[k] * (mpq_class(comp(q, k)) - a[static_cast<std::size_t>(k)]);
            // Inward normals (kBox winding): inside means s >= r |n|.
            if (sgn(s) < 0 || s * s < rr * nn) return false;
        }
    }
    return true;
}

}  // namespace

TEST_CASE("ortho_view_to_clip is the per-point formula bit for bit (all points, a part or named ones), and names the first bad point") {
    test::Rng rng(12);
    std::size_t compared = 0;
    for (int rep = 0; rep < 90; ++rep) {
        const auto axis = static_cast<raster::Axis>(rep % 3);
        const raster::OrthoView v = random_view(rng, axis, raster::DepthFormat::D24);
        auto pts = random_points(rng, v, 5);
        // The twin: view_axes per point, then (a - lo) * (2 / (hi - lo)) - 1 per axis.
        const Double3 lo = raster::view_axes(v, v.box_min), hi = raster::view_axes(v, v.box_max);
        const double sx = 2.0 / (hi.x - lo.x), sy = 2.0 / (hi.y - lo.y), sz = 2.0 / (hi.z - lo.z);
        auto c = raster::ortho_view_to_clip(v, pts);
        REQUIRE(c.ok());
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const Double3 a = raster::view_axes(v, pts[i]);
            const raster::Double4& g = c.value()[i];
            CHECK(g.x == (a.x - lo.x) * sx - 1.0);
            CHECK(g.y == (a.y - lo.y) * sy - 1.0);
            CHECK(g.z == (a.z - lo.z) * sz - 1.0);
            ++compared;
        }
        // The span overload on a part of the points writes that part of the output, the same bits.
        std::vector<raster::Double4> part_out(pts.size(), raster::Double4{7, 7, 7, 7});
        auto part = raster::ortho_view_to_clip(v, std::span<const Double3>(pts).subspan(1, 3),
                                               std::span<raster::Double4>(part_out).subspan(1, 3));
        REQUIRE(part.ok());
        CHECK(part.value() == 3);
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const bool inside = i >= 1 && i < 4;
            CHECK(part_out[i].x == (inside ? c.value()[i].x : 7.0));
            CHECK(part_out[i].z == (inside ? c.value()[i].z : 7.0));
        }
        // The overload for named points (repeats allowed) writes those and nothing else, the same bits.
        std::vector<raster::Double4> named_out(pts.size(), raster::Double4{7, 7, 7, 7});
        const std::vector<std::uint32_t> which = {3, 1, 3, 4};
        auto named = raster::ortho_view_to_clip(v, pts, which, named_out);
        REQUIRE(named.ok());
        CHECK(named.value() == 4);
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const bool listed = i == 1 || i == 3 || i == 4;
            CHECK(named_out[i].x == (listed ? c.value()[i].x : 7.0));
            CHECK(named_out[i].y == (listed ? c.value()[i].y : 7.0));
            CHECK(named_out[i].z == (listed ? c.value()[i].z : 7.0));
            CHECK(named_out[i].w == (listed ? 1.0 : 7.0));
        }
        const std::vector<std::uint32_t> beyond = {0, 5};
        auto out_of_range = raster::ortho_view_to_clip(v, pts, beyond, named_out);
        REQUIRE_FALSE(out_of_range.ok());
        CHECK(out_of_range.error().message == "ortho_view_to_clip: index 5 is out of range (5 points)");
        auto wrong = raster::ortho_view_to_clip(v, pts, std::span<raster::Double4>(part_out).subspan(0, 2));
        REQUIRE_FALSE(wrong.ok());
        CHECK(wrong.error().message == "ortho_view_to_clip: the output holds 2 points for 5");
        // A non-finite coordinate on any axis, then an overflow before it: the first one is named.
        const std::size_t bad = 1 + static_cast<std::size_t>(rep) % (pts.size() - 1);
        auto broken = pts;
        const double odd = rep % 2 == 0 ? std::numeric_limits<double>::infinity() : std::numeric_limits<double>::quiet_NaN();
        (rep % 3 == 0 ? broken[bad].x : rep % 3 == 1 ? broken[bad].y : broken[bad].z) = odd;
        auto e = raster::ortho_view_to_clip(v, broken);
        REQUIRE_FALSE(e.ok());
        CHECK(e.error().message == "ortho_view_to_clip: point " + std::to_string(bad) + " is not finite");
        // Named: the point's index in the list of points, not its place in `which`; a list that
        // leaves it out transforms the others.
        const std::vector<std::uint32_t> with_bad = {0, static_cast<std::uint32_t>(bad)};
        auto en = raster::ortho_view_to_clip(v, broken, with_bad, named_out);
        REQUIRE_FALSE(en.ok());
        CHECK(en.error().message == "ortho_view_to_clip: point " + std::to_string(bad) + " is not finite");
        const std::vector<std::uint32_t> without_bad = {0};
        CHECK(raster::ortho_view_to_clip(v, broken, without_bad, named_out).ok());
        // On a tiny box (scale 2e300 per unit) a finite point far outside overflows in clip space.
        auto tiny = raster::make_ortho_view(axis, {0, 0, 0}, {1e-300, 1e-300, 1e-300}, 8, 8, raster::DepthFormat::D24);
        REQUIRE(tiny.ok());
        std::vector<Double3> near(pts.size(), Double3{0.5e-300, 0.25e-300, 0.75e-300});
        near[bad] = broken[bad];
        near[bad - 1] = Double3{1e10, -1e10, 1e10};
        e = raster::ortho_view_to_clip(tiny.value(), near);
        REQUIRE_FALSE(e.ok());
        CHECK(e.error().message ==
              "ortho_view_to_clip: point " + std::to_string(bad - 1) + " overflows the double range in clip space");
    }
    CHECK(compared >= 90 * 5);
}

TEST_CASE("The orthographic view helper maps the box to [-1, 1] within its documented error") {
    test::Rng rng(11);
    for (int rep = 0; rep < 300; ++rep) {
        const auto axis = static_cast<raster::Axis>(rep % 3);
        const raster::OrthoView v = random_view(rng, axis, raster::DepthFormat::D24);
        const ExactView e(v);
        const auto pts = random_points(rng, v, 4);
        auto c = raster::ortho_view_to_clip(v, pts);
        REQUIRE(c.ok());
        // The overload into a caller's vector (longer than needed, holding old values) gives the
        // same bits and the point count.
        std::vector<raster::Double4> reused(pts.size() + 3, raster::Double4{7, 7, 7, 7});
        auto n = raster::ortho_view_to_clip(v, pts, reused);
        REQUIRE(n.ok());
        CHECK(n.value() == pts.size());
        REQUIRE(reused.size() == pts.size());
        for (std::size_t i = 0; i < pts.size(); ++i)
            CHECK((reused[i].x == c.value()[i].x && reused[i].y == c.value()[i].y && reused[i].z == c.value()[i].z &&
                   reused[i].w == c.value()[i].w));
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const Double3 a = raster::view_axes(v, pts[i]);
            const double got[3] = {c.value()[i].x, c.value()[i].y, c.value()[i].z};
            CHECK(c.value()[i].w == 1.0);
            for (int k = 0; k < 3; ++k) {
                const mpq_class exact = e.to_clip(k, mpq_class(comp(a, k)));
                mpq_class err = mpq_class(got[k]) - exact;
                if (sgn(err) < 0) err = -err;
                // 3 ulp(max(1, |clip|)) + 2^-52 with |clip| <= 1 here: below 2^-49.
                CHECK(err <= mpq_class(std::ldexp(1.0, -49)));
            }
        }
    }
    // Axis permutations are cyclic (orientation-preserving).
    auto v = raster::make_ortho_view(raster::Axis::X, {0, 0, 0}, {1, 2, 3}, 8, 8, raster::DepthFormat::D16);
    REQUIRE(v.ok());
    const Double3 a = raster::view_axes(v.value(), {10, 20, 30});
    CHECK(a.x == 20);
    CHECK(a.y == 30);
    CHECK(a.z == 10);
}

TEST_CASE("Offset boxes contain every triangle grown by the paper's radius, exactly") {
    test::Rng rng(12);
    for (int rep = 0; rep < 120; ++rep) {
        CAPTURE(rep);
        const auto f = static_cast<raster::DepthFormat>(rep % 3);
        const raster::OrthoView v = random_view(rng, static_cast<raster::Axis>((rep / 3) % 3), f);
        // Big depth extent vs pixels sometimes, so the boxes are not always clamped in depth.
        const auto pts = random_points(rng, v, 9);
        std::vector<std::uint32_t> idx = {0, 1, 2, 3, 4, 5, 6, 7, 8};
        if (rep % 4 == 0) idx = {0, 0, 1, 2, 2, 2, 3, 4, 3};  // degenerate: segments and points
        const double r = raster::offset_radius(v);
        CHECK(radius_is_enough(v, r));
        auto boxes = raster::triangle_offset_boxes(v, pts, idx);
        REQUIRE(boxes.ok());
        REQUIRE(boxes.value().vertices.size() == 24);
        REQUIRE(boxes.value().indices.size() == 108);
        for (std::size_t t = 0; t < 3; ++t) {
            CAPTURE(t);
            std::vector<Double3> tri = {pts[idx[3 * t]], pts[idx[3 * t + 1]], pts[idx[3 * t + 2]]};
            // Boxes are clamped to the view's depth range and to clip x, y in [-2, 2] (half a view
            // beyond each visible edge), so only balls inside that region must be contained.
            const Double3 lo = raster::view_axes(v, v.box_min), hi = raster::view_axes(v, v.box_max);
            bool inside = true;
            for (const auto& p : tri) {
                const Double3 q = raster::view_axes(v, p);
                inside = inside && q.z - r >= lo.z && q.z + r <= hi.z;
                inside = inside && q.x - r >= lo.x - 0.5 * (hi.x - lo.x) && q.x + r <= hi.x + 0.5 * (hi.x - lo.x);
                inside = inside && q.y - r >= lo.y - 0.5 * (hi.y - lo.y) && q.y + r <= hi.y + 0.5 * (hi.y - lo.y);
            }
            if (inside) CHECK(box_contains_balls(v, boxes.value(), t, tri, r));
        }
        auto obbs = raster::object_offset_obbs(v, pts, idx, 2);
        REQUIRE(obbs.ok());
        REQUIRE(obbs.value().vertices.size() == 16);
        const std::vector<Double3> g0 = {pts[idx[0]], pts[idx[1]], pts[idx[2]],
                                         pts[idx[3]], pts[idx[4]], pts[idx[5]]};
        const std::vector<Double3> g1 = {pts[idx[6]], pts[idx[7]], pts[idx[8]]};
        const Double3 lo = raster::view_axes(v, v.box_min), hi = raster::view_axes(v, v.box_max);
        auto within = [&](const std::vector<Double3>& g) {
            for (const auto& p : g) {
                const double d = raster::view_axes(v, p).z;
                if (d - 4 * r < lo.z || d + 4 * r > hi.z)
                    return false;  // may have fallen back to a clamped box
            }
            return true;
        };
        if (within(g0)) CHECK(box_contains_balls(v, obbs.value(), 0, g0, r));
        if (within(g1)) CHECK(box_contains_balls(v, obbs.value(), 1, g1, r));
    }
}

TEST_CASE("Offset boxes: CullFace::Back draws the near faces and CullFace::Front the far faces") {
    for (const auto axis : {raster::Axis::X, raster::Axis::Y, raster::Axis::Z}) {
        CAPTURE(static_cast<int>(axis));
        // Depth extent 1000 world units: r (about 1.7 pixels = 1.7 units) stays inside the range.
        auto v = raster::make_ortho_view(axis, {0, 0, 0}, {1000, 1000, 1000}, 1000, 1000,
                                         raster::DepthFormat::D24);
        REQUIRE(v.ok());
        const std::vector<Double3> tri = {{400, 400, 400}, {600, 450, 500}, {450, 600, 600}};
        const std::vector<std::uint32_t> idx = {0, 1, 2};
        for (int kind = 0; kind < 2; ++kind) {
            auto m = kind == 0 ? raster::triangle_offset_boxes(v.value(), tri, idx)
                               : raster::object_offset_obbs(v.value(), tri, idx, 1);
            REQUIRE(m.ok());
            double depth[2] = {};
            for (int pass = 0; pass < 2; ++pass) {
                auto t = raster::DepthTarget::create(1000, 1000, raster::DepthFormat::D24);
                REQUIRE(t.ok());
                raster::CommandBatch b(1000, 1000);
                raster::DrawState s;
                s.cull_face = pass == 0 ? raster::CullFace::Back : raster::CullFace::Front;
                s.depth_func = raster::DepthFunc::Always;
                b.draw(m.value().view(), s);
                REQUIRE(raster::execute(t.value(), b).ok());
                depth[pass] = t.value().depth(500, 500);
            }
            // The triangle's own depth at the pixel centre (500.5, 500.5), from its view-space plane.
            Double3 q[3];
            for (int k = 0; k < 3; ++k) q[k] = raster::view_axes(v.value(), tri[static_cast<std::size_t>(k)]);
            const double px = 500.5, py = 500.5;
            const double det = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
            const double b1 = ((px - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (py - q[0].y)) / det;
            const double b2 = ((q[1].x - q[0].x) * (py - q[0].y) - (px - q[0].x) * (q[1].y - q[0].y)) / det;
            const double dtri = (q[0].z + b1 * (q[1].z - q[0].z) + b2 * (q[2].z - q[0].z)) / 1000.0;
            CAPTURE(kind);
            CAPTURE(dtri);
            CHECK(depth[0] < dtri);
            CHECK(depth[1] > dtri);
            if (kind == 1) {  // an oriented box hugs the triangle's plane
                CHECK(depth[0] > dtri - 0.02);
                CHECK(depth[1] < dtri + 0.02);
            } else {  // an axis-aligned one spans the triangle's depth range, 0.4 .. 0.6, grown by r
                CHECK(depth[0] < 0.4);
                CHECK(depth[1] > 0.6);
            }
        }
    }
}

// The largest overshoot of the clip depth range over boxes [first, last) of a whole call's output,
// read from its corners: the reference for the part calls' results.
double scan_overshoot(const raster::OffsetMesh& m, std::size_t first, std::size_t last) {
    double o = 0.0;
    for (std::size_t k = 8 * first; k < 8 * last; ++k) {
        const double z = m.vertices[k].z;
        o = std::max({o, z - 1.0, -1.0 - z});
    }
    return o;
}

bool same_bits(const raster::Float4& a, const raster::Float4& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST_CASE("Offset boxes in parts are the whole call's, bit for bit: the overshoot alone is a part's") {
    test::Rng rng(31);
    int beyond = 0, fitting = 0;  // ranges whose overshoot is positive / zero (both must be met)
    for (int rep = 0; rep < 200; ++rep) {
        CAPTURE(rep);
        const auto f = static_cast<raster::DepthFormat>(rep % 3);
        const raster::OrthoView v = random_view(rng, static_cast<raster::Axis>((rep / 3) % 3), f);
        // Points in a box three times the view's, so that some boxes lie wholly beyond a depth plane
        // (those are the ones that overshoot), some cross one and some fit.
        std::vector<Double3> pts;
        const int n = 3 + static_cast<int>(rng.below(60));
        const Double3 ext{v.box_max.x - v.box_min.x, v.box_max.y - v.box_min.y, v.box_max.z - v.box_min.z};
        for (int i = 0; i < n; ++i) {
            const double x = rng.uniform(v.box_min.x - ext.x, v.box_max.x + ext.x);
            const double y = rng.uniform(v.box_min.y - ext.y, v.box_max.y + ext.y);
            const double z = rng.uniform(v.box_min.z - ext.z, v.box_max.z + ext.z);
            pts.push_back({x, y, z});
        }
        // Triangles of nearby points (small boxes), a few spanning ones, and degenerate ones.
        std::vector<std::uint32_t> idx;
        const std::size_t tris = 1 + rng.below(40);
        for (std::size_t t = 0; t < tris; ++t) {
            const auto a = static_cast<std::uint32_t>(rng.below(static_cast<std::uint64_t>(n)));
            for (int k = 0; k < 3; ++k)
                idx.push_back(rng.below(4) == 0 ? static_cast<std::uint32_t>(rng.below(static_cast<std::uint64_t>(n)))
                                                : a);
        }
        const auto whole_boxes = raster::triangle_offset_boxes(v, pts, idx);
        REQUIRE(whole_boxes.ok());
        const auto tpb = static_cast<std::uint32_t>(1 + rng.below(5));
        const auto whole_obbs = raster::object_offset_obbs(v, pts, idx, tpb);
        REQUIRE(whole_obbs.ok());
        for (int kind = 0; kind < 2; ++kind) {
            CAPTURE(kind);
            const raster::OffsetMesh& whole = kind == 0 ? whole_boxes.value() : whole_obbs.value();
            const std::size_t boxes = whole.vertices.size() / 8;
            // Cut points, the parts run in reverse order into a mesh holding stale values first.
            std::vector<std::size_t> cuts = {0, boxes};
            for (int c = 0; c < 3; ++c) cuts.push_back(rng.below(boxes + 1));
            std::sort(cuts.begin(), cuts.end());
            raster::OffsetMesh parts;
            parts.vertices.assign(8 * boxes + 5, raster::Float4{7, 7, 7, 7});
            raster::size_offset_boxes(boxes, parts);
            REQUIRE(parts.vertices.size() == 8 * boxes);
            REQUIRE(parts.indices.size() == 36 * boxes);
            for (std::size_t c = cuts.size() - 1; c-- > 0;) {
                const std::size_t b0 = cuts[c], b1 = cuts[c + 1];
                const raster::Result<double> o =
                    kind == 0 ? raster::triangle_offset_boxes_part(v, pts, idx, b0, b1, parts)
                              : raster::object_offset_obbs_part(v, pts, idx, b0, b1, parts, tpb);
                REQUIRE(o.ok());
                CHECK(o.value() == scan_overshoot(whole, b0, b1));
                if (kind == 1) continue;
                const raster::Result<double> alone = raster::triangle_offset_boxes_overshoot(v, pts, idx, b0, b1);
                REQUIRE(alone.ok());
                CHECK(alone.value() == o.value());
                if (b1 > b0) (o.value() > 0.0 ? beyond : fitting) += 1;
            }
            // Box b's indices are the first box's shifted to its own corners [8 b, 8 b + 8).
            bool shifted = true;
            for (std::size_t k = 0; k < whole.indices.size(); ++k)
                shifted = shifted && whole.indices[k] == whole.indices[k % 36] + 8 * (k / 36) && whole.indices[k % 36] < 8;
            CHECK(shifted);
            bool same = parts.indices == whole.indices;
            for (std::size_t k = 0; k < whole.vertices.size(); ++k)
                same = same && same_bits(parts.vertices[k], whole.vertices[k]);
            CHECK(same);
        }
    }
    CHECK(beyond > 20);
    CHECK(fitting > 20);
}

TEST_CASE("Offset boxes in parts check their output and range, and validate their own triangles only") {
    auto v = raster::make_ortho_view(raster::Axis::Z, {0, 0, 0}, {1, 1, 1}, 8, 8, raster::DepthFormat::D24);
    REQUIRE(v.ok());
    const raster::OrthoView& view = v.value();
    const std::vector<Double3> pts = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, std::nan(""), 0}};
    const std::vector<std::uint32_t> idx = {0, 1, 2, 0, 1, 3, 0, 1, 9};
    // Whether the call failed with a message containing `what`.
    const auto fails_with = [](const raster::Result<double>& r, const std::string& what) {
        CAPTURE(r.ok() ? std::string("(ok)") : r.error().message);
        return !r.ok() && r.error().message.find(what) != std::string::npos;
    };
    raster::OffsetMesh out;
    CHECK(fails_with(raster::triangle_offset_boxes_part(view, pts, idx, 0, 1, out),
                     "not those of 3 boxes (size_offset_boxes)"));
    raster::size_offset_boxes(3, out);
    CHECK(fails_with(raster::triangle_offset_boxes_part(view, pts, idx, 2, 4, out),
                     "boxes [2, 4) are not a range of the 3 boxes"));
    CHECK(fails_with(raster::triangle_offset_boxes_overshoot(view, pts, idx, 1, 0), "boxes [1, 0) are not a range"));
    // Triangle 0 is fine, 1 has a NaN vertex, 2 an index beyond the list: each part names its own.
    CHECK(raster::triangle_offset_boxes_part(view, pts, idx, 0, 1, out).ok());
    CHECK(fails_with(raster::triangle_offset_boxes_part(view, pts, idx, 1, 3, out), "triangle 1: vertex 3 is not finite"));
    CHECK(fails_with(raster::triangle_offset_boxes_overshoot(view, pts, idx, 2, 3), "triangle 2: index 9 at position 8"));
    CHECK(raster::object_offset_obbs_part(view, pts, idx, 0, 1, out, 1).ok());
    // With 2 triangles per box the list has 2 boxes, not the 3 `out` holds.
    CHECK(fails_with(raster::object_offset_obbs_part(view, pts, idx, 0, 1, out, 2), "not those of 2 boxes"));
    CHECK(fails_with(raster::object_offset_obbs_part(view, pts, idx, 0, 1, out, 0), "triangles_per_box must be >= 1"));
    CHECK(fails_with(raster::triangle_offset_boxes_overshoot(view, pts, std::vector<std::uint32_t>{0, 1}, 0, 0),
                     "multiple of 3"));
}

TEST_CASE("Offset geometry and view helpers reject bad input naming what is wrong") {
    auto bad = raster::make_ortho_view(raster::Axis::Z, {0, 0, 1}, {1, 1, 1}, 8, 8, raster::DepthFormat::D24);
    REQUIRE_FALSE(bad.ok());
    CHECK(bad.error().message.find("empty along z") != std::string::npos);
    bad = raster::make_ortho_view(raster::Axis::Z, {0, 0, 0}, {1, std::nan(""), 1}, 8, 8,
                                  raster::DepthFormat::D24);
    REQUIRE_FALSE(bad.ok());
    CHECK(bad.error().message.find("not finite") != std::string::npos);
    bad = raster::make_ortho_view(raster::Axis::Z, {0, 0, 0}, {1, 1, 1}, 0, 8, raster::DepthFormat::D24);
    REQUIRE_FALSE(bad.ok());
    auto v = raster::make_ortho_view(raster::Axis::Z, {0, 0, 0}, {1, 1, 1}, 8, 8, raster::DepthFormat::D24);
    REQUIRE(v.ok());
    const std::vector<Double3> pts = {{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}};
    auto m = raster::triangle_offset_boxes(v.value(), pts, std::vector<std::uint32_t>{0, 1, 2});
    REQUIRE_FALSE(m.ok());
    CHECK(m.error().message.find("triangle 0: vertex 2 is not finite") != std::string::npos);
    m = raster::object_offset_obbs(v.value(), pts, std::vector<std::uint32_t>{0, 1, 7});
    REQUIRE_FALSE(m.ok());
    CHECK(m.error().message.find("index 7 at position 2") != std::string::npos);
    m = raster::triangle_offset_boxes(v.value(), pts, std::vector<std::uint32_t>{0, 1});
    REQUIRE_FALSE(m.ok());
    CHECK(m.error().message.find("multiple of 3") != std::string::npos);
    auto c = raster::ortho_view_to_clip(v.value(), pts);
    REQUIRE_FALSE(c.ok());
    CHECK(c.error().message.find("point 2") != std::string::npos);
}
