// cullide/src/hunt.cpp: generators, check, shrinking and classification of `cullide hunt` (hunt.h).
//
// Determinism: every generator draws from its own splitmix64 stream (Steele, Lea and Flood, "Fast
// splittable pseudorandom number generators", OOPSLA 2014) and uses only IEEE-exact operations
// (+ - * /, std::round, std::ldexp, bit masks), so a seed gives the same frame everywhere.
#include "cullide/hunt.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <iterator>
#include <map>
#include <optional>
#include <set>

#include "cullide/predicates.h"
#include "cullide/tri_tri.h"
#include "cullide/visibility.h"
#include "box_mesh.h"
#include "scene_math.h"

namespace cullide::hunt {
namespace {

// The scenes' SplitMix64 (scene_math.h) with the draws the generators use.
class Rng {
 public:
    explicit Rng(std::uint64_t seed) : g_(seed) {}
    std::uint64_t next() { return g_.next(); }
    double unit() { return g_.uniform01(); }  // [0, 1)
    double range(double lo, double hi) { return g_.uniform(lo, hi); }
    int below(int n) { return static_cast<int>(g_.below(static_cast<std::uint64_t>(n))); }
    int between(int lo, int hi) { return lo + below(hi - lo + 1); }  // both included
    bool coin(int percent = 50) { return below(100) < percent; }
    Vec3 point(double lo, double hi) { return {range(lo, hi), range(lo, hi), range(lo, hi)}; }

 private:
    det::SplitMix64 g_;
};

// A seed's stream for one purpose, independent of the others drawn from the same seed.
std::uint64_t mix(std::uint64_t seed, std::uint64_t salt) {
    return Rng(seed ^ (salt * 0xD1B54A32D192ED03ULL)).next();
}

Mesh triangles_mesh(std::string name, const std::vector<std::array<Vec3, 3>>& tris) {
    Mesh m;
    m.name = std::move(name);
    for (const auto& t : tris) {
        const auto base = static_cast<std::uint32_t>(m.positions.size());
        m.positions.insert(m.positions.end(), t.begin(), t.end());
        m.triangles.push_back({base, base + 1, base + 2});
    }
    return m;
}

// A quad in the plane coordinate[axis] = c, spanning [lo, hi] in the two other axes, as an n x n grid
// of cells (2 n^2 triangles, shared vertices).
Mesh wall(std::string name, int axis, double c, double lo, double hi, int n) {
    Mesh m;
    m.name = std::move(name);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            Vec3 p;
            p[axis] = c;
            p[u] = lo + (hi - lo) * static_cast<double>(i) / n;
            p[v] = lo + (hi - lo) * static_cast<double>(j) / n;
            m.positions.push_back(p);
        }
    const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return m;
}

Mesh tetra(std::string name, Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    Mesh m;
    m.name = std::move(name);
    m.positions = {a, b, c, d};
    m.triangles = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
    return m;
}

double grid_or_raw(Rng& r, bool grid, double lo, double hi) {
    if (!grid) return r.range(lo, hi);
    return std::round(r.range(lo, hi) * 4.0) / 4.0;
}

Frame soup(Rng& r) {
    Frame f;
    const int objects = r.between(2, 6);
    const bool grid = r.coin();
    for (int o = 0; o < objects; ++o) {
        const Vec3 c = r.point(-0.5, 0.5);
        const double size = r.range(0.1, 0.8);
        std::vector<std::array<Vec3, 3>> tris;
        const int n = r.between(1, 8);
        for (int t = 0; t < n; ++t) {
            std::array<Vec3, 3> tri;
            for (Vec3& p : tri)
                for (int k = 0; k < 3; ++k) p[k] = c[k] + grid_or_raw(r, grid, -size, size);
            tris.push_back(tri);
        }
        f.push_back(triangles_mesh("soup_" + std::to_string(o), tris));
    }
    return f;
}

// Two in-plane directions and the normal of a plane: an axis plane most of the time, else a random
// one (then "in the plane" is only as exact as rounding allows: near-coplanar by construction).
struct Plane {
    Vec3 origin, u, v, n;
};
Plane random_plane(Rng& r) {
    Plane p;
    p.origin = r.point(-0.3, 0.3);
    if (r.coin(70)) {
        const int axis = r.below(3);
        p.u[(axis + 1) % 3] = 1;
        p.v[(axis + 2) % 3] = 1;
        p.n[axis] = 1;
    } else {
        p.u = r.point(-1, 1);
        p.v = r.point(-1, 1);
        p.n = cross(p.u, p.v);
    }
    return p;
}
Vec3 on_plane(const Plane& p, double a, double b, double offset) {
    return p.origin + a * p.u + b * p.v + offset * p.n;
}

Frame coplanar(Rng& r) {
    const Plane p = random_plane(r);
    Frame f;
    const int objects = r.between(2, 4);
    for (int o = 0; o < objects; ++o) {
        // Touching exactly (offset 0) half the time, else a power-of-two gap or overlap.
        const double offset =
            o == 0 || r.coin() ? 0.0 : (r.coin() ? 1 : -1) * std::ldexp(1.0, -r.between(8, 40));
        std::vector<std::array<Vec3, 3>> tris;
        const int n = r.between(1, 4);
        for (int t = 0; t < n; ++t) {
            std::array<Vec3, 3> tri;
            for (Vec3& q : tri)
                q = on_plane(p, grid_or_raw(r, r.coin(), -0.6, 0.6), grid_or_raw(r, r.coin(), -0.6, 0.6),
                             offset);
            tris.push_back(tri);
        }
        if (r.coin(30)) {  // a triangle leaving the plane, so the object is not flat
            tris.push_back({on_plane(p, 0, 0, offset), on_plane(p, 0.3, 0, offset),
                            on_plane(p, 0.1, 0.1, offset + r.range(-0.5, 0.5))});
        }
        f.push_back(triangles_mesh("plane_" + std::to_string(o), tris));
    }
    return f;
}

Frame grazing(Rng& r) {
    Frame f;
    const bool grid = r.coin();
    std::array<Vec3, 3> a;
    for (Vec3& q : a)
        for (int k = 0; k < 3; ++k) q[k] = grid_or_raw(r, grid, -0.7, 0.7);
    f.push_back(triangles_mesh("base", {a}));
    const int others = r.between(1, 3);
    for (int o = 0; o < others; ++o) {
        const Vec3 away = r.point(-0.6, 0.6);
        switch (r.below(3)) {
            case 0:  // a tetrahedron whose apex is a vertex of the base triangle
                f.push_back(tetra("apex_" + std::to_string(o), a[static_cast<std::size_t>(r.below(3))],
                                  away + r.point(-0.2, 0.2), away + r.point(-0.2, 0.2),
                                  away + r.point(-0.2, 0.2)));
                break;
            case 1: {  // a triangle sharing an edge of the base, folded out of its plane
                const int e = r.below(3);
                f.push_back(triangles_mesh(
                    "hinge_" + std::to_string(o),
                    {{a[static_cast<std::size_t>(e)], a[static_cast<std::size_t>((e + 1) % 3)], away}}));
                break;
            }
            default: {  // boxes on a grid, touching face to face or at a corner or edge
                const double s = 0.25 * r.between(1, 3);
                Vec3 lo{0.25 * r.between(-3, 2), 0.25 * r.between(-3, 2), 0.25 * r.between(-3, 2)};
                Vec3 hi{lo.x + s, lo.y + s, lo.z + s};
                f.push_back(detail::box_mesh("box_" + std::to_string(o), lo, hi));
                Vec3 d{0, 0, 0};
                for (int k = 0; k < 3; ++k)
                    if (k == 0 || r.coin()) d[k] = s;
                f.push_back(detail::box_mesh("box_" + std::to_string(o) + "b", lo + d, hi + d));
                break;
            }
        }
    }
    return f;
}

Frame sub_pixel(Rng& r) {
    Frame f;
    const int axis = r.below(3);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double c = r.range(-0.3, 0.3);
    f.push_back(wall("sheet", axis, c, -0.8, 0.8, r.between(1, 3)));
    // Tilt the sheet now and then, in both directions, so that no axis view sees it edge-on.
    double tu = 0, tv = 0;
    if (r.coin(60)) {
        tu = r.range(-0.4, 0.4);
        tv = r.range(-0.4, 0.4);
        for (Vec3& p : f.back().positions) p[axis] = c + tu * p[u] + tv * p[v];
    }
    const int pokes = r.between(1, 3);
    for (int o = 0; o < pokes; ++o) {
        const double depth = std::ldexp(1.0, -r.between(7, 24));
        const double side = r.coin() ? 1.0 : -1.0;
        Vec3 tip;
        tip[u] = r.range(-0.6, 0.6);
        tip[v] = r.range(-0.6, 0.6);
        // The sheet's height under the tip (rounding errors are far below `depth`), then past it.
        tip[axis] = c + tu * tip[u] + tv * tip[v] - side * depth;
        Vec3 b = tip, c2 = tip, d = tip;
        const double h = r.range(0.05, 0.5);
        b[axis] += side * h;
        b[u] += r.range(-0.2, 0.2);
        c2[axis] += side * h;
        c2[v] += r.range(-0.2, 0.2);
        d[axis] += side * h;
        d[u] -= r.range(0, 0.2);
        d[v] -= r.range(0, 0.2);
        f.push_back(r.coin() ? tetra("poke_" + std::to_string(o), tip, b, c2, d)
                             : triangles_mesh("poke_" + std::to_string(o), {{tip, b, c2}}));
    }
    return f;
}

// A solid crossing the plane coordinate[axis] = c at (pu, pv) in the other two axes.
Mesh crosser(Rng& r, std::string name, int axis, double c, double pu, double pv) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double h = r.range(0.03, 0.3);
    Vec3 centre;
    centre[axis] = c + r.range(-0.5, 0.5) * h;
    centre[u] = pu;
    centre[v] = pv;
    if (r.coin(60)) {
        Vec3 lo{centre.x - h, centre.y - h, centre.z - h}, hi{centre.x + h, centre.y + h, centre.z + h};
        return detail::box_mesh(std::move(name), lo, hi);
    }
    return tetra(std::move(name), centre + r.point(-h, h), centre + r.point(-h, h), centre + r.point(-h, h),
                 centre + r.point(-h, h));
}

Frame edge_on(Rng& r) {
    Frame f;
    const int walls = r.between(1, 2);
    for (int w = 0; w < walls; ++w) {
        const int axis = r.below(3);
        const double c = grid_or_raw(r, r.coin(), -0.5, 0.5);
        f.push_back(wall("wall_" + std::to_string(w), axis, c, -1, 1, r.between(1, 2)));
        const int crossers = r.between(1, 2);
        for (int o = 0; o < crossers; ++o)
            f.push_back(crosser(r, "crosser_" + std::to_string(w) + "_" + std::to_string(o), axis, c,
                                r.range(-0.8, 0.8), r.range(-0.8, 0.8)));
    }
    return f;
}

Frame sliver(Rng& r) {
    Frame f;
    const int objects = r.between(2, 4);
    for (int o = 0; o < objects; ++o) {
        std::vector<std::array<Vec3, 3>> tris;
        const int n = r.between(1, 4);
        for (int t = 0; t < n; ++t) {
            const Vec3 a = r.point(-0.7, 0.7), b = r.point(-0.7, 0.7);
            const double thin = std::ldexp(1.0, -r.between(6, 30));
            Vec3 c;
            if (r.coin()) {  // needle: the third vertex next to the first
                c = a + thin * r.point(-1, 1);
            } else {  // cap: the third vertex next to the middle of a b
                c = 0.5 * (a + b) + thin * r.point(-1, 1);
            }
            tris.push_back({a, b, c});
        }
        if (r.coin()) {  // an ordinary triangle too, for the needles to cross
            tris.push_back({r.point(-0.7, 0.7), r.point(-0.7, 0.7), r.point(-0.7, 0.7)});
        }
        f.push_back(triangles_mesh("sliver_" + std::to_string(o), tris));
    }
    return f;
}

Frame extreme(Rng& r) {
    Frame f = r.coin() ? soup(r) : grazing(r);
    if (r.coin()) {
        const int e = r.coin() ? r.between(20, 200) : -r.between(20, 200);
        for (Mesh& m : f)
            for (Vec3& p : m.positions) p = {std::ldexp(p.x, e), std::ldexp(p.y, e), std::ldexp(p.z, e)};
    } else {
        const Vec3 t{r.range(-1e6, 1e6), r.range(-1e6, 1e6), r.range(-1e6, 1e6)};
        for (Mesh& m : f)
            for (Vec3& p : m.positions) p = p + t;
    }
    return f;
}

Frame room(Rng& r) {
    Frame f;
    const double half = 1.0;
    const int cells = r.between(1, 3);
    const bool one_object = r.coin(30);
    Mesh all;
    all.name = "room";
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            Mesh w = wall(std::string("wall_") + "xyz"[axis] + (side ? "+" : "-"), axis, side ? half : -half,
                          -half, half, cells);
            if (!one_object) {
                f.push_back(std::move(w));
                continue;
            }
            const auto base = static_cast<std::uint32_t>(all.positions.size());
            all.positions.insert(all.positions.end(), w.positions.begin(), w.positions.end());
            for (Tri t : w.triangles) all.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
        }
    if (one_object) f.push_back(std::move(all));
    const int movers = r.between(1, 3);
    for (int o = 0; o < movers; ++o) {
        const int axis = r.below(3);
        f.push_back(crosser(r, "mover_" + std::to_string(o), axis, r.coin() ? half : -half,
                            r.range(-0.7, 0.7), r.range(-0.7, 0.7)));
    }
    return f;
}

// Coordinates outside the exact predicates' range (a tiny value after scaling) become 0, so every
// generated frame is one the ground truth accepts.
void clamp_to_exact_range(Frame& f) {
    for (Mesh& m : f)
        for (Vec3& p : m.positions)
            for (int k = 0; k < 3; ++k)
                if (!predicate_coordinate_ok(p[k])) p[k] = 0.0;
}

double max_abs(const Frame& f) {
    double m = 0;
    for (const Mesh& o : f)
        for (const Vec3& p : o.positions) m = std::max({m, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
    return m;
}

// x rounded to a multiple of the power of two `step` (exact: scaling by a power of two is exact away
// from the ends of the range, and round gives an integer).
double snap(double x, double step) { return std::round(x / step) * step; }

Vec3 centre_of(const Mesh& m) {
    const Aabb b = mesh_bounds(m);
    return 0.5 * (b.lo + b.hi);
}

// ---- shrinking ----

// ddmin: the smallest subset of 0..n-1 found for which fails(subset) holds (1-minimal when the check
// budget and the stop function allow). `fails` is called with sorted index lists.
std::vector<std::size_t> ddmin(std::size_t n,
                               const std::function<bool(const std::vector<std::size_t>&)>& fails,
                               const std::function<bool()>& out_of_budget) {
    std::vector<std::size_t> items(n);
    for (std::size_t i = 0; i < n; ++i) items[i] = i;
    std::size_t granularity = 2;
    while (items.size() >= 2 && !out_of_budget()) {
        const std::size_t parts = std::min(granularity, items.size());
        std::vector<std::vector<std::size_t>> chunks(parts);
        for (std::size_t i = 0; i < items.size(); ++i) chunks[i * parts / items.size()].push_back(items[i]);
        bool reduced = false;
        for (const auto& c : chunks) {
            if (out_of_budget()) return items;
            if (fails(c)) {
                items = c;
                granularity = 2;
                reduced = true;
                break;
            }
        }
        if (!reduced && parts > 2) {
            for (std::size_t k = 0; k < parts && !reduced; ++k) {
                if (out_of_budget()) return items;
                std::vector<std::size_t> rest;
                for (std::size_t j = 0; j < parts; ++j)
                    if (j != k) rest.insert(rest.end(), chunks[j].begin(), chunks[j].end());
                std::sort(rest.begin(), rest.end());
                if (fails(rest)) {
                    items = std::move(rest);
                    granularity = std::max<std::size_t>(parts - 1, 2);
                    reduced = true;
                }
            }
        }
        if (!reduced) {
            if (parts >= items.size()) break;
            granularity = std::min(parts * 2, items.size());
        }
    }
    return items;
}

// The frame with only the listed (object, triangle) entries, objects left empty dropped, and each
// mesh's vertex list reduced to the vertices its triangles use (in first-use order).
Frame keep_triangles(const Frame& f, const std::vector<std::pair<std::size_t, std::size_t>>& all,
                     const std::vector<std::size_t>& keep) {
    std::vector<std::vector<std::size_t>> per(f.size());
    for (std::size_t i : keep) per[all[i].first].push_back(all[i].second);
    Frame out;
    for (std::size_t o = 0; o < f.size(); ++o) {
        if (per[o].empty()) continue;
        Mesh m;
        m.name = f[o].name;
        std::map<std::uint32_t, std::uint32_t> index;
        for (std::size_t t : per[o]) {
            Tri tri = f[o].triangles[t];
            for (std::uint32_t& v : tri) {
                auto [it, fresh] = index.emplace(v, static_cast<std::uint32_t>(m.positions.size()));
                if (fresh) m.positions.push_back(f[o].positions[v]);
                v = it->second;
            }
            m.triangles.push_back(tri);
        }
        out.push_back(std::move(m));
    }
    return out;
}

Frame map_coordinates(const Frame& f, const std::function<double(double)>& g) {
    Frame out = f;
    for (Mesh& m : out)
        for (Vec3& p : m.positions)
            for (int k = 0; k < 3; ++k) p[k] = g(p[k]);
    return out;
}

std::size_t degenerate_triangles(const Frame& f) {
    std::size_t n = 0;
    for (const Mesh& m : f)
        for (const Tri& t : m.triangles) {
            const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
            if (orient2d_drop(a, b, c, 0) == 0 && orient2d_drop(a, b, c, 1) == 0 &&
                orient2d_drop(a, b, c, 2) == 0)
                ++n;
        }
    return n;
}

bool same_coordinates(const Frame& a, const Frame& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (a[i].positions != b[i].positions) return false;
    return true;
}

// Simpler values to try in place of x, simplest first; only those in the exact range and unlike x.
std::vector<double> simpler_values(double x) {
    std::vector<double> c{0.0, std::round(x)};
    for (int j = 1; j <= 12; ++j) c.push_back(std::ldexp(std::round(std::ldexp(x, j)), -j));
    for (int bits : {1, 2, 4, 8, 12, 16, 24, 32, 40}) {
        const auto u = std::bit_cast<std::uint64_t>(x);
        const std::uint64_t mask = ~((std::uint64_t{1} << (52 - bits)) - 1);
        c.push_back(std::bit_cast<double>(u & mask));
    }
    std::vector<double> out;
    for (double v : c)
        if (v != x && std::isfinite(v) && predicate_coordinate_ok(v) &&
            std::find(out.begin(), out.end(), v) == out.end())
            out.push_back(v);
    return out;
}

}  // namespace

const char* to_string(Generator g) {
    switch (g) {
        case Generator::Soup:
            return "soup";
        case Generator::Coplanar:
            return "coplanar";
        case Generator::Grazing:
            return "grazing";
        case Generator::SubPixel:
            return "subpixel";
        case Generator::EdgeOn:
            return "edge-on";
        case Generator::Sliver:
            return "sliver";
        case Generator::Extreme:
            return "extreme";
        case Generator::Room:
            return "room";
    }
    return "?";
}

std::vector<Generator> all_generators() {
    return {Generator::Soup,   Generator::Coplanar, Generator::Grazing, Generator::SubPixel,
            Generator::EdgeOn, Generator::Sliver,   Generator::Extreme, Generator::Room};
}

std::vector<std::string> generator_names() {
    std::vector<std::string> names;
    for (Generator g : all_generators()) names.emplace_back(to_string(g));
    return names;
}

Result<Generator> parse_generator(std::string_view name) {
    for (Generator g : all_generators())
        if (name == to_string(g)) return g;
    std::string valid;
    for (const std::string& n : generator_names()) valid += (valid.empty() ? "" : ", ") + n;
    return Error{"unknown generator '" + std::string(name) + "' (valid: " + valid + ")"};
}

Frame generate(Generator g, std::uint64_t seed) {
    Rng r(mix(seed, static_cast<std::uint64_t>(g) + 1));
    Frame f;
    switch (g) {
        case Generator::Soup:
            f = soup(r);
            break;
        case Generator::Coplanar:
            f = coplanar(r);
            break;
        case Generator::Grazing:
            f = grazing(r);
            break;
        case Generator::SubPixel:
            f = sub_pixel(r);
            break;
        case Generator::EdgeOn:
            f = edge_on(r);
            break;
        case Generator::Sliver:
            f = sliver(r);
            break;
        case Generator::Extreme:
            f = extreme(r);
            break;
        case Generator::Room:
            f = room(r);
            break;
    }
    clamp_to_exact_range(f);
    return f;
}

Frame perturb(const Frame& base, std::uint64_t seed) {
    Rng r(mix(seed, 101));
    Frame f = base;
    if (f.empty()) return f;
    const double extent = std::max(max_abs(f), 1e-300);
    switch (r.below(4)) {
        case 0:  // as given
            break;
        case 1: {  // a few vertices moved by a small relative amount
            const int moves = r.between(1, 8);
            for (int i = 0; i < moves; ++i) {
                Mesh& m = f[static_cast<std::size_t>(r.below(static_cast<int>(f.size())))];
                if (m.positions.empty()) continue;
                Vec3& p =
                    m.positions[static_cast<std::size_t>(r.below(static_cast<int>(m.positions.size())))];
                p = p + std::ldexp(extent, -r.between(4, 30)) * r.point(-1, 1);
            }
            break;
        }
        case 2: {  // one object moved part of the way towards another
            if (f.size() < 2) break;
            const auto i = static_cast<std::size_t>(r.below(static_cast<int>(f.size())));
            auto j = static_cast<std::size_t>(r.below(static_cast<int>(f.size()) - 1));
            if (j >= i) ++j;
            const Vec3 d = r.range(0, 1) * (centre_of(f[j]) - centre_of(f[i]));
            for (Vec3& p : f[i].positions) p = p + d;
            break;
        }
        default: {  // every coordinate snapped to a coarse grid: exact contacts and ties
            const double step = std::ldexp(1.0, std::ilogb(extent) - r.between(3, 10));
            f = map_coordinates(f, [step](double x) { return snap(x, step); });
            break;
        }
    }
    clamp_to_exact_range(f);
    return f;
}

Result<Verdict> check(std::span<const Mesh> objects, const RunOptions& options, FrameContext& context) {
    Result<FrameResult> got = process_frame(objects, options, context);
    if (!got) return got.error();
    ExactOptions eo;
    eo.self = options.self;
    eo.threads = options.threads;
    Result<std::vector<TrianglePair>> truth = exact_pairs(objects, eo);
    if (!truth) return truth.error();
    const std::vector<TrianglePair>& t = truth.value();
    const std::vector<TrianglePair>& g = got.value().pairs;
    Verdict v;
    v.truth_pairs = t.size();
    std::set_difference(t.begin(), t.end(), g.begin(), g.end(), std::back_inserter(v.missed));
    std::set_difference(g.begin(), g.end(), t.begin(), t.end(), std::back_inserter(v.extra));
    return v;
}

Frame shrink(const Frame& failing, const RunOptions& options, FrameContext& context, const StopFn& stop,
             std::uint64_t max_checks, ShrinkStats* stats) {
    ShrinkStats local;
    ShrinkStats& s = stats ? *stats : local;
    const auto out_of_budget = [&] {
        if (s.checks >= max_checks || (stop && stop())) s.stopped = true;
        return s.stopped;
    };
    // A miss of a crossing pair (interpenetration, the serious kind) stays one: when the input has
    // one, every step must keep one, so the shrinker cannot trade it for a mere touching contact
    // (two walls of a room meeting at a corner) that happens to be missed too.
    const auto crossing_miss = [&](const Frame& f, const Verdict& v) {
        return std::any_of(v.missed.begin(), v.missed.end(), [&](const TrianglePair& p) {
            const Mesh &a = f[p.object_a], &b = f[p.object_b];
            const Tri &ta = a.triangles[p.triangle_a], &tb = b.triangles[p.triangle_b];
            return tri_tri_relation(a.positions[ta[0]], a.positions[ta[1]], a.positions[ta[2]],
                                    b.positions[tb[0]], b.positions[tb[1]],
                                    b.positions[tb[2]]) == TriRelation::Crossing;
        });
    };
    bool want_crossing = false;
    if (Result<Verdict> v0 = check(failing, options, context); v0)
        want_crossing = crossing_miss(failing, v0.value());
    const auto same_failure = [&](const Frame& f, const Verdict& v) {
        return v.failed() && (!want_crossing || crossing_miss(f, v));
    };
    const auto fails = [&](const Frame& f) {
        if (f.empty()) return false;
        ++s.checks;
        Result<Verdict> v = check(f, options, context);
        return v && same_failure(f, v.value());
    };
    Frame cur = failing;

    // Objects.
    {
        const std::vector<std::size_t> keep = ddmin(
            cur.size(),
            [&](const std::vector<std::size_t>& idx) {
                Frame f;
                for (std::size_t i : idx) f.push_back(cur[i]);
                return fails(f);
            },
            out_of_budget);
        Frame f;
        for (std::size_t i : keep) f.push_back(cur[i]);
        cur = std::move(f);
    }
    // Triangles, over the whole frame.
    {
        std::vector<std::pair<std::size_t, std::size_t>> all;
        for (std::size_t o = 0; o < cur.size(); ++o)
            for (std::size_t t = 0; t < cur[o].triangles.size(); ++t) all.emplace_back(o, t);
        const std::vector<std::size_t> keep = ddmin(
            all.size(),
            [&](const std::vector<std::size_t>& idx) { return fails(keep_triangles(cur, all, idx)); },
            out_of_budget);
        // ddmin returns a failing subset, or all of them; keep_triangles also drops unused vertices,
        // which is kept for a full set only when the frame still fails (and nothing stopped).
        Frame f = keep_triangles(cur, all, keep);
        if (keep.size() < all.size() || (!out_of_budget() && fails(f))) cur = std::move(f);
    }
    // A simpler coordinate must keep the failure of the same kind: the same reason (classify), and no
    // triangle newly degenerate (else every finding collapses to a point triangle on another one,
    // a true but uninteresting miss: the rasterizer covers nothing of a point).
    const auto reason_of = [&](const Frame& f) -> std::optional<Reason> {
        if (f.empty()) return std::nullopt;
        ++s.checks;
        Result<Verdict> v = check(f, options, context);
        if (!v || !same_failure(f, v.value())) return std::nullopt;
        Result<Reason> r = classify(f, v.value(), options, context);
        s.checks += 4;
        if (!r) return std::nullopt;
        return r.value();
    };
    const std::optional<Reason> reason = out_of_budget() ? std::nullopt : reason_of(cur);
    s.reason = reason.value_or(Reason::Unclassified);
    const std::size_t degenerate = degenerate_triangles(cur);
    const auto keeps_kind = [&](const Frame& f) {
        return reason && degenerate_triangles(f) <= degenerate && reason_of(f) == reason;
    };
    // Coordinates: the whole frame onto the coarsest dyadic grid (relative to its size) that keeps
    // the failure, then each distinct value on its own (every occurrence at once, so exact contacts
    // built from equal coordinates stay equal).
    if (!out_of_budget()) {
        const int top = std::ilogb(std::max(max_abs(cur), 1e-300));
        for (int bits = 1; bits <= 40 && !out_of_budget(); bits += (bits < 8 ? 1 : 4)) {
            const double step = std::ldexp(1.0, top - bits);
            Frame f = map_coordinates(cur, [step](double x) { return snap(x, step); });
            bool in_range = true;
            for (const Mesh& m : f)
                for (const Vec3& p : m.positions)
                    for (int k = 0; k < 3; ++k) in_range = in_range && predicate_coordinate_ok(p[k]);
            const bool unchanged = same_coordinates(f, cur);
            if (in_range && !unchanged && keeps_kind(f)) {
                cur = std::move(f);
                break;
            }
            if (in_range && unchanged) break;  // already on this grid: no coarser one was kept
        }
    }
    {
        std::set<double> seen;
        std::vector<double> values;
        for (const Mesh& m : cur)
            for (const Vec3& p : m.positions)
                for (int k = 0; k < 3; ++k)
                    if (seen.insert(p[k]).second) values.push_back(p[k]);
        for (double x : values) {
            for (double y : simpler_values(x)) {
                if (out_of_budget()) break;
                Frame f = map_coordinates(cur, [x, y](double c) { return c == x ? y : c; });
                if (keeps_kind(f)) {
                    cur = std::move(f);
                    break;
                }
            }
        }
    }
    return cur;
}

const char* to_string(Reason r) {
    switch (r) {
        case Reason::DepthQuantization:
            return "depth-quantization";
        case Reason::PixelTie:
            return "pixel-tie";
        case Reason::SubPixel:
            return "sub-pixel";
        case Reason::EdgeOn:
            return "edge-on";
        case Reason::Touching:
            return "touching";
        case Reason::Unclassified:
            return "unclassified";
    }
    return "?";
}

bool edge_on(const Mesh& m, std::size_t t, int axis) {
    const Tri& tri = m.triangles[t];
    return orient2d_drop(m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]], axis) == 0;
}

Result<Reason> classify(std::span<const Mesh> objects, const Verdict& verdict, const RunOptions& options,
                        FrameContext& context) {
    if (!verdict.extra.empty() || verdict.missed.empty() || options.method == Method::Exact)
        return Reason::Unclassified;
    const int res = options.resolution == 0 ? default_resolution(options.method) : options.resolution;
    const auto caught = [&](const RunOptions& o) -> Result<bool> {
        Result<Verdict> v = check(objects, o, context);
        if (!v) return v.error();
        return !v.value().failed();
    };
    if (options.depth_format != raster::DepthFormat::D32F) {
        RunOptions o = options;
        o.depth_format = raster::DepthFormat::D32F;
        Result<bool> c = caught(o);
        if (!c) return c.error();
        if (c.value()) return Reason::DepthQuantization;
    }
    for (int r : {res + 1, res - 1}) {
        if (r < kMinViewResolution || r > kMaxViewResolution) continue;
        RunOptions o = options;
        o.resolution = r;
        Result<bool> c = caught(o);
        if (!c) return c.error();
        if (c.value()) return Reason::PixelTie;
    }
    if (const int r = std::min(4 * res, kMaxViewResolution); r > res) {
        RunOptions o = options;
        o.resolution = r;
        Result<bool> c = caught(o);
        if (!c) return c.error();
        if (c.value()) return Reason::SubPixel;
    }
    const bool all_touching =
        std::all_of(verdict.missed.begin(), verdict.missed.end(), [&](const TrianglePair& p) {
            const Mesh &a = objects[p.object_a], &b = objects[p.object_b];
            const Tri &ta = a.triangles[p.triangle_a], &tb = b.triangles[p.triangle_b];
            const TriRelation rel =
                tri_tri_relation(a.positions[ta[0]], a.positions[ta[1]], a.positions[ta[2]],
                                 b.positions[tb[0]], b.positions[tb[1]], b.positions[tb[2]]);
            return rel == TriRelation::Touching || rel == TriRelation::CoplanarOverlap;
        });
    if (all_touching) return Reason::Touching;
    const bool all_edge_on =
        std::all_of(verdict.missed.begin(), verdict.missed.end(), [&](const TrianglePair& p) {
            for (int axis = 0; axis < 3; ++axis)
                if (edge_on(objects[p.object_a], p.triangle_a, axis) ||
                    edge_on(objects[p.object_b], p.triangle_b, axis))
                    return true;
            return false;
        });
    if (all_edge_on) return Reason::EdgeOn;
    return Reason::Unclassified;
}

}  // namespace cullide::hunt
