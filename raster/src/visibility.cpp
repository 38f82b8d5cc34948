// visibility.cpp: the fused exact-bounds visibility pass (raster/visibility.h; the equivalence with
// the two recorded passes is argued there and in docs/reliable-raster.md).
#include "raster/visibility.h"

#include <algorithm>
#include <array>
#include <bit>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
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
// One tile holding the whole target, whatever the thread count, on targets up to kOneTileMax pixels
// a side: tiles are then only overhead (each triangle's Ref pushed per tile it overlaps, its box cut to
// each tile, the tasks); the answer is the same (see above), and the front end still runs its items
// on every thread. Session 6 kept four 16-pixel tiles for R-CULLIDE's 32^2 views with two threads
// (faster then, at load 1.7); after the exact stage got 1.5-3x faster they made two threads slower
// than one on every scene. One tile, 2 threads, interleaved with the four tiles, two rounds, quiet
// machine (load ~1.2): cylinders 4.99-5.01 against 5.38-5.75 ms per frame, breaking 18.5-18.7
// against 20.3-20.4, leaves 8.65-8.78 against 9.28-9.32, cloth 2.38 against 2.48-2.56.
constexpr int kOneTileMax = 128;
int tile_side(int width, int height) {
    const int m = std::max(width, height);
    if (m <= kOneTileMax) return m;
    return m <= 256 ? 32 : 64;
}
// Settling tiles from depth bounds (shade) pays where triangles are large: their pixels are the cost,
// and a 16-pixel tile skipped saves many. Where the triangles' boxes average fewer than
// kSettleMinArea pixels (R-CULLIDE's sub-objects in 32^2 views: a pixel or two each), the pass keeps
// the tiles above and tests every fragment, as the bounds would rarely settle a tile and cutting
// small triangles at more tile borders costs more than it saves (tori and breaking were 20-30%
// slower with 16-pixel tiles everywhere). Either way the answer is the same.
constexpr int kSettleTile = 16;
constexpr std::uint64_t kSettleMinArea = 16;
constexpr std::uint32_t kNoObject = 0xffffffffu;
// The one-tile pass is split between threads (split_pass) only with at least this many triangles
// per thread: below it a second parallel phase costs more than it saves.
constexpr std::uint64_t kSplitMinTriangles = 256;
constexpr std::uint64_t kSplitRunsPerThread = 4;
// The items-alone pre-pass (State::mark / alone) costs about a third of a triangle's setup per
// triangle, and spares the setup and drawing of the items alone. It paid on the cloth (90% of the
// first sub-object view's triangles spared: rcullide 1.20 -> 0.83 ms a frame at 2 threads) and on
// leaves (39%: within 2%), and cost 5-20% where few items are alone (cylinders, tori, bunny-dragon,
// breaking: 8-16%). So each shape of call (its object, item and triangle counts, each rounded to a
// power of two: a method's stages call with their own shapes, frame after frame) keeps the share
// of triangles its last pre-pass spared; a call runs the pre-pass when its shape has none yet or
// spared at least kAloneMinSpared, and otherwise after 2, 4, ... up to kAloneProbe calls without it
// (doubling after each run that did not pay, quadrupling after one that spared under half the bar),
// to notice when the scene changes (a probe every 8th call cost those scenes 1-6%, every 32nd
// under 1%). The settling pre-pass keeps such a history too (kSettleMinSpared). Calls of fewer
// than kAloneMinTriangles triangles always run it (cheap either way). Only the work depends on it,
// never an answer.
constexpr std::uint64_t kAloneMinTriangles = 1024;
constexpr double kAloneMinSpared = 0.3;
constexpr unsigned kAloneProbe = 32;
constexpr std::size_t kAloneShapes = 64;
// The settling pre-pass (State::presettle) runs on one-tile targets; its per-item verdicts. Its
// phases run in parts of at least kPresettlePartIndices indices (about 100 us of work each: below
// that, the five parallel regions cost more than they save).
constexpr std::uint8_t kOpen = 0, kNotHit = 1, kHit = 2;
constexpr std::size_t kPresettlePartIndices = 4096;
// The settling pre-pass pays where it leaves out at least this share of a call's triangles (it
// costs about a third of a triangle's setup and drawing per triangle, more on large meshes whose
// vertices miss the cache); its history per shape of call is kept as the alone pre-pass's.
constexpr double kSettleMinSpared = 0.75;
constexpr std::size_t kPrefetchVertices = std::size_t{1} << 15;  // 1 MB of Double4


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

bool valid_vertex(const Double4& d) {
    return d.w == 1.0 && std::fabs(d.x) <= kMaxExactBoundsCoordinate && std::fabs(d.y) <= kMaxExactBoundsCoordinate &&
           std::fabs(d.z) <= kMaxExactBoundsCoordinate;  // false for NaN too
}

// The input checks, in item and index order: the first failure's message, prefixed by `what`
// (called only when the front end found a failure, or an index count is not a multiple of 3).
// mesh_of(i) is item i's MeshViewD.
template <class MeshOf>
Error validate(const char* what, std::size_t n, MeshOf&& mesh_of) {
    for (std::size_t i = 0; i < n; ++i) {
        const MeshViewD& m = mesh_of(i);
        if (m.indices.size() % 3 != 0)
            return Error{std::string(what) + ": item " + std::to_string(i) + ": index count " +
                         std::to_string(m.indices.size()) + " is not a multiple of 3"};
        for (std::size_t k = 0; k < m.indices.size(); ++k) {
            if (m.indices[k] >= m.vertices.size())
                return Error{std::string(what) + ": item " + std::to_string(i) + ": index " +
                             std::to_string(m.indices[k]) + " at position " + std::to_string(k) +
                             " is beyond the vertex list (size " + std::to_string(m.vertices.size()) + ")"};
            const Double4& d = m.vertices[m.indices[k]];
            if (valid_vertex(d)) continue;
            if (std::string why = check_vertex(d); !why.empty())
                return Error{std::string(what) + ": item " + std::to_string(i) + ": vertex " +
                             std::to_string(m.indices[k]) + " " + why};
        }
    }
    return Error{std::string(what) + ": invalid input"};  // not reached: some check above fails
}
Error validate(std::span<const VisibilityItem> items) {
    return validate("visibility pass", items.size(), [&](std::size_t i) -> const MeshViewD& { return items[i].mesh; });
}

// The depth format and thread count checks of both passes' entry points, naming `what`.
std::optional<Error> check_format_threads(const char* what, DepthFormat format, int threads) {
    if (format != DepthFormat::D16 && format != DepthFormat::D24 && format != DepthFormat::D32F)
        return Error{std::string(what) + ": invalid depth format"};
    if (threads < 0)
        return Error{std::string(what) + ": threads = " + std::to_string(threads) +
                     " is out of range: it must be >= 0 (0 = all hardware threads)"};
    return std::nullopt;
}

// The target cut into square tiles of `side` pixels, row-major.
struct TileGrid {
    int side, x, y;  // tile side, tiles per row and per column
    [[nodiscard]] std::size_t count() const { return static_cast<std::size_t>(x) * static_cast<std::size_t>(y); }
    [[nodiscard]] std::size_t pixels() const { return static_cast<std::size_t>(side) * static_cast<std::size_t>(side); }
};

// Which objects' items may reach each cell of the target (detail::CellGrid): kOccNone, kOccOne (one
// object: `obj`) or kOccMany.
constexpr std::uint8_t kOccNone = 0, kOccOne = 1, kOccMany = 2;

// The cells of the pixel box [x0, x1] x [y0, y1] reached by the object `k`.
void occ_mark(const detail::CellGrid& g, std::uint32_t* key, std::uint8_t* state, int x0, int y0, int x1, int y1,
              std::uint32_t k) {
    for (int cy = y0 >> g.shift; cy <= y1 >> g.shift; ++cy) {
        const std::size_t row = static_cast<std::size_t>(cy) * static_cast<std::size_t>(g.x);
        for (int cx = x0 >> g.shift; cx <= x1 >> g.shift; ++cx) {
            const std::size_t c = row + static_cast<std::size_t>(cx);
            if (state[c] == kOccNone) {
                state[c] = kOccOne;
                key[c] = k;
            } else if (key[c] != k) {
                state[c] = kOccMany;
            }
        }
    }
}

// Merges cells of occ_mark (obj / state) b into a: kOccMany where they hold different objects.
void merge_occ(std::uint32_t* ao, std::uint8_t* as, const std::uint32_t* bo, const std::uint8_t* bs,
               std::size_t cells) {
    for (std::size_t c = 0; c < cells; ++c) {
        if (bs[c] == kOccNone) continue;
        if (as[c] == kOccNone) {
            as[c] = bs[c];
            ao[c] = bo[c];
        } else if (bs[c] == kOccMany || ao[c] != bo[c]) {
            as[c] = kOccMany;
        }
    }
}
// Whether every cell of the pixel box is reached by one object only.
inline bool occ_one(const detail::CellGrid& g, const std::uint8_t* state, int x0, int y0, int x1, int y1) {
    for (int cy = y0 >> g.shift; cy <= y1 >> g.shift; ++cy) {
        const std::size_t row = static_cast<std::size_t>(cy) * static_cast<std::size_t>(g.x);
        for (int cx = x0 >> g.shift; cx <= x1 >> g.shift; ++cx)
            if (state[row + static_cast<std::size_t>(cx)] != kOccOne) return false;
    }
    return true;
}

// Whether an item is alone, from its reach (cells as marked): it reaches nothing, or its one box's
// cells hold its key only and no fragment of it reaches the clear value. (Items of scattered
// triangles, several boxes, are always drawn.)
inline bool occ_alone(const detail::CellGrid& g, const std::uint8_t* state, const detail::BoundsReach& r, std::uint32_t clear) {
    if (!r.ok) return false;
    if (r.empty) return true;
    return r.single && r.zq_hi < clear && occ_one(g, state, r.x0, r.y0, r.x1, r.y1);
}

// The per-pixel record the pass keeps (see test_fragments), for an order `first` (std::less: the
// smallest values; std::greater: the largest): m1 the first value with its object o1, m2 the first
// value of any object other than o1.
template <class T, class First>
inline void by_object(T* m1, std::uint32_t* o1, T* m2, std::size_t p, std::uint32_t obj, T z, First first) {
    if (obj == o1[p]) {
        m1[p] = std::min(m1[p], z, first);
    } else if (first(z, m1[p])) {
        m2[p] = m1[p];
        m1[p] = z;
        o1[p] = obj;
    } else {
        m2[p] = std::min(m2[p], z, first);
    }
}
// Merges record b into record a, pixel by pixel: a then holds the record of both sets of values (the
// first m1 wins with its object; m2 becomes the first over the objects other than that one, which
// from the other record is its m2 if it holds the same object and its m1 otherwise).
template <class T, class First>
void merge_by_object(T* a1, std::uint32_t* ao, T* a2, const T* b1, const std::uint32_t* bo, const T* b2,
                     std::size_t pixels, First first) {
    for (std::size_t p = 0; p < pixels; ++p) {
        if (first(b1[p], a1[p])) {
            a2[p] = std::min(b2[p], ao[p] == bo[p] ? a2[p] : a1[p], first);
            a1[p] = b1[p];
            ao[p] = bo[p];
        } else {
            a2[p] = std::min(a2[p], bo[p] == ao[p] ? b2[p] : b1[p], first);
        }
    }
}
// The minima the pass keeps (each record starts at the clear value).
inline void min_by_object(std::uint32_t* m1, std::uint32_t* o1, std::uint32_t* m2, std::size_t p, std::uint32_t obj,
                          std::uint32_t z) {
    by_object(m1, o1, m2, p, obj, z, std::less<std::uint32_t>());
}
void merge_min_by_object(std::uint32_t* a1, std::uint32_t* ao, std::uint32_t* a2, const std::uint32_t* b1,
                         const std::uint32_t* bo, const std::uint32_t* b2, std::size_t pixels) {
    merge_by_object(a1, ao, a2, b1, bo, b2, pixels, std::less<std::uint32_t>());
}
// A record's first value at pixel p over the objects other than obj (the minima: the smallest, with
// the clear value; by std::greater: the largest).
template <class T>
inline T other_than(const T* m1, const std::uint32_t* o1, const T* m2, std::size_t p, std::uint32_t obj) {
    return o1[p] == obj ? m2[p] : m1[p];
}

// When a pre-pass that spares work runs (the items-alone pre-pass: kAloneMinSpared, kAloneProbe
// above; the settling pre-pass: kSettleMinSpared): per shape of call, the share of its triangles
// that its last run spared (negative: none yet) and the calls since. Only the work depends on it.
struct PayGuard {
    struct Shape {
        std::uint32_t key = 0;   // the shape whose history this is (another shape that hashes here
                                 // starts afresh: histories never mix)
        double spared = -1.0;
        unsigned off_calls = 0;  // calls without the pre-pass since it last ran
        unsigned wait = 1;       // ... before it runs again: doubled after each run that did not pay
    };
    explicit PayGuard(double pays_from) : min_spared(pays_from) {}
    double min_spared;  // a run that spares this share of the triangles or more pays
    std::array<Shape, kAloneShapes> shapes{};
    std::uint64_t last_spared = 0;  // the last call's spared triangles (0 without the pre-pass)

    // The shape of a call: its object, item and triangle counts, each rounded (key_of).
    struct Call {
        std::size_t objects, items;
        std::uint64_t triangles;
    };
    static Call call_of(std::span<const VisibilityItem> items) {
        // (the objects are the runs of equal object ids: each object's items are consecutive)
        Call c{0, items.size(), 0};
        for (std::size_t i = 0; i < items.size(); ++i) {
            c.objects += i == 0 || items[i].object != items[i - 1].object;
            c.triangles += items[i].mesh.indices.size() / 3;
        }
        return c;
    }
    static std::uint32_t key_of(const Call& c) {
        // Quarter octaves (the leading bit's place and the two bits after it): calls of one stage
        // of one scene fall in few of them frame after frame, and other scenes' calls rarely share
        // them (with whole octaves the cloth's first sub-object view had the shape of
        // bunny-dragon's third, whose history then skipped both pre-passes there).
        const auto q = [](std::uint64_t v) -> std::uint32_t {
            if (v < 4) return static_cast<std::uint32_t>(v);
            const int b = std::bit_width(v);
            return static_cast<std::uint32_t>(b) * 4 + static_cast<std::uint32_t>((v >> (b - 3)) & 3u);
        };
        return q(c.objects) << 20 | q(c.items) << 10 | q(c.triangles);  // (each < 2^10)
    }
    Shape& shape_of(const Call& c) {
        const std::uint32_t key = key_of(c);
        Shape& sh = shapes[((key >> 20) * 4099 + ((key >> 10) & 0x3ffu) * 67 + (key & 0x3ffu)) % kAloneShapes];
        if (sh.key != key) sh = Shape{key};
        return sh;
    }
    bool wanted(const Call& call) {
        last_spared = 0;
        if (call.triangles < kAloneMinTriangles) return true;
        Shape& sh = shape_of(call);
        if (sh.spared < 0.0 || sh.spared >= min_spared) return true;
        if (++sh.off_calls < sh.wait) return false;
        sh.off_calls = 0;
        return true;
    }
    void record(const Call& call, std::uint64_t spared_now) {
        last_spared = spared_now;
        if (call.triangles < kAloneMinTriangles) return;
        Shape& sh = shape_of(call);
        sh.spared = static_cast<double>(spared_now) / static_cast<double>(call.triangles);
        // (a run far from paying, under half the share, waits twice as long again)
        sh.wait = sh.spared >= min_spared         ? 1
                  : sh.spared >= 0.5 * min_spared ? std::min(2 * sh.wait, kAloneProbe)
                                                  : std::min(4 * sh.wait, kAloneProbe);
    }
};

}  // namespace

// run()'s phases, in order: reach and alone (the items that need drawing), front_end, bin, then
// shade per tile; buffers kept between calls.
struct VisibilityPass::State {
    std::vector<std::vector<detail::BoundsTri>> tris;     // per item
    std::vector<std::vector<detail::BoundsVertex>> pool;  // per item
    std::vector<std::uint8_t> bad;                        // per item: an input check failed
    std::vector<std::uint64_t> area;                      // per item: pixels of its triangles' boxes
    std::vector<std::uint8_t> hit;                        // per item: found not fully visible (atomic_ref)
    std::vector<std::vector<Ref>> bins;                   // per tile
    std::vector<std::vector<Fragment>> frags;             // per tile (scratch)
    std::vector<std::vector<std::uint8_t>> need;          // per tile (scratch): per ref, its queries can pass
    std::vector<std::uint32_t> min1, obj1, min2;          // per pixel, tile-major (one tile = side^2)
    // The split one-tile shade (split_pass): per part, its minima (side^2 each) and fragments.
    std::vector<std::vector<std::uint32_t>> part_min1, part_obj1, part_min2;
    std::vector<std::vector<Fragment>> part_frags;
    std::vector<std::size_t> part_first;  // per part, its first item; part_first[parts] = the item count

    // Front end per item (the recorded draws' own setup, so the same polygons). False when some
    // item failed an input check (bad[i]).
    bool front_end(int width, int height, DepthFormat format, std::span<const VisibilityItem> items, int threads,
                   bool use_alone);
    // Sizes the per-item buffers for n items.
    void reserve_items(std::size_t n);
    // One item's triangles set up into tris[i] and pool[i], their pixel-box area into area[i];
    // false (and bad[i] = 1) when an input check fails.
    bool setup_item(const detail::FrontEndParams& params, std::span<const VisibilityItem> items, std::size_t i);
    // Each triangle's encoded depth bounds (zq_lo, zq_hi), for settling tiles.
    void depth_bounds(DepthFormat format, std::size_t n_items);
    // Binning, in item order; with one tile and no settling nothing is built (every triangle is in it).
    void bin(std::span<const VisibilityItem> items, const TileGrid& grid, bool settle);
    // Per tile: settle what the triangles' depth bounds settle; then, only if some item not yet
    // found may pass there, every fragment's zmin into the two minima and the zmax of the items
    // that may pass against the minimum over the other objects; such items go to hit[].
    void shade(std::span<const VisibilityItem> items, const TileGrid& grid, int width, int height,
               DepthFormat format, std::size_t tile, bool settle);
    // One tile without settling, on `parts` threads, with the front end: see split_pass's comment.
    // Returns 0 when some item failed an input check, 1 when the split answered (hit[] is set), 2
    // when the triangles are large enough to settle tiles (the caller goes on with tris[] as set up).
    int split_pass(std::span<const VisibilityItem> items, int side, int width, int height, DepthFormat format,
                   int threads, std::size_t parts, bool use_alone);
    // Part `part`'s triangles into its own minima and fragments.
    void raster_part(std::span<const VisibilityItem> items, int side, int width, int height, DepthFormat format,
                     std::size_t part);
    std::vector<std::uint8_t> part_done;  // per part: raster_part ran in the first phase
    // Items alone in the view (see alone()): not set up, not drawn.
    std::vector<detail::BoundsReach> reach;                // per item
    std::vector<std::uint8_t> skip;                        // per item
    std::vector<std::uint32_t> occ_obj;                    // per cell (detail::CellGrid)
    std::vector<std::uint8_t> occ_state;                   // per cell: kOccNone / kOccOne / kOccMany
    std::vector<std::vector<std::uint32_t>> part_occ_obj;  // split_pass: per part, its own cells
    std::vector<std::vector<std::uint8_t>> part_occ_state;
    PayGuard guard{kAloneMinSpared};
    PayGuard settle_guard{kSettleMinSpared};
    // The settling pre-pass (presettle): per item, its boxes with encoded depth bounds and its
    // window vertices' records (each in slots reserved per item: a box per triangle, a record per
    // index); its verdict, and whether its fragments are tested.
    struct BoxBound {
        std::int16_t x0, y0, x1, y1;  // inclusive (one tile: <= 128 a side)
        std::uint32_t lo, hi;
    };
    struct VertexRec {
        std::uint32_t pixel;
        std::uint32_t zmax;  // <= the zmax of the item's fragment at `pixel`
    };
    // A vertex as the pre-pass found it: an input check failed, beyond the clip cube (|coordinate|
    // > 1), or inside it with its window position (setup's values), its pixel (kNoObject: outside
    // the target) and the zmax bound of its fragment there.
    struct VertexMap {
        static constexpr std::uint8_t kBad = 0, kBeyond = 1, kInside = 2;
        detail::BoundsVertex win;
        std::uint32_t pixel, zmax;
        std::uint8_t state;
    };
    std::vector<BoxBound> boxes;
    std::vector<VertexRec> vrec;
    // Per item with face records (detail::flat_triangle_pixels), where they are in its part's PrePart::frec.
    std::vector<std::uint32_t> face_first, face_count;
    std::vector<std::uint64_t> face_hits;  // per part: items certainly hit by a face record
    std::vector<std::size_t> box_first, rec_first;  // per item, its first slot; then the slot count
    std::vector<std::uint32_t> box_count, rec_count;  // per item (rec_count: | kHasFaces, see face_first)
    static constexpr std::uint32_t kHasFaces = 0x80000000u;
    std::vector<std::uint8_t> verdict;  // per item: kOpen, kNotHit, kHit
    std::vector<std::uint8_t> tested;   // per item of the pass: its fragments are tested
    // Per part of the pre-pass, per pixel: the minima of the boxes' lo (c*) and of the vertices'
    // zmin bounds (v*), the open items' largest hi + 1 by object (u*, 0: none). Merged into part 0.
    struct PrePart {
        std::vector<std::uint32_t> c1, co, c2, v1, vo, v2, uo;
        std::vector<std::uint64_t> u1, u2;
        std::vector<VertexRec> frec;         // the part's items' face records, in item order
        std::vector<std::uint32_t> vstamp;  // per vertex of the current run: mapped in generation gen
        std::vector<VertexMap> vcache;      // per vertex: what the run found
        std::uint32_t gen = 0;
    };
    std::vector<PrePart> pre;
    std::vector<std::size_t> pre_first;    // per part, its first item; then the item count
    std::vector<std::uint8_t> pre_failed;  // per part: an input check failed
    std::vector<std::uint64_t> pre_area;
    std::vector<std::uint8_t> drawn;              // per item: in `reduced`
    std::vector<VisibilityItem> reduced;          // the items drawn, in order
    std::vector<std::uint32_t> reduced_at;        // per item: its index in `reduced` (if drawn)
    PresettleStats settled;  // of the last run()
    bool presettle_on = true;
    // 0: not applied (input that fails a check, or large triangles: the caller goes on as without
    // it); 1: verdict[], reduced[], reduced_at[] and tested[] (per item of `reduced`) are set; 2:
    // every item has a verdict (nothing to draw).
    int presettle(int width, int height, DepthFormat format, std::span<const VisibilityItem> items, int threads);
    // guard.record() after a call that ran the pre-pass.
    void alone_record(std::span<const VisibilityItem> items, const PayGuard::Call& call);
    // Items [first, last): reach[i], and their reach marked into the cells obj / state.
    void mark(const detail::FrontEndParams& params, std::span<const VisibilityItem> items, DepthFormat format,
              const detail::CellGrid& g, std::size_t first, std::size_t last, std::uint32_t* obj, std::uint8_t* state);
    void mark_parts(const detail::FrontEndParams& params, std::span<const VisibilityItem> items, DepthFormat format,
                    const detail::CellGrid& g, int threads, std::size_t n_parts);
    // skip[i] for item i against the merged cells occ_obj / occ_state.
    void alone(const detail::CellGrid& g, DepthFormat format, std::size_t i);
    // One triangle's fragments into the minima of a tile at (x0, y0)..(x1, y1) of `side` pixels a
    // row; with `keep`, each fragment's zmax goes to `out` for the query test.
    __attribute__((always_inline)) void draw(std::span<const VisibilityItem> items, Ref r, bool keep, int x0, int y0,
                                             int x1, int y1, int side, DepthFormat format, std::uint32_t* tile_min1,
                                             std::uint32_t* tile_obj1, std::uint32_t* tile_min2,
                                             std::vector<Fragment>& out) const;
    // Each fragment of `frags` against the minima: its item goes to hit[] where the query passes.
    void test_fragments(std::span<const VisibilityItem> items, const std::vector<Fragment>& fragments,
                        const std::uint32_t* tile_min1, const std::uint32_t* tile_obj1,
                        const std::uint32_t* tile_min2);
};

void VisibilityPass::State::reserve_items(std::size_t n) {
    if (tris.size() < n) {
        tris.resize(n);
        pool.resize(n);
        bad.resize(n);
        area.resize(n);
        reach.resize(n);
        skip.resize(n);
    }
}

namespace {
detail::FrontEndParams front_end_params(int width, int height) {
    detail::FrontEndParams params{};
    params.target_width = width;
    params.target_height = height;
    params.viewport = Viewport{0, 0, width, height};
    params.cull_face = CullFace::None;
    params.front_face = FrontFace::CCW;
    return params;
}
}  // namespace

bool VisibilityPass::State::setup_item(const detail::FrontEndParams& params, std::span<const VisibilityItem> items,
                                       std::size_t i) {
    auto& item_tris = tris[i];
    auto& item_pool = pool[i];
    item_tris.clear();
    item_pool.clear();
    const MeshViewD& m = items[i].mesh;
    item_tris.reserve(m.indices.size() / 3);
    item_pool.reserve(m.indices.size());
    bad[i] = 0;
    area[i] = 0;
    if (skip[i]) return true;  // alone in the view: no triangle to draw (alone())
    const std::size_t nv = m.vertices.size();
    const std::size_t n_idx = m.indices.size() / 3 * 3;
    for (std::size_t k = 0; k < n_idx; k += 3) {  // the input checks first (a failed item is not drawn)
        const std::uint32_t ia = m.indices[k], ib = m.indices[k + 1], ic = m.indices[k + 2];
        if (ia >= nv || ib >= nv || ic >= nv ||
            !(valid_vertex(m.vertices[ia]) && valid_vertex(m.vertices[ib]) && valid_vertex(m.vertices[ic]))) {
            bad[i] = 1;
            return false;
        }
    }
    detail::setup_bounds_range(params, m.vertices, m.indices.first(n_idx), static_cast<std::uint32_t>(i), item_tris,
                               item_pool);
    for (const detail::BoundsTri& t : item_tris)
        area[i] += static_cast<std::uint64_t>(t.x1 - t.x0 + 1) * static_cast<std::uint64_t>(t.y1 - t.y0 + 1);
    return true;
}

bool VisibilityPass::State::front_end(int width, int height, DepthFormat format, std::span<const VisibilityItem> items,
                                      int threads, bool use_alone) {
    reserve_items(items.size());
    const detail::FrontEndParams params = front_end_params(width, height);
    const detail::CellGrid g = detail::CellGrid::of(width, height);
    if (use_alone) {
        occ_obj.resize(g.count());
        occ_state.assign(g.count(), kOccNone);
        mark(params, items, format, g, 0, items.size(), occ_obj.data(), occ_state.data());
    }
    detail::parallel_for(threads, items.size(), [&](std::size_t i) {
        if (use_alone)
            alone(g, format, i);
        else
            skip[i] = 0;
        (void)setup_item(params, items, i);
    });
    for (std::size_t i = 0; i < items.size(); ++i)
        if (bad[i]) return false;
    return true;
}

void VisibilityPass::State::depth_bounds(DepthFormat format, std::size_t n_items) {
    for (std::size_t i = 0; i < n_items; ++i)
        for (detail::BoundsTri& t : tris[i]) {
            double lo = 0, hi = 0;
            detail::bounds_depth_range(t, pool[i].data(), lo, hi);
            // The draw quantizes zlo - margin_z down and zhi + margin_z up; subtraction, addition
            // and both quantizations are monotone, so these bound every pixel's values.
            t.zq_lo = detail::quantize_down(lo - t.margin_z, format);
            t.zq_hi = detail::quantize_up(hi + t.margin_z, format);
        }
}

// Items alone in the view ("model only what a scene needs", issue #16). In an R-CULLIDE view many
// items lie far from every other object (the cloth's first sub-object view: 90% of its triangles),
// yet each was set up, drawn and tested. bounds_reach gives, from an item's vertices alone, a pixel
// box holding every pixel its fragments can reach and a bound on their encoded zmax. Let every cell
// of item i's box (object A) be reached by no other object's item (kOccOne). Then:
//  - no other object's fragment lies at a pixel of i's, so the minimum over the objects other than
//    A is the clear value at each of them: i's query passes iff some zmax >= the clear value, which
//    zq_hi < clear rules out (an empty box: no fragment at all);
//  - another object B's fragment lies in a cell that A's items do not reach, so the minimum over
//    the objects other than B there never holds a zmin of i: leaving i out changes no other test.
// So such an item is neither set up nor drawn (skip[i] = 1, hit[i] stays 0) and every answer is the
// same bit for bit. Cells are coarser than pixels on targets above 128 a side (a superset: more
// items drawn, never fewer than needed). An item that fails an input check is never skipped, so the
// front end still finds and reports it.
void VisibilityPass::State::mark(const detail::FrontEndParams& params, std::span<const VisibilityItem> items,
                                 DepthFormat format, const detail::CellGrid& g, std::size_t first, std::size_t last,
                                 std::uint32_t* obj, std::uint8_t* state) {
    for (std::size_t i = first; i < last; ++i) {
        const std::uint32_t o = items[i].object;
        reach[i] = detail::bounds_reach(params, items[i].mesh, format, g.shift, [&](int x0, int y0, int x1, int y1) {
            occ_mark(g, obj, state, x0, y0, x1, y1, o);
        });
    }
}

void VisibilityPass::State::alone(const detail::CellGrid& g, DepthFormat format, std::size_t i) {
    skip[i] = occ_alone(g, occ_state.data(), reach[i], DepthTarget::encode_clear(1.0, format)) ? 1 : 0;
}

void VisibilityPass::State::alone_record(std::span<const VisibilityItem> items, const PayGuard::Call& call) {
    std::uint64_t spared = 0;
    for (std::size_t i = 0; i < items.size(); ++i)
        if (skip[i]) spared += items[i].mesh.indices.size() / 3;
    guard.record(call, spared);
}

void VisibilityPass::State::bin(std::span<const VisibilityItem> items, const TileGrid& grid, bool settle) {
    const std::size_t tile_count = grid.count();
    if (bins.size() < tile_count) {
        bins.resize(tile_count);
        frags.resize(tile_count);
        need.resize(tile_count);
    }
    for (std::size_t t = 0; t < tile_count; ++t) bins[t].clear();
    if (tile_count == 1 && !settle) return;  // shade then takes every triangle, in item order
    for (std::size_t i = 0; i < items.size(); ++i) {
        for (std::size_t k = 0; k < tris[i].size(); ++k) {
            const detail::BoundsTri& t = tris[i][k];
            for (int ty = t.y0 / grid.side; ty <= t.y1 / grid.side; ++ty)
                for (int tx = t.x0 / grid.side; tx <= t.x1 / grid.side; ++tx)
                    bins[static_cast<std::size_t>(ty) * static_cast<std::size_t>(grid.x) + static_cast<std::size_t>(tx)]
                        .push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(k)});
        }
    }
}

inline void VisibilityPass::State::draw(std::span<const VisibilityItem> items, const Ref r, const bool keep, const int x0,
                                 const int y0, const int x1, const int y1, const int side, const DepthFormat format,
                                 std::uint32_t* tile_min1, std::uint32_t* tile_obj1, std::uint32_t* tile_min2,
                                 std::vector<Fragment>& out) const {
    const detail::BoundsTri& t = tris[r.item][r.tri];
    const std::uint32_t obj = items[r.item].object;
    const double mz = t.margin_z;
    double last_lo = std::numeric_limits<double>::quiet_NaN(), last_hi = last_lo;
    std::uint32_t zmin = 0, zmax = 0;  // quantized once per distinct depth
    const detail::PixelRect rect{std::max(x0, t.x0), std::max(y0, t.y0), std::min(x1, t.x1), std::min(y1, t.y1)};
    detail::bounds_pixels(t, pool[r.item].data(), rect, [&](int px, int py, double zlo, double zhi) {
        const auto p = static_cast<std::uint32_t>((py - y0) * side + (px - x0));
        if (!(zlo == last_lo)) {
            last_lo = zlo;
            zmin = detail::quantize_down(zlo - mz, format);
        }
        min_by_object(tile_min1, tile_obj1, tile_min2, p, obj, zmin);
        if (!keep) return;
        if (!(zhi == last_hi)) {
            last_hi = zhi;
            zmax = detail::quantize_up(zhi + mz, format);
        }
        out.push_back({r.item, p, zmax});
    });
}

// Tiles settled from depth bounds: an item's query can pass at a pixel only if one of its fragments
// there has zmax >= the minimum zmin over the other objects' fragments there (and the clear value).
// Every fragment in a tile comes from a triangle binned to it, and its zmin >= the triangle's zq_lo,
// its zmax <= zq_hi. So with L = the minimum of zq_lo over the tile's triangles of the other objects
// (the clear value if none), a triangle with zq_hi < L has no fragment in the tile whose query
// passes: its fragments need no test. A tile where no triangle of an item not yet found is left
// needs no per-pixel work at all. The zmin of every triangle in a tested tile still enters its
// minima, so each tested fragment meets exactly the value it met before; and an item's answer is the
// OR over tiles, so skipping the items already found changes nothing. The answer is therefore the
// same bit for bit, whatever the thread timing (the skip of found items reads flags another task
// may be setting: it only changes how much work is done).
void VisibilityPass::State::shade(std::span<const VisibilityItem> items, const TileGrid& grid, int width,
                                  int height, DepthFormat format, std::size_t tile, bool settle) {
    const bool one_tile = grid.count() == 1 && !settle;  // every triangle is in it: no bin was built
    auto& tile_bin = bins[tile];
    if (tile_bin.empty() && !one_tile) return;
    const auto found = [&](std::uint32_t item) {
        return std::atomic_ref<std::uint8_t>(hit[item]).load(std::memory_order_relaxed) != 0;
    };
    const std::uint32_t clear = DepthTarget::encode_clear(1.0, format);
    auto& tile_need = need[tile];
    if (settle) {  // (bins are always built when settling, so tile_bin holds the tile's triangles)
    // The two smallest zq_lo over objects, as the per-pixel minima below keep them.
    std::uint32_t m1 = clear, o1 = kNoObject, m2 = clear;
    for (const Ref& r : tile_bin) {
        const std::uint32_t obj = items[r.item].object;
        const std::uint32_t lo = tris[r.item][r.tri].zq_lo;
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
    tile_need.resize(tile_bin.size());
    bool any = false;
    for (std::size_t j = 0; j < tile_bin.size(); ++j) {
        const Ref r = tile_bin[j];
        const std::uint32_t other = items[r.item].object == o1 ? m2 : m1;
        const bool n = tested[r.item] && tris[r.item][r.tri].zq_hi >= other && !found(r.item);
        tile_need[j] = n ? 1 : 0;
        any = any || n;
    }
    if (!any) return;
    }

    auto& tile_frags = frags[tile];
    tile_frags.clear();
    const int side = grid.side;
    const int tx = static_cast<int>(tile % static_cast<std::size_t>(grid.x));
    const int ty = static_cast<int>(tile / static_cast<std::size_t>(grid.x));
    const int x0 = tx * side, y0 = ty * side;
    const int x1 = std::min(x0 + side, width) - 1, y1 = std::min(y0 + side, height) - 1;
    const std::size_t tile_pixels = grid.pixels();
    std::uint32_t* tile_min1 = min1.data() + tile * tile_pixels;
    std::uint32_t* tile_obj1 = obj1.data() + tile * tile_pixels;
    std::uint32_t* tile_min2 = min2.data() + tile * tile_pixels;
    std::fill(tile_min1, tile_min1 + tile_pixels, clear);
    std::fill(tile_obj1, tile_obj1 + tile_pixels, kNoObject);
    std::fill(tile_min2, tile_min2 + tile_pixels, clear);
    const auto draw = [&](const Ref r, const bool keep) __attribute__((always_inline)) {
        this->draw(items, r, keep, x0, y0, x1, y1, side, format, tile_min1, tile_obj1, tile_min2, tile_frags);
    };
    if (one_tile) {
        for (std::size_t i = 0; i < items.size(); ++i)
            for (std::size_t k = 0; k < tris[i].size(); ++k)
                draw({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(k)}, tested[i] != 0);
    } else if (settle) {
        for (std::size_t j = 0; j < tile_bin.size(); ++j) draw(tile_bin[j], tile_need[j] != 0);
    } else {
        for (const Ref& r : tile_bin) draw(r, tested[r.item] != 0);
    }
    test_fragments(items, tile_frags, tile_min1, tile_obj1, tile_min2);
}

// min1 is the minimum over all objects (with the clear value) and min2 the minimum over the
// objects other than obj1's, so the minimum over the objects other than o is min2 when o is obj1
// and min1 otherwise (ties between objects: then min2 == min1).
void VisibilityPass::State::test_fragments(std::span<const VisibilityItem> items, const std::vector<Fragment>& fragments,
                                           const std::uint32_t* tile_min1, const std::uint32_t* tile_obj1,
                                           const std::uint32_t* tile_min2) {
    std::uint32_t last = kNoObject;
    for (const Fragment& f : fragments) {
        if (f.item == last) continue;
        const std::uint32_t other = other_than(tile_min1, tile_obj1, tile_min2, f.pixel, items[f.item].object);
        if (f.zmax >= other) {  // the GEQUAL query passes here
            std::atomic_ref<std::uint8_t>(hit[f.item]).store(1, std::memory_order_relaxed);
            last = f.item;
        }
    }
}

// split_pass's marking: each part's reach into its own cells, in parallel, merged in part order
// (kOccMany where two parts hold different objects): the same cells as one marking of every item.
void VisibilityPass::State::mark_parts(const detail::FrontEndParams& params, std::span<const VisibilityItem> items,
                                       DepthFormat format, const detail::CellGrid& g, int threads, std::size_t n_parts) {
    if (part_occ_obj.size() < n_parts) {
        part_occ_obj.resize(n_parts);
        part_occ_state.resize(n_parts);
    }
    detail::parallel_for(threads, n_parts, [&](std::size_t part) {
        part_occ_obj[part].resize(g.count());
        part_occ_state[part].assign(g.count(), kOccNone);
        mark(params, items, format, g, part_first[part], part_first[part + 1], part_occ_obj[part].data(),
             part_occ_state[part].data());
    });
    occ_obj.assign(part_occ_obj[0].begin(), part_occ_obj[0].begin() + static_cast<std::ptrdiff_t>(g.count()));
    occ_state.assign(part_occ_state[0].begin(), part_occ_state[0].begin() + static_cast<std::ptrdiff_t>(g.count()));
    for (std::size_t part = 1; part < n_parts; ++part)
        merge_occ(occ_obj.data(), occ_state.data(), part_occ_obj[part].data(), part_occ_state[part].data(), g.count());
}

// The one-tile pass split by items (issue #16: R-CULLIDE's 32^2 views are one tile, so the tile
// loop gave a second thread nothing). What the pass computes per pixel does not depend on the order
// of the triangles: the minimum zmin over all objects and over the objects other than the one that
// holds it. So the items are cut into `parts` runs of about equal triangle counts; each run sets its
// items up and draws their triangles into the run's own minima (and its fragments into its own
// list) in one task, so that the set-up triangles are drawn from the cache of the core that made
// them; the runs' minima are merged pixel by pixel; then each run's fragments are tested against
// the merged minima. Merging (m1, o1, m2) records keeps their meaning exactly: the smaller m1 wins
// with its object, and m2 becomes the minimum over the objects other than that one, which from the
// other record is its m2 if it holds the same object and its m1 otherwise. Every fragment then meets
// the same value as in the serial pass, so hit[] is the same bit for bit, for any number of parts.
//
// Whether the tiles should rather be settled (large triangles) is known only once every item is set
// up, so a run whose own triangles are large skips its drawing; if the whole pass turns out to
// settle, the caller takes the settled path with the triangles as set up (any run's drawing is then
// wasted work, never a different answer), and otherwise the skipped runs are drawn afterwards.
int VisibilityPass::State::split_pass(std::span<const VisibilityItem> items, const int side, const int width,
                                      const int height, const DepthFormat format, const int threads,
                                      const std::size_t n_parts, const bool use_alone) {
    reserve_items(items.size());
    if (part_min1.size() < n_parts) {
        part_min1.resize(n_parts);
        part_obj1.resize(n_parts);
        part_min2.resize(n_parts);
        part_frags.resize(n_parts);
    }
    // Cut by triangle count, at item boundaries: the input decides it.
    std::uint64_t total = 0;
    for (const VisibilityItem& it : items) total += it.mesh.indices.size() / 3;
    part_first.assign(n_parts + 1, items.size());
    part_first[0] = 0;
    {
        std::uint64_t sum = 0;
        std::size_t part = 1;
        for (std::size_t i = 0; i < items.size() && part < n_parts; ++i) {
            // Item i starts part `part` once the items before it hold part/parts of the triangles.
            while (part < n_parts && sum * n_parts >= total * part) part_first[part++] = i;
            sum += items[i].mesh.indices.size() / 3;
        }
    }
    part_done.assign(n_parts, 0);
    const detail::FrontEndParams params = front_end_params(width, height);
    const detail::CellGrid g = detail::CellGrid::of(width, height);
    if (use_alone) mark_parts(params, items, format, g, threads, n_parts);
    detail::parallel_for(threads, n_parts, [&](std::size_t part) {
        std::uint64_t part_area = 0, part_count = 0;
        for (std::size_t i = part_first[part]; i < part_first[part + 1]; ++i) {
            if (use_alone)
                alone(g, format, i);
            else
                skip[i] = 0;
            if (!setup_item(params, items, i)) return;
            part_area += area[i];
            part_count += tris[i].size();
        }
        if (part_count > 0 && part_area >= kSettleMinArea * part_count) return;  // large: may settle
        raster_part(items, side, width, height, format, part);
        part_done[part] = 1;
    });
    std::uint64_t area_sum = 0, count = 0;
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (bad[i]) return 0;
        area_sum += area[i];
        count += tris[i].size();
    }
    if (count > 0 && area_sum >= kSettleMinArea * count) return 2;
    detail::parallel_for(threads, n_parts, [&](std::size_t part) {
        if (!part_done[part]) raster_part(items, side, width, height, format, part);
    });
    // Merge into part 0 (a few thousand pixels: serial).
    const std::size_t tile_pixels = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
    std::uint32_t* a1 = part_min1[0].data();
    std::uint32_t* ao = part_obj1[0].data();
    std::uint32_t* a2 = part_min2[0].data();
    for (std::size_t part = 1; part < n_parts; ++part)
        merge_min_by_object(a1, ao, a2, part_min1[part].data(), part_obj1[part].data(), part_min2[part].data(),
                            tile_pixels);
    hit.assign(items.size(), 0);
    detail::parallel_for(threads, n_parts,
                         [&](std::size_t part) { test_fragments(items, part_frags[part], a1, ao, a2); });
    return 1;
}

void VisibilityPass::State::raster_part(std::span<const VisibilityItem> items, const int side, const int width,
                                        const int height, const DepthFormat format, const std::size_t part) {
    const std::size_t tile_pixels = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
    const std::uint32_t clear = DepthTarget::encode_clear(1.0, format);
    auto& m1 = part_min1[part];
    auto& o1 = part_obj1[part];
    auto& m2 = part_min2[part];
    m1.assign(tile_pixels, clear);
    o1.assign(tile_pixels, kNoObject);
    m2.assign(tile_pixels, clear);
    auto& out = part_frags[part];
    out.clear();
    for (std::size_t i = part_first[part]; i < part_first[part + 1]; ++i)
        for (std::size_t k = 0; k < tris[i].size(); ++k)
            draw(items, {static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(k)}, tested[i] != 0, 0, 0, width - 1,
                 height - 1, side, format, m1.data(), o1.data(), m2.data(), out);
}

// The settling pre-pass (issue #16, "model only what a scene needs"). In R-CULLIDE's 32^2 views
// most items' answers are already certain from bounds that cost a fraction of a setup, and most
// items cannot change the answer of an item that is not. From the vertices alone
// (detail::WindowBoxer, or bounds_reach for items that may be clipped: an item's pixel box, or a box
// per triangle, with [lo, hi] holding every zmin and zmax of its fragments there;
// detail::WindowMap: the window position of each vertex inside the clip cube, setup's very values):
//  - coarse minima: per pixel, min_by_object of lo over every item whose box holds the pixel. An
//    item's fragments lie in its box with zmin >= lo, so at every pixel the coarse minimum over the
//    objects other than o is <= the pass's (min2 / min1 over the fragments, the clear value on
//    both sides).
//  - vertex minima: per pixel, min_by_object of encode_near(z + kVertexSlack) over the window
//    vertices in it (those inside the clip cube). A triangle has a fragment at the pixel holding
//    such a vertex, with zmin <= that value (detail::kVertexSlack, encode_near), so the vertex
//    minimum over the objects other than o is >= the pass's there.
//  - an item with hi < the coarse minimum over the other objects at every pixel of its box is NOT
//    hit: each of its fragments has zmax <= hi < the pass's minimum there.
//  - an item with a vertex whose zmax bound, encode_near(z - kVertexSlack), is >= the vertex minimum
//    over the other objects at its pixel IS hit: that fragment's zmax >= the bound >= the pass's
//    minimum there.
//  - the other items are open. The pass then draws only the open items and the items whose box
//    reaches a pixel where an open item of another object has a box with hi >= their lo, and tests
//    only the open items' fragments. At a pixel where an open item of object o has a fragment of
//    zmax z, an item left out is either of object o (not in the minimum over the objects other
//    than o) or has zmin >= lo > that item's hi >= z, and a minimum is <= z with or without values
//    above z: every tested fragment gets the answer it gets in the full pass.
// So the answers are the full pass's bit for bit (the settled items take their verdicts), for any
// thread count: every step is a function of the input (the parts' minima merge exactly, as the split
// pass's do). The alone pre-pass is not run then: an item it would spare is settled here too (no
// other object's box reaches its pixels, so the coarse minimum there is the clear value, above its
// hi unless it reaches the far plane within a step of the encoding) and left out.

namespace {
// Whether a box per triangle would say nothing more than the item's one box: one of its triangles
// (vertices mapped: cache[index].win) spans its whole window box [x0, x1] x [y0, y1] at its smallest
// depth z0, and one (the same or another) at its largest z1. Then at every pixel of the item's box
// the triangles' boxes reach, between them, down to the item's lo and up to its hi, as the item's
// box does, and a box per triangle only costs more (a box's faces seen along an axis: its near face
// spans the box at z0, its far face at z1). Otherwise the triangles' own depth ranges are tighter.
template <class Cache>
bool spans_box(const Cache* cache, std::span<const std::uint32_t> indices, double x0, double x1, double y0, double y1,
               double z0, double z1) {
    bool near = false, far = false;
    for (std::size_t k = 0; k < indices.size() && !(near && far); k += 3) {
        const auto& a = cache[indices[k]].win;
        const auto& b = cache[indices[k + 1]].win;
        const auto& c = cache[indices[k + 2]].win;
        if (std::min(std::min(a.x, b.x), c.x) != x0 || std::max(std::max(a.x, b.x), c.x) != x1 ||
            std::min(std::min(a.y, b.y), c.y) != y0 || std::max(std::max(a.y, b.y), c.y) != y1)
            continue;
        near = near || std::min(std::min(a.z, b.z), c.z) == z0;
        far = far || std::max(std::max(a.z, b.z), c.z) == z1;
    }
    return near && far;
}
}  // namespace

int VisibilityPass::State::presettle(int width, int height, DepthFormat format, std::span<const VisibilityItem> items,
                                     int threads) {
    const std::size_t n = items.size();
    const detail::FrontEndParams params = front_end_params(width, height);
    const auto w = static_cast<std::size_t>(width);
    const std::size_t pixels = w * static_cast<std::size_t>(height);
    const std::uint32_t clear = DepthTarget::encode_clear(1.0, format);
    box_first.resize(n + 1);
    rec_first.resize(n + 1);
    std::size_t total = 0, total_boxes = 0;  // indices, box slots
    for (std::size_t i = 0; i < n; ++i) {
        box_first[i] = total_boxes;
        rec_first[i] = total;
        total += items[i].mesh.indices.size();
        total_boxes += std::max<std::size_t>(1, items[i].mesh.indices.size() / 3);
    }
    box_first[n] = total_boxes;
    rec_first[n] = total;
    if (total == 0) return 0;
    vrec.resize(total);
    boxes.resize(total_boxes);
    box_count.resize(n);
    rec_count.resize(n);
    verdict.resize(n);
    drawn.resize(n);
    face_first.resize(n);
    face_count.resize(n);
    // Every pixel of item i's boxes while f(box, pixel) is true; false when f stopped it.
    const auto for_pixels = [&](std::size_t i, auto&& f) __attribute__((always_inline)) {
        for (std::size_t b = box_first[i]; b < box_first[i] + box_count[i]; ++b) {
            const BoxBound& t = boxes[b];
            for (int py = t.y0; py <= t.y1; ++py)
                for (int px = t.x0; px <= t.x1; ++px)
                    if (!f(t, static_cast<std::size_t>(py) * w + static_cast<std::size_t>(px))) return false;
        }
        return true;
    };
    // Parts of about equal index counts at item boundaries (the input decides them), each with its
    // own per-pixel records, merged in part order after each phase.
    const std::size_t n_parts =
        threads > 1 ? std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(threads) * 2,
                                                                      total / kPresettlePartIndices))
                    : 1;
    std::vector<std::size_t>& first = pre_first;
    first.assign(n_parts + 1, n);
    first[0] = 0;
    for (std::size_t i = 0, part = 1; i < n && part < n_parts; ++i)
        while (part < n_parts && rec_first[i] * n_parts >= total * part) first[part++] = i;
    if (pre.size() < n_parts) pre.resize(n_parts);
    pre_failed.assign(n_parts, 0);
    face_hits.assign(n_parts, 0);
    pre_area.assign(2 * n_parts, 0);  // per part: pixels of its boxes; then per part: its triangles
    PrePart& m = pre[0];              // the merged records

    // 1. Window vertices, the vertex minima and the records; boxes and the coarse minima. A vertex
    // shared by several items of a run of one object and one vertex array is checked, mapped and
    // marked once per part (what was found kept in vcache, stamped with the run's generation); an
    // item whose vertices are all inside the clip cube takes its boxes from their window positions
    // (detail::WindowBoxer), any other bounds_reach's boxes with the widest depth range.
    const detail::WindowMap window(params);
    const detail::WindowBoxer boxer(params, format);
    detail::parallel_for(threads, n_parts, [&](std::size_t part) {
        PrePart& ps = pre[part];
        ps.c1.assign(pixels, clear);
        ps.co.assign(pixels, kNoObject);
        ps.c2.assign(pixels, clear);
        ps.v1.assign(pixels, clear);
        ps.vo.assign(pixels, kNoObject);
        ps.v2.assign(pixels, clear);
        ps.frec.clear();
        const Double4* run_vertices = nullptr;
        std::uint32_t run_object = kNoObject;
        std::uint64_t box_area = 0, triangles = 0;
        for (std::size_t i = first[part]; i < first[part + 1]; ++i) {
            // The next item's vertices, where a mesh is larger than the caches (bunny-dragon: its
            // items' vertices are scattered over megabytes).
            if (i + 1 < first[part + 1] && items[i + 1].mesh.vertices.size() > kPrefetchVertices) {
                const MeshViewD& next = items[i + 1].mesh;
                for (std::size_t k = 0; k < next.indices.size() && k < 48; ++k)
                    if (next.indices[k] < next.vertices.size()) __builtin_prefetch(next.vertices.data() + next.indices[k]);
            }
            const std::uint32_t obj = items[i].object;
            const MeshViewD& mesh = items[i].mesh;
            BoxBound* bx = boxes.data() + box_first[i];
            std::uint32_t nbox = 0;
            std::uint64_t item_area = 0;
            const auto add_box = [&](int x0, int y0, int x1, int y1, std::uint32_t lo, std::uint32_t hi) {
                bx[nbox++] = {static_cast<std::int16_t>(x0), static_cast<std::int16_t>(y0),
                              static_cast<std::int16_t>(x1), static_cast<std::int16_t>(y1), lo, hi};
                item_area += static_cast<std::uint64_t>(x1 - x0 + 1) * static_cast<std::uint64_t>(y1 - y0 + 1);
                for (int py = y0; py <= y1; ++py)
                    for (int px = x0; px <= x1; ++px)
                        min_by_object(ps.c1.data(), ps.co.data(), ps.c2.data(),
                                      static_cast<std::size_t>(py) * w + static_cast<std::size_t>(px), obj, lo);
            };
            if (mesh.vertices.data() != run_vertices || obj != run_object) {  // a new run: new stamps
                run_vertices = mesh.vertices.data();
                run_object = obj;
                if (ps.vstamp.size() < mesh.vertices.size()) {
                    ps.vstamp.resize(mesh.vertices.size(), 0);
                    ps.vcache.resize(mesh.vertices.size());
                }
                if (++ps.gen == 0) {
                    std::fill(ps.vstamp.begin(), ps.vstamp.end(), 0u);
                    ps.gen = 1;
                }
            }
            // Each index: its vertex checked and, inside the clip cube, mapped to the window (once
            // per run); the item's window extremes; a record per vertex in the target.
            const std::size_t nv = mesh.vertices.size();
            VertexRec* rec = vrec.data() + rec_first[i];
            std::uint32_t nrec = 0;
            bool all_inside = true;
            constexpr double kInf = __builtin_inf();
            double x0 = kInf, x1 = -kInf, y0 = kInf, y1 = -kInf, z0 = kInf, z1 = -kInf;
            for (const std::uint32_t v : mesh.indices) {
                if (v >= nv) {
                    pre_failed[part] = 1;  // the front end finds and reports it
                    return;
                }
                VertexMap& c = ps.vcache[v];
                if (ps.vstamp[v] != ps.gen) {
                    ps.vstamp[v] = ps.gen;
                    const Double4& d = mesh.vertices[v];
                    // (valid_vertex compares each coordinate: std::max drops a NaN in its second argument.)
                    const double mag = std::max(std::max(std::fabs(d.x), std::fabs(d.y)), std::fabs(d.z));
                    c.state = !valid_vertex(d) ? VertexMap::kBad
                              : mag <= 1.0     ? VertexMap::kInside
                                               : VertexMap::kBeyond;
                    if (c.state == VertexMap::kInside) {
                        c.win = window(d);
                        c.pixel = kNoObject;  // outside the target: no fragment to name
                        if (c.win.x >= 0.0 && c.win.x < static_cast<double>(width) && c.win.y >= 0.0 &&
                            c.win.y < static_cast<double>(height)) {
                            c.pixel = static_cast<std::uint32_t>(static_cast<std::size_t>(c.win.y) * w +
                                                                 static_cast<std::size_t>(c.win.x));
                            // encode_near bounds quantize_down from above and quantize_up from below.
                            c.zmax = detail::encode_near(c.win.z - detail::kVertexSlack, format);
                            min_by_object(ps.v1.data(), ps.vo.data(), ps.v2.data(), c.pixel, obj,
                                          detail::encode_near(c.win.z + detail::kVertexSlack, format));
                        }
                    }
                }
                if (c.state == VertexMap::kBad) {
                    pre_failed[part] = 1;
                    return;
                }
                if (c.state == VertexMap::kBeyond) {
                    all_inside = false;
                    continue;
                }
                x0 = std::min(x0, c.win.x), x1 = std::max(x1, c.win.x);
                y0 = std::min(y0, c.win.y), y1 = std::max(y1, c.win.y);
                z0 = std::min(z0, c.win.z), z1 = std::max(z1, c.win.z);
                if (c.pixel != kNoObject) rec[nrec++] = {c.pixel, c.zmax};
            }
            const std::size_t n_idx = mesh.indices.size();
            if (!all_inside) {
                // May be clipped: bounds_reach's boxes (pixels on one-tile targets: shift 0) hold
                // every record's box; any depth.
                (void)detail::bounds_reach(params, mesh, format, 0, [&](int bx0, int by0, int bx1, int by1) {
                    add_box(bx0, by0, bx1, by1, 0u, 0xffffffffu);
                });
            } else if (n_idx > 0 && !boxer(x0, x1, y0, y1, z0, z1, n_idx > 3 ? detail::kReachSpread * (n_idx / 3) : 0,
                                          add_box) &&
                       !(spans_box(ps.vcache.data(), mesh.indices, x0, x1, y0, y1, z0, z1) &&
                         boxer(x0, x1, y0, y1, z0, z1, 0, add_box))) {
                for (std::size_t k = 0; k < n_idx; k += 3) {  // scattered: a box per triangle
                    const detail::BoundsVertex& a = ps.vcache[mesh.indices[k]].win;
                    const detail::BoundsVertex& b = ps.vcache[mesh.indices[k + 1]].win;
                    const detail::BoundsVertex& cc = ps.vcache[mesh.indices[k + 2]].win;
                    boxer(std::min(std::min(a.x, b.x), cc.x), std::max(std::max(a.x, b.x), cc.x),
                          std::min(std::min(a.y, b.y), cc.y), std::max(std::max(a.y, b.y), cc.y),
                          std::min(std::min(a.z, b.z), cc.z), std::max(std::max(a.z, b.z), cc.z), 0, add_box);
                }
            }
            // Flat triangles (one window depth: boxes' faces seen along an axis): a record at every
            // pixel they certainly reach, not only at their vertices' (detail::flat_triangle_pixels).
            // Only in items at least a pixel wide and high: in smaller ones the vertices' records
            // are most of what a face could add (R-CULLIDE's sub-objects: the scan cost tori and
            // breaking 2-3%).
            // face_first and face_count are written only for such items (kHasFaces in rec_count).
            const bool faces = all_inside && nbox > 0 && x1 - x0 >= 1.0 && y1 - y0 >= 1.0;
            if (faces) {
                face_first[i] = static_cast<std::uint32_t>(ps.frec.size());
                for (std::size_t k = 0; k < n_idx; k += 3) {
                    const detail::BoundsVertex& a = ps.vcache[mesh.indices[k]].win;
                    const detail::BoundsVertex& b = ps.vcache[mesh.indices[k + 1]].win;
                    const detail::BoundsVertex& cc = ps.vcache[mesh.indices[k + 2]].win;
                    if (a.z != b.z || a.z != cc.z) continue;
                    // Only the item's farthest faces bound its queries' zmax from below usefully, and
                    // only its nearest bound its writes' zmin from above (a box: its far face and its
                    // near face; a flat item: every triangle both); a face between gives nothing.
                    const bool query = a.z == z1, write = a.z == z0;
                    if (!query && !write) continue;
                    const std::uint32_t zmax = detail::encode_near(a.z - detail::kVertexSlack, format);
                    const std::uint32_t zmin = detail::encode_near(a.z + detail::kVertexSlack, format);
                    detail::flat_triangle_pixels(a, b, cc, width, height, [&](std::uint32_t pixel) {
                        if (query) ps.frec.push_back({pixel, zmax});
                        if (write) min_by_object(ps.v1.data(), ps.vo.data(), ps.v2.data(), pixel, obj, zmin);
                    });
                }
                face_count[i] = static_cast<std::uint32_t>(ps.frec.size()) - face_first[i];
            }
            box_count[i] = nbox;
            verdict[i] = kOpen;
            if (nbox > 0 && all_inside) {  // (a clipped item's box, the whole target, says nothing of its size)
                box_area += item_area;
                triangles += n_idx / 3;
            }
            rec_count[i] = nrec | (faces ? kHasFaces : 0u);
        }
        pre_area[part] = box_area;
        pre_area[n_parts + part] = triangles;
    });
    std::uint64_t box_area = 0, triangles = 0;
    for (std::size_t part = 0; part < n_parts; ++part) {
        if (pre_failed[part]) return 0;  // the front end finds and reports it
        box_area += pre_area[part];
        triangles += pre_area[n_parts + part];
    }
    // Large triangles (kSettleMinArea pixels of box or more per triangle): the tiles settled from
    // depth bounds instead.
    if (triangles > 0 && box_area >= kSettleMinArea * triangles) return 0;
    for (std::size_t part = 1; part < n_parts; ++part) {
        merge_min_by_object(m.c1.data(), m.co.data(), m.c2.data(), pre[part].c1.data(), pre[part].co.data(),
                            pre[part].c2.data(), pixels);
        merge_min_by_object(m.v1.data(), m.vo.data(), m.v2.data(), pre[part].v1.data(), pre[part].vo.data(),
                            pre[part].v2.data(), pixels);
    }

    // 2. Verdicts: certainly not hit (the coarse minima), certainly hit (the vertex minima), open;
    // the open items' largest hi by object per pixel.
    detail::parallel_for(threads, n_parts, [&](std::size_t part) {
        PrePart& ps = pre[part];
        ps.u1.assign(pixels, 0);
        ps.uo.assign(pixels, kNoObject);
        ps.u2.assign(pixels, 0);
        for (std::size_t i = first[part]; i < first[part + 1]; ++i) {
            const std::uint32_t obj = items[i].object;
            const bool not_hit = for_pixels(i, [&](const BoxBound& t, std::size_t p) {
                return t.hi < other_than(m.c1.data(), m.co.data(), m.c2.data(), p, obj);
            });
            if (not_hit) {
                verdict[i] = kNotHit;
                continue;
            }
            const VertexRec* rec = vrec.data() + rec_first[i];
            bool hit_sure = false;
            const std::uint32_t nrec = rec_count[i] & ~kHasFaces;
            for (std::uint32_t k = 0; k < nrec && !hit_sure; ++k)
                hit_sure = rec[k].zmax >= other_than(m.v1.data(), m.vo.data(), m.v2.data(), rec[k].pixel, obj);
            if (!hit_sure && (rec_count[i] & kHasFaces) != 0) {
                const VertexRec* face = ps.frec.data() + face_first[i];
                for (std::uint32_t k = 0; k < face_count[i] && !hit_sure; ++k)
                    hit_sure = face[k].zmax >= other_than(m.v1.data(), m.vo.data(), m.v2.data(), face[k].pixel, obj);
                face_hits[part] += hit_sure ? 1 : 0;
            }
            if (hit_sure) {
                verdict[i] = kHit;
                continue;
            }
            for_pixels(i, [&](const BoxBound& t, std::size_t p) {
                by_object(ps.u1.data(), ps.uo.data(), ps.u2.data(), p, obj, std::uint64_t{t.hi} + 1,
                          std::greater<std::uint64_t>());
                return true;
            });
        }
    });
    for (std::size_t part = 1; part < n_parts; ++part)
        merge_by_object(m.u1.data(), m.uo.data(), m.u2.data(), pre[part].u1.data(), pre[part].uo.data(),
                        pre[part].u2.data(), pixels, std::greater<std::uint64_t>());

    // 3. The items drawn: the open ones, and those whose lo an open item of another object may meet.
    detail::parallel_for(threads, n_parts, [&](std::size_t part) {
        for (std::size_t i = first[part]; i < first[part + 1]; ++i) {
            const std::uint32_t obj = items[i].object;
            drawn[i] = verdict[i] == kOpen || !for_pixels(i, [&](const BoxBound& t, std::size_t p) {
                return other_than(m.u1.data(), m.uo.data(), m.u2.data(), p, obj) <= t.lo;
            });
        }
    });
    reduced.clear();
    tested.clear();
    reduced_at.resize(n);
    std::uint64_t drawn_indices = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!drawn[i]) continue;
        reduced_at[i] = static_cast<std::uint32_t>(reduced.size());
        reduced.push_back(items[i]);
        tested.push_back(verdict[i] == kOpen ? 1 : 0);
        drawn_indices += items[i].mesh.indices.size();
    }
    settled = PresettleStats{};
    settled.ran = true;
    settled.triangles_left_out = (total - drawn_indices) / 3;
    for (std::size_t i = 0; i < n; ++i) {
        settled.items_hit += verdict[i] == kHit;
        settled.items_not_hit += verdict[i] == kNotHit;
        settled.items_open += verdict[i] == kOpen;
    }
    for (const std::uint64_t h : face_hits) settled.items_hit_by_face += h;
    return reduced.empty() ? 2 : 1;
}

VisibilityPass::VisibilityPass() : s_(std::make_unique<State>()) {}
std::uint64_t VisibilityPass::last_spared_triangles() const { return s_->guard.last_spared; }
PresettleStats VisibilityPass::last_presettle() const { return s_->settled; }
void VisibilityPass::set_presettle(bool on) { s_->presettle_on = on; }
VisibilityPass::~VisibilityPass() = default;

Result<std::vector<std::uint8_t>> VisibilityPass::run(int width, int height, DepthFormat format,
                                                      std::span<const VisibilityItem> items, int threads) {
    if (width < 1 || height < 1 || width > kMaxTargetSize || height > kMaxTargetSize)
        return Error{"visibility pass: target " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxTargetSize) + " per side"};
    if (std::optional<Error> e = check_format_threads("visibility pass", format, threads)) return *e;
    // Every index and vertex is checked in the front end, next to its use; only when some check
    // fails does `validate` run, to return the first error in item and index order.
    bool counts_ok = true;
    for (const VisibilityItem& it : items) counts_ok = counts_ok && it.mesh.indices.size() % 3 == 0;
    if (!counts_ok) return validate(items);
    threads = detail::effective_threads(threads);
    if (items.size() >= kNoObject) return Error{"visibility pass: too many items (limit 2^32 - 1)"};
    State& s = *s_;
    const int one_side = tile_side(width, height);
    const bool one_tile = one_side >= width && one_side >= height;
    // On one-tile targets the settling pre-pass first: the items it settles take their verdicts,
    // and the pass below runs on `reduced`, the items that can change an open item's answer, in
    // order (State::presettle).
    s.settled = PresettleStats{};
    int presettled = 0;
    const PayGuard::Call whole = PayGuard::call_of(items);
    if (one_tile && s.presettle_on) {
        if (s.settle_guard.wanted(whole)) {
            presettled = s.presettle(width, height, format, items, threads);
            s.settle_guard.record(whole, s.settled.triangles_left_out);
        }
    }
    const std::span<const VisibilityItem> all_items = items;
    const auto answer = [&]() {
        std::vector<std::uint8_t> out(all_items.size());
        for (std::size_t i = 0; i < out.size(); ++i)
            out[i] = presettled == 0              ? s.hit[i]
                     : s.verdict[i] == kOpen      ? s.hit[s.reduced_at[i]]
                     : s.verdict[i] == kHit       ? 1
                                                  : 0;
        return out;
    };
    if (presettled == 2) {  // (answer() reads no hit[]: every item has its verdict)
        s.guard.last_spared = 0;
        return answer();
    }
    if (presettled == 1) items = s.reduced;
    if (presettled == 0) s.tested.assign(items.size(), 1);
    // The call's shape for the items-alone pre-pass's history (PayGuard). Not with the settling
    // pre-pass, which settles what it would spare.
    const PayGuard::Call call = presettled == 0 ? whole : PayGuard::call_of(items);
    // One-tile targets with enough triangles for every thread: the split pass, front end included.
    const std::uint64_t submitted = call.triangles;
    bool use_alone = false;
    if (presettled == 0)
        use_alone = s.guard.wanted(call);
    else
        s.guard.last_spared = 0;
    if (one_tile && threads > 1 && submitted >= kSplitMinTriangles * static_cast<std::uint64_t>(threads)) {
        // A few runs per thread, so that runs of small and of large triangles even out between them.
        const std::size_t parts = static_cast<std::size_t>(std::min<std::uint64_t>(
            static_cast<std::uint64_t>(threads) * kSplitRunsPerThread, submitted / kSplitMinTriangles * kSplitRunsPerThread / 2));
        const int split =
            s.split_pass(items, one_side, width, height, format, threads, std::max<std::size_t>(parts, 2), use_alone);
        if (split == 0) return validate(all_items);
        if (use_alone) s.alone_record(items, call);
        if (split == 1) return answer();
        // split == 2: large triangles, set up; the settled path below.
    } else if (!s.front_end(width, height, format, items, threads, use_alone)) {
        return validate(all_items);
    } else if (use_alone) {
        s.alone_record(items, call);
    }

    std::uint64_t area = 0, count = 0;  // of the triangles' pixel boxes
    for (std::size_t i = 0; i < items.size(); ++i) {
        area += s.area[i];
        count += s.tris[i].size();
    }
    const bool settle = count > 0 && area >= kSettleMinArea * count;
    if (settle) s.depth_bounds(format, items.size());
    const int side = settle ? kSettleTile : tile_side(width, height);
    const TileGrid grid{side, (width + side - 1) / side, (height + side - 1) / side};
    s.bin(items, grid, settle);
    const std::size_t pixels = grid.count() * grid.pixels();
    if (s.min1.size() < pixels) {
        s.min1.resize(pixels);
        s.obj1.resize(pixels);
        s.min2.resize(pixels);
    }
    s.hit.assign(items.size(), 0);
    detail::parallel_for(threads, grid.count(),
                         [&](std::size_t tile) { s.shade(items, grid, width, height, format, tile, settle); });

    return answer();
}

}  // namespace raster

namespace raster {
namespace {

// One item's fragments at one pixel: the smallest zmin (what its write stores) and the largest zmax
// (what its query tests), encoded as the fused pass encodes them.
struct PixelRecord {
    std::uint32_t pixel;
    std::uint32_t zmin;
    std::uint32_t zmax;
};

}  // namespace

struct WindowedPasses::State {
    // Per chunk of triangles (equal counts of the used items' triangles, in item order: the input
    // decides the cut, so the records do not depend on the thread count). An item whose triangles
    // span several chunks has one segment in each: its records are their union (a pixel may appear
    // in two segments, which changes neither the minimum written nor the query's answer).
    struct Segment {
        std::uint32_t item, begin, end;  // records[begin, end) of the chunk
    };
    struct Chunk {
        std::vector<PixelRecord> records;
        std::vector<Segment> segments;     // in item order
        std::vector<std::uint32_t> stamp;  // per pixel: 1 + the item whose record is in `slot`
        std::vector<std::uint32_t> slot;   // per pixel: that record's index in `records`
        std::vector<detail::BoundsTri> tris;
        std::vector<detail::BoundsVertex> pool;
    };
    std::vector<Chunk> chunks;
    struct Span {
        const PixelRecord* begin;
        const PixelRecord* end;
    };
    std::vector<Span> spans;                 // every item's segments, in item order
    std::vector<std::uint32_t> first_span;   // per item, its first span; then spans.size()
    std::vector<std::uint64_t> tri_before;   // per item: the used items' triangles before it; then the total
    std::vector<std::uint8_t> bad;           // per item: an input check failed
    std::vector<std::uint8_t> used;          // per item: WindowedItem::used
    std::vector<std::uint32_t> near_lo, near_hi;
    mutable std::vector<std::uint32_t> depth;  // run()'s stored depth per pixel
    std::uint32_t clear = 0;
    std::size_t pixels = 0;
    bool ready = false;
};

WindowedPasses::WindowedPasses() : s_(std::make_unique<State>()) {}
WindowedPasses::~WindowedPasses() = default;

Result<std::size_t> WindowedPasses::prepare(int width, int height, DepthFormat format,
                                            std::span<const WindowedItem> items, int threads) {
    State& s = *s_;
    s.ready = false;
    if (width < 1 || height < 1 || static_cast<std::int64_t>(width) * height > kMaxWindowedPixels)
        return Error{"windowed passes: target " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(kMaxWindowedPixels) + " pixels"};
    if (std::optional<Error> e = check_format_threads("windowed passes", format, threads)) return *e;
    if (items.size() >= kNoObject) return Error{"windowed passes: too many items (limit 2^32 - 2)"};
    const std::size_t n = items.size();
    for (std::size_t i = 0; i < n; ++i) {
        const WindowedItem& it = items[i];
        if (it.mesh.indices.size() % 3 != 0)
            return Error{"windowed passes: item " + std::to_string(i) + ": index count " +
                         std::to_string(it.mesh.indices.size()) + " is not a multiple of 3"};
        if (it.near_lo > it.near_hi || it.near_hi >= n ||
            (i > 0 && (it.near_lo < items[i - 1].near_lo || it.near_hi < items[i - 1].near_hi)))
            return Error{"windowed passes: item " + std::to_string(i) + ": window [" + std::to_string(it.near_lo) +
                         ", " + std::to_string(it.near_hi) +
                         "] is not inside the item list or not after the previous item's"};
    }
    threads = detail::effective_threads(threads);
    s.pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    s.clear = DepthTarget::encode_clear(1.0, format);
    s.bad.assign(n, 0);
    s.near_lo.resize(n);
    s.near_hi.resize(n);
    s.used.resize(n);
    s.tri_before.resize(n + 1);
    std::uint64_t triangles = 0;
    for (std::size_t i = 0; i < n; ++i) {
        s.near_lo[i] = items[i].near_lo;
        s.near_hi[i] = items[i].near_hi;
        s.used[i] = items[i].used ? 1 : 0;
        s.tri_before[i] = triangles;
        if (items[i].used) triangles += items[i].mesh.indices.size() / 3;
    }
    s.tri_before[n] = triangles;
    // Up to 32 chunks per thread, none under kChunkMinTriangles triangles, and their stamp and slot
    // arrays (kept between calls) within kChunkPixels entries unless that leaves fewer than 4 chunks
    // per thread. Ours: chunks of equal triangle counts differ in the pixels they cover, and 4 per
    // thread were too few to even that out (leaves / qcullide, 2 threads: 21.1-22.5 -> 18.7-18.9 ms).
    constexpr std::uint64_t kChunkMinTriangles = 256;
    constexpr std::uint64_t kChunkPixels = std::uint64_t{1} << 21;  // 16 MB of stamps and slots
    const auto threads64 = static_cast<std::uint64_t>(threads);
    const std::uint64_t by_memory = std::max<std::uint64_t>(threads64 * 4, kChunkPixels / s.pixels);
    const std::uint64_t n_chunks64 = std::max<std::uint64_t>(
        1, std::min({threads64 * 32, triangles / kChunkMinTriangles, by_memory}));
    const auto n_chunks = static_cast<std::size_t>(n_chunks64);
    if (s.chunks.size() < n_chunks) s.chunks.resize(n_chunks);
    const detail::FrontEndParams params = front_end_params(width, height);
    // Whether triangles [a, b) of m pass the input checks (indices in range, valid vertices).
    const auto valid_triangles = [](const MeshViewD& m, std::uint64_t a, std::uint64_t b) {
        const std::size_t nv = m.vertices.size();
        for (std::uint64_t tri = a; tri < b; ++tri) {
            const std::size_t k = static_cast<std::size_t>(tri) * 3;
            const std::uint32_t ia = m.indices[k], ib = m.indices[k + 1], ic = m.indices[k + 2];
            if (ia >= nv || ib >= nv || ic >= nv || !valid_vertex(m.vertices[ia]) || !valid_vertex(m.vertices[ib]) ||
                !valid_vertex(m.vertices[ic]))
                return false;
        }
        return true;
    };
    // Folds triangle t's pixels into the chunk's records of item `tag` (the smallest zmin and the
    // largest zmax per pixel).
    const auto record_pixels = [&](State::Chunk& ch, const detail::BoundsTri& t, std::uint32_t tag)
        __attribute__((always_inline)) {
        const double mz = t.margin_z;
        double last_lo = std::numeric_limits<double>::quiet_NaN(), last_hi = last_lo;
        std::uint32_t zmin = 0, zmax = 0;  // quantized once per distinct depth
        detail::bounds_pixels(t, ch.pool.data(), detail::PixelRect{t.x0, t.y0, t.x1, t.y1},
                              [&](int px, int py, double zlo, double zhi) {
                                  if (!(zlo == last_lo)) {
                                      last_lo = zlo;
                                      zmin = detail::quantize_down(zlo - mz, format);
                                  }
                                  if (!(zhi == last_hi)) {
                                      last_hi = zhi;
                                      zmax = detail::quantize_up(zhi + mz, format);
                                  }
                                  const auto p = static_cast<std::uint32_t>(py * width + px);
                                  if (ch.stamp[p] != tag) {
                                      ch.stamp[p] = tag;
                                      ch.slot[p] = static_cast<std::uint32_t>(ch.records.size());
                                      ch.records.push_back({p, zmin, zmax});
                                  } else {
                                      PixelRecord& r = ch.records[ch.slot[p]];
                                      r.zmin = std::min(r.zmin, zmin);
                                      r.zmax = std::max(r.zmax, zmax);
                                  }
                              });
    };
    detail::parallel_for(threads, n_chunks, [&](std::size_t c) {
        State::Chunk& ch = s.chunks[c];
        ch.records.clear();
        ch.segments.clear();
        if (ch.stamp.size() < s.pixels) {
            ch.stamp.resize(s.pixels);
            ch.slot.resize(s.pixels);
        }
        std::fill(ch.stamp.begin(), ch.stamp.begin() + static_cast<std::ptrdiff_t>(s.pixels), 0u);
        // This chunk's triangles: [t0, t1) of the used items' triangles in item order.
        const std::uint64_t t0 = triangles * c / n_chunks64, t1 = triangles * (c + 1) / n_chunks64;
        if (t0 == t1) return;
        // The item holding triangle t0: the last item with tri_before <= t0 that has a triangle there.
        std::size_t i = static_cast<std::size_t>(
            std::upper_bound(s.tri_before.begin(), s.tri_before.begin() + static_cast<std::ptrdiff_t>(n), t0) -
            s.tri_before.begin() - 1);
        for (; i < n && s.tri_before[i] < t1; ++i) {
            if (!items[i].used) continue;
            const MeshViewD& m = items[i].mesh;
            const std::uint64_t item_tris = m.indices.size() / 3;
            const std::uint64_t k0 = std::max(t0, s.tri_before[i]) - s.tri_before[i];
            const std::uint64_t k1 = std::min(t1, s.tri_before[i] + item_tris) - s.tri_before[i];
            if (k0 >= k1) continue;
            const auto begin = static_cast<std::uint32_t>(ch.records.size());
            const auto tag = static_cast<std::uint32_t>(i + 1);
            // Runs of up to kSetupRun triangles: checked, set up together (setup_bounds_range: four
            // at a time with AVX2), then drawn in order, one record per triangle that has a pixel.
            constexpr std::uint64_t kSetupRun = 64;
            for (std::uint64_t run = k0; run < k1; run += kSetupRun) {
                const std::uint64_t run_end = std::min(k1, run + kSetupRun);
                if (!valid_triangles(m, run, run_end)) {
                    s.bad[i] = 1;  // (only ever set to 1: chunks sharing an item agree)
                    break;
                }
                ch.tris.clear();
                ch.pool.clear();
                detail::setup_bounds_range(params, m.vertices,
                                           m.indices.subspan(static_cast<std::size_t>(run) * 3,
                                                             static_cast<std::size_t>(run_end - run) * 3),
                                           static_cast<std::uint32_t>(i), ch.tris, ch.pool);
                for (const detail::BoundsTri& t : ch.tris) record_pixels(ch, t, tag);
            }
            ch.segments.push_back({static_cast<std::uint32_t>(i), begin, static_cast<std::uint32_t>(ch.records.size())});
        }
    });
    for (std::size_t i = 0; i < n; ++i) {
        if (!s.bad[i]) continue;
        return validate("windowed passes", n, [&](std::size_t j) -> const MeshViewD& { return items[j].mesh; });
    }
    // Every item's spans, in item order (the chunks' segments are in item order, chunk after chunk).
    s.spans.clear();
    s.first_span.assign(n + 1, 0);
    std::size_t records = 0;
    for (std::size_t c = 0; c < n_chunks; ++c) {
        const State::Chunk& ch = s.chunks[c];
        records += ch.records.size();
        for (const State::Segment& g : ch.segments) {
            s.spans.push_back({ch.records.data() + g.begin, ch.records.data() + g.end});
            ++s.first_span[g.item + 1];
        }
    }
    for (std::size_t i = 0; i < n; ++i) s.first_span[i + 1] += s.first_span[i];
    s.ready = true;
    return records;
}

Result<std::vector<std::uint8_t>> WindowedPasses::run(bool forward, std::span<const std::uint8_t> query,
                                                      std::span<const std::uint8_t> write) const {
    const State& s = *s_;
    if (!s.ready) return Error{"windowed passes: run without a successful prepare"};
    const std::size_t n = s.used.size();
    if (query.size() != n || write.size() != n)
        return Error{"windowed passes: masks of " + std::to_string(query.size()) + " and " +
                     std::to_string(write.size()) + " entries for " + std::to_string(n) + " items"};
    for (std::size_t i = 0; i < n; ++i)
        if (!s.used[i] && (query[i] != 0 || write[i] != 0))
            return Error{"windowed passes: item " + std::to_string(i) + " was prepared as unused"};
    std::vector<std::uint8_t> passed(n, 0);
    s.depth.assign(s.pixels, s.clear);
    std::uint32_t* depth = s.depth.data();
    const auto write_item = [&](std::size_t d) {
        if (write[d] == 0) return;
        for (std::uint32_t g = s.first_span[d]; g < s.first_span[d + 1]; ++g)
            for (const PixelRecord* r = s.spans[g].begin; r != s.spans[g].end; ++r)
                depth[r->pixel] = std::min(depth[r->pixel], r->zmin);
    };
    const auto query_item = [&](std::size_t k) {
        if (query[k] == 0) return;
        for (std::uint32_t g = s.first_span[k]; g < s.first_span[k + 1]; ++g) {
            for (const PixelRecord* r = s.spans[g].begin; r != s.spans[g].end; ++r) {
                if (r->zmax >= depth[r->pixel]) {  // the GEQUAL query passes here
                    passed[k] = 1;
                    return;
                }
            }
        }
    };
    if (forward) {
        std::size_t d = 0;  // items written so far
        for (std::size_t k = 0; k < n; ++k) {
            for (; d < n && s.near_hi[d] < k; ++d) write_item(d);
            query_item(k);
        }
    } else {
        std::size_t d = n;  // items n-1 .. d written so far
        for (std::size_t k = n; k-- > 0;) {
            for (; d > 0 && s.near_lo[d - 1] > k; --d) write_item(d - 1);
            query_item(k);
        }
    }
    return passed;
}

}  // namespace raster
