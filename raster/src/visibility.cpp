// visibility.cpp: the fused exact-bounds visibility pass (raster/visibility.h; the equivalence with
// the two recorded passes is argued there and in docs/reliable-raster.md).
#include "raster/visibility.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>

#include "exact_bounds.h"
#include "raster/detail/parallel.h"
#include "pipeline.h"
#include "raster/depth_target.h"


namespace raster {
namespace {

// Tile side: 64 like raster::execute, but smaller on small targets so that CULLIDE's low-resolution
// views still split into several tasks (the answer does not depend on it: every pixel's minima and
// every fragment's test are the same whichever tile holds them).
//
// One tile holding the whole target for one thread on targets up to kOneTileMax pixels a side: tiles
// are then only overhead (each triangle's Ref pushed per tile it overlaps, its box cut to each tile,
// the tasks); the answer is the same (see above). With two or more threads R-CULLIDE's 32^2 views
// keep their four 16-pixel tiles: on a quiet machine they beat one tile (cylinders 6.4-6.8 against
// 6.8-7.0 ms per frame, tori 36.0-36.3 against 36.8-37.1, 2 threads, load 1.7).
constexpr int kOneTileMax = 128;
int tile_side(int width, int height, int threads) {
    const int m = std::max(width, height);
    if (threads == 1 && m <= kOneTileMax) return m;
    return m <= 128 ? 16 : m <= 256 ? 32 : 64;
}
constexpr std::uint32_t kNoObject = 0xffffffffu;


std::string check_vertex(const Double4& d) {
    if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z) || !std::isfinite(d.w))
        return "is not finite";
    if (d.w != 1.0) return "has w = " + std::to_string(d.w) + " (the exact-bounds mode takes orthographic input, w = 1)";
    if (std::fabs(d.x) > kMaxExactBoundsCoordinate || std::fabs(d.y) > kMaxExactBoundsCoordinate ||
        std::fabs(d.z) > kMaxExactBoundsCoordinate)
        return "has a coordinate beyond +-2^100 (kMaxExactBoundsCoordinate)";
    return {};
}

// Encoded depths compare as unsigned integers in every format: unorm values directly, and D32F
// values are the bits of floats in [+0, 1] (quantize_down/up clamp to [0, 1] and never return
// -0), whose order is the integer order of their bits.
struct Fragment {
    std::uint32_t item;
    std::uint32_t pixel;  // index inside the tile
    std::uint32_t zmax;   // encoded, rounded up: the query's incoming value
};

struct Ref {
    std::uint32_t item;
    std::uint32_t tri;
};

// A triangle's encoded depth bounds: lo <= every zmin and hi >= every zmax of its pixels.
struct ZBound {
    std::uint32_t lo, hi;
};

// Block side inside a tile: the unit that the triangles' depth bounds settle at once.
constexpr int kBlock = 16;

bool valid_vertex(const Double4& d) {
    return d.w == 1.0 && std::fabs(d.x) <= kMaxExactBoundsCoordinate && std::fabs(d.y) <= kMaxExactBoundsCoordinate &&
           std::fabs(d.z) <= kMaxExactBoundsCoordinate;  // false for NaN too
}

// The input checks, in item and index order: the first failure's message (called only when the
// front end found a failure, or an index count is not a multiple of 3).
Error validate(std::span<const VisibilityItem> items) {
    for (std::size_t i = 0; i < items.size(); ++i) {
        const MeshViewD& m = items[i].mesh;
        if (m.indices.size() % 3 != 0)
            return Error{"visibility pass: item " + std::to_string(i) + ": index count " +
                         std::to_string(m.indices.size()) + " is not a multiple of 3"};
        for (std::size_t k = 0; k < m.indices.size(); ++k) {
            if (m.indices[k] >= m.vertices.size())
                return Error{"visibility pass: item " + std::to_string(i) + ": index " + std::to_string(m.indices[k]) +
                             " at position " + std::to_string(k) + " is beyond the vertex list (size " +
                             std::to_string(m.vertices.size()) + ")"};
            const Double4& d = m.vertices[m.indices[k]];
            if (valid_vertex(d)) continue;
            if (std::string why = check_vertex(d); !why.empty())
                return Error{"visibility pass: item " + std::to_string(i) + ": vertex " +
                             std::to_string(m.indices[k]) + " " + why};
        }
    }
    return Error{"visibility pass: invalid input"};  // not reached: some check above fails
}

// The target cut into square tiles of `side` pixels, row-major.
struct TileGrid {
    int side, x, y;  // tile side, tiles per row and per column
    [[nodiscard]] std::size_t count() const { return static_cast<std::size_t>(x) * static_cast<std::size_t>(y); }
    [[nodiscard]] std::size_t pixels() const { return static_cast<std::size_t>(side) * static_cast<std::size_t>(side); }
};

}  // namespace

// run()'s phases, in order: front_end, depth_bounds, bin, then shade per tile; buffers kept between
// calls.
struct VisibilityPass::State {
    std::vector<std::vector<detail::BoundsTri>> tris;     // per item
    std::vector<std::vector<detail::BoundsVertex>> pool;  // per item
    std::vector<std::vector<ZBound>> zq;                  // per item, per triangle: encoded depth bounds
    std::vector<std::uint8_t> bad;                        // per item: an input check failed
    std::vector<std::uint8_t> hit;                        // per item: found not fully visible (atomic_ref)
    std::vector<std::vector<Ref>> bins;                   // per tile
    std::vector<std::vector<Fragment>> frags;             // per tile (scratch)
    std::vector<std::vector<Ref>> block_refs;             // per tile (scratch): one block's triangles
    std::vector<std::vector<std::uint8_t>> block_need;    // per tile (scratch): ... whose queries can pass
    std::vector<std::uint32_t> min1, obj1, min2;          // per pixel, tile-major (one tile = side^2)

    // Front end per item (the recorded draws' own setup, so the same polygons). False when some
    // item failed an input check (bad[i]).
    bool front_end(int width, int height, std::span<const VisibilityItem> items, int threads);
    // Per triangle, the encoded bounds of every zmin and zmax its pixels can get (zq).
    void depth_bounds(std::size_t n_items, DepthFormat format);
    // Binning, in item order (one tile: every triangle, in item order).
    void bin(std::span<const VisibilityItem> items, const TileGrid& grid);
    // Per block of a tile: settle what the triangles' depth bounds settle; then, only if some item
    // not yet found may pass there, every fragment's zmin into the two minima and the zmax of the
    // items that may pass against the minimum over the other objects; such items go to hit[].
    void shade(std::span<const VisibilityItem> items, const TileGrid& grid, int width, int height,
               DepthFormat format, std::size_t tile);
};

bool VisibilityPass::State::front_end(int width, int height, std::span<const VisibilityItem> items, int threads) {
    if (tris.size() < items.size()) {
        tris.resize(items.size());
        pool.resize(items.size());
        bad.resize(items.size());
    }
    detail::FrontEndParams params{};
    params.target_width = width;
    params.target_height = height;
    params.viewport = Viewport{0, 0, width, height};
    params.cull_face = CullFace::None;
    params.front_face = FrontFace::CCW;
    detail::parallel_for(threads, items.size(), [&](std::size_t i) {
        auto& item_tris = tris[i];
        auto& item_pool = pool[i];
        item_tris.clear();
        item_pool.clear();
        const MeshViewD& m = items[i].mesh;
        item_tris.reserve(m.indices.size() / 3);
        item_pool.reserve(m.indices.size());
        bad[i] = 0;
        const std::size_t nv = m.vertices.size();
        for (std::size_t k = 0; k + 2 < m.indices.size(); k += 3) {
            const std::uint32_t ia = m.indices[k], ib = m.indices[k + 1], ic = m.indices[k + 2];
            if (ia >= nv || ib >= nv || ic >= nv) {
                bad[i] = 1;
                return;
            }
            const Double4 &a = m.vertices[ia], &b = m.vertices[ib], &c = m.vertices[ic];
            if (!(valid_vertex(a) && valid_vertex(b) && valid_vertex(c))) {
                bad[i] = 1;
                return;
            }
            detail::setup_bounds_triangle(params, a, b, c, static_cast<std::uint32_t>(i), item_tris, item_pool);
        }
    });
    for (std::size_t i = 0; i < items.size(); ++i)
        if (bad[i]) return false;
    return true;
}

void VisibilityPass::State::depth_bounds(std::size_t n_items, DepthFormat format) {
    if (zq.size() < n_items) zq.resize(n_items);
    for (std::size_t i = 0; i < n_items; ++i) {
        zq[i].resize(tris[i].size());
        for (std::size_t k = 0; k < tris[i].size(); ++k) {
            const detail::BoundsTri& t = tris[i][k];
            double lo = 0, hi = 0;
            detail::bounds_depth_range(t, pool[i].data(), lo, hi);
            // The draw quantizes zlo - margin_z down and zhi + margin_z up; subtraction, addition
            // and both quantizations are monotone, so these bound every pixel's values.
            zq[i][k] = {detail::quantize_down(lo - t.margin_z, format), detail::quantize_up(hi + t.margin_z, format)};
        }
    }
}

void VisibilityPass::State::bin(std::span<const VisibilityItem> items, const TileGrid& grid) {
    const std::size_t tile_count = grid.count();
    if (bins.size() < tile_count) {
        bins.resize(tile_count);
        frags.resize(tile_count);
        block_refs.resize(tile_count);
        block_need.resize(tile_count);
    }
    for (std::size_t t = 0; t < tile_count; ++t) bins[t].clear();
    for (std::size_t i = 0; i < items.size(); ++i) {
        for (std::size_t k = 0; k < tris[i].size(); ++k) {
            const detail::BoundsTri& t = tris[i][k];
            if (tile_count == 1) {
                bins[0].push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(k)});
                continue;
            }
            for (int ty = t.y0 / grid.side; ty <= t.y1 / grid.side; ++ty)
                for (int tx = t.x0 / grid.side; tx <= t.x1 / grid.side; ++tx)
                    bins[static_cast<std::size_t>(ty) * static_cast<std::size_t>(grid.x) + static_cast<std::size_t>(tx)]
                        .push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(k)});
        }
    }
}

// Blocks: an item's query can pass at a pixel only if one of its fragments there has zmax >= the
// minimum zmin over the other objects' fragments there (and the clear value). Every fragment in a
// block comes from a triangle whose pixel box meets the block, and its zmin >= the triangle's zq.lo,
// its zmax <= zq.hi. So with L = the minimum of zq.lo over the block's triangles of the other
// objects (the clear value if none), a triangle with zq.hi < L has no fragment in the block whose
// query passes: its fragments need no test. A block where no triangle of an item not yet found is
// left needs no per-pixel work at all. The zmin of every triangle in a tested block still enters
// its minima, so each tested fragment meets exactly the value the whole-tile pass gave it; and an
// item's answer is the OR over blocks, so skipping the items already found changes nothing. The
// answer is therefore the whole-tile pass's, bit for bit, whatever the thread timing (the skip of
// found items reads flags another task may be setting: it only changes how much work is done).
void VisibilityPass::State::shade(std::span<const VisibilityItem> items, const TileGrid& grid, int width,
                                  int height, DepthFormat format, std::size_t tile) {
    auto& tile_bin = bins[tile];
    if (tile_bin.empty()) return;
    auto& tile_frags = frags[tile];
    auto& blk = block_refs[tile];
    auto& need = block_need[tile];
    const int side = grid.side;
    const int tx = static_cast<int>(tile % static_cast<std::size_t>(grid.x));
    const int ty = static_cast<int>(tile / static_cast<std::size_t>(grid.x));
    const int x0 = tx * side, y0 = ty * side;
    const int x1 = std::min(x0 + side, width) - 1, y1 = std::min(y0 + side, height) - 1;
    const std::size_t tile_pixels = grid.pixels();
    const std::uint32_t clear = DepthTarget::encode_clear(1.0, format);
    std::uint32_t* tile_min1 = min1.data() + tile * tile_pixels;
    std::uint32_t* tile_obj1 = obj1.data() + tile * tile_pixels;
    std::uint32_t* tile_min2 = min2.data() + tile * tile_pixels;
    const auto found = [&](std::uint32_t item) {
        return std::atomic_ref<std::uint8_t>(hit[item]).load(std::memory_order_relaxed) != 0;
    };
    const int block = std::min(side, kBlock);
    for (int by0 = y0; by0 <= y1; by0 += block) {
        const int by1 = std::min(by0 + block - 1, y1);
        for (int bx0 = x0; bx0 <= x1; bx0 += block) {
            const int bx1 = std::min(bx0 + block - 1, x1);
            // The block's triangles (in item order) and the two smallest zq.lo over objects, as
            // the per-pixel minima below keep them.
            blk.clear();
            std::uint32_t m1 = clear, o1 = kNoObject, m2 = clear;
            for (const Ref& r : tile_bin) {
                const detail::BoundsTri& t = tris[r.item][r.tri];
                if (t.x1 < bx0 || t.x0 > bx1 || t.y1 < by0 || t.y0 > by1) continue;
                blk.push_back(r);
                const std::uint32_t obj = items[r.item].object;
                const std::uint32_t lo = zq[r.item][r.tri].lo;
                if (obj == o1) {
                    m1 = std::min(m1, lo);
                } else if (lo < m1) {
                    m2 = m1;
                    m1 = lo;
                    o1 = obj;
                } else {
                    m2 = std::min(m2, lo);
                }
            }
            need.resize(blk.size());
            bool any = false;
            for (std::size_t j = 0; j < blk.size(); ++j) {
                const Ref r = blk[j];
                const std::uint32_t other = items[r.item].object == o1 ? m2 : m1;
                need[j] = !found(r.item) && zq[r.item][r.tri].hi >= other ? 1 : 0;
                any = any || need[j] != 0;
            }
            if (!any) continue;

            for (int py = by0; py <= by1; ++py) {
                const std::size_t row = static_cast<std::size_t>(py - y0) * static_cast<std::size_t>(side);
                const std::size_t b = row + static_cast<std::size_t>(bx0 - x0), e = row + static_cast<std::size_t>(bx1 - x0) + 1;
                std::fill(tile_min1 + b, tile_min1 + e, clear);
                std::fill(tile_obj1 + b, tile_obj1 + e, kNoObject);
                std::fill(tile_min2 + b, tile_min2 + e, clear);
            }
            tile_frags.clear();
            for (std::size_t j = 0; j < blk.size(); ++j) {
                const Ref r = blk[j];
                const bool keep = need[j] != 0;
                const detail::BoundsTri& t = tris[r.item][r.tri];
                const std::uint32_t obj = items[r.item].object;
                const double mz = t.margin_z;
                double last_lo = std::numeric_limits<double>::quiet_NaN(), last_hi = last_lo;
                std::uint32_t zmin = 0, zmax = 0;  // quantized once per distinct depth
                const detail::PixelRect rect{std::max(bx0, t.x0), std::max(by0, t.y0), std::min(bx1, t.x1),
                                             std::min(by1, t.y1)};
                detail::bounds_pixels(t, pool[r.item].data(), rect, [&](int px, int py, double zlo, double zhi) {
                    const auto p = static_cast<std::uint32_t>((py - y0) * side + (px - x0));
                    if (!(zlo == last_lo)) {
                        last_lo = zlo;
                        zmin = detail::quantize_down(zlo - mz, format);
                    }
                    if (obj == tile_obj1[p]) {
                        tile_min1[p] = std::min(tile_min1[p], zmin);
                    } else if (zmin < tile_min1[p]) {
                        tile_min2[p] = tile_min1[p];
                        tile_min1[p] = zmin;
                        tile_obj1[p] = obj;
                    } else {
                        tile_min2[p] = std::min(tile_min2[p], zmin);
                    }
                    if (!keep) return;
                    if (!(zhi == last_hi)) {
                        last_hi = zhi;
                        zmax = detail::quantize_up(zhi + mz, format);
                    }
                    tile_frags.push_back({r.item, p, zmax});
                });
            }
            // min1 is the minimum over all objects (with the clear value) and min2 the minimum
            // over the objects other than obj1's, so the minimum over the objects other than o is
            // min2 when o is obj1 and min1 otherwise (ties between objects: then min2 == min1).
            std::uint32_t last = kNoObject;
            for (const Fragment& f : tile_frags) {
                if (f.item == last) continue;
                const std::uint32_t other =
                    items[f.item].object == tile_obj1[f.pixel] ? tile_min2[f.pixel] : tile_min1[f.pixel];
                if (f.zmax >= other) {  // the GEQUAL query passes here
                    std::atomic_ref<std::uint8_t>(hit[f.item]).store(1, std::memory_order_relaxed);
                    last = f.item;
                }
            }
        }
    }
}

VisibilityPass::VisibilityPass() : s_(std::make_unique<State>()) {}
VisibilityPass::~VisibilityPass() = default;

Result<std::vector<std::uint8_t>> VisibilityPass::run(int width, int height, DepthFormat format,
                                                      std::span<const VisibilityItem> items, int threads) {
    if (width < 1 || height < 1 || width > kMaxTargetSize || height > kMaxTargetSize)
        return Error{"visibility pass: target " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxTargetSize) + " per side"};
    if (format != DepthFormat::D16 && format != DepthFormat::D24 && format != DepthFormat::D32F)
        return Error{"visibility pass: invalid depth format"};
    if (threads < 0)
        return Error{"visibility pass: threads = " + std::to_string(threads) +
                     " is out of range: it must be >= 0 (0 = all hardware threads)"};
    // Every index and vertex is checked in the front end, next to its use; only when some check
    // fails does `validate` run, to return the first error in item and index order.
    bool counts_ok = true;
    for (const VisibilityItem& it : items) counts_ok = counts_ok && it.mesh.indices.size() % 3 == 0;
    if (!counts_ok) return validate(items);
    threads = detail::effective_threads(threads);
    State& s = *s_;
    if (!s.front_end(width, height, items, threads)) return validate(items);
    if (items.size() >= kNoObject) return Error{"visibility pass: too many items (limit 2^32 - 1)"};

    const int side = tile_side(width, height, threads);
    const TileGrid grid{side, (width + side - 1) / side, (height + side - 1) / side};
    s.depth_bounds(items.size(), format);
    s.bin(items, grid);
    const std::size_t pixels = grid.count() * grid.pixels();
    if (s.min1.size() < pixels) {
        s.min1.resize(pixels);
        s.obj1.resize(pixels);
        s.min2.resize(pixels);
    }
    s.hit.assign(items.size(), 0);
    detail::parallel_for(threads, grid.count(),
                         [&](std::size_t tile) { s.shade(items, grid, width, height, format, tile); });

    std::vector<std::uint8_t> result(s.hit.begin(), s.hit.begin() + static_cast<std::ptrdiff_t>(items.size()));
    return result;
}

}  // namespace raster
