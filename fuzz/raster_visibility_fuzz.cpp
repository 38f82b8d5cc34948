// libFuzzer target for raster::VisibilityPass, the fused exact-bounds visibility pass R-CULLIDE's
// views run (raster/visibility.h), and its settling pre-pass (visibility.cpp, State::presettle),
// which answers items from boxes, vertex records and flat-face records without drawing them.
// From the input: a one-tile target (1 to 128 pixels a side), a depth format, and up to 16
// objects of items: axis-aligned boxes seen along the view axis (12 triangles, as the box stage
// draws them), lone flat or sloped triangles, patches of triangles sharing vertices, and
// degenerate ones; coordinates on pixel borders and centres or a hair (2^-40) off them, depths tied
// between objects, on D16 / D24 quantization boundaries or a step apart, points beyond the clip
// volume, and specials. RASTER_FUZZ_DEBUG prints the decoded scene.
// Property: the per-item answers of the fused pass (pre-pass on, fresh and reused; pre-pass off;
// 1 and 3 threads) equal the two recorded passes run through raster::execute_reference
// (tests/raster/recorded_visibility.h); input with a non-finite or out-of-range vertex is rejected
// by both. On valid input, also raster::WindowedPasses (Quick-CULLIDE's passes: windows, unused
// items and masks from the input; both directions; 1 and 3 threads) equals its recorded form.
// Any violation aborts.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "raster/raster.h"
#include "raster/visibility.h"
#include "recorded_visibility.h"

namespace {

class Reader {
   public:
    Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
    std::uint8_t byte() { return p_ == end_ ? 0 : *p_++; }
    bool done() const { return p_ == end_; }

   private:
    const std::uint8_t* p_;
    const std::uint8_t* end_;
};

// Tallies for the docs (printed at exit when RASTER_FUZZ_STATS is set).
struct Stats {
    unsigned long long runs = 0, rejected = 0, items = 0, hit = 0, settled_hit = 0, by_face = 0, not_hit = 0,
                       windowed = 0, windowed_hit = 0;
    ~Stats() {
        if (std::getenv("RASTER_FUZZ_STATS") != nullptr)
            std::fprintf(stderr,
                         "raster_visibility_fuzz: %llu runs, %llu rejected, %llu items (%llu hit); pre-pass: "
                         "%llu certainly hit (%llu by a face), %llu certainly not; %llu windowed scenes (%llu "
                         "queries passed)\n",
                         runs, rejected, items, hit, settled_hit, by_face, not_hit, windowed, windowed_hit);
    }
};
Stats g_stats;

[[noreturn]] void fail(const char* what) {
    std::fprintf(stderr, "raster_visibility_fuzz: property violated: %s\n", what);
    std::abort();
}

struct Scene {
    std::vector<raster::Double4> vertices;
    std::vector<std::vector<std::uint32_t>> items;
    std::vector<std::uint32_t> object;
    std::uint32_t objects = 0;
};

// A clip coordinate along an axis of `pixels` pixels: a pixel border or centre, or a hair off one,
// or anywhere; now and then beyond the clip volume or special.
double coordinate(Reader& in, int pixels) {
    const std::uint8_t mode = in.byte();
    const double step = 2.0 / pixels;
    const double lattice = -1.0 + step * 0.5 * static_cast<double>(in.byte() % (2 * pixels + 1));
    switch (mode % 8) {
        case 0:
        case 1:
            return lattice;
        case 2:
            return lattice + 0x1p-40;
        case 3:
            return lattice - 0x1p-40;
        case 4:
        case 5:
            return static_cast<double>(static_cast<int>(in.byte()) - 128) / 128.0;
        case 6:
            return static_cast<double>(static_cast<int>(in.byte()) - 128) / 64.0;  // beyond [-1, 1] at times
        default: {  // specials, a quarter of them rejected (NaN, infinity, beyond 2^100)
            static const double kSpecial[] = {0.0,          -0.0, 1.0, -1.0, 1.0 + 0x1p-52, -1.0 - 0x1p-52, 0.5, -0.5,
                                              1.0 - 0x1p-53, 0x1p-1074, 0x1p100, -0x1p100, 0x1p101, std::nan(""),
                                              HUGE_VAL, -HUGE_VAL};
            return kSpecial[(mode >> 3) % 16];
        }
    }
}

// A depth: one of the scene's earlier depths (ties between objects), on a D16 or D24 quantization
// boundary, a step from one, or anywhere.
double depth(Reader& in, std::vector<double>& seen) {
    const std::uint8_t mode = in.byte();
    double z = static_cast<double>(static_cast<int>(in.byte()) - 128) / 128.0;
    const double n = (mode & 8U) != 0 ? 65535.0 : 16777215.0;
    switch (mode % 4) {
        case 0:
            if (!seen.empty()) z = seen[in.byte() % seen.size()];
            break;
        case 1:
            z = std::round((z + 1.0) * 0.5 * n) / n * 2.0 - 1.0;
            break;
        case 2:
            if (!seen.empty()) z = seen[in.byte() % seen.size()] + static_cast<double>(static_cast<int>(in.byte() % 7) - 3) * 2.0 / n;
            break;
        default:
            break;
    }
    seen.push_back(z);
    return z;
}

// The decoded scene, for reading a finding (RASTER_FUZZ_DEBUG set).
void dump(const Scene& s, int w, int h, raster::DepthFormat format, const char* recorded) {
    std::fprintf(stderr, "%d x %d, format %d, recorded passes: %s\n", w, h, static_cast<int>(format), recorded);
    for (std::size_t i = 0; i < s.items.size(); ++i) {
        std::fprintf(stderr, "item %zu, object %u, indices", i, s.object[i]);
        for (const std::uint32_t k : s.items[i]) std::fprintf(stderr, " %u", k);
        std::fprintf(stderr, "\n");
    }
    for (std::size_t k = 0; k < s.vertices.size(); ++k)
        std::fprintf(stderr, "vertex %zu: %a %a %a\n", k, s.vertices[k].x, s.vertices[k].y, s.vertices[k].z);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Reader in(data, size);
    ++g_stats.runs;
    const std::uint8_t h0 = in.byte();
    const auto format = static_cast<raster::DepthFormat>(h0 % 3);
    const int w = 1 + in.byte() % 128;
    const int h = 1 + in.byte() % 128;
    Scene s;
    s.objects = 1 + in.byte() % 16;
    std::vector<double> seen;
    static constexpr std::uint32_t kBox[36] = {0, 1, 3, 0, 3, 2, 4, 7, 5, 4, 6, 7, 0, 4, 6, 0, 6, 2,
                                               1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3};
    for (std::uint32_t o = 0; o < s.objects && !in.done(); ++o) {
        const int n_items = 1 + in.byte() % 3;
        for (int it = 0; it < n_items; ++it) {
            const auto base = static_cast<std::uint32_t>(s.vertices.size());
            std::vector<std::uint32_t> idx;
            const std::uint8_t kind = in.byte();
            switch (kind % 4) {
                case 0: {  // a box seen along the view axis
                    const double x0 = coordinate(in, w), x1 = coordinate(in, w);
                    const double y0 = coordinate(in, h), y1 = coordinate(in, h);
                    const double z0 = depth(in, seen), z1 = depth(in, seen);
                    for (int c = 0; c < 8; ++c)
                        s.vertices.push_back({(c & 1) ? x1 : x0, (c & 2) ? y1 : y0, (c & 4) ? z1 : z0, 1.0});
                    for (const std::uint32_t k : kBox) idx.push_back(base + k);
                    break;
                }
                case 1: {  // a lone triangle, flat (kind bit 2) or sloped
                    const double z = depth(in, seen);
                    for (int c = 0; c < 3; ++c)
                        s.vertices.push_back({coordinate(in, w), coordinate(in, h),
                                              (kind & 4U) != 0 || c == 0 ? z : depth(in, seen), 1.0});
                    idx = {base, base + 1, base + 2};
                    break;
                }
                case 2: {  // a 2 x 2 patch of quads sharing vertices, flat or sloped in x
                    const double x0 = coordinate(in, w), y0 = coordinate(in, h);
                    const double dx = std::fabs(coordinate(in, w)) * 0.5, dy = std::fabs(coordinate(in, h)) * 0.5;
                    const double z = depth(in, seen), slope = (kind & 4U) != 0 ? 0.0 : depth(in, seen) * 0.25;
                    for (int j = 0; j < 3; ++j)
                        for (int i = 0; i < 3; ++i)
                            s.vertices.push_back({x0 + i * dx, y0 + j * dy, z + i * slope, 1.0});
                    for (std::uint32_t j = 0; j < 2; ++j)
                        for (std::uint32_t i = 0; i < 2; ++i) {
                            const std::uint32_t a = base + j * 3 + i;
                            idx.insert(idx.end(), {a, a + 1, a + 4, a, a + 4, a + 3});
                        }
                    break;
                }
                default: {  // degenerate: a segment or a point
                    const raster::Double4 p{coordinate(in, w), coordinate(in, h), depth(in, seen), 1.0};
                    const raster::Double4 q = (kind & 4U) != 0 ? p : raster::Double4{coordinate(in, w), p.y, p.z, 1.0};
                    s.vertices.insert(s.vertices.end(), {p, q, (kind & 8U) != 0 ? p : q});
                    idx = {base, base + 1, base + 2};
                    break;
                }
            }
            s.items.push_back(std::move(idx));
            s.object.push_back(o);
        }
    }
    if (s.items.empty()) return 0;
    // Objects left without items (the input ran out) are dropped from the count.
    s.objects = s.object.back() + 1;
    std::vector<raster::VisibilityItem> items;
    for (std::size_t i = 0; i < s.items.size(); ++i) items.push_back({raster::MeshViewD{s.vertices, s.items[i]}, s.object[i]});

    std::string why;
    const auto want = test::recorded_visibility(s.vertices, s.items, s.object, s.objects, w, h, format, 1, true, &why);
    if (std::getenv("RASTER_FUZZ_DEBUG") != nullptr) dump(s, w, h, format, want ? "accepted" : why.c_str());
    static raster::VisibilityPass reused;  // keeps buffers and the pre-pass's history between inputs
    raster::VisibilityPass fresh, off;
    off.set_presettle(false);
    const auto a = fresh.run(w, h, format, items, 1);
    const auto b = reused.run(w, h, format, items, 3);
    const auto c = off.run(w, h, format, items, 3);
    if (!want) {
        ++g_stats.rejected;
        if (a.ok() || b.ok() || c.ok()) fail("input the recorded passes reject was accepted");
        return 0;
    }
    if (!a.ok() || !b.ok() || !c.ok()) fail("input the recorded passes accept was rejected");
    if (a.value() != *want) fail("fused pass (pre-pass on, 1 thread) differs from the recorded passes");
    if (b.value() != *want) fail("fused pass (pre-pass on, reused, 3 threads) differs from the recorded passes");
    if (c.value() != *want) fail("fused pass (pre-pass off, 3 threads) differs from the recorded passes");
    g_stats.items += want->size();
    for (const std::uint8_t v : *want) g_stats.hit += v;
    const raster::PresettleStats st = fresh.last_presettle();
    g_stats.settled_hit += st.items_hit;
    g_stats.by_face += st.items_hit_by_face;
    g_stats.not_hit += st.items_not_hit;

    // Quick-CULLIDE's windowed passes over the same (valid) items: per item a window [lo, hi]
    // around it (non-decreasing over the items), whether it is used, and the query and write masks
    // (an unused item neither), from the rest of the input; both directions, 1 and 3 threads,
    // against the recorded windowed pass.
    const std::size_t n = s.items.size();
    std::vector<std::uint32_t> lo(n), hi(n);
    std::vector<std::uint8_t> query(n), write(n);
    std::vector<raster::WindowedItem> windowed(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t shape = in.byte();
        lo[i] = static_cast<std::uint32_t>(i - std::min<std::size_t>(i, shape % 4));
        hi[i] = static_cast<std::uint32_t>(std::min(n - 1, i + (shape >> 2) % 4));
        if (i > 0) lo[i] = std::max(lo[i], lo[i - 1]), hi[i] = std::max(hi[i], hi[i - 1]);
        const bool used = (shape & 0x10U) == 0;
        query[i] = used && (shape & 0x20U) == 0 ? 1 : 0;
        write[i] = used && (shape & 0x40U) == 0 ? 1 : 0;
        windowed[i] = {raster::MeshViewD{s.vertices, s.items[i]}, lo[i], hi[i], used};
    }
    for (const int threads : {1, 3}) {
        raster::WindowedPasses passes;
        const auto prepared = passes.prepare(w, h, format, windowed, threads);
        if (!prepared.ok()) fail("windowed passes refused items the recorded passes accept");
        for (const bool forward : {true, false}) {
            const auto got = passes.run(forward, query, write);
            const auto ref = test::recorded_windowed(s.vertices, s.items, lo, hi, query, write, forward, w, h, format);
            if (!got.ok() || !ref) fail("windowed pass or its recorded form failed on valid input");
            if (got.value() != *ref) fail("windowed pass differs from the recorded windowed pass");
            if (threads == 1)
                for (std::size_t i = 0; i < n; ++i) g_stats.windowed_hit += query[i] && got.value()[i] ? 1 : 0;
        }
    }
    ++g_stats.windowed;
    return 0;
}
