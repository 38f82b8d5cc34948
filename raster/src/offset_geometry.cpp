// offset_geometry.cpp: R-CULLIDE's offset boxes (Govindaraju, Lin, Manocha 2004/2006) as triangles.
// See raster/offset_geometry.h.
#include "raster/offset_geometry.h"

#include "float_step.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

namespace raster {
namespace {

// Corner k = bit 0: +axis 0, bit 1: +axis 1, bit 2: +axis 2. Wound with inward right-hand normals in
// a right-handed (axis 0, axis 1, axis 2) frame: the view map keeps orientation and looks along +d,
// so the faces towards the viewer come out counter-clockwise in the window (front with CCW).
constexpr std::uint32_t kBox[36] = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
                                    2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};

double comp(const Double3& p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }

// A clip coordinate beyond +-2^64 lies far outside the clip volume, and clamp_box pulls every box
// that crosses it back to +-2 (x, y) or +-1 (z); so saturating at +-2^64 before the float conversion
// changes no drawn pixel, keeps an entirely outside box outside, and keeps a very anisotropic view
// (an extent of 2^-195 along one axis, a fuzzer finding) from overflowing float. The bound is far
// from +-1 on purpose: cullide.cpp widens the depth range by the solids' measured overshoot, which a
// bound near 1 would cap (a second fuzzer finding: 8 widening steps were not enough).
double saturate(double v) { return std::clamp(v, -0x1p64, 0x1p64); }

float round_down(double v) {
    v = saturate(v);
    float f = static_cast<float>(v);
    if (static_cast<double>(f) > v) f = detail::next_down(f);
    return f;
}
float round_up(double v) {
    v = saturate(v);
    float f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = detail::next_up(f);
    return f;
}

// GL clips at the near and far planes (no depth clamp), and a box grown by r often reaches past
// both: its near and far faces would vanish. Clamping an axis-aligned box's clip z to [-1, 1] keeps
// it conservative: the near face moves to depth 0 (written: <= every true depth) and the far face to
// depth 1 (queried: >= every true depth), and nothing outside [0, 1] is visible in the first place.
// x and y are clamped to [-2, 2] for precision, not visibility: GL's float clipper interpolates
// with errors relative to the coordinates, and a box reaching 1e8 would be clipped by whole pixels
// (a fuzzer finding); the part beyond +-1 is never drawn, so the clamped box covers the same pixels.
constexpr float kXYClamp = 2.0f;
void clamp_box(float* cmin, float* cmax) {
    const float lim[3] = {kXYClamp, kXYClamp, 1.0f};
    for (int k = 0; k < 3; ++k) {
        if (cmin[k] < -lim[k] && cmax[k] >= -lim[k]) cmin[k] = -lim[k];
        if (cmax[k] > lim[k] && cmin[k] <= lim[k]) cmax[k] = lim[k];
    }
}

struct Frame {
    Double3 lo;
    Double3 scale;  // clip = (a - lo) * scale - 1 per view axis
};
Frame frame_of(const OrthoView& view) {
    Frame f;
    f.lo = view_axes(view, view.box_min);
    const Double3 hi = view_axes(view, view.box_max);
    f.scale = {2.0 / (hi.x - f.lo.x), 2.0 / (hi.y - f.lo.y), 2.0 / (hi.z - f.lo.z)};
    return f;
}

// The checks of indices [first, last) of the list (positions named as in the whole list).
Status validate_range(std::span<const Double3> vertices, std::span<const std::uint32_t> indices, std::size_t first,
                      std::size_t last, const char* what) {
    for (std::size_t k = first; k < last; ++k) {
        if (indices[k] >= vertices.size())
            return Error{std::string(what) + ": triangle " + std::to_string(k / 3) + ": index " +
                         std::to_string(indices[k]) + " at position " + std::to_string(k) +
                         " is beyond the vertex list (size " + std::to_string(vertices.size()) + ")"};
        const Double3& p = vertices[indices[k]];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return Error{std::string(what) + ": triangle " + std::to_string(k / 3) + ": vertex " +
                         std::to_string(indices[k]) + " is not finite"};
    }
    return {};
}

Status check_count(std::span<const std::uint32_t> indices, const char* what) {
    if (indices.size() % 3 != 0)
        return Error{std::string(what) + ": index count " + std::to_string(indices.size()) +
                     " is not a multiple of 3"};
    return {};
}

Status validate_mesh(std::span<const Double3> vertices, std::span<const std::uint32_t> indices,
                     const char* what) {
    if (Status s = check_count(indices, what); !s) return s;
    return validate_range(vertices, indices, 0, indices.size(), what);
}

// A part call's check of its box range.
Status check_range(std::size_t total_boxes, std::size_t first_box, std::size_t last_box, const char* what) {
    if (first_box > last_box || last_box > total_boxes)
        return Error{std::string(what) + ": boxes [" + std::to_string(first_box) + ", " + std::to_string(last_box) +
                     ") are not a range of the " + std::to_string(total_boxes) + " boxes"};
    return {};
}

// A part call's checks of `out` and its box range.
Status check_part(const OffsetMesh& out, std::size_t total_boxes, std::size_t first_box, std::size_t last_box,
                  const char* what) {
    if (out.vertices.size() != 8 * total_boxes || out.indices.size() != 36 * total_boxes)
        return Error{std::string(what) + ": the output holds " + std::to_string(out.vertices.size()) + " vertices and " +
                     std::to_string(out.indices.size()) + " indices, not those of " + std::to_string(total_boxes) +
                     " boxes (size_offset_boxes)"};
    return check_range(total_boxes, first_box, last_box, what);
}

// How far a clip depth lies beyond [-1, 1] (0 inside).
double depth_overshoot(float z) {
    return std::max({0.0, static_cast<double>(z) - 1.0, -1.0 - static_cast<double>(z)});
}

// Box b's corners and indices into their places in `out` (sized for every box); returns the
// corners' overshoot of the clip depth range.
double store_box(OffsetMesh& out, std::size_t b, const std::array<Float4, 8>& corners) {
    std::copy(corners.begin(), corners.end(), out.vertices.begin() + static_cast<std::ptrdiff_t>(8 * b));
    const auto base = static_cast<std::uint32_t>(8 * b);
    std::uint32_t* idx = out.indices.data() + 36 * b;
    for (std::size_t k = 0; k < 36; ++k) idx[k] = base + kBox[k];
    double overshoot = 0.0;
    for (const Float4& v : corners) overshoot = std::max(overshoot, depth_overshoot(v.z));
    return overshoot;
}

// view_axes (transform.h) with the view's axis order decoded once (view_axis_indices): the
// function decodes it on every call, in another translation unit (2.5% of a leaves /
// rcullide-offset frame).
struct AxisMap {
    int u = 0, v = 0, d = 0;
    explicit AxisMap(const OrthoView& view) { view_axis_indices(view.axis, u, v, d); }
    [[nodiscard]] Double3 operator()(const Double3& p) const {
        const double c[3] = {p.x, p.y, p.z};
        return Double3{c[u], c[v], c[d]};
    }
};

Double3 sub(const Double3& a, const Double3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Double3 cross(const Double3& a, const Double3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot(const Double3& a, const Double3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Double3 normalized(const Double3& a) {
    const double n = std::sqrt(dot(a, a));
    return {a.x / n, a.y / n, a.z / n};
}

}  // namespace

double offset_radius(const OrthoView& view) {
    const ViewCell c = view_cell(view);
    const double p = std::max({2.0 * c.dx, 2.0 * c.dy, 2.0 * c.dz});
    // sqrt(3) / 2 rounded up, then one ulp up for the product's rounding.
    const double r = p * 0.86602540378443872;
    return std::nextafter(r, HUGE_VAL);
}

namespace {

// Axis k of a triangle box's clip bounds before their outward rounding: l, h, and the margins ml,
// mh that push them out (see write_triangle_boxes). The margins' product by 2^-49 is exact, so a
// compiler that fuses it into the subtraction rounds the same.
struct AxisBounds {
    double l, h, ml, mh;
};
AxisBounds axis_bounds(const Frame& f, double r, const Double3& lo, const Double3& hi, int k) {
    const double scale = comp(f.scale, k);
    const double l = (comp(lo, k) - r - comp(f.lo, k)) * scale - 1.0;
    const double h = (comp(hi, k) + r - comp(f.lo, k)) * scale - 1.0;
    const double big_l = (std::fabs(comp(lo, k)) + r + std::fabs(comp(f.lo, k))) * scale;
    const double big_h = (std::fabs(comp(hi, k)) + r + std::fabs(comp(f.lo, k))) * scale;
    return {l, h, (big_l + std::fabs(l) + 1.0) * 0x1p-49, (big_h + std::fabs(h) + 1.0) * 0x1p-49};
}

// Boxes [first, last) of (a) (= triangles), on validated input: their overshoot, and with Store
// the boxes into `out`.
template <bool Store>
Result<double> write_triangle_boxes(const OrthoView& view, std::span<const Double3> vertices,
                                    std::span<const std::uint32_t> indices, std::size_t first, std::size_t last,
                                    OffsetMesh* out) {
    const Frame f = frame_of(view);
    const double r = offset_radius(view);
    const AxisMap to_view(view);
    double overshoot = 0.0;
    for (std::size_t t = 3 * first; t < 3 * last; t += 3) {
        Double3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        for (int k = 0; k < 3; ++k) {
            const Double3 a = to_view(vertices[indices[t + static_cast<std::size_t>(k)]]);
            lo = {std::min(lo.x, a.x), std::min(lo.y, a.y), std::min(lo.z, a.z)};
            hi = {std::max(hi.x, a.x), std::max(hi.y, a.y), std::max(hi.z, a.z)};
        }
        // Clip bounds in double, then pushed out by more than their rounding error, then rounded
        // outward to float. The error is not relative to the result: a - r and (a - r) - lo each
        // err by u |operand| (u = 2^-53), the view's scale 2 / (hi - lo) by 2u, the product and the
        // final "- 1" by u each. With M = (|a| + r + |lo|) * scale (the largest magnitude met
        // before the "- 1"), the total is below 6u M + u |c|; the margin (M + |c| + 1) 2^-49 = 16u
        // (M + |c| + 1) covers it with room for its own rounding. (A margin relative to |c| alone
        // is too small when the view box lies far from the origin: the aarch64 run found one.)
        if constexpr (!Store) {
            // Only the overshoot is wanted, and a box adds to it only when it lies wholly beyond
            // a depth plane: cmin <= l and cmax >= h (with margins >= 0, the roundings go down and
            // up, saturation clamps beyond +-2^64), so with l <= 1 and h >= -1 in depth, clamp_box
            // leaves both depths in [-1, 1] and the box adds nothing. These are the same l and h
            // as below, and nothing below fails unless a rounding's argument is NaN (saturation
            // keeps the rest finite), so skipping the rest of such a box changes neither the
            // result nor the error.
            bool nan = false, inside = false;
            for (int k = 0; k < 3; ++k) {
                const AxisBounds b = axis_bounds(f, r, lo, hi, k);
                nan = nan || std::isnan(b.l - b.ml) || std::isnan(b.h + b.mh);
                inside = b.ml >= 0.0 && b.mh >= 0.0 && b.l <= 1.0 && b.h >= -1.0;  // kept for k = 2, the depth
            }
            if (!nan && inside) continue;
        }
        float cmin[3], cmax[3];
        for (int k = 0; k < 3; ++k) {
            const AxisBounds b = axis_bounds(f, r, lo, hi, k);
            cmin[k] = round_down(b.l - b.ml);
            cmax[k] = round_up(b.h + b.mh);
            if (!std::isfinite(cmin[k]) || !std::isfinite(cmax[k]))
                return Error{"triangle_offset_boxes: triangle " + std::to_string(t / 3) +
                             ": its box overflows float in clip space"};
        }
        clamp_box(cmin, cmax);
        if constexpr (!Store) {  // store_box's overshoot: the corners' depths are cmin[2] and cmax[2]
            overshoot = std::max({overshoot, depth_overshoot(cmin[2]), depth_overshoot(cmax[2])});
            continue;
        }
        std::array<Float4, 8> corners{};
        for (int c = 0; c < 8; ++c)
            corners[static_cast<std::size_t>(c)] = {(c & 1) ? cmax[0] : cmin[0], (c & 2) ? cmax[1] : cmin[1],
                                                    (c & 4) ? cmax[2] : cmin[2], 1.0f};
        overshoot = std::max(overshoot, store_box(*out, t / 3, corners));
    }
    return overshoot;
}

}  // namespace

Result<OffsetMesh> triangle_offset_boxes(const OrthoView& view, std::span<const Double3> vertices,
                                         std::span<const std::uint32_t> indices) {
    if (Status s = validate_mesh(vertices, indices, "triangle_offset_boxes"); !s) return s.error();
    OffsetMesh out;
    size_offset_boxes(indices.size() / 3, out);
    if (Result<double> w = write_triangle_boxes<true>(view, vertices, indices, 0, indices.size() / 3, &out); !w)
        return w.error();
    return out;
}

Result<double> triangle_offset_boxes_part(const OrthoView& view, std::span<const Double3> vertices,
                                          std::span<const std::uint32_t> indices, std::size_t first_box,
                                          std::size_t last_box, OffsetMesh& out) {
    constexpr const char* kWhat = "triangle_offset_boxes";
    if (Status s = check_count(indices, kWhat); !s) return s.error();
    if (Status s = check_part(out, indices.size() / 3, first_box, last_box, kWhat); !s) return s.error();
    if (Status s = validate_range(vertices, indices, 3 * first_box, 3 * last_box, kWhat); !s) return s.error();
    return write_triangle_boxes<true>(view, vertices, indices, first_box, last_box, &out);
}

Result<double> triangle_offset_boxes_overshoot(const OrthoView& view, std::span<const Double3> vertices,
                                               std::span<const std::uint32_t> indices, std::size_t first_box,
                                               std::size_t last_box) {
    constexpr const char* kWhat = "triangle_offset_boxes";
    if (Status s = check_count(indices, kWhat); !s) return s.error();
    if (Status s = check_range(indices.size() / 3, first_box, last_box, kWhat); !s) return s.error();
    if (Status s = validate_range(vertices, indices, 3 * first_box, 3 * last_box, kWhat); !s) return s.error();
    return write_triangle_boxes<false>(view, vertices, indices, first_box, last_box, nullptr);
}

namespace {

std::size_t obb_count(std::size_t triangles, std::uint32_t triangles_per_box) {
    return (triangles + triangles_per_box - 1) / triangles_per_box;
}

// Boxes [first, last) of (b) into `out`, on validated input; their overshoot.
Result<double> write_obbs(const OrthoView& view, std::span<const Double3> vertices,
                          std::span<const std::uint32_t> indices, std::size_t first, std::size_t last,
                          OffsetMesh& out, std::uint32_t triangles_per_box) {
    const Frame f = frame_of(view);
    const double r = offset_radius(view);
    const AxisMap to_view(view);
    const std::size_t tris = indices.size() / 3;
    double overshoot = 0.0;
    for (std::size_t g0 = first * triangles_per_box; g0 < std::min(tris, last * triangles_per_box);
         g0 += triangles_per_box) {
        const std::size_t g1 = std::min(tris, g0 + triangles_per_box);
        // Frame candidates, in view coordinates (u, v, d), each right-handed and Gram-Schmidt
        // orthonormalized (a0, a1, a2 = a0 x a1): the view axes, and for the group's largest
        // triangle its normal with each of its three edges. The candidate whose box (grown by r)
        // has the least volume wins (the first on ties), so a box-shaped group gets its own box.
        std::size_t largest = g1;
        double best_area = 0.0;
        for (std::size_t t = g0; t < g1; ++t) {
            const Double3 p0 = to_view(vertices[indices[3 * t]]);
            const Double3 n = cross(sub(to_view(vertices[indices[3 * t + 1]]), p0),
                                    sub(to_view(vertices[indices[3 * t + 2]]), p0));
            const double area2 = dot(n, n);
            if (area2 > best_area && std::isfinite(area2)) {
                best_area = area2;
                largest = t;
            }
        }
        std::array<std::array<Double3, 3>, 4> cand{};
        int ncand = 0;
        cand[static_cast<std::size_t>(ncand++)] = {Double3{1, 0, 0}, Double3{0, 1, 0}, Double3{0, 0, 1}};
        if (largest < g1) {
            const Double3 p[3] = {to_view(vertices[indices[3 * largest]]),
                                  to_view(vertices[indices[3 * largest + 1]]),
                                  to_view(vertices[indices[3 * largest + 2]])};
            const Double3 b2 = normalized(cross(sub(p[1], p[0]), sub(p[2], p[0])));
            for (int k = 0; k < 3; ++k) {
                const Double3 b0 = normalized(sub(p[(k + 1) % 3], p[k]));
                const Double3 b1 = normalized(cross(b2, b0));
                const Double3 c2 = cross(b0, b1);
                if (!std::isfinite(b0.x + b0.y + b0.z + b1.x + b1.y + b1.z + c2.x + c2.y + c2.z)) continue;
                cand[static_cast<std::size_t>(ncand++)] = {b0, b1, c2};
            }
        }
        Double3 a0{1, 0, 0}, a1{0, 1, 0}, a2{0, 0, 1};
        double best_volume = HUGE_VAL;
        for (int ci = 0; ci < ncand; ++ci) {
            const auto& ax = cand[static_cast<std::size_t>(ci)];
            double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
            for (std::size_t k = 3 * g0; k < 3 * g1; ++k) {
                const Double3 q = to_view(vertices[indices[k]]);
                for (std::size_t a = 0; a < 3; ++a) {
                    const double d = dot(q, ax[a]);
                    lo[a] = std::min(lo[a], d);
                    hi[a] = std::max(hi[a], d);
                }
            }
            const double volume = (hi[0] - lo[0] + 2 * r) * (hi[1] - lo[1] + 2 * r) * (hi[2] - lo[2] + 2 * r);
            if (volume < best_volume) {
                best_volume = volume;
                a0 = ax[0];
                a1 = ax[1];
                a2 = ax[2];
            }
        }
        const Double3 axes[3] = {a0, a1, a2};
        // Extents along the frame, exact radius r added; then grown by g, which covers the frame's
        // departure from orthonormality (<= 2^-40 relative) and the float rounding of the corners.
        double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        double radius = 0.0;
        for (std::size_t k = 3 * g0; k < 3 * g1; ++k) {
            const Double3 p = to_view(vertices[indices[k]]);
            for (int a = 0; a < 3; ++a) {
                const double d = dot(p, axes[a]);
                lo[a] = std::min(lo[a], d);
                hi[a] = std::max(hi[a], d);
            }
            radius = std::max({radius, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
        }
        auto corners_for = [&](double grow, double& cmax) {
            std::array<Double4, 8> c{};
            cmax = 1.0;
            for (int k = 0; k < 8; ++k) {
                Double3 p{0, 0, 0};
                for (int a = 0; a < 3; ++a) {
                    const double t = (k & (1 << a)) ? hi[a] + r + grow : lo[a] - r - grow;
                    p = {p.x + t * axes[a].x, p.y + t * axes[a].y, p.z + t * axes[a].z};
                }
                Double4& q = c[static_cast<std::size_t>(k)];
                q.x = (p.x - f.lo.x) * f.scale.x - 1.0;
                q.y = (p.y - f.lo.y) * f.scale.y - 1.0;
                q.z = (p.z - f.lo.z) * f.scale.z - 1.0;
                cmax = std::max({cmax, std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
            }
            return c;
        };
        double cmax = 1.0;
        (void)corners_for(0.0, cmax);
        const double inv_scale = std::max({1.0 / f.scale.x, 1.0 / f.scale.y, 1.0 / f.scale.z});
        const double grow =
            8.0 * cmax * 0x1p-24 * inv_scale +
            0x1p-40 * (radius + r + std::fabs(f.lo.x) + std::fabs(f.lo.y) + std::fabs(f.lo.z));
        const std::array<Double4, 8> c = corners_for(grow, cmax);
        std::array<Float4, 8> corners{};
        bool beyond_depth = false;
        for (const Double4& q : c)
            beyond_depth =
                beyond_depth || q.z < -1.0 || q.z > 1.0 || std::fabs(q.x) > 2.0 || std::fabs(q.y) > 2.0;
        if (beyond_depth) {
            // An oriented box cannot be clamped and stay a box: use its axis-aligned bounding box
            // instead (it contains the oriented one), clamped as above.
            float bmin[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF}, bmax[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
            for (const Double4& q : c) {
                const double v[3] = {q.x, q.y, q.z};
                for (int k = 0; k < 3; ++k) {
                    bmin[k] = std::min(bmin[k], round_down(v[k]));
                    bmax[k] = std::max(bmax[k], round_up(v[k]));
                }
            }
            clamp_box(bmin, bmax);
            for (int k = 0; k < 8; ++k)
                corners[static_cast<std::size_t>(k)] = {(k & 1) ? bmax[0] : bmin[0],
                                                        (k & 2) ? bmax[1] : bmin[1],
                                                        (k & 4) ? bmax[2] : bmin[2], 1.0f};
        }
        for (std::size_t k = 0; k < 8; ++k) {
            if (!beyond_depth)
                corners[k] = {static_cast<float>(c[k].x), static_cast<float>(c[k].y),
                              static_cast<float>(c[k].z), 1.0f};
            if (!std::isfinite(corners[k].x) || !std::isfinite(corners[k].y) || !std::isfinite(corners[k].z))
                return Error{"object_offset_obbs: box of triangles " + std::to_string(g0) + ".." +
                             std::to_string(g1 - 1) + " overflows float in clip space"};
        }
        overshoot = std::max(overshoot, store_box(out, g0 / triangles_per_box, corners));
    }
    return overshoot;
}

}  // namespace

Result<OffsetMesh> object_offset_obbs(const OrthoView& view, std::span<const Double3> vertices,
                                      std::span<const std::uint32_t> indices,
                                      std::uint32_t triangles_per_box) {
    if (Status s = validate_mesh(vertices, indices, "object_offset_obbs"); !s) return s.error();
    if (triangles_per_box < 1) return Error{"object_offset_obbs: triangles_per_box must be >= 1"};
    OffsetMesh out;
    const std::size_t boxes = obb_count(indices.size() / 3, triangles_per_box);
    size_offset_boxes(boxes, out);
    if (Result<double> w = write_obbs(view, vertices, indices, 0, boxes, out, triangles_per_box); !w)
        return w.error();
    return out;
}

Result<double> object_offset_obbs_part(const OrthoView& view, std::span<const Double3> vertices,
                                       std::span<const std::uint32_t> indices, std::size_t first_box,
                                       std::size_t last_box, OffsetMesh& out, std::uint32_t triangles_per_box) {
    constexpr const char* kWhat = "object_offset_obbs";
    if (Status s = check_count(indices, kWhat); !s) return s.error();
    if (triangles_per_box < 1) return Error{"object_offset_obbs: triangles_per_box must be >= 1"};
    const std::size_t tris = indices.size() / 3;
    if (Status s = check_part(out, obb_count(tris, triangles_per_box), first_box, last_box, kWhat); !s)
        return s.error();
    if (Status s = validate_range(vertices, indices, 3 * std::min(tris, first_box * triangles_per_box),
                                  3 * std::min(tris, last_box * triangles_per_box), kWhat);
        !s)
        return s.error();
    return write_obbs(view, vertices, indices, first_box, last_box, out, triangles_per_box);
}

void size_offset_boxes(std::size_t boxes, OffsetMesh& out) {
    out.vertices.resize(8 * boxes);
    out.indices.resize(36 * boxes);
}

}  // namespace raster
