// execute.cpp: the scalar reference executor and the tiled (optionally multithreaded) executor.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "exact_bounds.h"
#include "pipeline.h"
#include "raster/command_batch.h"
#include "raster/detail/parallel.h"
#include "target_blocks.h"
#include "validate.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif


namespace raster {
namespace {

constexpr std::uint32_t kNoQuery = std::numeric_limits<std::uint32_t>::max();
constexpr int kTileSize = kExecuteTileSize;  // llvmpipe's tile size (64); one task owns one tile
// Rectangles of many-tile triangles smaller than this are not shrunk (shrink_rect): the test costs
// about 100 instructions, as much as the kernel spends on a few rows (callgrind, cylinders frame:
// shrinking every such rectangle 4.218e9 Ir, none 4.210e9, from 256 pixels up 4.182e9).
constexpr int kShrinkMinArea = 256;
// The fewest triangles per part of a batch's binning (bin): smaller batches are binned on the
// calling thread.
constexpr std::size_t kMinBinPart = 2048;

detail::FrontEndParams params_for(const DepthTarget& target, RasterRules rules, const DrawState& s) {
    detail::FrontEndParams p{};
    p.rules = rules;
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
    if (c.double_input) {
        detail::setup_bounds_range(p, c.mesh_d.vertices, idx.first(idx.size() / 3 * 3), draw, out, pool);
        return;
    }
    const auto& v = c.mesh.vertices;  // float input, widened exactly
    for (std::size_t k = 0; k + 2 < idx.size(); k += 3)
        detail::setup_bounds_triangle(p, widen(v[idx[k]]), widen(v[idx[k + 1]]), widen(v[idx[k + 2]]), draw, out, pool);
}

// CULLIDE_RASTER_NO_HIZ set to anything but "" or "0" turns hierarchical Z off (read once).
bool hiz_allowed_by_environment() {
    static const bool ok = [] {
        const char* v = std::getenv("CULLIDE_RASTER_NO_HIZ");
        return v == nullptr || v[0] == '\0' || (v[0] == '0' && v[1] == '\0');
    }();
    return ok;
}

void finish_results(const CommandBatch& batch, QueryResults& r) {
    const auto& kinds = batch.query_kinds();
    for (std::size_t q = 0; q < r.size(); ++q)
        if (kinds[q] == QueryKind::AnySamplesPassed) r[q] = r[q] > 0 ? 1 : 0;
}


}  // namespace

Result<QueryResults> execute_reference(DepthTarget& target, const CommandBatch& batch, const ExecuteOptions& options) {
    if (Status s = detail::validate(target, batch); !s) return s.error();
    if (options.clear_depth) {
        if (Status s = target.clear(*options.clear_depth); !s) return Error{"execute: clear_depth: " + s.error().message};
    }
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
        const detail::FrontEndParams p = params_for(target, batch.rules(), c.state);
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

namespace {

// The tiled executor's phases, in order: draws(), front_end(), bin(), then shade() per tile.

// The front end's unit of parallel work: with several threads, a GL-exact draw of more than
// kFrontEndPiece triangles is cut into entries (pieces) of kFrontEndPiece triangles.
constexpr std::size_t kFrontEndPiece = 2048;

// Cuts items [0, n) into runs of about `per_run` work each (work(i): an item's cost), in order:
// run r is [first[r], first[r + 1]). The reach pass and the front end of a CULLIDE batch run over
// many small draws (its sub-objects' queries) and a few big ones (its writes): runs of equal item
// counts put the big ones in one run, and with 2 threads the reach pass took as long as with 1
// (14.5 ms against 14.9 over a cylinders / cullide benchmark run). The items' results do not depend
// on the runs.
template <class Work>
void runs_by_work(int threads, std::size_t n, std::size_t per_run, const Work& work, std::vector<std::size_t>& first) {
    first.clear();
    first.push_back(0);
    if (threads <= 1) per_run = std::numeric_limits<std::size_t>::max();  // one run: no job to balance
    std::size_t acc = 0;
    for (std::size_t i = 0; i < n; ++i) {
        acc += work(i);
        if (acc >= per_run && i + 1 < n) {  // (acc never reaches max(): it counts indices of memory)
            first.push_back(i + 1);
            acc = 0;
        }
    }
    first.push_back(n);
}
// The reach pass's and the front end's run sizes, in indices read (a draw's fixed cost counted as
// that many indices).
constexpr std::size_t kReachRunIndices = 16384, kReachDrawCost = 32;
constexpr std::size_t kSetupRunTriangles = 1024, kSetupDrawCost = 4;

// The draw commands of a sequence of batches (execute: one batch), in order: batch k's entries are
// [first[k], first[k + 1]). An entry is a draw command, or with several threads one piece of a big
// GL-exact draw (a run of its index list: the pieces of a draw follow one another with the draw's
// state and query, so their triangles keep the draw's order and every result is the same as with
// the draw whole). Each entry's triangles are set up into their own list on some thread; pieces
// used to be set up apart and then appended to their draw's list on the calling thread, a serial
// copy (with reallocation) of up to the whole list: 10% of the calling thread's samples in a leaves
// / qcullide-gl frame at 2 threads (perf, DWARF call graphs).
struct Draws {
    std::vector<const Command*> cmd;    // per entry: its command
    std::vector<std::uint32_t> index;   // per entry: the command's index in its batch
    std::vector<std::uint32_t> query;   // per entry: its batch's query active at it, or kNoQuery
    std::vector<RasterRules> rules;     // per entry: its batch's rules
    std::vector<std::size_t> k0, k1;    // per entry: its part [k0, k1) of the command's index list
    // Per entry: the pixels outside which it need not be drawn (queries_only: observed_draws' clip
    // of a write outside every query), else the whole target.
    std::vector<detail::PixelRect> clip;
    // Per entry with a clip: its part in each row of tiles from the clip's first (tile_of(clip.y0)
    // + i: spans[i], empty when x0 > x1); nullptr when the clip is the whole target.
    std::vector<const detail::PixelRect*> spans;
    std::vector<std::size_t> first;     // per batch, and the total at the end
};

// ExecuteOptions::queries_only: which draw commands of a batch a query can observe.
//
// A draw changes the stored depth only at pixels it covers, and a query's count reads the stored
// depth only at pixels its draws cover; so a write (depth mask on) matters only if a later query
// of the batch covers one of its pixels, and a draw that neither writes nor counts for a query
// matters not at all. On a batch that starts cleared to 1, a query draw with the mask off whose
// pixels no earlier kept write covers meets 1 everywhere: with GEQUAL, GREATER or EQUAL and every
// fragment's window depth below 1 (NEVER: always) no sample passes, so its count is 0 without
// drawing it. Skipped writes are not counted as earlier writes: a later query's pixels do not meet
// them (else they would be kept). So the query results are the same bit for bit; only the target's
// final content differs (the option says so).
//
// "Covers" is taken from a box that holds every pixel the draw's GL-exact rasterization can touch:
// orthographic input (every used vertex with w = 1) maps to window X = x * (w / 2) + (x0 + w / 2)
// (the viewport; clipping only shrinks the triangle), a pixel is covered only if its centre is inside
// the snapped triangle, so [floor(min X) - 1, ceil(max X) + 1] with a whole pixel of slack for the
// snapping and the float arithmetic, cut to the target; the same in Y; and window depth z * 0.5 +
// 0.5 (GL) or z (Vulkan's half-z), so the largest vertex depth bounds every fragment's up to the
// plane's float rounding (far below the 2^-10 the test above keeps from 1). Draws of double input,
// of exact bounds or with w != 1 cover the whole target at an unknown depth (never skipped by the
// query rule). Pixels are grouped in square cells (8 x 8 at 1024^2: at most 128 a side), which can
// only keep more draws.
struct DrawReach {
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // cells, inclusive; empty when x0 > x1
    bool depth_known = false;
    double zmax = 1.0;  // window depth bound
};

// The units whose reach is taken: a draw command, or a piece of kObservePiece triangles of a big
// GL-exact draw (so that the parts of a whole object far from every other object are skipped: the
// cloth, the tree of leaves). Pieces keep the draw's order, state and query, as the front end's
// pieces do (Draws), so a draw run as its kept pieces gives its results.
constexpr std::size_t kObservePiece = 1024;
struct ObservedUnit {
    std::uint32_t cmd;
    std::uint32_t query;  // the query active at it, or kNoQuery
    std::size_t k0, k1;   // its part of the command's index list
};
// One batch's units in command order, and which of them run.
// observed_draws' clips: none (every pixel may matter), and empty (no pixel does).
constexpr detail::PixelRect kNoClip{-1, -1, -1, -1};
constexpr detail::PixelRect kEmptyClip{1, 1, 0, 0};
struct ObservedBatch {
    std::vector<ObservedUnit> units;
    std::vector<std::uint8_t> keep;
    // Per unit, where a kept write matters: the box in pixels and its part per row of tiles (its
    // entries in `spans` from span_first); `no_clip` when every pixel may.
    std::vector<detail::PixelRect> clip;
    std::vector<std::uint32_t> span_first;
    std::vector<detail::PixelRect> spans;
};

// Flags over the cells, with a coarse level (8 x 8 cells) so that a large box costs a few coarse
// cells: `fine` per cell, and per coarse cell `some` (a fine flag or a large box is inside) and
// `all` (a large box reached it: every cell counts as flagged). Both answers are supersets, which
// can only keep more draws. Rows of bits (a grid has at most CellGrid::kMaxCells = 128 cells a side:
// two words per fine row, one per coarse row), so a box is a mask per row: the serial sweeps of
// observed_draws marked and tested byte by byte, reloading the vectors after every byte store
// (bunny-dragon / cullide at 2 threads: 10% of the samples, all on the calling thread).
class CellFlags {
   public:
    void reset(const detail::CellGrid& g) {
        const auto rows = static_cast<std::size_t>(g.y);
        fine_.assign(rows * 2, 0);
        some_.assign((rows + 7) / 8, 0);
        all_.assign(some_.size(), 0);
    }
    [[nodiscard]] bool any(const DrawReach& r) const {
        const bool large = (r.x1 - r.x0 + 1) * (r.y1 - r.y0 + 1) > kSmall;
        const std::uint64_t cmask = span_bits(r.x0 >> 3, r.x1 >> 3, 0);
        for (int y = r.y0 >> 3; y <= r.y1 >> 3; ++y) {
            const auto c = static_cast<std::size_t>(y);
            if ((all_[c] | (large ? some_[c] : 0)) & cmask) return true;
        }
        if (large) return false;
        const std::uint64_t m0 = span_bits(r.x0, r.x1, 0), m1 = span_bits(r.x0, r.x1, 1);
        for (int y = r.y0; y <= r.y1; ++y) {
            const std::uint64_t* row = fine_.data() + 2 * static_cast<std::size_t>(y);
            if ((row[0] & m0) | (row[1] & m1)) return true;
        }
        return false;
    }
    // The smallest box of cells holding every flagged cell of r (a coarse cell flagged `all`
    // counts as all its cells); empty (x0 > x1) when there is none.
    [[nodiscard]] DrawReach bounds_in(const DrawReach& r) const {
        DrawReach b;
        b.x0 = b.y0 = std::numeric_limits<int>::max();
        b.x1 = b.y1 = -1;
        const auto extend = [&](int x0, int y0, int x1, int y1) {
            b.x0 = std::min(b.x0, x0), b.y0 = std::min(b.y0, y0);
            b.x1 = std::max(b.x1, x1), b.y1 = std::max(b.y1, y1);
        };
        const std::uint64_t cmask = span_bits(r.x0 >> 3, r.x1 >> 3, 0);
        const std::uint64_t m0 = span_bits(r.x0, r.x1, 0), m1 = span_bits(r.x0, r.x1, 1);
        for (int y = r.y0 >> 3; y <= r.y1 >> 3; ++y) {
            const auto c = static_cast<std::size_t>(y);
            const int fy0 = std::max(r.y0, y * 8), fy1 = std::min(r.y1, y * 8 + 7);
            // The `all` cells of this coarse row share its rows: their union is one box, from the
            // first to the last of them, cut to r.
            const std::uint64_t all = all_[c] & cmask;
            if (all != 0) {
                extend(std::max(r.x0, std::countr_zero(all) * 8), fy0,
                       std::min(r.x1, (63 - std::countl_zero(all)) * 8 + 7), fy1);
            }
            // Fine flags lie only in cells flagged `some`; those inside an `all` cell are in its box
            // already, so with any `some` cell not `all`, each row's flags within r extend the box.
            if ((some_[c] & ~all_[c] & cmask) == 0) continue;
            for (int fy = fy0; fy <= fy1; ++fy) {
                const std::uint64_t* row = fine_.data() + 2 * static_cast<std::size_t>(fy);
                const std::uint64_t w0 = row[0] & m0, w1 = row[1] & m1;
                if ((w0 | w1) == 0) continue;
                const int lo = w0 != 0 ? std::countr_zero(w0) : 64 + std::countr_zero(w1);
                const int hi = w1 != 0 ? 127 - std::countl_zero(w1) : 63 - std::countl_zero(w0);
                extend(lo, fy, hi, fy);
            }
        }
        return b;
    }
    void mark(const DrawReach& r) {
        const bool large = (r.x1 - r.x0 + 1) * (r.y1 - r.y0 + 1) > kSmall;
        const std::uint64_t cmask = span_bits(r.x0 >> 3, r.x1 >> 3, 0);
        for (int y = r.y0 >> 3; y <= r.y1 >> 3; ++y) {
            const auto c = static_cast<std::size_t>(y);
            some_[c] |= cmask;
            if (large) all_[c] |= cmask;
        }
        if (large) return;
        const std::uint64_t m0 = span_bits(r.x0, r.x1, 0), m1 = span_bits(r.x0, r.x1, 1);
        for (int y = r.y0; y <= r.y1; ++y) {
            std::uint64_t* row = fine_.data() + 2 * static_cast<std::size_t>(y);
            row[0] |= m0;
            row[1] |= m1;
        }
    }

   private:
    static constexpr int kSmall = 64;  // boxes of more cells go to the coarse level
    static_assert(detail::CellGrid::kMaxCells <= 128, "two words per fine row");
    // The bits of columns [a, b] (a <= b) that fall in word w (columns 64 w .. 64 w + 63).
    [[nodiscard]] static std::uint64_t span_bits(int a, int b, int w) {
        const int lo = std::max(a, 64 * w), hi = std::min(b, 64 * w + 63);
        if (lo > hi) return 0;
        return (~std::uint64_t{0} >> (63 - (hi - lo))) << (lo - 64 * w);
    }
    std::vector<std::uint64_t> fine_;       // per fine row, two words
    std::vector<std::uint64_t> some_, all_;  // per coarse row, one word (at most 16 coarse columns)
};

DrawReach draw_reach(const DepthTarget& target, RasterRules rules, const Command& c, std::size_t k0, std::size_t k1,
                     int shift) {
    DrawReach r;
    const auto whole = [&] {
        r.x0 = 0, r.y0 = 0, r.x1 = (target.width() - 1) >> shift, r.y1 = (target.height() - 1) >> shift;
        r.depth_known = false;
        return r;
    };
    if (c.double_input || c.state.mode != RasterMode::GLExact) return whole();
    k1 = k0 + (k1 - k0) / 3 * 3;
    if (k1 == k0) return r;
    constexpr float kInf = __builtin_inff();
    float x0 = kInf, x1 = -kInf, y0 = kInf, y1 = -kInf, z1 = -kInf;
    const Float4* verts = c.mesh.vertices.data();
    const std::uint32_t* idx = c.mesh.indices.data();
#if defined(__SSE2__)
    // All four coordinates per vertex in one register: a min and a max per index (the scalar loop
    // was 20 instructions per index: 9% of a 2-thread cloth / cullide frame, perf). The vertices
    // were validated finite, so minps / maxps with the running value second are std::min / std::max
    // with it first (ties keep it), and every w is 1 exactly when the least and the greatest are.
    static_assert(sizeof(Float4) == 4 * sizeof(float), "a vertex is read as 4 floats");
    __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
    for (std::size_t k = k0; k < k1; ++k) {
        const __m128 v = _mm_loadu_ps(&verts[idx[k]].x);
        lo = _mm_min_ps(v, lo);
        hi = _mm_max_ps(v, hi);
    }
    alignas(16) float l[4], h[4];
    _mm_store_ps(l, lo);
    _mm_store_ps(h, hi);
    const bool ortho = l[3] == 1.0f && h[3] == 1.0f;
    x0 = l[0], y0 = l[1], x1 = h[0], y1 = h[1], z1 = h[2];
#else
    bool ortho = true;
    for (std::size_t k = k0; k < k1; ++k) {
        const Float4& v = verts[idx[k]];
        ortho = ortho && v.w == 1.0f;
        x0 = std::min(x0, v.x), x1 = std::max(x1, v.x);
        y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
        z1 = std::max(z1, v.z);
    }
#endif
    if (!ortho) return whole();
    const Viewport vp = c.state.viewport ? *c.state.viewport : Viewport{0, 0, target.width(), target.height()};
    const double hw = vp.width * 0.5, hh = vp.height * 0.5;
    const double wx0 = static_cast<double>(x0) * hw + (vp.x + hw), wx1 = static_cast<double>(x1) * hw + (vp.x + hw);
    const double wy0 = static_cast<double>(y0) * hh + (vp.y + hh), wy1 = static_cast<double>(y1) * hh + (vp.y + hh);
    const double w1 = target.width() - 1, h1 = target.height() - 1;
    const double bx0 = std::max(std::floor(wx0) - 1.0, 0.0), bx1 = std::min(std::ceil(wx1) + 1.0, w1);
    const double by0 = std::max(std::floor(wy0) - 1.0, 0.0), by1 = std::min(std::ceil(wy1) + 1.0, h1);
    if (!(bx0 <= bx1 && by0 <= by1)) return r;  // outside the target: no pixel
    r.x0 = static_cast<int>(bx0) >> shift, r.x1 = static_cast<int>(bx1) >> shift;
    r.y0 = static_cast<int>(by0) >> shift, r.y1 = static_cast<int>(by1) >> shift;
    r.depth_known = true;
    r.zmax = rules == RasterRules::Vulkan ? static_cast<double>(z1) : static_cast<double>(z1) * 0.5 + 0.5;
    return r;
}

// The batch's units into ob.units and whether each must run into ob.keep; see above. The reaches
// are found in parallel chunks of units; the two sweeps are serial but touch cells only. `read`
// holds the cells that queries after the batch may read (reset by the caller: empty when the next
// batch starts on a cleared target) and is left holding the batch's own as well.
void observed_draws(const DepthTarget& target, const detail::CellGrid& grid, const CommandBatch& batch,
                    bool cleared_to_one, int threads, std::vector<DrawReach>& reach, CellFlags& read,
                    ObservedBatch& ob) {
    const auto& cmds = batch.commands();
    ob.units.clear();
    std::uint32_t active = kNoQuery;
    for (std::size_t i = 0; i < cmds.size(); ++i) {
        const Command& c = cmds[i];
        if (c.kind == Command::Kind::BeginQuery) {
            active = c.query;
        } else if (c.kind == Command::Kind::EndQuery) {
            active = kNoQuery;
        } else {
            const std::size_t n = c.double_input ? c.mesh_d.indices.size() : c.mesh.indices.size();
            const bool pieces = c.state.mode == RasterMode::GLExact && !c.double_input && n > 3 * 3 * kObservePiece;
            const std::size_t step = pieces ? 3 * kObservePiece : std::max<std::size_t>(n, 1);
            for (std::size_t k = 0; k == 0 || k < n; k += step)
                ob.units.push_back({static_cast<std::uint32_t>(i), active, k, std::min(n, k + step)});
        }
    }
    const std::size_t n_units = ob.units.size();
    reach.resize(n_units);
    ob.keep.assign(n_units, 0);
    ob.clip.assign(n_units, kNoClip);
    ob.span_first.assign(n_units, 0);
    ob.spans.clear();
    // Cells to pixels: a cell's first pixel, and its last cut to the target.
    const int shift = grid.shift;
    const auto first_px = [&](int cell) { return cell << shift; };
    const auto last_px = [&](int cell, int last) { return std::min(((cell + 1) << shift) - 1, last); };
    const int last_x = target.width() - 1, last_y = target.height() - 1;
    thread_local std::vector<std::size_t> reach_runs;
    std::vector<std::size_t>& run_first = reach_runs;  // this thread's (a thread_local named in a job is the job thread's)
    runs_by_work(
        threads, n_units, kReachRunIndices, [&](std::size_t u) { return ob.units[u].k1 - ob.units[u].k0 + kReachDrawCost; },
        run_first);
    detail::parallel_for(threads, run_first.size() - 1, [&](std::size_t run) {
        for (std::size_t u = run_first[run]; u < run_first[run + 1]; ++u)
            reach[u] = draw_reach(target, batch.rules(), cmds[ob.units[u].cmd], ob.units[u].k0, ob.units[u].k1, grid.shift);
    });
    for (std::size_t u = n_units; u-- > 0;) {  // backward: the writes a later query may read
        const DrawReach& r = reach[u];
        if (r.x0 > r.x1 || r.y0 > r.y1) continue;  // no pixel
        const bool counted = ob.units[u].query != kNoQuery;
        ob.keep[u] = counted || (cmds[ob.units[u].cmd].state.depth_write && read.any(r)) ? 1 : 0;
        // A kept write outside every query: only its pixels in cells that later queries read
        // matter, so it is drawn within the box of those cells (exact: the other pixels' stored
        // depth is never read again; the target's final content is unspecified). A write inside a
        // query is drawn whole (its count is the query's).
        if (!counted && ob.keep[u]) {
            // Per row of tiles of its box, the box of the read cells there (at 1024^2 a row of
            // tiles is a row of CellFlags' coarse cells): the clip follows the reading queries
            // more closely than one box around them (leaves / cullide: a third fewer cells). The
            // clip's box is their union; rows before the first and after the last read cell are
            // left out.
            const std::size_t first = ob.spans.size();
            detail::PixelRect box = kEmptyClip;
            std::size_t last_used = first;  // one past the last row of tiles with a read cell
            const int ry0 = first_px(r.y0), ry1 = last_px(r.y1, last_y);
            for (int ty = ry0 / kTileSize; ty <= ry1 / kTileSize; ++ty) {
                DrawReach band = r;
                band.y0 = std::max(ry0, ty * kTileSize) >> shift;
                band.y1 = std::min(ry1, ty * kTileSize + kTileSize - 1) >> shift;
                const DrawReach sb = read.bounds_in(band);
                if (sb.x0 > sb.x1) {
                    if (ob.spans.size() > first) ob.spans.push_back(kEmptyClip);  // none before the first
                    continue;
                }
                const detail::PixelRect span{first_px(sb.x0), first_px(sb.y0), last_px(sb.x1, last_x), last_px(sb.y1, last_y)};
                if (ob.spans.size() == first) box = span;
                box = {std::min(box.x0, span.x0), box.y0, std::max(box.x1, span.x1), span.y1};
                ob.spans.push_back(span);
                last_used = ob.spans.size();
            }
            ob.spans.resize(last_used);  // none after the last
            ob.clip[u] = box;  // kEmptyClip when no read cell is in the box: not drawn
            ob.span_first[u] = static_cast<std::uint32_t>(first);
        }
        if (counted) read.mark(r);
    }
    if (!cleared_to_one) return;
    thread_local CellFlags written;
    written.reset(grid);
    constexpr double kBelowClear = 1.0 - 0x1p-10;
    for (std::size_t u = 0; u < n_units; ++u) {  // forward: queries that meet only the clear value
        if (!ob.keep[u]) continue;
        const Command& c = cmds[ob.units[u].cmd];
        const DrawReach& r = reach[u];
        if (ob.units[u].query != kNoQuery && !c.state.depth_write) {
            const DepthFunc f = c.state.depth_func;
            const bool fails_on_clear =
                f == DepthFunc::Never || ((f == DepthFunc::GEqual || f == DepthFunc::Greater || f == DepthFunc::Equal) &&
                                          r.depth_known && r.zmax <= kBelowClear);
            if (fails_on_clear && (f == DepthFunc::Never || !written.any(r))) {
                ob.keep[u] = 0;
                continue;
            }
        }
        if (c.state.depth_write) written.mark(r);
    }
}

void draws(std::span<const CommandBatch* const> batches, int threads, Draws& d, const DepthTarget& target,
           const ExecuteOptions& options) {
    thread_local std::vector<DrawReach> reach;
    thread_local CellFlags read;
    thread_local std::vector<ObservedBatch> observed;
    if (options.queries_only) {
        // Each batch on a cleared target (clear_depth): its queries read only its own writes.
        // Otherwise a batch starts on the one before's depth, so a write is kept when a query of
        // its own or of any later batch may read it: the batches from the last, the cells carried.
        if (observed.size() < batches.size()) observed.resize(batches.size());
        const detail::CellGrid grid = detail::CellGrid::of(target.width(), target.height());
        const bool cleared_to_one = options.clear_depth && *options.clear_depth >= 1.0;
        read.reset(grid);
        for (std::size_t k = batches.size(); k-- > 0;) {
            if (options.clear_depth) read.reset(grid);
            observed_draws(target, grid, *batches[k], cleared_to_one, threads, reach, read, observed[k]);
        }
    }
    d.cmd.clear();
    d.index.clear();
    d.query.clear();
    d.rules.clear();
    d.k0.clear();
    d.k1.clear();
    d.clip.clear();
    d.spans.clear();
    d.first.clear();
    // Part [u0, u1) of command i's index list as one entry, or with several threads a big GL-exact
    // part as pieces of kFrontEndPiece triangles.
    const detail::PixelRect whole{0, 0, target.width() - 1, target.height() - 1};
    const auto add = [&](const CommandBatch& batch, std::size_t i, std::uint32_t query, std::size_t u0, std::size_t u1,
                         const detail::PixelRect& clip, const detail::PixelRect* spans) {
        const Command& c = batch.commands()[i];
        const bool split = threads > 1 && c.state.mode == RasterMode::GLExact && !c.double_input &&
                           u1 - u0 > 3 * kFrontEndPiece;
        for (std::size_t k = u0; k == u0 || (split && k < u1); k += 3 * kFrontEndPiece) {
            d.cmd.push_back(&c);
            d.index.push_back(static_cast<std::uint32_t>(i));
            d.query.push_back(query);
            d.rules.push_back(batch.rules());
            d.k0.push_back(k);
            d.k1.push_back(split ? std::min(u1, k + 3 * kFrontEndPiece) : u1);
            d.clip.push_back(clip);
            d.spans.push_back(spans);
        }
    };
    for (std::size_t b = 0; b < batches.size(); ++b) {
        const CommandBatch& batch = *batches[b];
        d.first.push_back(d.cmd.size());
        if (options.queries_only) {  // the kept units (observed_draws)
            const ObservedBatch& ob = observed[b];
            for (std::size_t u = 0; u < ob.units.size(); ++u) {
                if (!ob.keep[u]) continue;
                // An empty clip (the coarse test kept the write, no read cell is in its box): not
                // drawn at all.
                const detail::PixelRect& c = ob.clip[u];
                if (c.x0 > c.x1) continue;
                const bool clipped = c.x0 != kNoClip.x0;
                add(batch, ob.units[u].cmd, ob.units[u].query, ob.units[u].k0, ob.units[u].k1, clipped ? c : whole,
                    clipped ? ob.spans.data() + ob.span_first[u] : nullptr);
            }
            continue;
        }
        const auto& cmds = batch.commands();
        std::uint32_t active = kNoQuery;
        for (std::size_t i = 0; i < cmds.size(); ++i) {
            if (cmds[i].kind == Command::Kind::BeginQuery) {
                active = cmds[i].query;
            } else if (cmds[i].kind == Command::Kind::EndQuery) {
                active = kNoQuery;
            } else {
                const Command& c = cmds[i];
                add(batch, i, active, 0, c.double_input ? c.mesh_d.indices.size() : c.mesh.indices.size(), whole, nullptr);
            }
        }
    }
    d.first.push_back(d.cmd.size());
}

// The front end's output, one list per draw (a GL-exact draw fills `tris`, an exact-bounds draw
// `bounds` and its vertex `pool`).
struct SetupDraws {
    std::vector<std::uint32_t> src;  // per draw: the draw whose `tris` it uses (itself, or an equal earlier one)
    // Per draw: the face culling the list still needs at binning (CullFace::None when the list
    // was set up with the draw's own culling), and per source draw, the culling its list is set
    // up with (share_setup).
    std::vector<CullFace> bin_cull;
    std::vector<CullFace> setup_cull;
    std::vector<std::vector<detail::SetupTri>> tris;
    // The pieces' lists (Draws), by piece number in the call: a sequence's big draws come back call
    // after call, so each piece number keeps a list of about its size (a list per entry index was
    // reallocated, and its new pages faulted in, in almost every call).
    std::vector<std::vector<detail::SetupTri>> piece_tris;
    // Per entry with a list of its own: tris[d], or its piece's list.
    std::vector<std::vector<detail::SetupTri>*> list;
    [[nodiscard]] const std::vector<detail::SetupTri>& tris_of(std::size_t d) const { return *list[src[d]]; }
    std::vector<std::vector<detail::BoundsTri>> bounds;
    std::vector<std::vector<detail::BoundsVertex>> pool;
};

// Front end, per entry in parallel; each entry's triangles land in its own list, so the order is
// the command order whatever the schedule (see Draws for the pieces of big draws).
// Resizes a list of lists to n and empties the first n (capacity kept: see Scratch).
template <class T>
void reset_lists(std::vector<std::vector<T>>& lists, std::size_t n) {
    if (lists.size() < n) lists.resize(n);
    for (std::size_t i = 0; i < n; ++i) lists[i].clear();
}

// What a GL-exact draw's front end reads: its vertex and index spans (by address: the same
// triangles) and the state it depends on (the target and rules are the batch's), except face
// culling, which only drops some of the list's triangles (SetupTri::front).
struct SetupKey {
    const Float4* vertices;
    std::size_t n_vertices;
    const std::uint32_t* indices;
    std::size_t n_indices;
    int vx, vy, vw, vh;
    FrontFace front;
    RasterRules rules;
    bool operator==(const SetupKey&) const = default;
};
// The first draw of a sequence with each SetupKey: an open-addressing table (linear probing) kept
// between calls, its slots emptied by a new call's stamp instead of a sweep. A std::unordered_map
// allocated a node per draw and freed them all on clear(), on the calling thread before every
// sequence: share_setup was 12 ms of a cylinders / qcullide-gl benchmark run's 200 in execute at 2
// threads (steady_clock accumulators). Which draw a key maps to is the first one found in command
// order, as before.
class SetupIndex {
public:
    // Starts a sequence of up to n draws.
    void reset(std::size_t n) {
        std::size_t cap = 16;
        while (cap < 2 * n) cap *= 2;
        if (slots_.size() < cap || ++stamp_ == 0) {  // (a wrapped stamp: every slot is emptied anew)
            slots_.assign(std::max(cap, slots_.size()), Slot{});
            stamp_ = 1;
        }
        mask_ = slots_.size() - 1;
    }
    // The draw recorded for `key`, recording `d` first if there is none.
    std::uint32_t first_with(const SetupKey& key, std::uint32_t d) {
        for (std::size_t i = hash(key) & mask_;; i = (i + 1) & mask_) {
            Slot& s = slots_[i];
            if (s.stamp != stamp_) {
                s = {key, d, stamp_};
                return d;
            }
            if (s.key == key) return s.draw;
        }
    }

private:
    struct Slot {
        SetupKey key{};
        std::uint32_t draw = 0;
        std::uint32_t stamp = 0;  // the sequence that filled it (0: never)
    };
    static std::size_t hash(const SetupKey& k) {
        std::uint64_t h = reinterpret_cast<std::uintptr_t>(k.vertices) * 0x9e3779b97f4a7c15ull;
        h ^= (reinterpret_cast<std::uintptr_t>(k.indices) + k.n_indices * 0x100000001b3ull) * 0xc2b2ae3d27d4eb4full;
        return static_cast<std::size_t>(h ^ (h >> 29));
    }
    std::vector<Slot> slots_;
    std::size_t mask_ = 0;
    std::uint32_t stamp_ = 0;
};

// Marks draws that repeat an earlier GL-exact draw of the batch (same spans, same front-end state
// but for culling) as users of that draw's setup list: CULLIDE draws each item twice in a batch (its
// query, then its write), and the setup list is a pure function of the key and the culling, so
// sharing it changes no bit. When the users of one list cull differently (R-CULLIDE's offset
// solids: the query culls front faces, the write back faces), the list is set up without culling
// and each draw drops the faces it culls at binning: setup's list with culling is exactly the
// unculled list without those triangles, in the same order (setup culls each triangle, and each
// triangle of a clipped fan, by its own facing, after everything else that decides whether it
// exists). So the triangles are clipped, snapped and set up once instead of once per culling.
void share_setup(const DepthTarget& target, const Draws& draws, SetupDraws& out, SetupIndex& index) {
    const std::size_t n_draws = draws.cmd.size();
    out.src.resize(n_draws);
    out.bin_cull.assign(n_draws, CullFace::None);
    out.setup_cull.assign(n_draws, CullFace::None);
    index.reset(n_draws);
    for (std::size_t d = 0; d < n_draws; ++d) {
        out.src[d] = static_cast<std::uint32_t>(d);
        const Command& c = *draws.cmd[d];
        out.setup_cull[d] = c.state.cull_face;
        if (c.state.mode == RasterMode::ExactBounds || c.double_input) continue;
        const detail::FrontEndParams p = params_for(target, draws.rules[d], c.state);
        const SetupKey key{c.mesh.vertices.data(), c.mesh.vertices.size(), c.mesh.indices.data() + draws.k0[d],
                           draws.k1[d] - draws.k0[d],
                           p.viewport.x, p.viewport.y, p.viewport.width, p.viewport.height, p.front_face, p.rules};
        const std::uint32_t src = index.first_with(key, static_cast<std::uint32_t>(d));
        out.src[d] = src;
        if (out.setup_cull[src] != c.state.cull_face) out.setup_cull[src] = CullFace::None;
    }
    for (std::size_t d = 0; d < n_draws; ++d) {
        const CullFace own = draws.cmd[d]->state.cull_face;
        if (out.setup_cull[out.src[d]] != own) out.bin_cull[d] = own;
    }
}

void front_end(const DepthTarget& target, const Draws& draws, int threads, SetupDraws& out,
               std::vector<std::uint32_t>& own) {
    const std::size_t n_draws = draws.cmd.size();
    reset_lists(out.tris, n_draws);
    reset_lists(out.bounds, n_draws);
    reset_lists(out.pool, n_draws);
    own.clear();  // the entries with a list of their own
    const auto is_piece = [&](std::size_t d) {
        const Command& c = *draws.cmd[d];
        return !c.double_input && draws.k1[d] - draws.k0[d] != c.mesh.indices.size();
    };
    std::size_t pieces = 0;
    for (std::size_t d = 0; d < n_draws; ++d) {
        if (out.src[d] != d) continue;
        own.push_back(static_cast<std::uint32_t>(d));
        pieces += is_piece(d) ? 1 : 0;
    }
    reset_lists(out.piece_tris, pieces);  // sized before any list's address is taken
    out.list.resize(n_draws);
    pieces = 0;
    for (const std::uint32_t d : own) out.list[d] = is_piece(d) ? &out.piece_tris[pieces++] : &out.tris[d];
    thread_local std::vector<std::size_t> setup_runs;
    std::vector<std::size_t>& run_first = setup_runs;  // this thread's (a thread_local named in a job is the job thread's)
    runs_by_work(
        threads, own.size(), kSetupRunTriangles,
        [&](std::size_t j) { return (draws.k1[own[j]] - draws.k0[own[j]]) / 3 + kSetupDrawCost; }, run_first);
    const auto setup_one = [&](std::size_t j) {
        const std::size_t d = own[j];
        const Command& c = *draws.cmd[d];
        detail::FrontEndParams p = params_for(target, draws.rules[d], c.state);
        p.cull_face = out.setup_cull[d];  // None when draws of other culling share this list
        if (c.state.mode == RasterMode::ExactBounds) {
            setup_bounds_draw(p, c, draws.index[d], out.bounds[d], out.pool[d]);
            return;
        }
        const std::size_t k0 = draws.k0[d], n = (draws.k1[d] - k0) / 3 * 3;
        auto& list = *out.list[d];
        list.reserve(n / 3);  // one SetupTri per unclipped triangle
        detail::setup_range(p, c.mesh.vertices, c.mesh.indices.subspan(k0, n), draws.index[d], list);
    };
    detail::parallel_for(threads, run_first.size() - 1, [&](std::size_t run) {
        for (std::size_t j = run_first[run]; j < run_first[run + 1]; ++j) setup_one(j);
    });
}

// The target cut into kTileSize squares, row-major.
struct Tiles {
    int x, y;  // tiles per row and per column
    [[nodiscard]] std::size_t count() const { return static_cast<std::size_t>(x) * static_cast<std::size_t>(y); }
    [[nodiscard]] std::size_t index(int tx, int ty) const {
        return static_cast<std::size_t>(ty) * static_cast<std::size_t>(x) + static_cast<std::size_t>(tx);
    }
};

struct Ref {
    std::uint32_t draw;
    std::uint32_t tri;
};

// Binning: each tile lists the triangles overlapping it, in command order. In parallel over
// contiguous parts of the batch's triangles (in command order, a draw's GL-exact list then its
// exact-bounds list): part p fills its own lists, bins[p * tiles + tile], and a tile's list is its
// parts' lists one after another (shade), so every tile sees the same list for any number of parts.
// Bands of tile rows, as before, made every band walk every triangle: a 2-thread batch binned no
// faster than a 1-thread one. Returns the number of parts; `cum` is scratch.
std::size_t bin(const SetupDraws& setup, const Draws& draws, std::size_t d0, std::size_t d1, const Tiles& tiles,
                int threads, std::vector<std::vector<Ref>>& bins, std::vector<std::size_t>& cum) {
    const auto count_of = [&](std::size_t d) { return setup.tris_of(d).size() + setup.bounds[d].size(); };
    cum.resize(d1 - d0 + 1);
    cum[0] = 0;
    for (std::size_t d = d0; d < d1; ++d) cum[d - d0 + 1] = cum[d - d0] + count_of(d);
    const std::size_t total = cum.back();
    const std::size_t parts =
        threads > 1 ? std::clamp<std::size_t>(total / kMinBinPart, 1, static_cast<std::size_t>(threads)) : 1;
    reset_lists(bins, parts * tiles.count());
    detail::parallel_for(threads, parts, [&](std::size_t part) {
        std::vector<Ref>* const part_bins = bins.data() + part * tiles.count();
        const std::size_t g0 = total * part / parts, g1 = total * (part + 1) / parts;  // [g0, g1) of the batch
        const int top_ty = 0, bottom_ty = tiles.y - 1;  // the target's rows of tiles
        const auto add = [&](std::size_t d, std::size_t t, int tx, int ty) {
            part_bins[tiles.index(tx, ty)].push_back({static_cast<std::uint32_t>(d), static_cast<std::uint32_t>(t)});
        };
        // The tile of a pixel coordinate. Setup's boxes lie inside the target (>= 0), so an unsigned
        // shift is the division, without the signed one's fix-up on every triangle.
        const auto tile_of = [](int p) { return static_cast<int>(static_cast<unsigned>(p) / unsigned{kTileSize}); };
        // A draw's tiles lie in those of its clip (Draws::clip): [cx0, cx1] x [cy0, cy1], and in
        // each row of tiles in those of its part there (Draws::spans).
        int cx0 = 0, cy0 = 0, cx1 = 0, cy1 = 0;
        const detail::PixelRect* spans = nullptr;
        const auto bin_box = [&](std::size_t d, std::size_t t, int bx0, int by0, int bx1, int by1) {
            for (int ty = std::max({tile_of(by0), top_ty, cy0}); ty <= std::min({tile_of(by1), bottom_ty, cy1}); ++ty)
                for (int tx = std::max(tile_of(bx0), cx0); tx <= std::min(tile_of(bx1), cx1); ++tx) add(d, t, tx, ty);
        };
        // Draw d's GL-exact triangles [t0, t1) into this part's lists; with Cull, without those of the
        // facing the draw culls (share_setup left its culling to binning: CullFace::Front drops
        // front-facing triangles, CullFace::Back back-facing ones). A template, so that draws
        // without it keep a loop with no test (the test cost 0.6% of a cullide frame's instructions).
        // With Clip, only the tiles of the draw's clip; a template too (most draws have none).
        const auto bin_list = [&]<bool Cull, bool Clip>(std::size_t d, const std::vector<detail::SetupTri>& tris,
                                                        std::size_t t0, std::size_t t1, bool drop_front) {
            for (std::size_t t = t0; t < t1; ++t) {
                const auto& tri = tris[t];
                if constexpr (Cull) {
                    if (tri.front == drop_front) continue;
                }
                int tile_y0 = tile_of(tri.y0), tile_y1 = tile_of(tri.y1);
                int tx0 = tile_of(tri.x0), tx1 = tile_of(tri.x1);
                if constexpr (Clip) {
                    tile_y0 = std::max(tile_y0, cy0), tile_y1 = std::min(tile_y1, cy1);
                    tx0 = std::max(tx0, cx0), tx1 = std::min(tx1, cx1);
                    if (tx0 > tx1) continue;
                }
                const int ty0 = std::max(tile_y0, top_ty), ty1 = std::min(tile_y1, bottom_ty);
                if (ty0 > ty1) continue;
                if (tile_y0 == tile_y1 && tx0 == tx1) {  // one tile (most triangles at CULLIDE's sizes)
                    if constexpr (Clip) {
                        const detail::PixelRect& sp = spans[tile_y0 - cy0];
                        if (sp.x0 > sp.x1 || tx0 < tile_of(sp.x0) || tx0 > tile_of(sp.x1)) continue;
                    }
                    add(d, t, tx0, tile_y0);
                    continue;
                }
                // GL-exact triangles over several tiles: tile-level trivial reject (no centre of the
                // tile's part of the box is covered), exact integers (detail::RectReject, the
                // corner test of detail::rect_outside with the row part set once per row of tiles).
                detail::RectReject reject(tri);
                for (int ty = ty0; ty <= ty1; ++ty) {
                    int row_tx0 = tx0, row_tx1 = tx1;
                    if constexpr (Clip) {
                        const detail::PixelRect& sp = spans[ty - cy0];
                        if (sp.x0 > sp.x1) continue;
                        row_tx0 = std::max(tx0, tile_of(sp.x0)), row_tx1 = std::min(tx1, tile_of(sp.x1));
                    }
                    reject.set_rows(std::max(tri.y0, ty * kTileSize), std::min(tri.y1, ty * kTileSize + kTileSize - 1));
                    for (int tx = row_tx0; tx <= row_tx1; ++tx) {
                        const int rx0 = std::max(tri.x0, tx * kTileSize);
                        const int rx1 = std::min(tri.x1, tx * kTileSize + kTileSize - 1);
                        if (!reject.outside(rx0, rx1)) add(d, t, tx, ty);
                    }
                }
            }
        };
        // The first draw with triangles in [g0, g1): the last d with cum[d - d0] <= g0.
        std::size_t d = d0 + static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.end(), g0) - cum.begin()) - 1;
        for (; d < d1 && cum[d - d0] < g1; ++d) {
            const std::size_t base = cum[d - d0];
            const std::size_t lo = std::max(g0, base) - base, hi = std::min(g1, cum[d - d0 + 1]) - base;  // [lo, hi) of d
            if (lo >= hi) continue;
            const detail::PixelRect& clip = draws.clip[d];
            cx0 = tile_of(clip.x0), cy0 = tile_of(clip.y0), cx1 = tile_of(clip.x1), cy1 = tile_of(clip.y1);
            spans = draws.spans[d];
            const auto& tris = setup.tris_of(d);
            const std::size_t n_tris = tris.size();
            const std::size_t t0 = std::min(lo, n_tris), t1 = std::min(hi, n_tris);
            if (t0 < t1) {
                const CullFace cull = setup.bin_cull[d];
                const bool clipped = spans != nullptr;
                if (cull == CullFace::None && !clipped)
                    bin_list.template operator()<false, false>(d, tris, t0, t1, false);
                else if (cull == CullFace::None)
                    bin_list.template operator()<false, true>(d, tris, t0, t1, false);
                else if (!clipped)
                    bin_list.template operator()<true, false>(d, tris, t0, t1, cull == CullFace::Front);
                else
                    bin_list.template operator()<true, true>(d, tris, t0, t1, cull == CullFace::Front);
            }
            // Then its exact-bounds triangles in [lo, hi).
            for (std::size_t t = std::max(lo, n_tris) - n_tris; t < std::max(hi, n_tris) - n_tris; ++t) {
                const auto& tri = setup.bounds[d][t];
                bin_box(d, t, tri.x0, tri.y0, tri.x1, tri.y1);
            }
        }
    });
    return parts;
}

// What shade() needs of one draw, gathered once per batch (draw_infos): a bin reference then
// reads this record and its triangle instead of a chain of loads through the command, the query
// tables and the setup lists (the shade loop's time looked like memory stalls, perf, issue #17).
struct DrawInfo {
    const detail::SetupTri* tris;  // the draw's GL-exact setup list (shared or its own); unused for exact bounds
    detail::RectKernel kernel;     // GL-exact: the kernel for its depth state (hiz as the batch)
    std::uint32_t query;           // the active query, or kNoQuery
    bool exact_bounds;             // RasterMode::ExactBounds
    bool write;                    // depth mask on
    bool any_only;                 // an any-samples query with the mask off (see shade)
    // Draws::spans: pixels outside them are not drawn (nullptr: no clip); spans[ty - span_ty0] for
    // the row of tiles ty.
    const detail::PixelRect* spans;
    int span_ty0;
};

// For the draws [d0, d1) of `batch` (a sequence's batch k: d0 = first[k], d1 = first[k + 1]);
// `out` is indexed by the sequence's draw index.
void draw_infos(const CommandBatch& batch, const Draws& draws, std::size_t d0, std::size_t d1,
                const SetupDraws& setup, DepthFormat format, bool allow_simd, bool hiz,
                std::vector<DrawInfo>& out) {
    const auto& query_kinds = batch.query_kinds();
    if (out.size() < d1) out.resize(d1);
    for (std::size_t d = d0; d < d1; ++d) {
        const Command& c = *draws.cmd[d];
        DrawInfo& info = out[d];
        info.query = draws.query[d];
        info.spans = draws.spans[d];
        info.span_ty0 = draws.clip[d].y0 / kTileSize;
        info.exact_bounds = c.state.mode == RasterMode::ExactBounds;
        info.write = c.state.depth_write;
        info.any_only = info.query != kNoQuery && !c.state.depth_write &&
                        query_kinds[info.query] == QueryKind::AnySamplesPassed;
        info.tris = info.exact_bounds ? nullptr : setup.tris_of(d).data();
        info.kernel = info.exact_bounds
                          ? nullptr
                          : detail::select_rect_kernel({format, c.state.depth_func, c.state.depth_write},
                                                       allow_simd, hiz);
    }
}

// What every tile's back end reads (shared, read-only but for the depth values of its own tile
// and the any-samples flags).
struct ShadeContext {
    const Draws& draws;
    const SetupDraws& setup;
    const DrawInfo* info;  // per draw (draw_infos)
    detail::DepthRows depth;
    int width, height;
    DepthFormat format;
    bool allow_simd;
    bool hiz;                     // hierarchical Z on D16 / D24 targets (pipeline.h, HizTile)
    detail::HizTile* hiz_tiles;   // per tile, owned by the tile's task
    std::uint64_t* written_blocks;  // per tile: the 8 x 8 blocks where a writing draw passed (or nullptr)
    std::atomic<bool>* answered;  // per query: an any-samples query already has a passing sample
    // ExecuteOptions::clear_depth: fill the tile with copies of *clear_row (kTileSize values) first
    // (all of it, or with written_blocks the blocks flagged); nullptr: no clear.
    const std::uint32_t* clear_row;
};

// How many bin references ahead shade prefetches a GL-exact triangle's set-up record.
constexpr std::size_t kPrefetchAhead = 4;

// Back end of one tile: its bin in command order; counters kept as (query, count) runs.
void shade(const ShadeContext& ctx, int tx, int ty, const std::vector<Ref>& bin,
           std::vector<std::pair<std::uint32_t, std::uint64_t>>& counts) {
    const int x0 = tx * kTileSize, y0 = ty * kTileSize;
    const int x1 = std::min(x0 + kTileSize, ctx.width) - 1, y1 = std::min(y0 + kTileSize, ctx.height) - 1;
    const auto clip_to_tile = [&](int bx0, int by0, int bx1, int by1) {
        return detail::PixelRect{std::max(x0, bx0), std::max(y0, by0), std::min(x1, bx1), std::min(y1, by1)};
    };
    // A draw's clip (its part in this row of tiles: Draws::spans) on a rectangle of this tile;
    // false when nothing is left.
    const auto clip_draw = [ty](const DrawInfo& info, detail::PixelRect& r) __attribute__((always_inline)) {
        if (info.spans == nullptr) return true;
        const detail::PixelRect& c = info.spans[ty - info.span_ty0];
        r = {std::max(r.x0, c.x0), std::max(r.y0, c.y0), std::min(r.x1, c.x1), std::min(r.y1, c.y1)};
        return r.x0 <= r.x1 && r.y0 <= r.y1;
    };
    const std::size_t tile_index = static_cast<std::size_t>(ty) * static_cast<std::size_t>((ctx.width + kTileSize - 1) / kTileSize) +
                                   static_cast<std::size_t>(tx);
    detail::HizTile* const hiz = ctx.hiz ? &ctx.hiz_tiles[tile_index] : nullptr;
    // The set-up records are stored in command order and read here in tile order: a tile's
    // triangles lie scattered over the list (20,000 small triangles are 2.2 MB), and the load of the
    // record's box missed the cache on most triangles (perf, raster_bench SmallTris). Each is
    // fetched kPrefetchAhead references early, the tile's first ones before its clear; only the
    // timing changes.
    const auto prefetch = [&](const Ref a) __attribute__((always_inline)) {
        if (const detail::SetupTri* t = ctx.info[a.draw].tris; t != nullptr) {
            const char* p = reinterpret_cast<const char*>(t + a.tri);
            __builtin_prefetch(p);
            __builtin_prefetch(p + sizeof(detail::SetupTri) - 1);
        }
    };
    for (std::size_t j = 0; j < kPrefetchAhead && j < bin.size(); ++j) prefetch(bin[j]);
    std::uint64_t* const written = ctx.written_blocks != nullptr ? &ctx.written_blocks[tile_index] : nullptr;
    if (ctx.clear_row != nullptr) {
        detail::clear_blocks(ctx.depth, ctx.clear_row, {x0, y0, x1, y1},
                             written != nullptr ? *written : ~std::uint64_t{0});
        if (written != nullptr) *written = 0;
    }
    if (hiz != nullptr) {
        hiz->tile = {x0, y0, x1, y1};
        hiz->valid = 0;  // bounds are read from the buffer afresh in every batch
    }
    // The blocks where a writing draw passed the depth test in this batch (a kernel's count is the
    // number of samples that passed, and a writing draw writes exactly those).
    std::uint64_t wrote = 0;
    const auto mark = [&](const detail::PixelRect& rect) __attribute__((always_inline)) {
        wrote |= detail::block_mask((rect.x0 - x0) >> 3, (rect.x1 - x0) >> 3, (rect.y0 - y0) >> 3, (rect.y1 - y0) >> 3);
    };
    const std::size_t n_refs = bin.size();
    for (std::size_t j = 0; j < n_refs; ++j) {
        if (j + kPrefetchAhead < n_refs) prefetch(bin[j + kPrefetchAhead]);
        const Ref& r = bin[j];
        const DrawInfo& info = ctx.info[r.draw];
        const std::uint32_t q = info.query;
        std::uint64_t passed;
        if (info.exact_bounds) {
            const Command& c = *ctx.draws.cmd[r.draw];
            const detail::DepthState depth_state{ctx.format, c.state.depth_func, c.state.depth_write};
            const auto& tri = ctx.setup.bounds[r.draw][r.tri];
            detail::PixelRect rect = clip_to_tile(tri.x0, tri.y0, tri.x1, tri.y1);
            if (!clip_draw(info, rect)) continue;
            passed = detail::bounds_rect(tri, ctx.setup.pool[r.draw].data(), depth_state, ctx.depth, rect);
            if (written != nullptr && c.state.depth_write && passed != 0) mark(rect);
            if (hiz != nullptr && c.state.depth_write) hiz->valid = 0;  // its writes are not tracked
        } else {
            // Any-samples query with the mask off: once this query has a passing sample (in this
            // tile, or in any tile: the flag), further draws in it change nothing; the kernel also
            // stops at its first passing row. The boolean is the same whatever the schedule.
            const bool any_only = info.any_only;
            if (any_only && ((!counts.empty() && counts.back().first == q) ||
                             ctx.answered[q].load(std::memory_order_relaxed)))
                continue;
            const detail::SetupTri& tri = info.tris[r.tri];
            detail::PixelRect rect = clip_to_tile(tri.x0, tri.y0, tri.x1, tri.y1);
            if (!clip_draw(info, rect)) continue;
            // A triangle over several tiles: its part of this tile may be much smaller than the
            // box's (a thin triangle through a corner). Within one tile the box is already tight.
            // Exact: the kernel counts and writes the same on the shrunk rectangle.
            if ((rect.x0 != tri.x0 || rect.y0 != tri.y0 || rect.x1 != tri.x1 || rect.y1 != tri.y1) &&
                (rect.x1 - rect.x0 + 1) * (rect.y1 - rect.y0 + 1) >= kShrinkMinArea && !detail::shrink_rect(tri, rect))
                continue;
            passed = info.kernel(tri, ctx.depth, rect, hiz, any_only);
            if (written != nullptr && info.write && passed != 0) mark(rect);
            if (any_only && passed != 0) ctx.answered[q].store(true, std::memory_order_relaxed);
        }
        if (q == kNoQuery || passed == 0) continue;
        if (!counts.empty() && counts.back().first == q) counts.back().second += passed;
        else counts.emplace_back(q, passed);
    }
    if (written != nullptr) *written |= wrote;
}

}  // namespace

Result<std::vector<QueryResults>> execute_sequence(DepthTarget& target, std::span<const CommandBatch* const> batches,
                                                   const ExecuteOptions& options,
                                                   const std::function<void(std::size_t)>& between) {
    if (options.threads < 0)
        return Error{"execute: threads = " + std::to_string(options.threads) +
                     " is out of range: it must be >= 0 (0 = all hardware threads)"};
    // The batches in order up to the first null one, then that one: the first problem in order.
    std::size_t first_null = 0;
    while (first_null < batches.size() && batches[first_null] != nullptr) ++first_null;
    if (detail::SequenceCheck c = detail::validate_sequence(target, batches.first(first_null)); !c.status) {
        if (batches.size() == 1) return c.status.error();
        return Error{"execute_sequence: batch " + std::to_string(c.batch) + ": " + c.status.error().message};
    }
    if (first_null < batches.size())
        return Error{"execute_sequence: batch " + std::to_string(first_null) + " is null"};
    // The buffers below are this thread's: a call from inside `between` would overwrite the
    // running sequence's front end. Refused instead (raster/command_batch.h).
    thread_local bool running = false;
    if (running) return Error{"execute_sequence: execute or execute_sequence called from a between() callback"};
    struct Running {
        bool& flag;
        explicit Running(bool& f) : flag(f) { flag = true; }
        ~Running() { flag = false; }
        Running(const Running&) = delete;
        Running& operator=(const Running&) = delete;
    } running_scope(running);
    if (options.clear_depth && !std::isfinite(*options.clear_depth))
        return Error{"execute: clear_depth is not finite"};
    const int threads = detail::effective_threads(options.threads);
    // Buffers kept from one call to the next on this thread (capacity only: every list is
    // emptied before use, so no result depends on an earlier call). CULLIDE issues thousands of
    // small batches per frame; allocating these afresh each time returned memory to the kernel and
    // faulted it back in, serial work that made 2 threads slower than 1 (perf, issue #17).
    struct Scratch {
        Draws draw_list;
        SetupDraws setup;
        std::vector<std::uint32_t> own_setup;
        std::vector<std::vector<Ref>> bins;  // per part of the binning, per tile (bin)
        std::vector<std::size_t> bin_cum;
        std::vector<std::vector<std::pair<std::uint32_t, std::uint64_t>>> tile_counts;
        std::vector<std::atomic<bool>> answered;
        std::vector<detail::HizTile> hiz_tiles;
        SetupIndex setup_index;
        std::vector<DrawInfo> infos;
    };
    thread_local Scratch scratch;
    Draws& draw_list = scratch.draw_list;
    // One front end for the whole sequence: a triangle list is set up once for every draw of any
    // batch with the same spans and front-end state (share_setup). Every batch's spans are alive
    // and unchanged for the whole call (the lifetime rule of raster/types.h), so this is exact.
    draws(batches, threads, draw_list, target, options);
    share_setup(target, draw_list, scratch.setup, scratch.setup_index);
    front_end(target, draw_list, threads, scratch.setup, scratch.own_setup);
    const SetupDraws& setup = scratch.setup;
    const Tiles tiles{(target.width() + kTileSize - 1) / kTileSize, (target.height() + kTileSize - 1) / kTileSize};
    static_assert(kTileSize == detail::kHizTile, "HizTile holds the 8 x 8 blocks of one executor tile");
    const bool hiz = options.hierarchical_z && hiz_allowed_by_environment() && target.format() != DepthFormat::D32F;
    if (hiz && scratch.hiz_tiles.size() < tiles.count()) scratch.hiz_tiles.resize(tiles.count());

    std::array<std::uint32_t, kTileSize> clear_row{};
    if (options.clear_depth) clear_row.fill(DepthTarget::encode_clear(*options.clear_depth, target.format()));

    std::vector<QueryResults> all_results;
    all_results.reserve(batches.size());
    for (std::size_t k = 0; k < batches.size(); ++k) {
        if (k > 0 && between) between(k);
        const CommandBatch& batch = *batches[k];
        const std::size_t d0 = draw_list.first[k], d1 = draw_list.first[k + 1];
        const std::size_t parts = bin(setup, draw_list, d0, d1, tiles, threads, scratch.bins, scratch.bin_cum);
        std::vector<std::vector<Ref>>& bins = scratch.bins;

        // Back end: one task per tile.
        const std::size_t n_queries = batch.query_kinds().size();
        if (scratch.answered.size() < n_queries + 1) scratch.answered = std::vector<std::atomic<bool>>(n_queries + 1);
        for (std::size_t q = 0; q <= n_queries; ++q) scratch.answered[q].store(false, std::memory_order_relaxed);
        // The blocks to fill before drawing and to flag where draws write: the caller's (resized:
        // new entries 0, nothing written, or every block when this call clears, content unknown),
        // or else the target's own record (DepthTarget's fast clear), which the caller's list
        // replaces.
        std::uint64_t* flags = nullptr;
        if (options.written_blocks != nullptr) {
            if (options.written_blocks->size() != tiles.count())
                options.written_blocks->assign(tiles.count(), options.clear_depth ? ~std::uint64_t{0} : 0);
            flags = options.written_blocks->data();
            detail::TargetBlocks::forget(target);
        } else {
            flags = detail::TargetBlocks::begin_batch(target, options.clear_depth.has_value(), clear_row[0]);
        }
        draw_infos(batch, draw_list, d0, d1, setup, target.format(), options.allow_simd, hiz, scratch.infos);
        const ShadeContext ctx{draw_list,
                               setup,
                               scratch.infos.data(),
                               {detail::TargetBlocks::values(target), target.width()},
                               target.width(),
                               target.height(),
                               target.format(),
                               options.allow_simd,
                               hiz,
                               scratch.hiz_tiles.data(),
                               flags,
                               scratch.answered.data(),
                               options.clear_depth ? clear_row.data() : nullptr};
        auto& tile_counts = scratch.tile_counts;
        reset_lists(tile_counts, tiles.count());
        detail::parallel_for(threads, tiles.count(), [&](std::size_t tile) {
            const int tx = static_cast<int>(tile % static_cast<std::size_t>(tiles.x));
            const int ty = static_cast<int>(tile / static_cast<std::size_t>(tiles.x));
            std::vector<Ref>& list = bins[tile];  // part 0's, then the later parts' in order (bin)
            for (std::size_t p = 1; p < parts; ++p) {
                const std::vector<Ref>& more = bins[p * tiles.count() + tile];
                list.insert(list.end(), more.begin(), more.end());
            }
            shade(ctx, tx, ty, list, tile_counts[tile]);
        });
        if (options.written_blocks == nullptr && flags != nullptr) detail::TargetBlocks::commit(target);

        QueryResults results(n_queries, 0);
        for (std::size_t tile = 0; tile < tiles.count(); ++tile)
            for (const auto& [q, n] : tile_counts[tile]) results[q] += n;
        finish_results(batch, results);
        all_results.push_back(std::move(results));
    }
    return all_results;
}

Result<QueryResults> execute(DepthTarget& target, const CommandBatch& batch, const ExecuteOptions& options) {
    const CommandBatch* const one[1] = {&batch};
    Result<std::vector<QueryResults>> r = execute_sequence(target, one, options);
    if (!r) return r.error();
    return std::move(r.value()[0]);
}

}  // namespace raster
