// execute.cpp: the scalar reference executor and the tiled (optionally multithreaded) executor.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "exact_bounds.h"
#include "raster/detail/parallel.h"
#include "pipeline.h"
#include "raster/command_batch.h"
#include "validate.h"


namespace raster {
namespace {

constexpr std::uint32_t kNoQuery = std::numeric_limits<std::uint32_t>::max();
constexpr int kTileSize = 64;  // llvmpipe's tile size; one task owns one tile

detail::FrontEndParams params_for(const DepthTarget& target, const DrawState& s) {
    detail::FrontEndParams p{};
    p.target_width = target.width();
    p.target_height = target.height();
    p.viewport = s.viewport ? *s.viewport : Viewport{0, 0, target.width(), target.height()};
    p.cull_face = s.cull_face;
    p.front_face = s.front_face;
    return p;
}

Double4 widen(const Float4& v) {
    return Double4{static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z), static_cast<double>(v.w)};
}

// Front end of one exact-bounds draw (float input is widened exactly).
void setup_bounds_draw(const detail::FrontEndParams& p, const Command& c, std::uint32_t draw,
                       std::vector<detail::BoundsTri>& out, std::vector<detail::BoundsVertex>& pool) {
    const auto& idx = c.double_input ? c.mesh_d.indices : c.mesh.indices;
    for (std::size_t k = 0; k + 2 < idx.size(); k += 3) {
        if (c.double_input) {
            const auto& v = c.mesh_d.vertices;
            detail::setup_bounds_triangle(p, v[idx[k]], v[idx[k + 1]], v[idx[k + 2]], draw, out, pool);
        } else {
            const auto& v = c.mesh.vertices;
            detail::setup_bounds_triangle(p, widen(v[idx[k]]), widen(v[idx[k + 1]]), widen(v[idx[k + 2]]), draw, out,
                                          pool);
        }
    }
}

void finish_results(const CommandBatch& batch, QueryResults& r) {
    const auto& kinds = batch.query_kinds();
    for (std::size_t q = 0; q < r.size(); ++q)
        if (kinds[q] == QueryKind::AnySamplesPassed) r[q] = r[q] > 0 ? 1 : 0;
}


}  // namespace

Result<QueryResults> execute_reference(DepthTarget& target, const CommandBatch& batch, const ExecuteOptions& options) {
    if (Status s = detail::validate(target, batch); !s) return s.error();
    QueryResults results(batch.query_kinds().size(), 0);
    std::uint32_t active = kNoQuery;
    std::vector<detail::SetupTri> tris;
    std::vector<detail::BoundsTri> btris;
    std::vector<detail::BoundsVertex> bpool;
    const detail::DepthRows depth{target.mutable_values().data(), target.width()};
    const auto& cmds = batch.commands();
    for (std::size_t i = 0; i < cmds.size(); ++i) {
        const Command& c = cmds[i];
        if (c.kind == Command::Kind::BeginQuery) {
            active = c.query;
            continue;
        }
        if (c.kind == Command::Kind::EndQuery) {
            active = kNoQuery;
            continue;
        }
        const detail::FrontEndParams p = params_for(target, c.state);
        const detail::DepthState depth_state{target.format(), c.state.depth_func, c.state.depth_write};
        if (c.state.mode == RasterMode::ExactBounds) {
            btris.clear();
            bpool.clear();
            setup_bounds_draw(p, c, static_cast<std::uint32_t>(i), btris, bpool);
            for (const auto& t : btris) {
                const std::uint64_t passed =
                    detail::bounds_rect(t, bpool.data(), depth_state, depth, {t.x0, t.y0, t.x1, t.y1});
                if (active != kNoQuery) results[active] += passed;
            }
            continue;
        }
        const auto& idx = c.mesh.indices;
        const auto& vtx = c.mesh.vertices;
        for (std::size_t k = 0; k + 2 < idx.size(); k += 3) {
            tris.clear();
            detail::setup_triangle(p, vtx[idx[k]], vtx[idx[k + 1]], vtx[idx[k + 2]], static_cast<std::uint32_t>(i),
                                   tris);
            for (const auto& t : tris) {
                const std::uint64_t passed =
                    detail::raster_rect(t, depth_state, depth, {t.x0, t.y0, t.x1, t.y1}, options.allow_simd);
                if (active != kNoQuery) results[active] += passed;
            }
        }
    }
    finish_results(batch, results);
    return results;
}

Result<QueryResults> execute(DepthTarget& target, const CommandBatch& batch, const ExecuteOptions& options) {
    if (options.threads < 0)
        return Error{"execute: threads = " + std::to_string(options.threads) +
                     " is out of range: it must be >= 0 (0 = all hardware threads)"};
    if (Status s = detail::validate(target, batch); !s) return s.error();
    const int threads = detail::effective_threads(options.threads);
    const auto& cmds = batch.commands();

    // Front end, per draw in parallel; each draw's triangles land in its own list so the order is
    // the command order whatever the schedule.
    std::vector<std::uint32_t> draw_cmds;
    std::vector<std::uint32_t> draw_query;  // active query of each draw command (by command index)
    std::vector<std::uint32_t> cmd_query(cmds.size(), kNoQuery);
    {
        std::uint32_t active = kNoQuery;
        for (std::size_t i = 0; i < cmds.size(); ++i) {
            if (cmds[i].kind == Command::Kind::BeginQuery) active = cmds[i].query;
            else if (cmds[i].kind == Command::Kind::EndQuery) active = kNoQuery;
            else {
                draw_cmds.push_back(static_cast<std::uint32_t>(i));
                cmd_query[i] = active;
            }
        }
    }
    std::vector<std::vector<detail::SetupTri>> per_draw(draw_cmds.size());
    std::vector<std::vector<detail::BoundsTri>> per_draw_bounds(draw_cmds.size());  // exact-bounds draws
    std::vector<std::vector<detail::BoundsVertex>> per_draw_pool(draw_cmds.size());
    // With several threads, a big GL-exact draw is split into pieces of kFrontEndPiece triangles;
    // piece 0 fills the draw's list, the others their own lists, appended after in piece order
    // (so the list is the same as one serial pass, whatever the thread count).
    constexpr std::size_t kFrontEndPiece = 2048;
    struct Piece {
        std::uint32_t draw;
        std::size_t k0, k1;  // index range [k0, k1) of the draw's index list (whole triangles)
    };
    std::vector<Piece> pieces;
    for (std::size_t d = 0; d < draw_cmds.size(); ++d) {
        const Command& c = cmds[draw_cmds[d]];
        const std::size_t n = c.state.mode == RasterMode::ExactBounds ? 0 : c.mesh.indices.size() / 3 * 3;
        if (threads == 1 || n <= 3 * kFrontEndPiece) {
            pieces.push_back({static_cast<std::uint32_t>(d), 0, n});
            continue;
        }
        for (std::size_t k = 0; k < n; k += 3 * kFrontEndPiece)
            pieces.push_back({static_cast<std::uint32_t>(d), k, std::min(n, k + 3 * kFrontEndPiece)});
    }
    std::vector<std::vector<detail::SetupTri>> piece_out(pieces.size());
    detail::parallel_for(threads, pieces.size(), [&](std::size_t j) {
        const std::size_t d = pieces[j].draw;
        const Command& c = cmds[draw_cmds[d]];
        const detail::FrontEndParams p = params_for(target, c.state);
        if (c.state.mode == RasterMode::ExactBounds) {
            setup_bounds_draw(p, c, draw_cmds[d], per_draw_bounds[d], per_draw_pool[d]);
            return;
        }
        const auto& idx = c.mesh.indices;
        const auto& vtx = c.mesh.vertices;
        auto& out = pieces[j].k0 == 0 ? per_draw[d] : piece_out[j];
        out.reserve(out.size() + (pieces[j].k1 - pieces[j].k0) / 3);  // one SetupTri per unclipped triangle
        for (std::size_t k = pieces[j].k0; k + 2 < pieces[j].k1; k += 3)
            detail::setup_triangle(p, vtx[idx[k]], vtx[idx[k + 1]], vtx[idx[k + 2]], draw_cmds[d], out);
    });
    for (std::size_t j = 0; j < pieces.size(); ++j)
        if (pieces[j].k0 != 0)
            per_draw[pieces[j].draw].insert(per_draw[pieces[j].draw].end(), piece_out[j].begin(), piece_out[j].end());

    // Binning: each tile lists the triangles overlapping it, in command order.
    const int tiles_x = (target.width() + kTileSize - 1) / kTileSize;
    const int tiles_y = (target.height() + kTileSize - 1) / kTileSize;
    const std::size_t tile_count = static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y);
    struct Ref {
        std::uint32_t draw;
        std::uint32_t tri;
    };
    std::vector<std::vector<Ref>> bins(tile_count);
    // Parallel binning over bands of tile rows: each band walks every triangle in command order and
    // fills only its own tiles, so every bin is the same list for any thread count.
    const int bands = threads > 1 ? std::min(threads, tiles_y) : 1;
    detail::parallel_for(threads, static_cast<std::size_t>(bands), [&](std::size_t band) {
        const int band_ty0 = static_cast<int>(static_cast<std::size_t>(tiles_y) * band / static_cast<std::size_t>(bands));
        const int band_ty1 =
            static_cast<int>(static_cast<std::size_t>(tiles_y) * (band + 1) / static_cast<std::size_t>(bands)) - 1;
        auto bin = [&](std::size_t d, std::size_t t, int bx0, int by0, int bx1, int by1) {
            for (int ty = std::max(by0 / kTileSize, band_ty0); ty <= std::min(by1 / kTileSize, band_ty1); ++ty)
                for (int tx = bx0 / kTileSize; tx <= bx1 / kTileSize; ++tx)
                    bins[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x) + static_cast<std::size_t>(tx)]
                        .push_back({static_cast<std::uint32_t>(d), static_cast<std::uint32_t>(t)});
        };
        for (std::size_t d = 0; d < per_draw.size(); ++d) {
            for (std::size_t t = 0; t < per_draw[d].size(); ++t) {
                const auto& tri = per_draw[d][t];
                const int ty0 = std::max(tri.y0 / kTileSize, band_ty0), ty1 = std::min(tri.y1 / kTileSize, band_ty1);
                if (ty0 > ty1) continue;
                if (tri.y0 / kTileSize == tri.y1 / kTileSize && tri.x0 / kTileSize == tri.x1 / kTileSize) {
                    bin(d, t, tri.x0, tri.y0, tri.x1, tri.y1);
                    continue;
                }
                // GL-exact triangles over several tiles: tile-level trivial reject (no centre of the
                // tile's part of the box is covered), exact integers (detail::rect_outside).
                for (int ty = ty0; ty <= ty1; ++ty)
                    for (int tx = tri.x0 / kTileSize; tx <= tri.x1 / kTileSize; ++tx) {
                        const int rx0 = std::max(tri.x0, tx * kTileSize);
                        const int rx1 = std::min(tri.x1, tx * kTileSize + kTileSize - 1);
                        const int ry0 = std::max(tri.y0, ty * kTileSize);
                        const int ry1 = std::min(tri.y1, ty * kTileSize + kTileSize - 1);
                        if (detail::rect_outside(tri, rx0, ry0, rx1, ry1)) continue;
                        bins[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x) + static_cast<std::size_t>(tx)]
                            .push_back({static_cast<std::uint32_t>(d), static_cast<std::uint32_t>(t)});
                    }
            }
            for (std::size_t t = 0; t < per_draw_bounds[d].size(); ++t) {
                const auto& tri = per_draw_bounds[d][t];
                bin(d, t, tri.x0, tri.y0, tri.x1, tri.y1);
            }
        }
    });

    // Back end: one task per tile; counters kept per tile as (query, count) runs.
    std::vector<std::vector<std::pair<std::uint32_t, std::uint64_t>>> tile_counts(tile_count);
    const detail::DepthRows depth{target.mutable_values().data(), target.width()};
    const int width = target.width();
    const int height = target.height();
    const DepthFormat format = target.format();
    const auto& query_kinds = batch.query_kinds();
    const std::unique_ptr<std::atomic<bool>[]> answered(new std::atomic<bool>[query_kinds.size() + 1]);
    for (std::size_t q = 0; q <= query_kinds.size(); ++q) answered[q].store(false, std::memory_order_relaxed);
    detail::parallel_for(threads, tile_count, [&](std::size_t tile) {
        const int tx = static_cast<int>(tile % static_cast<std::size_t>(tiles_x));
        const int ty = static_cast<int>(tile / static_cast<std::size_t>(tiles_x));
        const int x0 = tx * kTileSize, y0 = ty * kTileSize;
        const int x1 = std::min(x0 + kTileSize, width) - 1, y1 = std::min(y0 + kTileSize, height) - 1;
        const auto clip_to_tile = [&](int bx0, int by0, int bx1, int by1) {
            return detail::PixelRect{std::max(x0, bx0), std::max(y0, by0), std::min(x1, bx1), std::min(y1, by1)};
        };
        auto& counts = tile_counts[tile];
        for (const Ref& r : bins[tile]) {
            const std::uint32_t cmd = draw_cmds[r.draw];
            const Command& c = cmds[cmd];
            const detail::DepthState depth_state{format, c.state.depth_func, c.state.depth_write};
            std::uint64_t passed;
            if (c.state.mode == RasterMode::ExactBounds) {
                const auto& tri = per_draw_bounds[r.draw][r.tri];
                passed = detail::bounds_rect(tri, per_draw_pool[r.draw].data(), depth_state, depth,
                                             clip_to_tile(tri.x0, tri.y0, tri.x1, tri.y1));
            } else {
                // Any-samples query with the mask off: once this query has a passing sample (in this
                // tile, or in any tile: the flag), further draws in it change nothing; the kernel
                // also stops at its first passing row. The boolean is the same whatever the schedule.
                const std::uint32_t aq = cmd_query[cmd];
                const bool any_only = aq != kNoQuery && !c.state.depth_write &&
                                      query_kinds[aq] == QueryKind::AnySamplesPassed;
                if (any_only && ((!counts.empty() && counts.back().first == aq) ||
                                 answered[aq].load(std::memory_order_relaxed)))
                    continue;
                const auto& tri = per_draw[r.draw][r.tri];
                passed = detail::raster_rect(tri, depth_state, depth, clip_to_tile(tri.x0, tri.y0, tri.x1, tri.y1),
                                             options.allow_simd, any_only);
                if (any_only && passed != 0) answered[aq].store(true, std::memory_order_relaxed);
            }
            const std::uint32_t q = cmd_query[cmd];
            if (q == kNoQuery || passed == 0) continue;
            if (!counts.empty() && counts.back().first == q) counts.back().second += passed;
            else counts.emplace_back(q, passed);
        }
    });

    QueryResults results(batch.query_kinds().size(), 0);
    for (const auto& counts : tile_counts)
        for (const auto& [q, n] : counts) results[q] += n;
    finish_results(batch, results);
    return results;
}

}  // namespace raster
