// libFuzzer target: the GL-exact raster path that runs (dispatched: the AVX2+FMA kernel on x86-64
// when the CPU has it, tiled, several threads) equals the scalar reference (raster::execute_reference
// with allow_simd off: commands one by one, the portable kernel, one thread), every depth bit and every
// query count.
//
// From the input it builds a command batch for a target of 1..160 x 1..160 pixels (so up to 3 x 3
// tiles of 64), any depth format and clear value: up to 12 draws and queries (both kinds, sometimes
// left unbalanced), each draw 1..4 triangles (now and then repeated, shifted, up to 9..16, so that
// setup runs 8 triangles at once) of float clip coordinates (pixel-centre lattice values,
// fractions, 1/256 snapping ties, huge, tiny, non-finite and raw float bits; w = 1 mostly, else
// random, zero or negative, so the near/far and side clipping runs), every DepthFunc, depth mask on or
// off, culling and facing, an optional viewport (also partly outside the target), and now and then an
// ExactBounds draw between the GL-exact ones.
//
// Compared, all from the same cleared target:
//   want = execute_reference(allow_simd = false)           the scalar reference
//   execute_reference(allow_simd = true)                   the dispatched kernel, reference order
//   execute(threads = 1, allow_simd = true)                the tiled path, one thread
//   execute(threads = 3, allow_simd = true)                the tiled path, three threads
//   execute(threads = 2, allow_simd = false)               the tiled path, portable kernel
//   execute(threads = 2, queries_only, clear_depth = the clear value): draws no query observes are
//                                                          skipped (its query results only)
//   execute(threads = 2, clear_depth = the clear value) twice on one target: the second clear
//                                                          restores only the blocks the first run
//                                                          wrote (the target's fast clear)
// Property: each accepts exactly when the reference accepts (with the same message); when accepted,
// the query results and (but for queries_only) every stored depth value are equal; when refused,
// the target is unchanged.
// Any violation aborts (a finding). RASTER_FUZZ_STATS=1 prints tallies at exit.
#include <algorithm>
#include <cmath>
#include <span>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace {

class Reader {
   public:
    Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
    [[nodiscard]] bool done() const { return p_ == end_; }
    std::uint8_t byte() { return p_ == end_ ? 0 : *p_++; }
    // A clip coordinate (as a float, since GL-exact input is float).
    float value() {
        const std::uint8_t mode = byte();
        switch (mode & 7U) {
            case 0:  // -2 .. 2 in steps of 1/64: pixel edges and centres of small targets
                return static_cast<float>(static_cast<int>(byte()) - 128) / 64.0f;
            case 1:  // a fraction with low-order noise: near the 1/256 snapping ties
                return static_cast<float>(static_cast<int>(byte()) - 128) / 128.0f +
                       static_cast<float>(static_cast<int>(byte()) - 128) * 0x1p-20f;
            case 2:  // large: far outside the clip volume (clipping, huge triangles)
                return (static_cast<float>(byte()) / 127.5f - 1.0f) * std::ldexp(1.0f, static_cast<int>((mode >> 3) % 32));
            case 3: {
                static const float kSpecial[] = {0.0f,  -0.0f,   1.0f,   -1.0f,    0.5f,     -0.5f,  1e-30f,  1e30f,
                                                 -1e30f, 0x1p100f, 3e38f, 0.9999999f, -1.0000001f, NAN, INFINITY, 0x1p-24f};
                return kSpecial[(mode >> 3) % 16];
            }
            case 4: {  // raw float bits
                std::uint32_t bits = 0;
                for (int i = 0; i < 4; ++i) bits |= static_cast<std::uint32_t>(byte()) << (8 * i);
                float v = 0.0f;
                std::memcpy(&v, &bits, sizeof v);
                return v;
            }
            default:
                return static_cast<float>(static_cast<int>(byte()) - 128) / 100.0f;
        }
    }

   private:
    const std::uint8_t* p_;
    const std::uint8_t* end_;
};

struct Stats {
    unsigned long long runs = 0, rejected = 0, draws = 0, queries = 0, samples = 0, pixels_written = 0, grouped = 0;
    ~Stats() {
        if (std::getenv("RASTER_FUZZ_STATS") != nullptr)
            std::fprintf(stderr,
                         "raster_gl_exact_fuzz: %llu runs, %llu rejected, %llu draws, %llu queries, %llu samples "
                         "passed, %llu pixels written, %llu draws of 9-16 triangles\n",
                         runs, rejected, draws, queries, samples, pixels_written, grouped);
    }
};
Stats g_stats;

[[noreturn]] void fail(const char* what, const char* path) {
    std::fprintf(stderr, "raster_gl_exact_fuzz: property violated: %s (%s vs scalar reference)\n", what, path);
    std::abort();
}

raster::DepthTarget make_target(int w, int h, raster::DepthFormat format, double clear) {
    auto t = raster::DepthTarget::create(w, h, format);
    if (!t.ok()) fail("target creation", "setup");
    if (!t.value().clear(clear).ok()) fail("clear", "setup");
    return std::move(t).value();
}

bool same(std::span<const std::uint32_t> a, std::span<const std::uint32_t> b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Reader in(data, size);
    ++g_stats.runs;
    const std::uint8_t h0 = in.byte();
    const auto format = static_cast<raster::DepthFormat>(h0 % 3);
    static const double kClear[] = {1.0, 0.0, 0.5, 0.75};
    const double clear = kClear[(h0 >> 2) % 4];
    const int w = 1 + in.byte() % 160;
    const int h = 1 + in.byte() % 160;
    const int commands = 1 + in.byte() % 12;

    // Storage first (the batch keeps spans into it).
    std::vector<std::vector<raster::Float4>> vertices(static_cast<std::size_t>(commands));
    std::vector<std::vector<std::uint32_t>> indices(static_cast<std::size_t>(commands));
    raster::CommandBatch batch(w, h);
    bool query_open = false;
    for (int c = 0; c < commands && !in.done(); ++c) {
        const std::uint8_t kind = in.byte();
        if ((kind & 3U) == 0) {  // query begin or end (queries do not nest)
            if (query_open) {
                batch.end_query();
            } else {
                batch.begin_query((kind & 4U) != 0 ? raster::QueryKind::AnySamplesPassed
                                                   : raster::QueryKind::SamplesPassed);
                ++g_stats.queries;
            }
            query_open = !query_open;
            continue;
        }
        auto& v = vertices[static_cast<std::size_t>(c)];
        auto& idx = indices[static_cast<std::size_t>(c)];
        const int tris = 1 + (kind >> 2) % 4;
        const std::uint8_t wmode = in.byte();
        for (int k = 0; k < 3 * tris; ++k) {
            raster::Float4 p;
            p.x = in.value();
            p.y = in.value();
            p.z = in.value();
            switch (wmode % 8) {
                case 6: p.w = in.value(); break;  // anything, 0 and negative included
                case 7: p.w = 0.25f + static_cast<float>(in.byte()) / 64.0f; break;
                default: p.w = 1.0f; break;
            }
            if ((wmode & 8U) != 0 && k % 3 == 2) p = v[v.size() - 1];  // a repeated vertex: zero area
            v.push_back(p);
            // Indices: mostly in order, sometimes shared or reversed (winding), rarely out of range.
            const std::uint8_t ib = (wmode & 16U) != 0 ? in.byte() : 0;
            std::uint32_t index = static_cast<std::uint32_t>(k);
            if (ib == 255) index = 1000;
            else if ((ib & 7U) == 1) index = static_cast<std::uint32_t>(k - k % 3 + (2 - k % 3));
            idx.push_back(index);
        }
        // Now and then the draw's triangles again, shifted by whole pixels and with every other
        // copy's winding reversed, up to 9-16 triangles: the tiled path then sets up groups of 8
        // triangles at once (setup_avx2.cpp), which draws of 1-4 triangles never reach.
        if ((kind & 0xc0U) == 0xc0U) {
            const std::size_t n0 = idx.size();
            const float dx = 2.0f / static_cast<float>(w), dy = 2.0f / static_cast<float>(h);
            for (int copy = 1; idx.size() < 27; ++copy) {
                for (std::size_t k = 0; k < n0; ++k) {
                    const std::uint32_t src = idx[k] < v.size() ? idx[k] : 0;
                    raster::Float4 p = v[src];
                    p.x += static_cast<float>(copy) * dx;
                    p.y -= static_cast<float>(copy % 3) * dy;
                    v.push_back(p);
                }
                const auto base = static_cast<std::uint32_t>(v.size() - n0);
                for (std::size_t k = 0; k < n0; k += 3) {
                    const bool flip = copy % 2 == 1;
                    idx.push_back(base + static_cast<std::uint32_t>(k));
                    idx.push_back(base + static_cast<std::uint32_t>(flip ? k + 2 : k + 1));
                    idx.push_back(base + static_cast<std::uint32_t>(flip ? k + 1 : k + 2));
                }
            }
            ++g_stats.grouped;
        }
        raster::DrawState s;
        const std::uint8_t sb = in.byte();
        s.depth_func = static_cast<raster::DepthFunc>(sb % 8);
        s.depth_write = (sb & 8U) == 0;
        s.cull_face = static_cast<raster::CullFace>((sb >> 4) % 3);
        s.front_face = (sb & 64U) != 0 ? raster::FrontFace::CW : raster::FrontFace::CCW;
        if ((sb & 128U) != 0) {
            const std::uint8_t vb = in.byte();
            s.viewport = raster::Viewport{static_cast<int>(vb % 16) - 4, static_cast<int>(vb >> 4) - 4,
                                          1 + static_cast<int>(in.byte() % 170), 1 + static_cast<int>(in.byte() % 170)};
        }
        if ((wmode & 32U) != 0 && (wmode & 64U) != 0) s.mode = raster::RasterMode::ExactBounds;
        batch.draw(raster::MeshView{v, idx}, s);
        ++g_stats.draws;
    }
    if (query_open && (h0 & 128U) == 0) batch.end_query();  // else left open: must be refused

    raster::DepthTarget reference = make_target(w, h, format, clear);
    const auto want = raster::execute_reference(reference, batch, raster::ExecuteOptions{1, false});
    const raster::DepthTarget cleared_target = make_target(w, h, format, clear);
    const auto cleared = cleared_target.values();
    if (!want.ok()) {
        ++g_stats.rejected;
        if (!same(reference.values(), cleared)) fail("a refused batch changed the target", "reference");
    } else {
        for (auto q : want.value()) g_stats.samples += q;
        for (std::size_t i = 0; i < cleared.size(); ++i) g_stats.pixels_written += reference.values()[i] != cleared[i];
    }

    struct Path {
        const char* name;
        bool tiled;
        raster::ExecuteOptions options;
    };
    raster::ExecuteOptions queries_only{2, true};
    queries_only.queries_only = true;
    queries_only.clear_depth = clear;
    const Path paths[] = {
        {"reference order, dispatched kernel", false, {1, true}},
        {"tiled, 1 thread, dispatched kernel", true, {1, true}},
        {"tiled, 3 threads, dispatched kernel", true, {3, true}},
        {"tiled, 2 threads, portable kernel", true, {2, false}},
        {"tiled, 2 threads, queries only", true, queries_only},
    };
    for (const Path& p : paths) {
        raster::DepthTarget t = make_target(w, h, format, clear);
        const auto got = p.tiled ? raster::execute(t, batch, p.options) : raster::execute_reference(t, batch, p.options);
        if (got.ok() != want.ok()) fail(want.ok() ? "refused a batch the reference ran" : "ran a batch the reference refused", p.name);
        if (!want.ok()) {
            if (got.error().message != want.error().message) fail("a different error message", p.name);
            if (!same(t.values(), cleared)) fail("a refused batch changed the target", p.name);
            continue;
        }
        if (got.value() != want.value()) fail("query results differ", p.name);
        if (!p.options.queries_only && !same(t.values(), reference.values())) fail("depth values differ", p.name);
    }
    if (want.ok()) {
        // The fast clear (raster/depth_target.h): after a first run with clear_depth, the second
        // one's clear fills only the blocks the first wrote, and must leave the reference's buffer.
        raster::ExecuteOptions twice{2, true};
        twice.clear_depth = clear;
        raster::DepthTarget t = make_target(w, h, format, clear);
        for (int run = 0; run < 2; ++run) {
            const auto got = raster::execute(t, batch, twice);
            if (!got.ok()) fail("refused a batch the reference ran", "fast clear, same target twice");
            if (got.value() != want.value()) fail("query results differ", "fast clear, same target twice");
            if (!same(t.values(), reference.values())) fail("depth values differ", "fast clear, same target twice");
        }
    }
    return 0;
}
