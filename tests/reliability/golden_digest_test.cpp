// golden_digest_test.cpp: pinned digests of every deterministic result, checked for 1, 2, 3 and 8
// threads, the scalar and SIMD raster paths, and (the same literals, built by scripts/cross-aarch64.sh
// and run under qemu) aarch64 as well as x86-64. A digest that moves is a determinism or portability
// bug, or a deliberate change of results: then the literal is updated in the same commit, saying why.
//
// The literals prove "same bits everywhere"; they do not prove the bits are right. That is checked
// here against independent twins: the ground truth against a brute-force loop over every triangle pair
// (no box prefilter, no threads), the broad phase against a plain O(n^2) loop, and the tiled raster
// executor against the scalar reference; the visibility methods' pairs against the ground truth
// (equal for the reliable ones, a subset for the GL-exact ones). Every method of
// cullide::method_names() must have a row per scene and frame (a new method fails until its rows are
// pasted in: CULLIDE_PRINT_GOLDEN=1 prints them).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/query_device.h"
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

// The visibility methods (CULLIDE, R-CULLIDE, ...) cost ~30 ms a run, 60 rows: the unit build checks
// 1 and 3 threads with the pipeline's own device (SIMD kernel where the CPU has it) and 2 threads with
// the kernel forced scalar; golden_digest_full_test (label slow, CULLIDE_GOLDEN_FULL) checks all of
// 1, 2, 3 and 8 threads on both kernels. Every run must give the same pinned row.
#if defined(CULLIDE_GOLDEN_FULL)
#define GOLDEN_CASE(name) "golden digests (full): " name  // distinct ctest names from the unit build
constexpr int kVisibilityThreads[] = {1, 2, 3, 8};
constexpr int kScalarThreads[] = {1, 2, 3, 8};
#else
#define GOLDEN_CASE(name) "golden digests: " name
constexpr int kVisibilityThreads[] = {1, 3};
constexpr int kScalarThreads[] = {2};
#endif

// Lets TBB run 8 workers even on a 2-core machine, so that 3 and 8 threads really happen.
struct AllowThreads {
#if defined(CULLIDE_HAVE_TBB)
    tbb::global_control control{tbb::global_control::max_allowed_parallelism, 8};
#endif
};

// ---- Scenes x methods -------------------------------------------------------------------------

// One pinned row: a built-in scene at scale 0.05 with procedural stand-ins (no ../shared meshes), one
// frame, one method of cullide::method_names(). `result_digest` digests the pair list and the method's
// deterministic counts (exact: its ExactStats; visibility methods: candidate triangles and exact
// tests); `pcs_digest` digests the PCS sizes and query counts of the visibility methods (0 for exact,
// which has no PCS). Kept apart so that a change of the culling (PCS sizes) shows apart from a change
// of the answer (pairs). Visibility methods run at kResolution pixels per view, D24.
struct Row {
    const char* scene;
    int frame;
    const char* method;
    bool self;  // exact only: self pairs too (cloth); the visibility methods never test self pairs
    std::uint64_t frame_digest;
    std::uint64_t pair_count;
    std::uint64_t result_digest;
    std::uint64_t pcs_digest;
};

constexpr int kResolution = 32;
constexpr int kFrames[] = {0, 5};

// CULLIDE_PRINT_GOLDEN=1 build/bin/golden_digest_test -tc='*every built-in scene*' prints the whole table as it reads now,
// in this order (scene_names() x frames x method_names()), to paste here after a deliberate change.
// clang-format off
constexpr Row kRows[] = {
    {"cylinders", 0, "exact", false, 0x69317a89632646d0ull, 57, 0xb75082e0ef150da9ull, 0},
    {"cylinders", 0, "cullide", false, 0x69317a89632646d0ull, 19, 0xdf302eb03a4aa48eull, 0x7cc16c28792a979full},
    {"cylinders", 0, "rcullide", false, 0x69317a89632646d0ull, 57, 0x8d9c53c700cedd7cull, 0xf8ce08f0a4a0ad1bull},
    {"cylinders", 0, "rcullide-offset", false, 0x69317a89632646d0ull, 57, 0xa451d5e001ec7dadull, 0xd4fd77148a52cebfull},
    {"cylinders", 0, "qcullide", false, 0x69317a89632646d0ull, 57, 0xcfc891e700bbe81dull, 0x7ee4839893f6026dull},
    {"cylinders", 0, "qcullide-gl", false, 0x69317a89632646d0ull, 7, 0x00c3c6afa99bd5deull, 0x6e452726fd5254f4ull},
    {"cylinders", 0, "auto", false, 0x69317a89632646d0ull, 57, 0x0778b68ff0c5bb8cull, 0xb9b23f3a46fd0825ull},
    {"cylinders", 5, "exact", false, 0x26a61df84cfe3965ull, 166, 0xd8c26e85e2d1cd21ull, 0},
    {"cylinders", 5, "cullide", false, 0x26a61df84cfe3965ull, 81, 0x4c58ec5d512a2a31ull, 0xe8edbd5d44a6d813ull},
    {"cylinders", 5, "rcullide", false, 0x26a61df84cfe3965ull, 166, 0x71544c191a961c63ull, 0x1510e99cfcec2136ull},
    {"cylinders", 5, "rcullide-offset", false, 0x26a61df84cfe3965ull, 166, 0x8ffa67fda61e0043ull, 0x39a8ccc5460cbc03ull},
    {"cylinders", 5, "qcullide", false, 0x26a61df84cfe3965ull, 166, 0xacddd756671fbbceull, 0x3a1c43c6060eac6dull},
    {"cylinders", 5, "qcullide-gl", false, 0x26a61df84cfe3965ull, 12, 0x32a196fa91f8d3d8ull, 0x66bd5131ca79211full},
    {"cylinders", 5, "auto", false, 0x26a61df84cfe3965ull, 166, 0x79adcc85db4195e8ull, 0xb9b23f3a46fd0825ull},
    {"tori", 0, "exact", false, 0xdf006acf8e9e7225ull, 1058, 0x53a8ed44976595e0ull, 0},
    {"tori", 0, "cullide", false, 0xdf006acf8e9e7225ull, 0, 0x81d23fd7003c2305ull, 0x79a8bb84d4b04269ull},
    {"tori", 0, "rcullide", false, 0xdf006acf8e9e7225ull, 1058, 0x05567f87436f02e6ull, 0xa325585d21d23a59ull},
    {"tori", 0, "rcullide-offset", false, 0xdf006acf8e9e7225ull, 1058, 0x0737295ff4bfad98ull, 0x2bfcbcb34e3b8ff0ull},
    {"tori", 0, "qcullide", false, 0xdf006acf8e9e7225ull, 1058, 0x15be4e3f3668fbffull, 0x05932f1601548745ull},
    {"tori", 0, "qcullide-gl", false, 0xdf006acf8e9e7225ull, 0, 0x81d23fd7003c2305ull, 0xbb983704a4644dc8ull},
    {"tori", 0, "auto", false, 0xdf006acf8e9e7225ull, 1058, 0xb24545163b6c39c2ull, 0xb9b23f3a46fd0825ull},
    {"tori", 5, "exact", false, 0x710d2db0403cfd3aull, 1002, 0x2897d4d6b36726d8ull, 0},
    {"tori", 5, "cullide", false, 0x710d2db0403cfd3aull, 7, 0x266ba02da4a1bd2aull, 0x2aa1c2a5e0bf1c47ull},
    {"tori", 5, "rcullide", false, 0x710d2db0403cfd3aull, 1002, 0xfcf50154a2351f34ull, 0xc824b496b83c5cf5ull},
    {"tori", 5, "rcullide-offset", false, 0x710d2db0403cfd3aull, 1002, 0x48df4e88a1300481ull, 0x9b4f8fb9e34cdf33ull},
    {"tori", 5, "qcullide", false, 0x710d2db0403cfd3aull, 1002, 0x434085b8baa6ba4full, 0x2353fe911a2398a4ull},
    {"tori", 5, "qcullide-gl", false, 0x710d2db0403cfd3aull, 0, 0x81d23fd7003c2305ull, 0x3021f9a890f49384ull},
    {"tori", 5, "auto", false, 0x710d2db0403cfd3aull, 1002, 0xa7427cedf012a346ull, 0xb9b23f3a46fd0825ull},
    {"bunny-dragon", 0, "exact", false, 0xc4e801f5da59f7d9ull, 0, 0xf66d9459ba2a9a37ull, 0},
    {"bunny-dragon", 0, "cullide", false, 0xc4e801f5da59f7d9ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"bunny-dragon", 0, "rcullide", false, 0xc4e801f5da59f7d9ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"bunny-dragon", 0, "rcullide-offset", false, 0xc4e801f5da59f7d9ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"bunny-dragon", 0, "qcullide", false, 0xc4e801f5da59f7d9ull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"bunny-dragon", 0, "qcullide-gl", false, 0xc4e801f5da59f7d9ull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"bunny-dragon", 0, "auto", false, 0xc4e801f5da59f7d9ull, 0, 0x81d23fd7003c2305ull, 0xb9b23f3a46fd0825ull},
    {"bunny-dragon", 5, "exact", false, 0x094d564c6dbf2928ull, 0, 0xf66d9459ba2a9a37ull, 0},
    {"bunny-dragon", 5, "cullide", false, 0x094d564c6dbf2928ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"bunny-dragon", 5, "rcullide", false, 0x094d564c6dbf2928ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"bunny-dragon", 5, "rcullide-offset", false, 0x094d564c6dbf2928ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"bunny-dragon", 5, "qcullide", false, 0x094d564c6dbf2928ull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"bunny-dragon", 5, "qcullide-gl", false, 0x094d564c6dbf2928ull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"bunny-dragon", 5, "auto", false, 0x094d564c6dbf2928ull, 0, 0x81d23fd7003c2305ull, 0xb9b23f3a46fd0825ull},
    {"breaking", 0, "exact", false, 0xb6645b94696fa191ull, 5225, 0xb147e5ab8d8dced4ull, 0},
    {"breaking", 0, "cullide", false, 0xb6645b94696fa191ull, 0, 0x81d23fd7003c2305ull, 0xdbb129feb3ba45c6ull},
    {"breaking", 0, "rcullide", false, 0xb6645b94696fa191ull, 5225, 0x63426ce2aad1a2fcull, 0x08bcb8fe48529f0bull},
    {"breaking", 0, "rcullide-offset", false, 0xb6645b94696fa191ull, 5225, 0x40d32695a39125baull, 0x771df5083e7350bbull},
    {"breaking", 0, "qcullide", false, 0xb6645b94696fa191ull, 5225, 0xe412dd9f4c9914f8ull, 0x03c879737aa1fce0ull},
    {"breaking", 0, "qcullide-gl", false, 0xb6645b94696fa191ull, 0, 0x81d23fd7003c2305ull, 0x4d6462f2dd1c9484ull},
    {"breaking", 0, "auto", false, 0xb6645b94696fa191ull, 5225, 0x8771211b75e3497dull, 0xb9b23f3a46fd0825ull},
    {"breaking", 5, "exact", false, 0xc439bc1415a1def8ull, 5225, 0xb147e5ab8d8dced4ull, 0},
    {"breaking", 5, "cullide", false, 0xc439bc1415a1def8ull, 0, 0x81d23fd7003c2305ull, 0xdbb129feb3ba45c6ull},
    {"breaking", 5, "rcullide", false, 0xc439bc1415a1def8ull, 5225, 0x63426ce2aad1a2fcull, 0x08bcb8fe48529f0bull},
    {"breaking", 5, "rcullide-offset", false, 0xc439bc1415a1def8ull, 5225, 0x40d32695a39125baull, 0x771df5083e7350bbull},
    {"breaking", 5, "qcullide", false, 0xc439bc1415a1def8ull, 5225, 0xe412dd9f4c9914f8ull, 0x1f8cde8c2c48be31ull},
    {"breaking", 5, "qcullide-gl", false, 0xc439bc1415a1def8ull, 0, 0x81d23fd7003c2305ull, 0x4d6462f2dd1c9484ull},
    {"breaking", 5, "auto", false, 0xc439bc1415a1def8ull, 5225, 0x8771211b75e3497dull, 0xb9b23f3a46fd0825ull},
    {"leaves", 0, "exact", false, 0xab850e61547e8565ull, 0, 0xce6e4b4b6f1d7881ull, 0},
    {"leaves", 0, "cullide", false, 0xab850e61547e8565ull, 0, 0x81d23fd7003c2305ull, 0x75abe812658baf55ull},
    {"leaves", 0, "rcullide", false, 0xab850e61547e8565ull, 0, 0x81d23fd7003c2305ull, 0x53a5a95c6106d91aull},
    {"leaves", 0, "rcullide-offset", false, 0xab850e61547e8565ull, 0, 0x81d23fd7003c2305ull, 0x92b32b3272701889ull},
    {"leaves", 0, "qcullide", false, 0xab850e61547e8565ull, 0, 0x81d23fd7003c2305ull, 0x7a5359f4b48f3543ull},
    {"leaves", 0, "qcullide-gl", false, 0xab850e61547e8565ull, 0, 0x81d23fd7003c2305ull, 0x7a5359f4b48f3543ull},
    {"leaves", 0, "auto", false, 0xab850e61547e8565ull, 0, 0x81d23fd7003c2305ull, 0xb9b23f3a46fd0825ull},
    {"leaves", 5, "exact", false, 0x0841066c2cade3ffull, 0, 0xce6e4b4b6f1d7881ull, 0},
    {"leaves", 5, "cullide", false, 0x0841066c2cade3ffull, 0, 0x81d23fd7003c2305ull, 0x53a5a95c6106d91aull},
    {"leaves", 5, "rcullide", false, 0x0841066c2cade3ffull, 0, 0x81d23fd7003c2305ull, 0xe7c8bde6624df075ull},
    {"leaves", 5, "rcullide-offset", false, 0x0841066c2cade3ffull, 0, 0x81d23fd7003c2305ull, 0x541aaf0cb45fe8a1ull},
    {"leaves", 5, "qcullide", false, 0x0841066c2cade3ffull, 0, 0x81d23fd7003c2305ull, 0x7a5359f4b48f3543ull},
    {"leaves", 5, "qcullide-gl", false, 0x0841066c2cade3ffull, 0, 0x81d23fd7003c2305ull, 0x7a5359f4b48f3543ull},
    {"leaves", 5, "auto", false, 0x0841066c2cade3ffull, 0, 0x81d23fd7003c2305ull, 0xb9b23f3a46fd0825ull},
    {"cloth", 0, "exact", true, 0xd2f123b3c2cfede6ull, 0, 0xe3eed39028ac42c9ull, 0},
    {"cloth", 0, "cullide", false, 0xd2f123b3c2cfede6ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"cloth", 0, "rcullide", false, 0xd2f123b3c2cfede6ull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"cloth", 0, "rcullide-offset", false, 0xd2f123b3c2cfede6ull, 0, 0x81d23fd7003c2305ull, 0x97637a5be02dc8d3ull},
    {"cloth", 0, "qcullide", false, 0xd2f123b3c2cfede6ull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"cloth", 0, "qcullide-gl", false, 0xd2f123b3c2cfede6ull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"cloth", 0, "auto", false, 0xd2f123b3c2cfede6ull, 0, 0x81d23fd7003c2305ull, 0xb9b23f3a46fd0825ull},
    {"cloth", 5, "exact", true, 0x8a37d16cc90bfd7cull, 0, 0x6d3ac5c95cdaa187ull, 0},
    {"cloth", 5, "cullide", false, 0x8a37d16cc90bfd7cull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"cloth", 5, "rcullide", false, 0x8a37d16cc90bfd7cull, 0, 0x81d23fd7003c2305ull, 0xb8840f7e19c8c648ull},
    {"cloth", 5, "rcullide-offset", false, 0x8a37d16cc90bfd7cull, 0, 0x81d23fd7003c2305ull, 0x7802882d2db4ca76ull},
    {"cloth", 5, "qcullide", false, 0x8a37d16cc90bfd7cull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"cloth", 5, "qcullide-gl", false, 0x8a37d16cc90bfd7cull, 0, 0x81d23fd7003c2305ull, 0xc4207c21fa11b37cull},
    {"cloth", 5, "auto", false, 0x8a37d16cc90bfd7cull, 0, 0x81d23fd7003c2305ull, 0xb9b23f3a46fd0825ull},
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
    REQUIRE_MESSAGE(gen.ok(), (gen.ok() ? std::string() : gen.error().message));
    return gen.value()->frame(frame);
}

struct Outcome {
    std::vector<TrianglePair> pairs;
    std::uint64_t digest = 0;
    std::uint64_t pcs = 0;
};

// The built-in emulator device with the raster kernel choice exposed: allow_simd = false forces the
// portable (scalar) kernel, true lets raster dispatch to its AVX2+FMA kernel where the CPU has it.
class KernelDevice final : public cullide::QueryDevice {
   public:
    KernelDevice(int threads, bool allow_simd) : options_{threads, allow_simd} {}
    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        auto t = raster::DepthTarget::create(width, height, format);
        if (!t) return cullide::Error{t.error().message};
        target_.emplace(std::move(t).value());
        return cullide::Status{};
    }
    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        if (!target_) return cullide::Error{"execute before clear"};
        auto r = raster::execute(*target_, batch, options_);
        if (!r) return cullide::Error{r.error().message};
        return std::move(r).value();
    }
    std::string name() const override { return "golden kernel device"; }

   private:
    raster::ExecuteOptions options_;
    std::optional<raster::DepthTarget> target_;
};

// Runs one method. `simd`: nullopt = the pipeline's own emulator device; true / false = KernelDevice
// with SIMD allowed / forced off.
Outcome run_method(const std::string& method, const cullide::Frame& frame, bool self, int threads,
                   std::optional<bool> simd = std::nullopt) {
    Outcome out;
    if (method == "exact") {
        cullide::ExactStats stats;
        auto r = cullide::exact_pairs(frame, cullide::ExactOptions{self, threads}, &stats);
        REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
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
    // Every other method through the front door (visibility methods: CULLIDE, R-CULLIDE, ...).
    auto parsed = cullide::parse_method(method);
    REQUIRE_MESSAGE(parsed.ok(), (parsed.ok() ? std::string() : parsed.error().message));
    cullide::RunOptions o;
    o.method = parsed.value();
    o.threads = threads;
    o.resolution = kResolution;
    std::optional<KernelDevice> device;
    if (simd) {
        device.emplace(threads, *simd);
        o.device = &*device;
    }
    auto r = cullide::process_frame(std::span<const cullide::Mesh>(frame), o);
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? std::string() : r.error().message));
    const cullide::FrameStats& st = r.value().stats;
    out.pairs = std::move(r).value().pairs;
    out.digest = reliability::Digest{}.pairs(out.pairs).u64(st.candidate_triangles).u64(st.exact_tests).value();
    out.pcs = reliability::Digest{}
                  .u64(st.pcs_boxes)
                  .u64(st.pcs_objects)
                  .u64(st.subobjects)
                  .u64(st.pcs_subobjects)
                  .u64(st.subobject_pairs)
                  .u64(st.queries)
                  .u64(st.triangles_rasterized)
                  .u64(st.views.size())
                  .value();
    return out;
}

std::string row_text(const std::string& scene, int frame, const std::string& method, bool self, std::uint64_t fd,
                     const Outcome& got) {
    std::ostringstream s;
    s << "{\"" << scene << "\", " << frame << ", \"" << method << "\", " << (self ? "true" : "false") << ", "
      << hex(fd) << ", " << got.pairs.size() << ", " << hex(got.digest) << ", " << (got.pcs == 0 ? "0" : hex(got.pcs))
      << "},";
    return s.str();
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

TEST_CASE(GOLDEN_CASE("every built-in scene and method, 1, 2, 3 and 8 threads, scalar and SIMD raster")) {
    [[maybe_unused]] AllowThreads allow;
    const bool print = std::getenv("CULLIDE_PRINT_GOLDEN") != nullptr;
    if (print) std::cout << "// golden rows (CULLIDE_PRINT_GOLDEN=1), to paste into kRows:\n";
    int compared = 0;
    for (const std::string& scene : cullide::scene_names()) {
        for (const int frame_index : kFrames) {
            const cullide::Frame frame = make_frame(scene.c_str(), frame_index);
            const std::uint64_t fd = cullide::frame_digest(frame);
            std::vector<TrianglePair> exact;  // the ground truth of this frame (method_names() starts with exact)
            for (const std::string& method : cullide::method_names()) {
                CAPTURE(scene);
                CAPTURE(frame_index);
                CAPTURE(method);
                const bool self = method == "exact" && scene == "cloth";  // self pairs: exact only
                const Row* row = nullptr;
                for (const Row& r : kRows)
                    if (scene == r.scene && r.frame == frame_index && method == r.method) row = &r;
                // Visibility methods: the pipeline's own device, then the kernel forced scalar.
                std::vector<std::optional<bool>> kernels{std::nullopt};
                if (method != "exact") kernels.push_back(false);
                Outcome first;
                bool have_first = false;
                for (const auto kernel : kernels) {
                    std::vector<int> thread_counts(std::begin(kThreadCounts), std::end(kThreadCounts));
                    if (method != "exact" && !kernel)
                        thread_counts.assign(std::begin(kVisibilityThreads), std::end(kVisibilityThreads));
                    if (method != "exact" && kernel)
                        thread_counts.assign(std::begin(kScalarThreads), std::end(kScalarThreads));
                    for (const int threads : thread_counts) {
                        CAPTURE(threads);
                        const std::string kernel_name = !kernel ? "default" : (*kernel ? "simd" : "scalar");
                        CAPTURE(kernel_name);
                        Outcome got = run_method(method, frame, self, threads, kernel);
                        if (!have_first) {
                            first = std::move(got);
                            have_first = true;
                            if (print) std::cout << "    " << row_text(scene, frame_index, method, self, fd, first) << "\n";
                            continue;
                        }
                        CHECK(got.pairs == first.pairs);
                        CHECK(got.digest == first.digest);
                        CHECK(got.pcs == first.pcs);
                    }
                }
                if (method == "exact") {
                    // The visibility methods are compared with the pairs between objects only.
                    exact = self ? run_method("exact", frame, false, 1).pairs : first.pairs;
                    // Under emulation or a sanitizer (CULLIDE_RELIABILITY_QUICK=1) the O(n^2) twin is left to
                    // the native run: the literals already tie every platform to the pairs it checked.
                    if (!reliability::quick_mode()) CHECK(first.pairs == test::brute_force_pairs(frame, self));
                } else if (method.rfind("rcullide", 0) == 0 || method == "qcullide") {
                    CHECK(first.pairs == exact);  // R-CULLIDE and Q-CULLIDE (exact-bounds) never miss
                } else {
                    // GL-exact methods may miss pairs but never report a pair that does not collide.
                    CHECK(std::includes(exact.begin(), exact.end(), first.pairs.begin(), first.pairs.end()));
                }
                if (print) continue;
                // On a mismatch, the row as it would read now (to update the table after a deliberate
                // change; CULLIDE_PRINT_GOLDEN=1 prints them all).
                const std::string measured = row_text(scene, frame_index, method, self, fd, first);
                REQUIRE_MESSAGE(row != nullptr, "no golden row; measured " << measured);
                CHECK(row->self == self);
                CHECK_MESSAGE(fd == row->frame_digest, "measured " << measured);
                CHECK_MESSAGE((first.pairs.size() == row->pair_count && first.digest == row->result_digest),
                              "pairs changed; measured " << measured);
                CHECK_MESSAGE(first.pcs == row->pcs_digest, "PCS sizes changed; measured " << measured);
                ++compared;
            }
        }
    }
    if (!print) CHECK(compared == static_cast<int>(std::size(kRows)));  // no stale rows left in the table
}

TEST_CASE(GOLDEN_CASE("raster depth buffer and queries, reference vs tiled, scalar vs SIMD, 1 to 8 threads")) {
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
            REQUIRE_MESSAGE(want.ok(), (want.ok() ? std::string() : want.error().message));
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
                REQUIRE_MESSAGE(got.ok(), (got.ok() ? std::string() : got.error().message));
                CHECK(got.value() == want.value());
                CHECK(raster_digest(t.value(), got.value()) == row.digest);
            }
        }
    }
}

TEST_CASE(GOLDEN_CASE("spatial hash pairs for every method and 1, 2, 3 and 8 threads")) {
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
