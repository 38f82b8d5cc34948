// libFuzzer target for the reliable raster modes. From the input it builds two triangle sets in
// clip space (w = 1): A (written, LEQUAL, mask on) and B (queried, GEQUAL, mask off): near-touching
// and nearly coplanar pairs, gaps down to 2^-30 (about 1e-9) of the scene, huge offsets, degenerate
// triangles (segments, points, edge-on), any depth format and resolution, double or float input.
// Property (R-CULLIDE's guarantee): whenever the exact rational reference says that, in some pixel,
// B's surface reaches at or behind A's nearest surface, the exact-bounds query counts at least one
// sample, and so does the paper's offset-box query drawn through the GL-exact mode. Also: the tiled
// executor (3 threads) equals the scalar reference bit for bit, and input with a non-finite or
// out-of-range vertex is rejected with the target unchanged. Any violation aborts.
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "exact_bounds_reference.h"
#include "raster/raster.h"

namespace {

class Reader {
 public:
    Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
    std::uint8_t byte() { return p_ == end_ ? 0 : *p_++; }
    // A clip coordinate: lattice values (pixel edges and centres), fractions, tiny and huge values,
    // specials, raw doubles.
    double value() {
        const std::uint8_t mode = byte();
        switch (mode & 7U) {
            case 0:
                return static_cast<double>(static_cast<int>(byte()) - 128) / 64.0;
            case 1:
                return static_cast<double>(static_cast<int>(byte()) - 128) / 128.0 +
                       static_cast<double>(byte()) * 0x1p-30;
            case 2:
                return (static_cast<double>(byte()) / 127.5 - 1.0) *
                       std::ldexp(1.0, (mode >> 3) % 32);  // huge
            case 3: {
                static const double kSpecial[] = {
                    0.0,   -0.0,    1.0,  -1.0,        0.5,          -0.5,         1e-300,   1e30,
                    -1e30, 0x1p100, 1e31, 0.999999999, -1.000000001, std::nan(""), HUGE_VAL, 0x1p-30};
                return kSpecial[(mode >> 3) % 16];
            }
            case 4: {
                double v = 0.0;
                std::uint8_t raw[8];
                for (std::uint8_t& b : raw) b = byte();
                std::memcpy(&v, raw, sizeof v);
                return v;
            }
            default:
                return static_cast<double>(static_cast<int>(byte()) - 128) / 100.0;
        }
    }

 private:
    const std::uint8_t* p_;
    const std::uint8_t* end_;
};

// Tallies for the docs (printed at exit when RASTER_FUZZ_STATS is set): how often each property
// was actually exercised.
struct Stats {
    unsigned long long runs = 0, rejected = 0, overlaps = 0, offset_checked = 0;
    ~Stats() {
        if (std::getenv("RASTER_FUZZ_STATS") != nullptr)
            std::fprintf(stderr,
                         "raster_exact_bounds_fuzz: %llu runs, %llu rejected, %llu exact overlaps, %llu "
                         "offset checks\n",
                         runs, rejected, overlaps, offset_checked);
    }
};
Stats g_stats;

[[noreturn]] void fail(const char* what) {
    std::fprintf(stderr, "raster_exact_bounds_fuzz: property violated: %s\n", what);
    std::abort();
}

bool valid(const raster::Double4& v) {
    const double lim = raster::kMaxExactBoundsCoordinate;
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::fabs(v.x) <= lim &&
           std::fabs(v.y) <= lim && std::fabs(v.z) <= lim;
}

// Exact truth: a pixel where B's exact max depth is >= A's exact min depth.
bool exact_overlap(const raster::Viewport& vp, int w, int h, const std::vector<raster::Double4>& a,
                   const std::vector<raster::Double4>& b) {
    std::vector<raster_ref::ExactTriangle> ta, tb;
    for (std::size_t k = 0; k + 2 < a.size(); k += 3) ta.emplace_back(vp, a[k], a[k + 1], a[k + 2]);
    for (std::size_t k = 0; k + 2 < b.size(); k += 3) tb.emplace_back(vp, b[k], b[k + 1], b[k + 2]);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool have_b = false;
            mpq_class bmax;
            for (const auto& t : tb) {
                if (t.empty() || x < t.x0 || x > t.x1 || y < t.y0 || y > t.y1) continue;
                const auto r = t.pixel(x, y);
                if (r.covered && (!have_b || r.zmax > bmax)) bmax = r.zmax, have_b = true;
            }
            if (!have_b) continue;
            for (const auto& t : ta) {
                if (t.empty() || x < t.x0 || x > t.x1 || y < t.y0 || y > t.y1) continue;
                const auto r = t.pixel(x, y);
                if (r.covered && bmax >= r.zmin) return true;
            }
        }
    return false;
}

std::vector<std::uint32_t> iota(std::size_t n) {
    std::vector<std::uint32_t> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint32_t>(i);
    return v;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Reader in(data, size);
    ++g_stats.runs;
    const std::uint8_t h0 = in.byte();
    const auto format = static_cast<raster::DepthFormat>(h0 % 3);
    const bool float_input = (h0 & 4U) != 0;
    const int w = 1 + in.byte() % 24;
    const int h = 1 + in.byte() % 24;
    const std::uint8_t counts = in.byte();
    const int na = 1 + counts % 3, nb = 1 + (counts >> 2) % 3;
    const std::uint8_t vpb = in.byte();
    raster::Viewport vp{0, 0, w, h};
    if ((vpb & 1U) != 0)
        vp = {static_cast<int>(vpb >> 4) - 8, static_cast<int>(vpb >> 1 & 7U) - 4, w + 3, h - h / 3};

    // A: free triangles. B: each either free, a copy of an A triangle moved by a tiny or huge
    // offset (nearly coplanar, near-touching), or degenerate.
    std::vector<raster::Double4> a, b;
    for (int i = 0; i < 3 * na; ++i) a.push_back({in.value(), in.value(), in.value(), 1.0});
    for (int i = 0; i < nb; ++i) {
        const std::uint8_t kind = in.byte();
        const std::size_t src = 3 * static_cast<std::size_t>(kind % na);
        switch ((kind >> 2) % 4) {
            case 0:
                for (int k = 0; k < 3; ++k) b.push_back({in.value(), in.value(), in.value(), 1.0});
                break;
            case 1: {  // nearly coplanar: A's triangle moved in depth by +-2^-e, e in [0, 63]
                const double dz =
                    ((kind & 128U) != 0 ? -1.0 : 1.0) * std::ldexp(1.0, -static_cast<int>(in.byte() % 64));
                for (int k = 0; k < 3; ++k)
                    b.push_back({a[src + static_cast<std::size_t>(k)].x,
                                 a[src + static_cast<std::size_t>(k)].y,
                                 a[src + static_cast<std::size_t>(k)].z + dz, 1.0});
                break;
            }
            case 2: {  // near-touching: one vertex shared up to a tiny gap, the others free
                const double g = std::ldexp(static_cast<double>(static_cast<int>(in.byte()) - 128), -37);
                const raster::Double4& p = a[src];
                b.push_back({p.x + g, p.y - g, p.z + g, 1.0});
                b.push_back({in.value(), in.value(), in.value(), 1.0});
                b.push_back({in.value(), in.value(), in.value(), 1.0});
                break;
            }
            default: {  // degenerate: a segment or a point (edge-on in the view when x, y agree)
                const raster::Double4 p{in.value(), in.value(), in.value(), 1.0};
                const raster::Double4 q = (kind & 64U) != 0 ? p : raster::Double4{p.x, p.y, in.value(), 1.0};
                b.push_back(p);
                b.push_back(q);
                b.push_back((kind & 32U) != 0 ? p : q);
                break;
            }
        }
    }
    if (float_input) {  // the float path: every coordinate as the float the caller would pass
        for (auto* s : {&a, &b})
            for (auto& v : *s) {
                const float fx = static_cast<float>(v.x), fy = static_cast<float>(v.y),
                            fz = static_cast<float>(v.z);
                v = {static_cast<double>(fx), static_cast<double>(fy), static_cast<double>(fz), 1.0};
            }
    }
    if (std::getenv("RASTER_FUZZ_VERBOSE") != nullptr) {  // to read a finding
        std::fprintf(stderr, "format %d, %dx%d, viewport (%d, %d, %d, %d), %s input\n",
                     static_cast<int>(format), w, h, vp.x, vp.y, vp.width, vp.height,
                     float_input ? "float" : "double");
        for (const auto* s : {&a, &b})
            for (const auto& v : *s)
                std::fprintf(stderr, "  %s (%.17g, %.17g, %.17g)\n", s == &a ? "A" : "B", v.x, v.y, v.z);
    }
    bool all_valid = true;
    for (const auto* s : {&a, &b})
        for (const auto& v : *s) all_valid = all_valid && valid(v);

    std::vector<raster::Float4> fa, fb;
    for (const auto& v : a)
        fa.push_back({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z), 1.0f});
    for (const auto& v : b)
        fb.push_back({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z), 1.0f});
    const auto ia = iota(a.size()), ib = iota(b.size());
    raster::CommandBatch batch(w, h);
    raster::DrawState ws;
    ws.mode = raster::RasterMode::ExactBounds;
    ws.depth_func = raster::DepthFunc::LEqual;
    ws.viewport = vp;
    raster::DrawState qs = ws;
    qs.depth_func = raster::DepthFunc::GEqual;
    qs.depth_write = false;
    if (float_input)
        batch.draw(raster::MeshView{fa, ia}, ws);
    else
        batch.draw(raster::MeshViewD{a, ia}, ws);
    batch.begin_query(raster::QueryKind::SamplesPassed);
    if (float_input)
        batch.draw(raster::MeshView{fb, ib}, qs);
    else
        batch.draw(raster::MeshViewD{b, ib}, qs);
    batch.end_query();

    auto target = raster::DepthTarget::create(w, h, format);
    if (!target.ok()) fail("target creation");
    auto reference = raster::DepthTarget::create(w, h, format);
    auto got = raster::execute(target.value(), batch, raster::ExecuteOptions{3});
    auto want = raster::execute_reference(reference.value(), batch);
    if (!all_valid) {
        ++g_stats.rejected;
        if (got.ok() || want.ok()) fail("invalid input was accepted");
        const std::uint32_t clear = raster::DepthTarget::encode_clear(1.0, format);
        for (const auto v : target.value().values())
            if (v != clear) fail("a rejected batch changed the target");
        return 0;
    }
    if (!got.ok() || !want.ok()) fail("valid input was rejected");
    if (got.value() != want.value()) fail("tiled and reference query results differ");
    for (std::size_t i = 0; i < target.value().values().size(); ++i)
        if (target.value().values()[i] != reference.value().values()[i])
            fail("tiled and reference depth differ");

    if (!exact_overlap(vp, w, h, a, b)) return 0;
    ++g_stats.overlaps;
    if (got.value()[0] == 0) fail("exact-bounds query missed an exact overlap (false negative)");

    // The paper's offset boxes: world = clip through a [-1, 1]^3 view along z (only when the
    // viewport is the whole target, as the offset construction assumes).
    if (vp.x != 0 || vp.y != 0 || vp.width != w || vp.height != h) return 0;
    auto view = raster::make_ortho_view(raster::Axis::Z, {-1, -1, -1}, {1, 1, 1}, w, h, format);
    if (!view.ok()) fail("view");
    std::vector<raster::Double3> pa, pb;
    for (const auto& v : a) pa.push_back({v.x, v.y, v.z});
    for (const auto& v : b) pb.push_back({v.x, v.y, v.z});
    auto oa = raster::triangle_offset_boxes(view.value(), pa, ia);
    auto ob = raster::triangle_offset_boxes(view.value(), pb, ib);
    if (!oa.ok() || !ob.ok()) return 0;  // a box beyond the float range: nothing to draw in GL
    raster::CommandBatch ob_batch(w, h);
    raster::DrawState ow;
    ow.cull_face = raster::CullFace::Back;
    ow.depth_func = raster::DepthFunc::LEqual;
    raster::DrawState oq;
    oq.cull_face = raster::CullFace::Front;
    oq.depth_func = raster::DepthFunc::GEqual;
    oq.depth_write = false;
    ob_batch.draw(oa.value().view(), ow);
    ob_batch.begin_query(raster::QueryKind::SamplesPassed);
    ob_batch.draw(ob.value().view(), oq);
    ob_batch.end_query();
    auto t2 = raster::DepthTarget::create(w, h, format);
    auto r2 = raster::execute(t2.value(), ob_batch);
    if (!r2.ok()) fail("offset batch rejected");
    ++g_stats.offset_checked;
    if (r2.value()[0] == 0) fail("offset-box query missed an exact overlap (false negative)");
    return 0;
}
