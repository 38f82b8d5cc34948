// quick_cullide.cpp: Quick-CULLIDE (see cullide/quick_cullide.h, docs/quick-cullide.md).
#include "cullide/quick_cullide.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "cullide_detail.h"
#include "exact_stage.h"
#include "parallel.h"
#include "raster/command_batch.h"
#include "raster/depth_target.h"
#include "raster/transform.h"

namespace cullide {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

constexpr std::uint8_t kFFV = 1;  // apart from every earlier item that is not near
constexpr std::uint8_t kSFV = 2;  // apart from every later item that is not near
constexpr std::uint8_t kBFV = kFFV | kSFV;

// Box corners: x from bit 0, y from bit 1, z from bit 2 (as cullide.cpp; no face culling).
constexpr std::array<std::uint32_t, 36> kBoxIndices = {0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4,
                                                       2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6};

// One object's geometry for a stage: triangles in the stage's order (`order[p]` is the mesh
// triangle at position p; for a box, the 12 box triangles and an empty order).
struct Geom {
    std::uint32_t object = 0;  // index into `objects`
    std::vector<raster::Double3> positions;
    std::vector<std::uint32_t> indices;  // three per position
    std::vector<std::uint32_t> order;
    std::vector<Aabb> tri_box;           // per position (exact stage)
    std::vector<std::uint32_t> weld;     // welded vertex ids (self only)
    std::vector<raster::Float4> clip;
    std::vector<raster::Double4> clip_d;
};

// One item: positions [first, first + count) of its geometry. near_lo..near_hi (global item
// positions, inclusive) are the items it is never tested against by the visibility passes.
struct Item {
    std::uint32_t geom = 0;
    std::uint32_t first = 0, count = 0;
    Aabb box;
    std::uint8_t tag = 0;
    std::uint32_t near_lo = 0, near_hi = 0;
    std::uint32_t query = 0;
};

Result<ViewSize> check_inputs(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                              const QuickOptions& o, bool scene_checked) {
    if (o.mode == VisibilityMode::Offset)
        return Error{"Quick-CULLIDE runs in GL-exact or exact-bounds mode, not with offset solids"};
    return detail::check_visibility_inputs(objects, active, o, o.mode, scene_checked);
}

std::uint64_t count_live(const std::vector<Item>& items) {
    return static_cast<std::uint64_t>(
        std::count_if(items.begin(), items.end(), [](const Item& it) { return it.tag != kBFV; }));
}

std::uint64_t record_draw(raster::CommandBatch& batch, const Geom& g, const Item& it, VisibilityMode mode, bool query) {
    raster::DrawState state;
    state.depth_func = query ? raster::DepthFunc::GEqual : raster::DepthFunc::LEqual;
    state.depth_write = !query;
    const auto idx = std::span<const std::uint32_t>(g.indices).subspan(std::size_t{it.first} * 3, std::size_t{it.count} * 3);
    if (mode == VisibilityMode::ExactBounds) {
        state.mode = raster::RasterMode::ExactBounds;
        batch.draw(raster::MeshViewD{g.clip_d, idx}, state);
    } else {
        batch.draw(raster::MeshView{g.clip, idx}, state);
    }
    return it.count;
}

Status run_device(QueryDevice& device, const raster::CommandBatch& batch, ViewSize size, raster::DepthFormat format,
                  raster::QueryResults& out) {
    // On a cleared target: execute_cleared, so that the emulator restores each written tile in
    // that tile's own task (ExecuteOptions::clear_depth) instead of a clear pass before it.
    const raster::CommandBatch* const one[1] = {&batch};
    Result<std::vector<raster::QueryResults>> r = device.execute_cleared(size.width(), size.height(), format, one);
    if (!r) return r.error();
    if (r.value().size() != 1)
        return Error{"device returned " + std::to_string(r.value().size()) + " result lists for 1 batch"};
    if (r.value()[0].size() != batch.query_kinds().size())
        return Error{"device returned " + std::to_string(r.value()[0].size()) + " query results for " +
                     std::to_string(batch.query_kinds().size()) + " queries"};
    out = std::move(r.value()[0]);
    return Status{};
}

// This view's clip coordinates of every geometry with a live item, one geometry per parallel job
// (each writes only its own; the first failure in geometry order is reported).
Status transform_geoms(std::vector<Geom>& geoms, const std::vector<char>& geom_live, const raster::OrthoView& view,
                       VisibilityMode mode, raster::RasterRules rules, int threads) {
    std::vector<std::size_t> live;
    for (std::size_t gi = 0; gi < geoms.size(); ++gi)
        if (geom_live[gi]) live.push_back(gi);
    // Parts of detail::kTransformPart positions per parallel job, each writing only its own part
    // of its geometry's clip arrays (one job per geometry left the second thread idle on
    // one-object scenes such as the cloth).
    struct Part {
        std::size_t gi, b, e;
    };
    std::vector<Part> parts;
    for (const std::size_t gi : live) {
        Geom& g = geoms[gi];
        const std::size_t n = g.positions.size();
        g.clip_d.resize(n);
        if (mode != VisibilityMode::ExactBounds) g.clip.resize(n);
        for (std::size_t b = 0; b < n; b += detail::kTransformPart)
            parts.push_back({gi, b, std::min(n, b + detail::kTransformPart)});
    }
    std::vector<char> ok(parts.size(), 0);
    detail::parallel_chunks(threads, parts.size(), [&](std::size_t j) {
        Geom& g = geoms[parts[j].gi];
        const std::size_t b = parts[j].b, len = parts[j].e - parts[j].b;
        const std::span<raster::Float4> clip = mode != VisibilityMode::ExactBounds
                                                   ? std::span<raster::Float4>(g.clip).subspan(b, len)
                                                   : std::span<raster::Float4>();
        ok[j] = detail::transform_to_clip(view, std::span<const raster::Double3>(g.positions).subspan(b, len),
                                          std::span<raster::Double4>(g.clip_d).subspan(b, len), clip, rules)
                    ? 1 : 0;
    });
    for (std::size_t j = 0; j < parts.size(); ++j) {
        if (ok[j]) continue;
        // The first failure in geometry order, named as the whole geometry's transform names it.
        raster::Result<std::size_t> c = raster::ortho_view_to_clip(view, geoms[parts[j].gi].positions, geoms[parts[j].gi].clip_d);
        if (c) return Error{"view transform: a part of a geometry failed but the whole geometry passed"};
        return Error{"view transform: " + c.error().message};
    }
    return Status{};
}

// One pass of a view: forward (pass 1) queries items that are not FFV and draws those that are not
// SFV, item j right after the query of item near_hi[j]; backward (pass 2) the mirror image, with
// near_lo (detail::quick_pass_schedule). Items whose query passes no sample gain the pass's tag;
// returns how many did.
Result<std::uint64_t> run_pass(const std::vector<Geom>& geoms, std::vector<Item>& items, bool forward,
                               const QuickOptions& o, ViewSize size, QueryDevice& device, ViewStats& vs) {
    const std::uint8_t proven = forward ? kFFV : kSFV;  // what this pass proves
    const std::uint8_t other = forward ? kSFV : kFFV;   // items with this tag are not drawn
    thread_local raster::CommandBatch batch(1, 1);  // memory kept from pass to pass (cullide.cpp's recorded_view)
    batch.reset(size.width(), size.height(), o.gpu_rules);
    detail::quick_pass_schedule(
        items.size(), forward, [&](std::size_t k) { return items[k].near_lo; },
        [&](std::size_t k) { return items[k].near_hi; },
        [&](std::size_t k) {
            Item& it = items[k];
            if (it.tag & proven) return;
            it.query = batch.begin_query(raster::QueryKind::AnySamplesPassed);
            vs.triangles_rasterized += record_draw(batch, geoms[it.geom], it, o.mode, true);
            batch.end_query();
            ++vs.queries;
        },
        [&](std::size_t d) {
            if (!(items[d].tag & other)) vs.triangles_rasterized += record_draw(batch, geoms[items[d].geom], items[d], o.mode, false);
        });
    raster::QueryResults res;
    if (Status s = run_device(device, batch, size, o.depth_format, res); !s) return s.error();
    std::uint64_t changed = 0;
    for (Item& it : items) {
        if (!(it.tag & proven) && res[it.query] == 0) {
            it.tag |= proven;
            ++changed;
        }
    }
    return changed;
}

// What one recorded pass (run_pass) would submit of item `it` (of n) with tag `tag`, the native
// view reporting what it replaces: its query (0 or 1) and its draws (the query's and the write's),
// in closed form: detail::quick_pass_schedule queries every item once and, the windows being
// non-decreasing (the device checked them), writes exactly the items whose window ends before the
// pass's last query: near_hi <= n - 2 forward, near_lo >= 1 backward
// (tests/cullide/quick_cullide_test.cpp compares every view's counts with the recorded passes',
// which run the schedule).
struct PassCounts {
    std::uint64_t queries = 0, draws = 0;
};
PassCounts pass_counts(const Item& it, std::uint8_t tag, bool forward, std::size_t n) {
    const std::uint8_t proven = forward ? kFFV : kSFV;
    const std::uint8_t other = forward ? kSFV : kFFV;
    const bool queried = !(tag & proven);
    const bool written = !(tag & other) && (forward ? std::size_t{it.near_hi} + 2 <= n : it.near_lo >= 1);
    return {queried ? 1u : 0u, (queried ? 1u : 0u) + (written ? 1u : 0u)};
}

// Both passes of one exact-bounds view as the device's quick_view (query_device.h: natively on the
// emulator, raster::WindowedPasses); returns the tags gained. `live` lists the items that are not
// BFV, in item order: only they go to the device, their windows mapped onto the shorter list. A BFV
// item is neither queried nor drawn by either pass, so the live items' queries and draws keep their
// order: live item d's draw, after the query of item near_hi forward, comes after the query of the
// last live item at or before near_hi and before the next live one's (backward the mirror image with
// near_lo). Ours: in later views most items are BFV (tori: 6,200 of 30,000 live after ten views), and
// every per-item loop of the view (these, the device's, WindowedPasses' serial passes) ran over all.
Result<std::uint64_t> native_view(const std::vector<Geom>& geoms, std::vector<Item>& items,
                                  const std::vector<std::uint32_t>& live, const QuickOptions& o, ViewSize size,
                                  QueryDevice& device, ViewStats& vs) {
    static_assert(kFFV == QueryDevice::kQuickFFV && kSFV == QueryDevice::kQuickSFV);
    const std::size_t m = live.size();
    std::vector<raster::WindowedItem> wi(m);
    std::vector<std::uint8_t> tags(m);
    std::size_t lo = 0, hi = 0;  // the first live position at or after near_lo, after near_hi
    for (std::size_t j = 0; j < m; ++j) {
        const Item& it = items[live[j]];
        const Geom& g = geoms[it.geom];
        while (lo < m && live[lo] < it.near_lo) ++lo;  // (windows are non-decreasing over the items)
        while (hi < m && live[hi] <= it.near_hi) ++hi;
        // lo <= j < hi: an item's window holds the item.
        wi[j] = {raster::MeshViewD{g.clip_d, std::span<const std::uint32_t>(g.indices)
                                                 .subspan(std::size_t{it.first} * 3, std::size_t{it.count} * 3)},
                 static_cast<std::uint32_t>(lo), static_cast<std::uint32_t>(hi - 1), true};
        tags[j] = it.tag;
    }
    Result<std::vector<std::uint8_t>> r = device.quick_view(size, o.depth_format, wi, tags);
    if (!r) return r.error();
    if (r.value().size() != m)
        return Error{"device returned " + std::to_string(r.value().size()) + " tags for " + std::to_string(m) + " items"};
    // One pass over the live items (a BFV item gains nothing, and pass_counts gives it no query and
    // no draw): the tags gained, the new tags, the items left live, and both passes' counts
    // (pass_counts, with the full list's windows and size; the backward pass with the tags the
    // forward pass left).
    std::uint64_t changed = 0, queries = 0, triangles = 0, still_live = 0;
    const std::size_t n = items.size();
    for (std::size_t j = 0; j < m; ++j) {
        Item& it = items[live[j]];
        const std::uint8_t before = tags[j], now = r.value()[j];
        const auto after_forward = static_cast<std::uint8_t>(before | (now & kFFV));
        const PassCounts f = pass_counts(it, before, true, n), b = pass_counts(it, after_forward, false, n);
        queries += f.queries + b.queries;
        triangles += (f.draws + b.draws) * it.count;
        changed += static_cast<std::uint64_t>(((now & kFFV) && !(before & kFFV)) + ((now & kSFV) && !(before & kSFV)));
        it.tag = now;
        still_live += now != kBFV ? 1 : 0;
    }
    vs.queries += queries;
    vs.triangles_rasterized += triangles;
    vs.items_after = still_live;
    return changed;
}

// Views until three views in a row are quiet (gain at most 1/64 of the live items' count in tags)
// or 3 * max_rounds ran.
Status run_stage(std::vector<Geom>& geoms, std::vector<Item>& items, CullStage stage, const QuickOptions& o,
                 ViewSize size, QueryDevice& device, QuickStats& st) {
    if (o.skip_visibility) return Status{};
    int quiet = 0;
    int first_axis = -1;  // the thinnest axis of the stage's first live bounds (see below)
    std::vector<std::uint32_t> live_items;  // the items that are not BFV, in order (shrinks view by view)
    for (std::size_t i = 0; i < items.size(); ++i)
        if (items[i].tag != kBFV) live_items.push_back(static_cast<std::uint32_t>(i));
    for (int view = 0; view < 3 * o.max_rounds && quiet < 3; ++view) {
        Aabb bounds;
        std::vector<char> geom_live(geoms.size(), 0);
        const std::uint64_t live = live_items.size();
        for (const std::uint32_t i : live_items) {
            bounds = detail::unite(bounds, items[i].box);
            geom_live[items[i].geom] = 1;
        }
        if (live == 0) return Status{};
        // Views start along the axis of least extent (ours: a sheet seen face-on is proven apart in
        // one view, where CULLIDE's fixed x, y, z cycle may spend two edge-on views first), then cycle.
        if (first_axis < 0) {
            first_axis = 0;
            for (int k = 1; k < 3; ++k)
                if (bounds.hi[k] - bounds.lo[k] < bounds.hi[first_axis] - bounds.lo[first_axis]) first_axis = k;
        }
        const int axis = (first_axis + view) % 3;
        Result<raster::OrthoView> v = detail::make_view(axis, bounds, 0.0, size, o.depth_format);
        if (!v) return v.error();
        if (Status s = transform_geoms(geoms, geom_live, v.value(), o.mode, o.gpu_rules, o.threads); !s) return s;
        ViewStats vs;
        vs.stage = stage;
        vs.axis = axis;
        vs.items_before = live;
        std::uint64_t changed = 0;  // tags gained in this view
        if (o.mode == VisibilityMode::ExactBounds && o.fused_visibility) {
            Result<std::uint64_t> gained = native_view(geoms, items, live_items, o, size, device, vs);  // sets items_after
            if (!gained) return gained.error();
            changed = gained.value();
        } else {
            for (const bool forward : {true, false}) {
                Result<std::uint64_t> gained = run_pass(geoms, items, forward, o, size, device, vs);
                if (!gained) return gained.error();
                changed += gained.value();
            }
            vs.items_after = count_live(items);
        }
        st.queries += vs.queries;
        st.triangles_rasterized += vs.triangles_rasterized;
        st.views.push_back(vs);
        // A view is quiet when it proved (nearly) nothing: fewer new tags than 1/64 of the live
        // items (ours: touching pieces that can never be proven apart otherwise keep every view
        // busy for a handful of tags; what is left goes to the exact stage, which decides).
        quiet = changed > live / 64 ? 0 : quiet + 1;
        std::erase_if(live_items, [&](std::uint32_t i) { return items[i].tag == kBFV; });
    }
    return Status{};
}

// Welded-vertex -> triangles (CSR), triangles listed in increasing id.
struct VertexTriangles {
    std::vector<std::uint32_t> start, tris;
};

VertexTriangles vertex_triangles(const Mesh& m, const std::vector<std::uint32_t>& weld) {
    std::uint32_t nv = 0;
    for (std::uint32_t w : weld) nv = std::max(nv, w + 1);
    VertexTriangles vt;
    vt.start.assign(std::size_t{nv} + 1, 0);
    for (const Tri& t : m.triangles)
        for (std::uint32_t v : t) ++vt.start[weld[v] + 1];
    for (std::size_t i = 0; i < nv; ++i) vt.start[i + 1] += vt.start[i];
    vt.tris.resize(vt.start[nv]);
    std::vector<std::uint32_t> fill(vt.start.begin(), vt.start.end() - 1);
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (std::uint32_t v : m.triangles[t]) vt.tris[fill[weld[v]]++] = static_cast<std::uint32_t>(t);
    return vt;
}

// Breadth-first order over vertex-sharing triangles (Cuthill-McKee without the degree sort),
// components started from `seeds` in turn; `last` receives each component's last triangle.
std::vector<std::uint32_t> bfs_order(const Mesh& m, const std::vector<std::uint32_t>& weld, const VertexTriangles& vt,
                                     const std::vector<std::uint32_t>& seeds, std::vector<std::uint32_t>* last) {
    const std::size_t nt = m.triangles.size();
    std::vector<char> seen(nt, 0);
    std::vector<std::uint32_t> order;
    order.reserve(nt);
    auto grow = [&](std::uint32_t s) {
        if (seen[s]) return;
        seen[s] = 1;
        std::size_t head = order.size();
        order.push_back(s);
        for (; head < order.size(); ++head) {
            for (std::uint32_t v : m.triangles[order[head]]) {
                const std::uint32_t w = weld[v];
                for (std::uint32_t k = vt.start[w]; k < vt.start[w + 1]; ++k) {
                    const std::uint32_t u = vt.tris[k];
                    if (!seen[u]) {
                        seen[u] = 1;
                        order.push_back(u);
                    }
                }
            }
        }
        if (last != nullptr) last->push_back(order.back());
    };
    for (std::uint32_t s : seeds) grow(s);
    for (std::size_t t = 0; t < nt; ++t) grow(static_cast<std::uint32_t>(t));
    return order;
}

// The window of a triangle order grouped `group` per item: the largest item distance between
// two triangles sharing a welded vertex.
std::uint32_t window_of(const std::vector<std::uint32_t>& order, std::size_t group, const VertexTriangles& vt) {
    std::vector<std::uint32_t> item_of(order.size());
    for (std::size_t p = 0; p < order.size(); ++p) item_of[order[p]] = static_cast<std::uint32_t>(p / group);
    std::uint32_t w = 0;
    for (std::size_t v = 0; v + 1 < vt.start.size(); ++v) {
        std::uint32_t lo = UINT32_MAX, hi = 0;
        for (std::uint32_t k = vt.start[v]; k < vt.start[v + 1]; ++k) {
            lo = std::min(lo, item_of[vt.tris[k]]);
            hi = std::max(hi, item_of[vt.tris[k]]);
        }
        if (lo <= hi) w = std::max(w, hi - lo);
    }
    return w;
}

// The mesh geometry of `object` with its triangles in `order`.
Geom make_mesh_geom(const Mesh& m, std::uint32_t object, std::vector<std::uint32_t> order) {
    Geom g;
    g.object = object;
    g.positions.resize(m.positions.size());
    for (std::size_t i = 0; i < m.positions.size(); ++i) g.positions[i] = {m.positions[i].x, m.positions[i].y, m.positions[i].z};
    g.order = std::move(order);
    g.indices.reserve(g.order.size() * 3);
    g.tri_box.reserve(g.order.size());
    for (std::uint32_t t : g.order) {
        g.indices.insert(g.indices.end(), m.triangles[t].begin(), m.triangles[t].end());
        g.tri_box.push_back(triangle_bounds(m, t));
    }
    return g;
}

// Splits every geometry with a live parent into items of `group` positions, inheriting the
// parent's tag; parents are consecutive runs of `parents` per geometry. Non-self near range: the
// object's items.
// The parents' items are counted first and made in parallel parts of about kSplitPart parents, each
// writing its own run of the list (perf: 4.6% of a 2-thread bunny-dragon frame's calling thread,
// splitting 42,000 sub-objects into single triangles).
std::vector<Item> split_items(const std::vector<Geom>& geoms, const std::vector<Item>& parents, std::size_t group,
                              int threads) {
    std::vector<std::size_t> at(parents.size() + 1, 0);
    for (std::size_t i = 0; i < parents.size(); ++i)
        at[i + 1] = at[i] + (parents[i].tag == kBFV ? 0 : (parents[i].count + group - 1) / group);
    std::vector<Item> items(at.back());
    constexpr std::size_t kSplitPart = 2048;
    detail::parallel_chunks(threads, (parents.size() + kSplitPart - 1) / kSplitPart, [&](std::size_t part) {
        for (std::size_t i = part * kSplitPart; i < std::min(parents.size(), (part + 1) * kSplitPart); ++i) {
            const Item& p = parents[i];
            if (p.tag == kBFV) continue;
            std::size_t out = at[i];
            for (std::uint32_t f = p.first; f < p.first + p.count; f += static_cast<std::uint32_t>(group)) {
                Item& it = items[out++];
                it.geom = p.geom;
                it.first = f;
                it.count = std::min<std::uint32_t>(static_cast<std::uint32_t>(group), p.first + p.count - f);
                for (std::uint32_t q = f; q < f + it.count; ++q) it.box = detail::unite(it.box, geoms[p.geom].tri_box[q]);
                it.tag = p.tag;
            }
        }
    });
    return items;
}

// near range = all items of the same geometry (no self-collision).
void set_object_near(std::vector<Item>& items) {
    std::size_t s = 0;
    while (s < items.size()) {
        std::size_t e = s;
        while (e < items.size() && items[e].geom == items[s].geom) ++e;
        for (std::size_t k = s; k < e; ++k) {
            items[k].near_lo = static_cast<std::uint32_t>(s);
            items[k].near_hi = static_cast<std::uint32_t>(e - 1);
        }
        s = e;
    }
}

bool near(const Item& a, std::size_t b) { return b >= a.near_lo && b <= a.near_hi; }

using ItemPair = std::pair<std::uint32_t, std::uint32_t>;

// The items' boxes for the sweep and prune (exact_stage.h), BFV items only when `with_bfv`.
std::vector<detail::SweepRef> item_refs(const std::vector<Item>& items, bool with_bfv) {
    std::vector<detail::SweepRef> refs;
    for (std::size_t i = 0; i < items.size(); ++i)
        if (with_bfv || items[i].tag != kBFV)
            refs.push_back({items[i].box, items[i].geom, static_cast<std::uint32_t>(i), detail::kWholeSet});
    return refs;
}

// Item pairs (a < b) whose boxes overlap, BFV items included. Sorted.
std::vector<ItemPair> box_pairs(const std::vector<Item>& items, int threads) {
    return detail::overlapping_sets(item_refs(items, true), threads);
}

// Self-collision box classification (ours, before the visibility passes): an item whose box meets
// no earlier non-near item's box is FFV, none later: SFV. Geometric facts, like the passes' tags.
void box_tags(std::vector<Item>& items, const std::vector<ItemPair>& overlapping) {
    std::vector<std::uint8_t> open(items.size(), 0);  // the tag bits that are NOT proven
    for (const auto& [a, b] : overlapping) {
        if (near(items[a], b)) continue;
        open[a] |= kSFV;
        open[b] |= kFFV;
    }
    for (std::size_t i = 0; i < items.size(); ++i) items[i].tag |= static_cast<std::uint8_t>(kBFV & ~open[i]);
}

// The overlapping item pairs filtered by the tags, then triangle pairs by box, adjacency, and the
// exact test.
std::vector<TrianglePair> exact_stage(std::span<const Mesh> objects, const std::vector<Geom>& geoms,
                                      const std::vector<Item>& items, const std::vector<ItemPair>& overlapping,
                                      const QuickOptions& o, QuickStats& st) {
    using Pair = detail::CandidatePair;
    std::vector<Pair> pairs;
    if (o.self)
        for (std::size_t i = 0; i < items.size(); ++i)
            if (items[i].count > 1) pairs.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i), true});
    const std::size_t self_pairs = pairs.size();
    if (o.self) st.item_pairs = overlapping.size();  // (without self: counted by the sweep, which filtered)
    for (const auto& [a, b] : overlapping) {
        const bool is_near = near(items[a], b);
        if (is_near && !o.self) continue;  // pieces of one object (no self-collision)
        if (!is_near && ((items[b].tag & kFFV) || (items[a].tag & kSFV))) continue;  // proven apart
        pairs.push_back({a, b, is_near});
    }
    // Both runs are sorted by (a, b) already (the self pairs by i; overlapping_sets returns its pairs
    // sorted, a < b) and no key repeats, so merging them gives the order a full sort gave.
    std::inplace_merge(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(self_pairs),
                       pairs.end(), [](const Pair& x, const Pair& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
    st.item_pairs_kept = pairs.size();
    std::vector<char> counted(items.size(), 0);
    for (const Pair& p : pairs) {
        st.near_item_pairs += p.near ? 1 : 0;
        for (std::uint32_t i : {p.a, p.b}) {
            if (!counted[i]) st.candidate_triangles += items[i].count;
            counted[i] = 1;
        }
    }

    std::vector<detail::ExactObject> exact(geoms.size());
    for (std::size_t g = 0; g < geoms.size(); ++g)
        exact[g] = {&objects[geoms[g].object], geoms[g].object, Aabb{}, geoms[g].tri_box, geoms[g].order, geoms[g].weld};
    std::vector<detail::CandidateSet> sets(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) sets[i] = {items[i].geom, items[i].first, items[i].count, items[i].box};
    detail::ExactStageResult r = detail::listed_exact_stage(exact, sets, pairs, o.threads);
    st.exact_tests = r.stats.tests;
    st.near_exact_tests = r.stats.near_tests;
    st.adjacent_skipped = r.stats.adjacent_skipped;
    return std::move(r.pairs);
}

// Self-collision off: object boxes -> objects -> sub-objects -> single triangles, tags inherited
// from stage to stage. Leaves the last stage's geometry and items in `geoms` and `items`.
Status separate_stages(std::span<const Mesh> objects, std::span<const std::uint32_t> active,
                       const QuickOptions& options, ViewSize size, QueryDevice& device, std::vector<Geom>& geoms,
                       std::vector<Item>& items, QuickStats& st) {
    const auto group = static_cast<std::size_t>(options.subobject_triangles);
    // Stage 1: object boxes.
    auto t0 = Clock::now();
    std::vector<Geom> boxes(active.size());
    std::vector<Item> box_items(active.size());
    const std::vector<Aabb> bounds = detail::object_bounds(objects, active, options.threads);
    for (std::size_t k = 0; k < active.size(); ++k) {
        const Aabb& b = bounds[k];
        Geom& g = boxes[k];
        g.object = active[k];
        g.positions.resize(8);
        for (std::size_t c = 0; c < 8; ++c)
            g.positions[c] = {(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z};
        g.indices.assign(kBoxIndices.begin(), kBoxIndices.end());
        box_items[k].geom = static_cast<std::uint32_t>(k);
        box_items[k].first = 0;
        box_items[k].count = 12;
        box_items[k].box = b;
    }
    set_object_near(box_items);
    if (Status s = run_stage(boxes, box_items, CullStage::Boxes, options, size, device, st); !s) return s;
    st.pcs_boxes = count_live(box_items);
    st.boxes_ms = ms_since(t0);

    // Stage 2: whole objects (the live boxes' objects, tags inherited).
    t0 = Clock::now();
    for (const Item& b : box_items) {
        if (b.tag == kBFV) continue;
        const std::uint32_t object = boxes[b.geom].object;
        const Mesh& m = objects[object];
        std::vector<std::uint32_t> order(m.triangles.size());
        for (std::size_t t = 0; t < order.size(); ++t) order[t] = static_cast<std::uint32_t>(t);
        Item it;
        it.geom = static_cast<std::uint32_t>(geoms.size());
        it.first = 0;
        it.count = static_cast<std::uint32_t>(order.size());
        it.box = b.box;
        it.tag = b.tag;
        geoms.push_back(make_mesh_geom(m, object, std::move(order)));
        items.push_back(it);
    }
    set_object_near(items);
    if (Status s = run_stage(geoms, items, CullStage::Objects, options, size, device, st); !s) return s;
    st.pcs_objects = count_live(items);
    st.objects_ms = ms_since(t0);

    // Stage 3: sub-objects; stage 4: single triangles (when sub-objects hold more than one).
    t0 = Clock::now();
    items = split_items(geoms, items, group, options.threads);
    set_object_near(items);
    st.subobjects = items.size();
    if (Status s = run_stage(geoms, items, CullStage::SubObjects, options, size, device, st); !s) return s;
    st.pcs_subobjects = count_live(items);
    if (group > 1) {
        items = split_items(geoms, items, 1, options.threads);
        set_object_near(items);
        st.triangles_in = items.size();
        if (Status s = run_stage(geoms, items, CullStage::SubObjects, options, size, device, st); !s) return s;
        st.pcs_triangles = count_live(items);
    }
    st.subobjects_ms = ms_since(t0);
    return Status{};
}

// Self-collision on: one stage over every object's sub-objects, each object's triangles in a
// bandwidth-reducing order, near = within the object's window. Leaves the geometry, the items and
// their overlapping box pairs (BFV items included: their near pairs stay open).
Status self_stage(std::span<const Mesh> objects, std::span<const std::uint32_t> active, const QuickOptions& options,
                  ViewSize size, QueryDevice& device, std::vector<Geom>& geoms, std::vector<Item>& items,
                  std::vector<ItemPair>& overlapping, QuickStats& st, detail::QuickSelfCache* cache) {
    const auto group = static_cast<std::size_t>(options.subobject_triangles);
    auto t0 = Clock::now();
    if (cache != nullptr && cache->entries.size() < objects.size()) cache->entries.resize(objects.size());
    for (std::uint32_t object : active) {
        const Mesh& m = objects[object];
        std::vector<std::uint32_t> weld = weld_vertices(m);
        std::vector<std::uint32_t> order;
        std::uint32_t w = 0;
        detail::QuickSelfCache::Entry* entry = cache != nullptr ? &cache->entries[object] : nullptr;
        if (entry != nullptr && entry->valid && entry->group == group && entry->weld == weld &&
            entry->triangles == m.triangles) {
            order = entry->order;  // the same topology: the order below would be this one
            w = entry->window;
        } else {
            const VertexTriangles vt = vertex_triangles(m, weld);
            std::vector<std::uint32_t> input(m.triangles.size());
            for (std::size_t t = 0; t < input.size(); ++t) input[t] = static_cast<std::uint32_t>(t);
            std::vector<std::uint32_t> last;
            (void)bfs_order(m, weld, vt, {}, &last);
            std::vector<std::uint32_t> bfs = bfs_order(m, weld, vt, last, nullptr);
            const std::uint32_t w_in = window_of(input, group, vt);
            const std::uint32_t w_bfs = window_of(bfs, group, vt);
            w = std::min(w_in, w_bfs);
            order = w_bfs < w_in ? std::move(bfs) : std::move(input);
            if (entry != nullptr) {
                entry->valid = false;  // (until every field below is set)
                entry->triangles = m.triangles;
                entry->weld = weld;
                entry->group = group;
                entry->order = order;
                entry->window = w;
                entry->valid = true;
            }
        }
        st.window_max = std::max<std::uint64_t>(st.window_max, w);
        const auto gi = static_cast<std::uint32_t>(geoms.size());
        geoms.push_back(make_mesh_geom(m, object, std::move(order)));
        geoms.back().weld = std::move(weld);
        Item whole;
        whole.geom = gi;
        whole.count = static_cast<std::uint32_t>(m.triangles.size());
        const std::size_t s = items.size();
        std::vector<Item> parts = split_items(geoms, std::vector<Item>{whole}, group, 1);
        const std::size_t e = s + parts.size();
        for (std::size_t k = 0; k < parts.size(); ++k) {
            const std::size_t pos = s + k;
            parts[k].near_lo = static_cast<std::uint32_t>(pos >= s + w ? pos - w : s);
            parts[k].near_hi = static_cast<std::uint32_t>(std::min<std::size_t>(e - 1, pos + w));
            items.push_back(parts[k]);
        }
    }
    st.subobjects = items.size();
    // Box pairs once (they include BFV items: their near pairs stay open); the box tags leave
    // to the passes only the items with a far overlapping box.
    overlapping = box_pairs(items, options.threads);
    if (!options.skip_visibility) box_tags(items, overlapping);
    st.pcs_boxes = count_live(items);
    if (Status s = run_stage(geoms, items, CullStage::SubObjects, options, size, device, st); !s) return s;
    st.pcs_subobjects = count_live(items);
    st.subobjects_ms = ms_since(t0);
    return Status{};
}

}  // namespace

Result<std::vector<TrianglePair>> quick_cullide_pairs(std::span<const Mesh> objects,
                                                      std::span<const std::uint32_t> active,
                                                      const QuickOptions& options, QueryDevice& device,
                                                      QuickStats* stats) {
    return detail::quick_cullide_pairs(objects, active, options, device, stats, false);
}

Result<std::vector<TrianglePair>> detail::quick_cullide_pairs(std::span<const Mesh> objects,
                                                              std::span<const std::uint32_t> active,
                                                              const QuickOptions& options, QueryDevice& device,
                                                              QuickStats* stats, bool scene_checked,
                                                              detail::QuickSelfCache* self_cache) {
    Result<ViewSize> checked = check_inputs(objects, active, options, scene_checked);
    if (!checked) return checked.error();
    const ViewSize size = checked.value();
    QuickStats st;
    st.objects_in = active.size();
    std::vector<Geom> geoms;
    std::vector<Item> items;
    std::vector<ItemPair> overlapping;

    const Status ran = options.self
                           ? self_stage(objects, active, options, size, device, geoms, items, overlapping, st,
                                        self_cache)
                           : separate_stages(objects, active, options, size, device, geoms, items, st);
    if (!ran) return ran.error();

    auto t0 = Clock::now();
    if (!options.self) {
        // Without self-collision the exact stage drops the pairs of one object's items and those the
        // tags prove apart (exact_stage's own filter): the sweep drops them as it meets them, and
        // counts every overlapping pair for item_pairs.
        overlapping = detail::overlapping_sets(
            item_refs(items, false), options.threads,
            [&](std::uint32_t a, std::uint32_t b) {
                return !near(items[a], b) && !(items[b].tag & kFFV) && !(items[a].tag & kSFV);
            },
            st.item_pairs);
    }
    std::vector<TrianglePair> pairs = exact_stage(objects, geoms, items, overlapping, options, st);
    st.exact_ms = ms_since(t0);
    if (stats != nullptr) *stats = std::move(st);
    return pairs;
}

}  // namespace cullide
