// triangle_setup.cpp: llvmpipe's triangle front end (clipping, viewport, 16.8 snapping, edge and
// depth-plane setup: setup_triangle). See pipeline.h.
#include "pipeline.h"

#include "float_step.h"
#include "setup_simd.h"

#include "raster/command_batch.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace raster::detail {
namespace {

// A vertex as the draw module carries it: the clip-space position (used for clipping) and the
// window position computed from it (used by setup).
struct ClipVertex {
    float clip[4];
    float win[3];
};

// A vertex through the clip test (its mask) and the viewport, once for all its triangles
// (setup_range_for).
struct TransformedVertex {
    ClipVertex v;
    unsigned mask;
};

constexpr int kFixedOrder = 8;  // 16.8: 1/256 pixel
constexpr float kFixedOne = 256.0f;

// Plane i of the clip volume as draw_context.c lists them: dot(clip, plane) >= 0 is inside.
constexpr float kPlanes[6][4] = {
    {-1.0f, 0.0f, 0.0f, 1.0f},  // x <= w
    {1.0f, 0.0f, 0.0f, 1.0f},   // x >= -w
    {0.0f, -1.0f, 0.0f, 1.0f},  // y <= w
    {0.0f, 1.0f, 0.0f, 1.0f},   // y >= -w
    {0.0f, 0.0f, 1.0f, 1.0f},   // z >= -w (near, GL depth mode)
    {0.0f, 0.0f, -1.0f, 1.0f},  // z <= w (far)
};
// The near plane in the [0, 1] depth mode (gallium's clip_halfz, which lavapipe always sets).
constexpr float kNearPlaneHalfZ[4] = {0.0f, 0.0f, 1.0f, 0.0f};  // z >= 0

// What the front end does differently under each rule set (raster.h). Both sets share everything
// else: pixel centres at +0.5 (half_pixel_center), 16.8 snapping, no guard band, the depth plane.
struct RuleSet {
    bool half_z;              // clip 0 <= z <= w, z_w = z/w (scale 1, bias 0); else -w <= z <= w, z/w * 0.5 + 0.5
    bool bottom_edge_rule;    // llvmpipe's bottom_edge_rule (the horizontal-edge tie)
    bool lp_positive_is_ccw;  // llvmpipe's positive area is the API's counter-clockwise
    bool provoking_first;     // flatshade_first: the provoking vertex is a triangle's first (Vulkan) or last (GL)
};

// Vulkan as lavapipe sets gallium's rasterizer state: clip_halfz, flatshade_first (Vulkan's
// provoking vertex is the first), front_ccw straight from VkFrontFace, which reads Vulkan's
// counter-clockwise (y down) as llvmpipe's positive area, the opposite of GL on a y-up FBO; the same
// fill convention as GL (no bottom_edge_rule: both APIs' top/bottom edge is at framebuffer y's low
// end). Pinned against lavapipe by tests/raster/vulkan_conformance_test.cpp.
constexpr RuleSet rule_set(RasterRules rules) {
    if (rules == RasterRules::Vulkan) return {true, kBottomEdgeRule, !kLpPositiveIsCcw, true};
    return {false, kBottomEdgeRule, kLpPositiveIsCcw, false};
}

// Left to right, as the C compiler evaluates it (no contraction on baseline x86-64).
float dot4(const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]; }

const float* clip_plane(const RuleSet& r, int plane) {
    return plane == 4 && r.half_z ? kNearPlaneHalfZ : kPlanes[plane];
}

// The clip mask bits, as the vertex shader computes them (same plane order).
template <bool HalfZ>
unsigned clip_mask(const float* p) {
    unsigned m = 0;
    if (p[0] > p[3]) m |= 1u;
    if (0.0f > p[0] + p[3]) m |= 2u;
    if (p[1] > p[3]) m |= 4u;
    if (0.0f > p[1] + p[3]) m |= 8u;
    if (HalfZ ? 0.0f > p[2] : 0.0f > p[2] + p[3]) m |= 16u;
    if (p[2] > p[3]) m |= 32u;
    return m;
}

struct ViewportXform {
    float scale[3];
    float translate[3];
};

ViewportXform make_xform(const RuleSet& r, const Viewport& vp) {
    ViewportXform x{};
    const float hw = static_cast<float>(vp.width) * 0.5f;
    const float hh = static_cast<float>(vp.height) * 0.5f;
    x.scale[0] = hw;
    x.scale[1] = hh;
    x.scale[2] = r.half_z ? 1.0f : 0.5f;  // Vulkan: maxDepth - minDepth; GL: (far - near) / 2
    x.translate[0] = hw + static_cast<float>(vp.x);
    x.translate[1] = hh + static_cast<float>(vp.y);
    x.translate[2] = r.half_z ? 0.0f : 0.5f;  // Vulkan: minDepth; GL: (far + near) / 2
    return x;
}

// Window position of an unclipped vertex (the vertex shader's viewport stage: one division,
// then a multiply-add that LLVM fuses on an FMA host).
void shader_viewport(const ViewportXform& xf, ClipVertex& v) {
    const float oow = 1.0f / v.clip[3];
    for (int i = 0; i < 3; ++i) {
        const float ndc = v.clip[i] * oow;
        v.win[i] = kFusedViewport ? std::fma(ndc, xf.scale[i], xf.translate[i]) : ndc * xf.scale[i] + xf.translate[i];
    }
}

// Window position of a vertex made by the clipper (C code: never fused).
void clipper_viewport(const ViewportXform& xf, ClipVertex& v) {
    const float oow = 1.0f / v.clip[3];
    for (int i = 0; i < 3; ++i) v.win[i] = v.clip[i] * oow * xf.scale[i] + xf.translate[i];
}

// dst = out + t * (in - out), per clip coordinate.
ClipVertex interpolate(const ViewportXform& xf, float t, const ClipVertex& out, const ClipVertex& in) {
    ClipVertex d{};
    for (int i = 0; i < 4; ++i) d.clip[i] = out.clip[i] + t * (in.clip[i] - out.clip[i]);
    clipper_viewport(xf, d);
    return d;
}

struct PlaneCoeffs {
    float z0, dzdx, dzdy;
};

// The depth plane from the float window positions, in llvmpipe's operation order (setup_avx2.cpp
// computes the same for 8 triangles at once).
PlaneCoeffs depth_plane(const ClipVertex* v0, const ClipVertex* v1, const ClipVertex* v2) {
    const float x0c = v0->win[0] - 0.5f;
    const float y0c = v0->win[1] - 0.5f;
    const float dx01 = v0->win[0] - v1->win[0];
    const float dy01 = v0->win[1] - v1->win[1];
    const float dx20 = v2->win[0] - v0->win[0];
    const float dy20 = v2->win[1] - v0->win[1];
    const float e = dx01 * dy20;
    const float f = dy01 * dx20;
    const float ooa = 1.0f / (e - f);
    const float dy20_ooa = dy20 * ooa;
    const float dy01_ooa = dy01 * ooa;
    const float dx20_ooa = dx20 * ooa;
    const float dx01_ooa = dx01 * ooa;
    const float da01 = v0->win[2] - v1->win[2];
    const float da20 = v2->win[2] - v0->win[2];
    const float dadx = da01 * dy20_ooa - da20 * dy01_ooa;
    const float dady = da20 * dx01_ooa - da01 * dx20_ooa;
    const float a0 = v0->win[2] - (dadx * x0c + dady * y0c);
    return {a0, dadx, dady};
}

// SetupTri::fits32 from the snapped extents span_x = max x - min x, span_y = max y - min y (16.8;
// each < 2^31): see setup_snapped.
inline bool fits32_of(int64_t span_x, int64_t span_y) {
    return span_y * (span_x + 2048) + span_x * (span_y + 256) + 1 < (int64_t{1} << 31);
}

// llvmpipe's setup of one (post-clip) triangle after the snap: x, y are its corners in 16.8 in the
// given order, plane_of(swapped) its depth plane for the given order (false) or for the order that
// setup uses for a negative triangle (true: see below). A template on the rules, so each rule set's
// front end is compiled with its choices as constants (the GL path is as it was).
template <RasterRules Rules, class PlaneOf>
inline void setup_snapped(const FrontEndParams& p, int64_t* x, int64_t* y, const PlaneOf& plane_of,
                          std::uint32_t draw, std::vector<SetupTri>& out) {
    constexpr RuleSet rules = rule_set(Rules);
    // llvmpipe's area: positive is clockwise in GL window coordinates (y up).
    const int64_t area = (x[0] - x[1]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[0] - y[1]);
    if (area == 0) return;

    const bool lp_positive = area > 0;
    const bool gl_ccw = rules.lp_positive_is_ccw ? lp_positive : !lp_positive;
    const bool front = gl_ccw == (p.front_face == FrontFace::CCW);
    if (p.cull_face == CullFace::Back && !front) return;
    if (p.cull_face == CullFace::Front && front) return;

    // Setup works on llvmpipe's positive orientation; a negative triangle swaps vertices 0 and 1
    // (provoking vertex last) or 1 and 2 (provoking vertex first), which also decides the vertex
    // order of the depth plane below.
    if (!lp_positive) {
        const int a = rules.provoking_first ? 1 : 0;
        std::swap(x[a], x[a + 1]);
        std::swap(y[a], y[a + 1]);
    }

    // Bounding box (inclusive), llvmpipe's rounding for its fill convention.
    const int adj = rules.bottom_edge_rule ? 1 : 0;
    const int64_t minx = std::min({x[0], x[1], x[2]}), maxx = std::max({x[0], x[1], x[2]});
    const int64_t miny = std::min({y[0], y[1], y[2]}), maxy = std::max({y[0], y[1], y[2]});
    int64_t bx0 = minx >> kFixedOrder;
    int64_t bx1 = (maxx - 1) >> kFixedOrder;
    int64_t by0 = (miny + adj) >> kFixedOrder;
    int64_t by1 = (maxy - 1 + adj) >> kFixedOrder;
    bx0 = std::max<int64_t>(bx0, 0);
    by0 = std::max<int64_t>(by0, 0);
    bx1 = std::min<int64_t>(bx1, p.target_width - 1);
    by1 = std::min<int64_t>(by1, p.target_height - 1);
    if (bx0 > bx1 || by0 > by1) return;
    // Every field is written below, so the record starts uninitialized, in the list itself:
    // emplace_back() zeroed its 112 bytes first (rep stos, out of line: 14.6% of SmallTris' samples
    // at 256^2), a zeroed local copied into the list cost more still (session 9), and an
    // uninitialized local's copy stalled on store forwarding (pipeline.h, SetupTri).
    SetupTri& t = out.emplace_back(SetupTri::Uninitialized{});
    t.x0 = static_cast<int>(bx0);
    t.y0 = static_cast<int>(by0);
    t.x1 = static_cast<int>(bx1);
    t.y1 = static_cast<int>(by1);

    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        const int64_t dcdx = y[i] - y[j];
        const int64_t dcdy = x[i] - x[j];
        int64_t c = dcdx * x[i] - dcdy * y[i];
        // Fill-rule bias: a centre exactly on the edge counts for left edges (dcdx < 0) and, for
        // horizontal edges, on the side the convention picks.
        const bool horizontal_in = rules.bottom_edge_rule ? dcdy < 0 : dcdy >= 0;
        if (dcdx < 0 || (dcdx == 0 && horizontal_in)) c += 1;
        t.c[i] = c;
        t.dcdx[i] = dcdx;
        t.dcdy[i] = dcdy;
    }

    const PlaneCoeffs plane = plane_of(!lp_positive);
    t.z0 = plane.z0;
    t.dzdx = plane.dzdx;
    t.dzdy = plane.dzdy;
    t.draw = draw;
    t.front = front;
    // SetupTri::fits32 from the snapped extents (two products; an exact bound over the box's
    // corners cost about 40 instructions per triangle, more than the kernel saved: callgrind,
    // cylinders frame). Edge i at the pixel centre (px, py) is
    // dcdx (x_i - 256 px) - dcdy (y_i - 256 py) (+1), with |dcdx| <= span_y, |dcdy| <= span_x and,
    // for px in [x0, x1 + 7], py in [y0, y1] (the box rounding above, clamping only narrows it):
    // |x_i - 256 px| <= span_x + 1791, |y_i - 256 py| <= span_y + 255.
    t.fits32 = fits32_of(maxx - minx, maxy - miny);
}

// llvmpipe's setup of one (post-clip) triangle in window coordinates.
template <RasterRules Rules>
void setup_window_triangle(const FrontEndParams& p, const ClipVertex* v0, const ClipVertex* v1, const ClipVertex* v2,
                           std::uint32_t draw, std::vector<SetupTri>& out) {
    constexpr RuleSet rules = rule_set(Rules);
    // Window positions outside the fixed-point range are dropped. Clipping (no guard band) keeps a
    // finite vertex inside the viewport, so only two things put one outside: a clipped vertex with
    // w = 0 (1/w overflows, NaN or infinite position) and the rounding of the clip interpolation
    // on coordinates near 2^100 (errors of 2^75 px and more). llvmpipe converts such a position to
    // 0x80000000 (cvtps2dq's integer indefinite) and rasterizes the edges that make; our 64-bit
    // edge functions would overflow (undefined, and the kernels then disagreed: the raster_gl_exact
    // fuzz finding of session 7). |snapped| < 2^30 keeps every product of setup and the kernels
    // within 62 bits; it is 4,194,304 px, far beyond any target (kMaxTargetSize) or viewport.
    // docs/raster-known-differences.md, "Window positions out of range".
    const auto in_range = [](float w) { return std::fabs((w - 0.5f) * kFixedOne) < 0x1p30f; };  // NaN: false
    if (!(in_range(v0->win[0]) && in_range(v0->win[1]) && in_range(v1->win[0]) && in_range(v1->win[1]) &&
          in_range(v2->win[0]) && in_range(v2->win[1])))
        return;
    // Snap to 16.8 after moving the pixel centre to the integer lattice (round half to even, as
    // cvtps2dq does in the default rounding mode).
    // (|value| < 2^30 by in_range: lrint32's cvtss2si is exact lrint there.)
    auto snap = [](float w) { return static_cast<int64_t>(lrint32((w - 0.5f) * kFixedOne)); };
    int64_t x[3] = {snap(v0->win[0]), snap(v1->win[0]), snap(v2->win[0])};
    int64_t y[3] = {snap(v0->win[1]), snap(v1->win[1]), snap(v2->win[1])};
    setup_snapped<Rules>(
        p, x, y,
        [&](bool swapped) {
            if (!swapped) return depth_plane(v0, v1, v2);
            return rules.provoking_first ? depth_plane(v0, v2, v1) : depth_plane(v1, v0, v2);
        },
        draw, out);
}

// Lane t of setup_lanes8: setup_window_triangle's result, from the lanes' snap,
// planes and integer setup (setup_avx2.cpp: the same operations, so the same values). Only the
// record is written here; the integer part ran 8 triangles at a time (its compares and selects
// per triangle, the orientation swap above all, were most of this function's samples on small
// random triangles: perf, raster_bench SmallTris).
void setup_lane(const SetupLanes8& lanes, int t, std::uint32_t draw, std::vector<SetupTri>& out) {
    if (((lanes.keep >> t) & 1u) == 0) return;
    SetupTri& r = out.emplace_back(SetupTri::Uninitialized{});
    for (int e = 0; e < 3; ++e) {
        r.c[e] = lanes.c[e][t] + static_cast<int64_t>((lanes.bias_bits[e] >> t) & 1u);
        r.dcdx[e] = lanes.dcdx[e][t];
        r.dcdy[e] = lanes.dcdy[e][t];
    }
    r.x0 = lanes.box[0][t];
    r.y0 = lanes.box[1][t];
    r.x1 = lanes.box[2][t];
    r.y1 = lanes.box[3][t];
    const int o = static_cast<int>((lanes.swapped >> t) & 1u);
    r.z0 = lanes.z0[o][t];
    r.dzdx = lanes.dzdx[o][t];
    r.dzdy = lanes.dzdy[o][t];
    r.draw = draw;
    r.front = ((lanes.front >> t) & 1u) != 0;
    r.fits32 = fits32_of(lanes.span_x[t], lanes.span_y[t]);
}

template <RasterRules Rules>
SetupIntRules int_rules(const FrontEndParams& p) {
    constexpr RuleSet rules = rule_set(Rules);
    return {rules.bottom_edge_rule,
            rules.lp_positive_is_ccw,
            rules.provoking_first,
            p.front_face == FrontFace::CCW,
            p.cull_face == CullFace::Front ? 1 : p.cull_face == CullFace::Back ? 2 : 0,
            p.target_width,
            p.target_height};
}

// The rest of setup_triangle_for, from vertices already through the clip test (masks m0..m2) and the
// viewport: whole-triangle rejection, then setup, or clipping and the setup of the fan.
template <RasterRules Rules>
void setup_transformed(const FrontEndParams& params, const ViewportXform& xf, const ClipVertex* v0,
                       const ClipVertex* v1, const ClipVertex* v2, unsigned m0, unsigned m1, unsigned m2,
                       std::uint32_t draw, std::vector<SetupTri>& out) {
    constexpr RuleSet rules = rule_set(Rules);
    if ((m0 & m1 & m2) != 0) return;  // wholly outside one plane
    if ((m0 | m1 | m2) == 0) {
        setup_window_triangle<Rules>(params, v0, v1, v2, draw, out);
        return;
    }

    // Sutherland-Hodgman against each plane in the mask, lowest bit first, keeping the polygon's
    // first vertex first (draw_pipe_clip.c's do_clip_tri).
    constexpr int kMaxVerts = 3 + 6 + 1;
    ClipVertex pool[2 * kMaxVerts];
    int pool_used = 0;
    const ClipVertex* list_a[kMaxVerts + 1] = {v0, v1, v2};
    const ClipVertex* list_b[kMaxVerts + 1] = {};
    const ClipVertex** inlist = list_a;
    const ClipVertex** outlist = list_b;
    int n = 3;
    unsigned mask = m0 | m1 | m2;
    while (mask != 0 && n >= 3) {
        const int plane = std::countr_zero(mask);
        mask &= ~(1u << plane);
        const ClipVertex* prev = inlist[0];
        float dp_prev = dot4(prev->clip, clip_plane(rules, plane));
        if (!std::isfinite(dp_prev)) return;
        inlist[n] = inlist[0];
        int count = 0;
        for (int i = 1; i <= n; ++i) {
            const ClipVertex* cur = inlist[i];
            const float dp = dot4(cur->clip, clip_plane(rules, plane));
            if (!std::isfinite(dp)) return;
            bool different;
            if (dp_prev >= 0.0f) {
                outlist[count++] = prev;
                different = dp < 0.0f;
            } else {
                different = !(dp < 0.0f);
            }
            if (different) {
                if (pool_used >= 2 * kMaxVerts || count >= kMaxVerts) return;
                ClipVertex& nv = pool[pool_used++];
                const float denom = dp - dp_prev;
                if (dp < 0.0f) {  // leaving
                    if (!kSymmetricClipT || -dp < dp_prev) {
                        nv = interpolate(xf, dp / denom, *cur, *prev);
                    } else {
                        nv = interpolate(xf, -dp_prev / denom, *prev, *cur);
                    }
                } else {  // entering
                    if (!kSymmetricClipT || -dp_prev < dp) {
                        nv = interpolate(xf, -dp_prev / denom, *prev, *cur);
                    } else {
                        nv = interpolate(xf, dp / denom, *cur, *prev);
                    }
                }
                outlist[count++] = &nv;
            }
            prev = cur;
            dp_prev = dp;
        }
        std::swap(inlist, outlist);
        n = count;
    }
    // The polygon as a fan, its first vertex (the provoking one) last in each triangle, or first when
    // the provoking vertex is the first (draw_pipe_clip.c's emit_poly).
    for (int i = 2; i < n; ++i) {
        if (rules.provoking_first)
            setup_window_triangle<Rules>(params, inlist[0], inlist[i - 1], inlist[i], draw, out);
        else
            setup_window_triangle<Rules>(params, inlist[i - 1], inlist[i], inlist[0], draw, out);
    }
}

}  // namespace

template <RasterRules Rules>
void setup_triangle_for(const FrontEndParams& params, const Float4& a, const Float4& b, const Float4& c,
                        std::uint32_t draw, std::vector<SetupTri>& out) {
    constexpr RuleSet rules = rule_set(Rules);
    const ViewportXform xf = make_xform(rules, params.viewport);
    ClipVertex in[3] = {{{a.x, a.y, a.z, a.w}, {}}, {{b.x, b.y, b.z, b.w}, {}}, {{c.x, c.y, c.z, c.w}, {}}};
    unsigned m[3];
    for (int i = 0; i < 3; ++i) m[i] = clip_mask<rules.half_z>(in[i].clip);
    if ((m[0] & m[1] & m[2]) != 0) return;  // wholly outside one plane
    for (auto& v : in) shader_viewport(xf, v);
    setup_transformed<Rules>(params, xf, &in[0], &in[1], &in[2], m[0], m[1], m[2], draw, out);
}

template <RasterRules Rules>
void setup_range_for(const FrontEndParams& params, std::span<const Float4> vertices,
                     std::span<const std::uint32_t> indices, std::uint32_t draw, std::vector<SetupTri>& out) {
    constexpr RuleSet rules = rule_set(Rules);
    static_assert(kFusedViewport, "setup_avx2.cpp's viewport is the fused one");
    static_assert(sizeof(Float4) == 4 * sizeof(float), "corners are read as 4 floats");
    const std::size_t n = indices.size() / 3 * 3;
    const bool simd = simd_kernel_active();  // setup 8 triangles at a time (setup_avx2.cpp)
    const ViewportXform xf = make_xform(rules, params.viewport);
    const SetupIntRules ints = int_rules<Rules>(params);
    if (n < vertices.size()) {  // a few triangles of a large list (a sub-object's draw): per corner
        std::size_t k = 0;
        // Groups of 8 triangles: the clip test, the viewport, the snap and the depth planes for all
        // 8 at once, then each triangle in order: a clipped one through the scalar front end (as
        // ever), the others' setup from the lanes (the same values: setup_avx2.cpp).
        if (simd) {
            SetupLanes8 lanes;
            const float* corners[24];
            for (; k + 24 <= n; k += 24) {
                for (std::size_t j = 0; j < 24; ++j) corners[j] = &vertices[indices[k + j]].x;
                viewport_lanes8_avx2(lanes, corners, xf.scale, xf.translate, rules.half_z);
                setup_lanes8_avx2(lanes, ints);
                for (int t = 0; t < 8; ++t) {
                    const std::size_t c = k + 3 * static_cast<std::size_t>(t);
                    if ((lanes.clipped >> t) & 1u)
                        setup_triangle_for<Rules>(params, vertices[indices[c]], vertices[indices[c + 1]],
                                                  vertices[indices[c + 2]], draw, out);
                    else
                        setup_lane(lanes, t, draw, out);
                }
            }
        }
        for (; k < n; k += 3)
            setup_triangle_for<Rules>(params, vertices[indices[k]], vertices[indices[k + 1]], vertices[indices[k + 2]],
                                      draw, out);
        return;
    }
    // Each vertex through the clip test and the viewport once. An unused vertex of the list may be
    // anything (validation checks only the vertices that triangles use): its values are never read.
    thread_local std::vector<TransformedVertex> cache;
    cache.resize(vertices.size());
    std::size_t i0 = 0;
    if (simd) {  // 8 vertices at a time (setup_avx2.cpp: the same tests and operations)
        float win[3][8];
        std::uint32_t mask[8];
        for (; i0 + 8 <= vertices.size(); i0 += 8) {
            vertices8_avx2(&vertices[i0].x, xf.scale, xf.translate, rules.half_z, win, mask);
            for (std::size_t t = 0; t < 8; ++t) {
                const Float4& p = vertices[i0 + t];
                TransformedVertex& tv = cache[i0 + t];
                tv.v.clip[0] = p.x;
                tv.v.clip[1] = p.y;
                tv.v.clip[2] = p.z;
                tv.v.clip[3] = p.w;
                for (int c = 0; c < 3; ++c) tv.v.win[c] = win[c][t];
                tv.mask = mask[t];
            }
        }
    }
    for (std::size_t i = i0; i < vertices.size(); ++i) {
        const Float4& p = vertices[i];
        TransformedVertex& t = cache[i];
        t.v.clip[0] = p.x;
        t.v.clip[1] = p.y;
        t.v.clip[2] = p.z;
        t.v.clip[3] = p.w;
        t.mask = clip_mask<rules.half_z>(t.v.clip);
        shader_viewport(xf, t.v);
    }
    std::size_t k = 0;
    if (simd) {  // groups of 8 unclipped triangles' snap and planes at once, as above
        SetupLanes8 lanes;
        for (; k + 24 <= n; k += 24) {
            std::uint32_t clipped = 0;
            for (int t = 0; t < 8; ++t) {
                for (int j = 0; j < 3; ++j) {
                    const TransformedVertex& v = cache[indices[k + 3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(j)]];
                    for (int c = 0; c < 3; ++c) lanes.win[j][c][t] = v.v.win[c];
                    clipped |= v.mask != 0 ? (1u << t) : 0u;
                }
            }
            setup_lanes8_avx2(lanes, ints);
            for (int t = 0; t < 8; ++t) {
                const std::size_t c = k + 3 * static_cast<std::size_t>(t);
                const TransformedVertex &a = cache[indices[c]], &b = cache[indices[c + 1]], &d = cache[indices[c + 2]];
                if ((clipped >> t) & 1u)
                    setup_transformed<Rules>(params, xf, &a.v, &b.v, &d.v, a.mask, b.mask, d.mask, draw, out);
                else
                    setup_lane(lanes, t, draw, out);
            }
        }
    }
    for (; k < n; k += 3) {
        const TransformedVertex &a = cache[indices[k]], &b = cache[indices[k + 1]], &c = cache[indices[k + 2]];
        setup_transformed<Rules>(params, xf, &a.v, &b.v, &c.v, a.mask, b.mask, c.mask, draw, out);
    }
}

template void setup_range_for<RasterRules::GlLlvmpipe>(const FrontEndParams&, std::span<const Float4>,
                                                       std::span<const std::uint32_t>, std::uint32_t,
                                                       std::vector<SetupTri>&);
template void setup_range_for<RasterRules::Vulkan>(const FrontEndParams&, std::span<const Float4>,
                                                   std::span<const std::uint32_t>, std::uint32_t,
                                                   std::vector<SetupTri>&);
template void setup_triangle_for<RasterRules::GlLlvmpipe>(const FrontEndParams&, const Float4&, const Float4&,
                                                          const Float4&, std::uint32_t, std::vector<SetupTri>&);
template void setup_triangle_for<RasterRules::Vulkan>(const FrontEndParams&, const Float4&, const Float4&,
                                                      const Float4&, std::uint32_t, std::vector<SetupTri>&);

}  // namespace raster::detail

namespace raster {

bool simd_kernel_active() { return detail::kernel_avx2_available() && detail::simd_allowed_by_environment(); }

}  // namespace raster
