// pipeline.h (private): llvmpipe's triangle pipeline, split in a front end (clip, viewport,
// snap, edge and depth-plane setup: one SetupTri per rasterized triangle) and a back end (coverage
// and depth test of one SetupTri over a pixel rectangle). Both the scalar reference and the tiled
// executor use these two functions, so they agree bit for bit by construction; they differ only in
// traversal (whole bounding box vs. tile by tile).
//
// Sources of the rules (read for facts, code ours): Mesa src/gallium/auxiliary/draw/draw_pipe_clip.c
// (Sutherland-Hodgman clipping in clip space), draw_llvm.c (clip mask, viewport), llvmpipe
// lp_setup_tri.c (16.8 snapping, edge functions, fill-rule bias, bounding box), lp_state_setup.c
// (depth plane), lp_bld_interp.c (per-pixel evaluation), lp_bld_conv.c (unorm conversion).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "depth_dispatch.h"
#include "raster/types.h"

namespace raster::detail {

// Experiment switches (each pinned against OSMesa; docs/conventions.md). Not user options.
inline constexpr bool kFusedViewport = true;   // draw_llvm: fmuladd(x * (1/w), scale, trans)
inline constexpr bool kFusedInterp = true;     // lp_bld_interp: fmuladd(dady, y, fmuladd(dadx, x, a0))
inline constexpr bool kSymmetricClipT = true;  // draw_pipe_clip: t measured from the nearer vertex
inline constexpr bool kBottomEdgeRule = false;  // llvmpipe bottom_edge_rule for a GL FBO
inline constexpr bool kLpPositiveIsCcw = false;  // llvmpipe's positive area is GL counter-clockwise?

// One triangle ready for the back end. Edge i at pixel (px, py) (centre at 16.8 (px*256, py*256)
// after the half-pixel offset): e_i = c[i] - dcdx[i] * 256 * px + dcdy[i] * 256 * py; the pixel is
// covered when all three are > 0 (the fill-rule bias is folded into c).
struct SetupTri {
    // Setup writes every field of a record in place (triangle_setup.cpp): built in a local and
    // pushed, its narrow field stores were read back by the copy's 16-byte loads, which stalled
    // store forwarding three times per triangle (perf, raster_bench SmallTris); emplace_back()
    // would zero the 112 bytes first. SetupTri() stays the trivial default.
    struct Uninitialized {};
    SetupTri() = default;
    explicit SetupTri(Uninitialized) {}  // NOLINT: every field is set by its caller
    std::int64_t c[3];
    std::int64_t dcdx[3];
    std::int64_t dcdy[3];
    int x0, y0, x1, y1;  // inclusive pixel bounding box, already inside the target
    float z0, dzdx, dzdy;  // depth plane: z(px, py) = fma(dzdy, py, fma(dzdx, px, z0))
    std::uint32_t draw;  // index of the draw command in the batch
    // Set by setup (false is always safe): every edge value at a pixel of the box widened by 7
    // columns to the right, [x0, x1 + 7] x [y0, y1], fits in 32 bits, so the AVX2 kernel's narrow
    // path may run on any rectangle inside the box without its own bound (triangle_setup.cpp).
    bool fits32;
    // Whether the triangle is front-facing under its draw's FrontFace (the face culling test of
    // setup). The tiled executor sets up a triangle once for draws that differ only in culling and
    // culls at binning by this flag (execute.cpp, share_setup).
    bool front;
};

struct FrontEndParams {
    int target_width;
    int target_height;
    Viewport viewport;
    CullFace cull_face;
    FrontFace front_face;
    RasterRules rules = RasterRules::GlLlvmpipe;  // GL-exact setup only (exact bounds ignore it)
};

// Runs clipping and setup for one input triangle (clip-space vertices a, b, c), appending 0..n
// SetupTri (a clipped triangle becomes a fan). Inputs were validated (finite). One instantiation per
// rule set (src/triangle_setup.cpp), so each is compiled with its rules as constants; the choice is
// inline here, where a caller's loop over a draw's triangles can hoist it.
template <RasterRules Rules>
void setup_triangle_for(const FrontEndParams& params, const Float4& a, const Float4& b, const Float4& c,
                        std::uint32_t draw, std::vector<SetupTri>& out);
inline void setup_triangle(const FrontEndParams& params, const Float4& a, const Float4& b, const Float4& c,
                           std::uint32_t draw, std::vector<SetupTri>& out) {
    if (params.rules == RasterRules::Vulkan)
        setup_triangle_for<RasterRules::Vulkan>(params, a, b, c, draw, out);
    else
        setup_triangle_for<RasterRules::GlLlvmpipe>(params, a, b, c, draw, out);
}

// setup_triangle for the triangles of `indices` (whole triangles; a remainder is ignored) over
// `vertices`, appending in order. When they hold at least as many indices as the list has vertices
// (a whole object's draw), each vertex goes through the clip test and the viewport once instead of
// once per triangle corner: the same operations on the same values, so the same SetupTri.
template <RasterRules Rules>
void setup_range_for(const FrontEndParams& params, std::span<const Float4> vertices,
                     std::span<const std::uint32_t> indices, std::uint32_t draw, std::vector<SetupTri>& out);
inline void setup_range(const FrontEndParams& params, std::span<const Float4> vertices,
                        std::span<const std::uint32_t> indices, std::uint32_t draw, std::vector<SetupTri>& out) {
    if (params.rules == RasterRules::Vulkan)
        setup_range_for<RasterRules::Vulkan>(params, vertices, indices, draw, out);
    else
        setup_range_for<RasterRules::GlLlvmpipe>(params, vertices, indices, draw, out);
}

// Rasterizes `tri` over `rect` (inside the target and the triangle's box) into `depth` with the
// draw's depth `state`. Returns the samples that passed.
// allow_simd picks the 16-wide AVX-512 kernel or else the 8-wide AVX2+FMA kernel when the CPU has
// it and the environment variable CULLIDE_RASTER_NO_SIMD is not set to a non-empty value other than
// "0" (CULLIDE_RASTER_NO_AVX512 likewise keeps AVX2); bit-identical results.
// stop_at_first: the caller only needs to know whether any sample passes (an any-samples query
// with the depth mask off): the kernel may return any count >= 1 as soon as one sample passed.
// Ownership: `rect` lies in one column group of kHizTile pixels (columns [64k, 64k + 63]) of the
// target or the caller runs alone, and no other thread reads or writes those pixels of rect's rows
// during the call: a kernel may read the group's pixels there and rewrite them with the values they
// hold (the AVX2 kernel does, instead of masked stores). The tiled executor's tasks own their tiles.
std::uint64_t raster_rect(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                          bool allow_simd, bool stop_at_first = false);
std::uint64_t raster_rect_portable(const SetupTri& tri, const DepthState& state, DepthRows depth,
                                   PixelRect rect, bool stop_at_first);
std::uint64_t raster_rect_avx2(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                               bool stop_at_first);
// The two kernels with the flat argument list that the white-box test (tests/raster/simd_test.cpp)
// calls them with.
inline std::uint64_t raster_rect_portable(const SetupTri& tri, DepthFormat format, DepthFunc func, bool write,
                                          std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1,
                                          bool stop_at_first) {
    return raster_rect_portable(tri, {format, func, write}, {depth, stride}, {rx0, ry0, rx1, ry1}, stop_at_first);
}
inline std::uint64_t raster_rect_avx2(const SetupTri& tri, DepthFormat format, DepthFunc func, bool write,
                                      std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1,
                                      bool stop_at_first) {
    return raster_rect_avx2(tri, {format, func, write}, {depth, stride}, {rx0, ry0, rx1, ry1}, stop_at_first);
}
// The 16-wide AVX-512 kernel (kernel_avx512.cpp), chosen before the AVX2 one where the CPU has
// AVX-512F and VL and CULLIDE_RASTER_NO_AVX512 is not set to a non-empty value other than "0".
std::uint64_t raster_rect_avx512(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                                 bool stop_at_first);
inline std::uint64_t raster_rect_avx512(const SetupTri& tri, DepthFormat format, DepthFunc func, bool write,
                                        std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1,
                                        bool stop_at_first) {
    return raster_rect_avx512(tri, {format, func, write}, {depth, stride}, {rx0, ry0, rx1, ry1}, stop_at_first);
}
// Hierarchical Z (issue #17): bounds of the stored depth per 8 x 8 pixel block of one 64 x 64 tile,
// so that a query triangle (depth mask off) whose depth test certainly fails over a whole block
// skips it without touching its pixels. Kept by the tile's task (no sharing between threads) for
// one batch: a block's bounds are read from the buffer the first time a query meets it (`valid`
// bit); a writing draw runs the plain kernel and clears the valid bits of the blocks it touches.
// Only for D16 / D24 (stored values compare as unsigned integers, a total order whatever they
// hold); D32F draws take the plain kernel.
inline constexpr int kHizTile = 64;   // the executor's tile side (execute.cpp's kTileSize)
inline constexpr int kHizBlock = 8;   // block side: 8 x 8 blocks per tile, one bit each in `valid`
struct HizTile {
    PixelRect tile;            // the tile's pixels (inside the target; smaller at the right/top edge)
    std::uint64_t valid = 0;   // bit by * 8 + bx: lo/hi of block (bx, by) hold bounds
    std::uint32_t lo[64];      // every stored value of the block is >= lo ...
    std::uint32_t hi[64];      // ... and <= hi
};
// The 8 x 8 blocks [bx0, bx1] x [by0, by1] of a tile (each in 0..7) as a mask, bit by * 8 + bx (the
// layout of HizTile::valid and ExecuteOptions::written_blocks): the row's bits (under 256) times one
// bit per block row (whole bytes, so the product has no carries), without a loop. Empty (0) when
// by1 < by0.
[[gnu::always_inline]] inline std::uint64_t block_mask(int bx0, int bx1, int by0, int by1) {
    if (by1 < by0) return 0;
    const std::uint64_t row = ((std::uint64_t{2} << bx1) - 1) & ~((std::uint64_t{1} << bx0) - 1);
    const std::uint64_t rows = (std::uint64_t{0x0101010101010101} >> (8 * (7 - (by1 - by0)))) << (8 * by0);
    return row * rows;
}
// raster_rect with the tile's block bounds: skips the blocks where the depth test certainly fails,
// runs the kernel on the rest (in runs of blocks); writing draws run it on all of rect. `rect` lies
// inside hiz.tile. Same samples and the same stored values as raster_rect on `rect`: the skipped
// blocks have no passing sample by the bound below.
// The bound: a pixel's incoming value is enc(clamp(fma(dzdy, y, fma(dzdx, x, z0)))) with float x, y
// exact integers. For finite plane coefficients each correctly rounded fma is monotone in its
// addend and (as the exact product-sum is linear) in x and in y separately; the clamp and the D16 /
// D24 encodings are monotone too. So over a rectangle of pixel centres the value is monotone in x
// for every y and in y for every x (non-decreasing along the sign of dzdx, dzdy), so its minimum and
// maximum are the values at two opposite corners of the rectangle.
std::uint64_t raster_rect_hiz(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                              HizTile& hiz, bool allow_simd, bool stop_at_first = false);
std::uint64_t raster_rect_hiz_portable(const SetupTri& tri, const DepthState& state, DepthRows depth,
                                       PixelRect rect, HizTile& hiz, bool stop_at_first);
std::uint64_t raster_rect_hiz_avx2(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                                   HizTile& hiz, bool stop_at_first);
std::uint64_t raster_rect_hiz_avx512(const SetupTri& tri, const DepthState& state, DepthRows depth, PixelRect rect,
                                     HizTile& hiz, bool stop_at_first);

// The kernel that raster_rect (hiz false) or raster_rect_hiz (hiz true) runs for a draw's depth
// state, resolved once: the tiled executor picks it per draw instead of dispatching per rectangle
// (the two dispatch layers cost about 100 instructions per rectangle). `hiz` is the HizTile of the
// rectangle's tile for a kernel selected with hiz = true, else ignored (may be nullptr).
using RectKernel = std::uint64_t (*)(const SetupTri& tri, DepthRows depth, PixelRect rect, HizTile* hiz,
                                     bool stop_at_first);
RectKernel select_rect_kernel(const DepthState& state, bool allow_simd, bool hiz);
RectKernel select_rect_kernel_portable(const DepthState& state, bool hiz);
RectKernel select_rect_kernel_avx2(const DepthState& state, bool hiz);
RectKernel select_rect_kernel_avx512(const DepthState& state, bool hiz);

// True when the CPU has AVX2 and FMA and this build has the AVX2 kernel (x86-64 GCC/Clang).
bool kernel_avx2_available();
// True when the CPU has AVX-512F, AVX-512VL, AVX2 and FMA and this build has the AVX-512 kernel.
bool kernel_avx512_available();
// Whether raster_rect_avx2 / raster_rect_avx512 (and their _hiz forms) may be called on this CPU:
// the SIMD build only where it is available, the scalar build of the same entry points (other
// targets) always. The white-box tests call them directly; the executors pick through
// select_rect_kernel, which never picks one that is not available.
bool kernel_avx2_callable();
bool kernel_avx512_callable();
// False when CULLIDE_RASTER_NO_AVX512 keeps the AVX2 kernel where AVX-512 is available (read once).
bool avx512_allowed_by_environment();
// The HiZ block scan of the AVX2 kernel (8-pixel rows in one register; the scalar loop otherwise),
// for the AVX-512 kernel's HiZ entry: the stored minimum and maximum of [x0, x1] x [y0, y1].
void stored_bounds_avx2(DepthRows d, int x0, int y0, int x1, int y1, std::uint32_t& lo, std::uint32_t& hi);
// False when CULLIDE_RASTER_NO_SIMD forces the portable kernel everywhere (read once).
bool simd_allowed_by_environment();

// rect_outside (below) for many rectangles of one triangle, as binning asks it tile by tile: an
// edge e = c - sx px + sy py is largest over a rectangle at the corner that the signs of sx and sy
// pick (the larger of -sx x0, -sx x1 and of sy y0, sy y1), so the row part is set once per row of
// tiles and a tile costs one product per edge. The same integers as the four-corner maximum.
class RectReject {
public:
    explicit RectReject(const SetupTri& t) {
        for (int i = 0; i < 3; ++i) {
            sx_[i] = t.dcdx[i] * 256;
            sy_[i] = t.dcdy[i] * 256;
            c_[i] = t.c[i];
        }
    }
    // The rows [y0, y1] of the next rectangles.
    void set_rows(int y0, int y1) {
        for (int i = 0; i < 3; ++i) row_best_[i] = c_[i] + (sy_[i] > 0 ? sy_[i] * y1 : sy_[i] * y0);
    }
    // True when no pixel centre of [x0, x1] x (the rows) can be covered.
    [[nodiscard]] bool outside(int x0, int x1) const {
        for (int i = 0; i < 3; ++i)
            if (row_best_[i] - (sx_[i] < 0 ? sx_[i] * x1 : sx_[i] * x0) <= 0) return true;
        return false;
    }

private:
    std::int64_t sx_[3], sy_[3], c_[3], row_best_[3];
};

// True when no pixel centre of [x0, x1] x [y0, y1] can be covered by `t`: one edge function is <= 0
// at all four corner centres (edge functions are linear, so at every centre). Exact integers.
inline bool rect_outside(const SetupTri& t, int x0, int y0, int x1, int y1) {
    RectReject r(t);
    r.set_rows(y0, y1);
    return r.outside(x0, x1);
}

// Floor of a / b for b > 0 (exact integers).
[[gnu::always_inline]] inline std::int64_t floor_div_pos(std::int64_t a, std::int64_t b) {
    const std::int64_t q = a / b;
    return q - ((a % b) != 0 && a < 0 ? 1 : 0);
}

// Shrinks `r` to the rows, then to the columns, in which each edge alone is > 0 at some pixel
// centre of the rectangle; false when nothing is left. Exact integers (the kernels' own edge
// values): every pixel centre removed has an edge <= 0 there, so it is not covered, and a kernel
// run on the result counts and writes exactly what it would on `r`. Thin triangles whose box is
// cut to a tile often touch only a corner of it (issue #17: the write kernel visited 313 pixels per
// rectangle for 58 written). An edge e(px, py) = c - sx px + sy py is largest over the columns
// [x0, x1] at the column of the larger of -sx x0, -sx x1 (linear), and over the rows likewise; a
// bound is divided out only when it falls strictly inside the rectangle.
[[gnu::always_inline]] inline bool shrink_rect(const SetupTri& t, PixelRect& r) {
    for (int i = 0; i < 3; ++i) {
        const std::int64_t sx = t.dcdx[i] * 256, sy = t.dcdy[i] * 256;
        const std::int64_t m = t.c[i] - sx * (sx < 0 ? r.x1 : r.x0);    // e <= m + sy py on the row py
        const std::int64_t top = m + sy * r.y0, bottom = m + sy * r.y1;  // that bound on the first, last row
        if (top > 0 && bottom > 0) continue;
        if (top <= 0 && bottom <= 0) return false;
        if (sy > 0) r.y0 = static_cast<int>(floor_div_pos(-m, sy) + 1);  // top <= 0 < bottom
        else r.y1 = static_cast<int>(floor_div_pos(m - 1, -sy));          // bottom <= 0 < top
    }
    for (int i = 0; i < 3; ++i) {
        const std::int64_t sx = t.dcdx[i] * 256, sy = t.dcdy[i] * 256;
        const std::int64_t m = t.c[i] + sy * (sy > 0 ? r.y1 : r.y0);     // e <= m - sx px on the column px
        const std::int64_t left = m - sx * r.x0, right = m - sx * r.x1;
        if (left > 0 && right > 0) continue;
        if (left <= 0 && right <= 0) return false;
        if (sx > 0) r.x1 = static_cast<int>(floor_div_pos(m - 1, sx));  // right <= 0 < left
        else r.x0 = static_cast<int>(floor_div_pos(-m, -sx) + 1);       // left <= 0 < right
    }
    return true;
}

// Square cells of 2^shift pixels over a width x height target, at most kMaxCells per row and
// column: the coarse occupancy grids of the fused visibility pass's items-alone pre-pass and of the
// executor's queries_only (which draws a query may observe).
struct CellGrid {
    static constexpr int kMaxCells = 128;
    int shift = 0;
    int x = 0, y = 0;  // cells per row and per column
    static CellGrid of(int width, int height) {
        CellGrid g;
        while ((std::max(width, height) + (1 << g.shift) - 1) >> g.shift > kMaxCells) ++g.shift;
        g.x = (width + (1 << g.shift) - 1) >> g.shift;
        g.y = (height + (1 << g.shift) - 1) >> g.shift;
        return g;
    }
    [[nodiscard]] std::size_t count() const { return static_cast<std::size_t>(x) * static_cast<std::size_t>(y); }
};

}  // namespace raster::detail
