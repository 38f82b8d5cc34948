// golden_digest_test.cpp: pinned digests of every deterministic result, checked for 1, 2, 3 and 8
// threads, the scalar and SIMD raster paths, and (the same literals, built by scripts/cross-aarch64.sh
// and run under qemu) aarch64 as well as x86-64. A digest that moves is a determinism or portability
// bug, or a deliberate change of results: then the literal is updated in the same commit, saying why.
//
// The literals prove "same bits everywhere"; they do not prove the bits are right. That is checked
// here against independent twins: the ground truth against a brute-force loop over every triangle pair
// (no box prefilter, no threads), the broad phase against a plain O(n^2) loop, and the tiled raster
// executor against the scalar reference. The rows are a table so that further methods (CULLIDE,
// R-CULLIDE through cullide::process_frame, with their PCS sizes in the digest) are added as rows.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/scenes.h"
#include "cullide/tri_tri.h"
#include "brute_force_pairs.h"
#include "digest.h"
#include "raster/raster.h"
#include "spatialhash/broad_phase.h"
#include "test_rng.h"

#if defined(CULLIDE_HAVE_TBB)
#include <tbb/global_control.h>
#endif

using cullide::Mesh;
using cullide::TrianglePair;

namespace {

constexpr int kThreadCounts[] = {1, 2, 3, 8};

// Lets TBB run 8 workers even on a 2-core machine, so that 3 and 8 threads really happen.
struct AllowThreads {
#if defined(CULLIDE_HAVE_TBB)
    tbb::global_control control{tbb::global_control::max_allowed_parallelism, 8};
#endif
};

// ---- Scenes x methods -------------------------------------------------------------------------

// One pinned row: a built-in scene at scale 0.05 with procedural stand-ins (no ../shared meshes), one
// frame, one method. `result` digests the pair list and the method's deterministic counts (for exact:
// box_pairs and candidate_triangles; visibility methods will add their PCS sizes).
struct Row {
    const char* scene;
    int frame;
    const char* method;  // "exact" today; "cullide", "rcullide", ... as they land
    bool self;
    std::uint64_t frame_digest;
    std::uint64_t pair_count;
    std::uint64_t result_digest;
};

// clang-format off
constexpr Row kRows[] = {
    {"cylinders",    0, "exact", false, 0x69317a89632646d0ull,   57, 0xb75082e0ef150da9ull},
    {"cylinders",    5, "exact", false, 0x26a61df84cfe3965ull,  166, 0xd8c26e85e2d1cd21ull},
    {"tori",         0, "exact", false, 0xdf006acf8e9e7225ull, 1058, 0x53a8ed44976595e0ull},
    {"tori",         5, "exact", false, 0x710d2db0403cfd3aull, 1002, 0x2897d4d6b36726d8ull},
    {"bunny-dragon", 0, "exact", false, 0xc4e801f5da59f7d9ull,    0, 0xf66d9459ba2a9a37ull},
    {"bunny-dragon", 5, "exact", false, 0x094d564c6dbf2928ull,    0, 0xf66d9459ba2a9a37ull},
    {"breaking",     0, "exact", false, 0xb6645b94696fa191ull, 5225, 0xb147e5ab8d8dced4ull},
    {"breaking",     5, "exact", false, 0xc439bc1415a1def8ull, 5225, 0xb147e5ab8d8dced4ull},
    {"leaves",       0, "exact", false, 0xab850e61547e8565ull,    0, 0xce6e4b4b6f1d7881ull},
    {"leaves",       5, "exact", false, 0x0841066c2cade3ffull,    0, 0xce6e4b4b6f1d7881ull},
    {"cloth",        0, "exact", true,  0xd2f123b3c2cfede6ull,    0, 0xe3eed39028ac42c9ull},
    {"cloth",        5, "exact", true,  0x8a37d16cc90bfd7cull,    0, 0x6d3ac5c95cdaa187ull},
};
// clang-format on

std::string hex(std::uint64_t v) {
    static const char* digits = "0123456789abcdef";
    std::string s = "0x";
    for (int i = 60; i >= 0; i -= 4) s += digits[(v >> i) & 0xfu];
    return s + "ull";
}

cullide::Frame make_frame(const char* scene, int frame) {
    cullide::SceneOptions options;
    options.scale = 0.05;
    options.mesh_dir = "";  // stand-ins: the digest must not depend on ../shared
    auto gen = cullide::make_scene(scene, options);
    REQUIRE_MESSAGE(gen.ok(), gen.error().message);
    return gen.value()->frame(frame);
}

struct Outcome {
    std::vector<TrianglePair> pairs;
    std::uint64_t digest = 0;
};

// Runs one method; the only place that knows the methods (a new method is one more branch here).
Outcome run_method(const std::string& method, const cullide::Frame& frame, bool self, int threads) {
    Outcome out;
    if (method == "exact") {
        cullide::ExactStats stats;
        auto r = cullide::exact_pairs(frame, cullide::ExactOptions{self, threads}, &stats);
        REQUIRE_MESSAGE(r.ok(), r.error().message);
        out.pairs = std::move(r).value();
        out.digest = reliability::Digest{}
                         .pairs(out.pairs)
                         .u64(stats.triangles)
                         .u64(stats.candidate_triangles)
                         .u64(stats.box_pairs)
                         .u64(stats.adjacent_skipped)
                         .value();
        return out;
    }
    FAIL("unknown method in the golden table: " << method);
    return out;
}


// ---- Raster -----------------------------------------------------------------------------------

float unit_float(test::Rng& rng) { return static_cast<float>(rng.next() >> 40) * (1.0f / 16777216.0f); }

// A fixed random batch: per object a query over a small random mesh, then usually a draw of it;
// coordinates on and off the 1/256-pixel grid, some outside the clip volume, some with w != 1.
struct RasterBatch {
    std::vector<std::vector<raster::Float4>> vertices;
    std::vector<std::vector<std::uint32_t>> indices;
    raster::CommandBatch batch{1, 1};
};

void build_raster_batch(RasterBatch& b, std::uint64_t seed, int width, int height, int objects) {
    test::Rng rng(seed);
    b.batch = raster::CommandBatch(width, height);
    b.vertices.resize(static_cast<std::size_t>(objects));
    b.indices.resize(static_cast<std::size_t>(objects));
    const raster::DepthFunc funcs[] = {raster::DepthFunc::Less, raster::DepthFunc::LEqual, raster::DepthFunc::GEqual,
                                       raster::DepthFunc::Greater, raster::DepthFunc::Equal};
    for (int o = 0; o < objects; ++o) {
        auto& v = b.vertices[static_cast<std::size_t>(o)];
        auto& idx = b.indices[static_cast<std::size_t>(o)];
        const float cx = -1.0f + 2.0f * unit_float(rng), cy = -1.0f + 2.0f * unit_float(rng);
        const float size = 0.05f + 0.5f * unit_float(rng);
        const int tris = 1 + static_cast<int>(rng.below(6));
        for (int t = 0; t < 3 * tris; ++t) {
            raster::Float4 p;
            p.w = rng.below(4) == 0 ? 0.5f + 2.0f * unit_float(rng) : 1.0f;
            p.x = (cx + size * (2.0f * unit_float(rng) - 1.0f)) * p.w;
            p.y = (cy + size * (2.0f * unit_float(rng) - 1.0f)) * p.w;
            p.z = (-1.2f + 2.4f * unit_float(rng)) * p.w;  // some cross the near or far plane
            if (rng.below(3) == 0) {
                // Snap to pixel centres of the window, where ties and the fill rule decide.
                p.x = (std::floor((p.x / p.w + 1.0f) * 0.5f * static_cast<float>(width)) + 0.5f) /
                          (0.5f * static_cast<float>(width)) -
                      1.0f;
                p.w = 1.0f;
            }
            v.push_back(p);
            idx.push_back(static_cast<std::uint32_t>(t));
        }
        const raster::MeshView mesh{v, idx};
        raster::DrawState query_state;
        query_state.depth_func = funcs[rng.below(5)];
        query_state.depth_write = false;
        b.batch.begin_query(rng.below(2) == 0 ? raster::QueryKind::SamplesPassed
                                              : raster::QueryKind::AnySamplesPassed);
        b.batch.draw(mesh, query_state);
        b.batch.end_query();
        if (rng.below(4) != 0) {
            raster::DrawState draw;
            draw.depth_func = raster::DepthFunc::LEqual;
            if (rng.below(5) == 0) draw.cull_face = raster::CullFace::Back;
            b.batch.draw(mesh, draw);
        }
    }
}

std::uint64_t raster_digest(const raster::DepthTarget& target, const raster::QueryResults& queries) {
    reliability::Digest d;
    d.u64(target.values().size());
    for (auto v : target.values()) d.u32(v);
    d.u64(queries.size());
    for (auto q : queries) d.u64(q);
    return d.value();
}

// ---- Spatial hash ------------------------------------------------------------------------------

std::vector<spatialhash::Box> random_boxes(std::uint64_t seed, int n) {
    test::Rng rng(seed);
    std::vector<spatialhash::Box> boxes;
    for (int i = 0; i < n; ++i) {
        spatialhash::Box b{};
        const bool giant = i % 500 == 7;
        for (int k = 0; k < 3; ++k) {
            // Corners on a 1/8 grid, so that closed boxes touch exactly in many pairs.
            const double lo = rng.grid(0, 40, 8);
            b.lo[k] = lo;
            b.hi[k] = lo + (giant ? 15.0 : rng.grid(0, 1.5, 8));
        }
        boxes.push_back(b);
    }
    return boxes;
}

std::uint64_t pairs_digest(const std::vector<spatialhash::Pair>& pairs) {
    reliability::Digest d;
    d.u64(pairs.size());
    for (const auto& p : pairs) d.u32(p.a).u32(p.b);
    return d.value();
}

}  // namespace

TEST_CASE("golden digests: scene frames and exact pairs of every built-in scene, for 1, 2, 3 and 8 threads") {
    [[maybe_unused]] AllowThreads allow;
    for (const Row& row : kRows) {
        const std::string scene = row.scene, method = row.method;
        CAPTURE(scene);
        CAPTURE(row.frame);
        CAPTURE(method);
        const cullide::Frame frame = make_frame(row.scene, row.frame);
        const std::uint64_t fd = cullide::frame_digest(frame);
        CHECK(fd == row.frame_digest);
        Outcome first;
        for (const int threads : kThreadCounts) {
            CAPTURE(threads);
            Outcome got = run_method(row.method, frame, row.self, threads);
            // On a mismatch, the row as it would read now (to update the table after a deliberate change).
            CHECK_MESSAGE((got.pairs.size() == row.pair_count && got.digest == row.result_digest),
                          "measured {\"" << std::string(row.scene) << "\", " << row.frame << ", \""
                                        << std::string(row.method) << "\", "
                                        << std::string(row.self ? "true" : "false") << ", " << hex(fd) << ", "
                                        << got.pairs.size() << ", " << hex(got.digest) << "}");
            if (threads == 1) {
                first = std::move(got);
            } else {
                CHECK(got.pairs == first.pairs);
                CHECK(got.digest == first.digest);
            }
        }
        // Under emulation or a sanitizer (CULLIDE_RELIABILITY_QUICK=1) the O(n^2) twin is left to the
        // native run: the literals already tie every platform to the pairs it checked.
        if (method == "exact" && !reliability::quick_mode()) {
            // The pinned pairs are right, not only stable: the brute-force twin agrees.
            CHECK(first.pairs == test::brute_force_pairs(frame, row.self));
        }
    }
}

TEST_CASE("golden digests: the table covers every built-in scene at frames 0 and 5") {
    for (const std::string& name : cullide::scene_names()) {
        CAPTURE(name);
        for (const int f : {0, 5}) {
            CAPTURE(f);
            const bool found = std::any_of(std::begin(kRows), std::end(kRows), [&](const Row& r) {
                return name == r.scene && r.frame == f && std::string(r.method) == "exact";
            });
            CHECK(found);
        }
    }
}

TEST_CASE("golden digests: raster depth buffer and queries, reference vs tiled, scalar vs SIMD, 1 to 8 threads") {
    [[maybe_unused]] AllowThreads allow;
    struct RasterRow {
        raster::DepthFormat format;
        std::uint64_t digest;
    };
    // One fixed batch (seed 20240611, 200 x 150 pixels, 120 objects), cleared to 1.
    const RasterRow rows[] = {
        {raster::DepthFormat::D16, 0x8d21f03dcc6b6ec9ull},
        {raster::DepthFormat::D24, 0x0106598960b2d7d3ull},
        {raster::DepthFormat::D32F, 0x25f36d453b1ed93bull},
    };
    RasterBatch b;
    build_raster_batch(b, 20240611, 200, 150, 120);
    for (const RasterRow& row : rows) {
        CAPTURE(static_cast<int>(row.format));
        for (const bool simd : {false, true}) {
            CAPTURE(simd);
            auto ref = raster::DepthTarget::create(200, 150, row.format);
            REQUIRE(ref.ok());
            REQUIRE(ref.value().clear(1.0).ok());
            auto want = raster::execute_reference(ref.value(), b.batch, raster::ExecuteOptions{1, simd});
            REQUIRE_MESSAGE(want.ok(), want.error().message);
            const std::uint64_t ref_digest = raster_digest(ref.value(), want.value());
            CHECK_MESSAGE(ref_digest == row.digest, "measured " << hex(ref_digest));
            std::uint64_t passed = 0;
            for (auto q : want.value()) passed += q;
            CHECK(passed > 0);  // the batch is not trivially empty
            for (const int threads : kThreadCounts) {
                CAPTURE(threads);
                auto t = raster::DepthTarget::create(200, 150, row.format);
                REQUIRE(t.ok());
                REQUIRE(t.value().clear(1.0).ok());
                auto got = raster::execute(t.value(), b.batch, raster::ExecuteOptions{threads, simd});
                REQUIRE_MESSAGE(got.ok(), got.error().message);
                CHECK(got.value() == want.value());
                CHECK(raster_digest(t.value(), got.value()) == row.digest);
            }
        }
    }
}

TEST_CASE("golden digests: spatial hash pairs for every method and 1, 2, 3 and 8 threads") {
    [[maybe_unused]] AllowThreads allow;
    // 3000 boxes (seed 424242) on a 1/8 grid, with a few giants.
    constexpr std::uint64_t kDigest = 0x534342f7f762b5faull;
    constexpr std::size_t kPairs = 1013;
    const auto boxes = random_boxes(424242, 3000);
    // The independent twin: every pair, the closed-box test written out here.
    std::vector<spatialhash::Pair> want;
    for (std::uint32_t a = 0; a < boxes.size(); ++a) {
        for (std::uint32_t b = a + 1; b < boxes.size(); ++b) {
            bool meet = true;
            for (int k = 0; k < 3; ++k) meet = meet && boxes[a].lo[k] <= boxes[b].hi[k] && boxes[b].lo[k] <= boxes[a].hi[k];
            if (meet) want.push_back({a, b});
        }
    }
    CHECK_MESSAGE(want.size() == kPairs, "measured " << want.size());
    CHECK_MESSAGE(pairs_digest(want) == kDigest, "measured " << hex(pairs_digest(want)));
    for (const auto method :
         {spatialhash::Method::SpatialHash, spatialhash::Method::SweepAndPrune, spatialhash::Method::BruteForce}) {
        for (const int threads : kThreadCounts) {
            CAPTURE(static_cast<int>(method));
            CAPTURE(threads);
            spatialhash::Options o;
            o.method = method;
            o.threads = static_cast<unsigned>(threads);
            auto r = spatialhash::find_pairs(std::span<const spatialhash::Box>(boxes), o);
            REQUIRE(r.ok());
            CHECK(pairs_digest(r.value().pairs) == kDigest);
            CHECK(r.value().pairs == want);
        }
    }
}
