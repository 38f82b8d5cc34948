// llvmpipe_scene_test.cpp: the whole-batch disagreement of issue #17, reduced to GL calls.
//
// A CULLIDE pass hands the OSMesa oracle (Mesa 22.3 llvmpipe) one batch of thousands of occlusion
// queries. Issued as one stream of GL commands, llvmpipe answered some query with samples that the
// emulator and the scalar reference do not see; the same stream with a glFlush before every 64th
// glBeginQuery agreed query for query. Under the GL rules glFlush changes no result, so the fault
// is llvmpipe's, not the submission's (docs/raster-known-differences.md, "Whole batches").
//
// The batches come from the Quick-CULLIDE GL-exact pass of the cylinders scene at 1024^2 (frame
// 0, built in, no mesh files): a capturing device records every batch of at least 1000 queries
// with copies of its vertex data, next to the emulator's answers. Each is then run on
// cullide_oracle::OsmesaDevice, which issues plain GL 4.5 calls, once with bounded scenes (the
// device's default) and once as one stream. LP_NUM_THREADS=0 (set before the first GL context of
// this process) bins and rasterizes in one thread, which makes llvmpipe's answer the same on every
// run; with its worker threads the wrong answers come and go from run to run.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cullide/pipeline.h"
#include "cullide/query_device.h"
#include "cullide/scenes.h"
#include "osmesa_device.h"

namespace {

// One batch with its own copy of the vertex and index data (the pass frees its views afterwards).
// Draws that shared a vertex span share its copy, so the oracle lays the buffers out as it did.
struct CapturedBatch {
    std::vector<std::unique_ptr<std::vector<raster::Float4>>> vertices;
    std::vector<std::unique_ptr<std::vector<std::uint32_t>>> indices;
    std::unique_ptr<raster::CommandBatch> batch;
    raster::QueryResults emulator;
};

class CaptureDevice final : public cullide::QueryDevice {
   public:
    explicit CaptureDevice(std::size_t min_queries) : emu_(cullide::make_emulator_device(1)), min_(min_queries) {}
    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        return emu_->clear(width, height, format);
    }
    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        auto r = emu_->execute(batch);
        if (!r.ok() || batch.query_kinds().size() < min_) return r;
        CapturedBatch c;
        c.batch = std::make_unique<raster::CommandBatch>(batch.target_width(), batch.target_height());
        std::map<const raster::Float4*, const std::vector<raster::Float4>*> copy_of;
        for (const raster::Command& cmd : batch.commands()) {
            switch (cmd.kind) {
                case raster::Command::Kind::BeginQuery:
                    (void)c.batch->begin_query(batch.query_kinds()[cmd.query]);
                    break;
                case raster::Command::Kind::EndQuery:
                    c.batch->end_query();
                    break;
                case raster::Command::Kind::Draw: {
                    auto [it, fresh] = copy_of.try_emplace(cmd.mesh.vertices.data(), nullptr);
                    if (fresh) {
                        c.vertices.push_back(std::make_unique<std::vector<raster::Float4>>(
                            cmd.mesh.vertices.begin(), cmd.mesh.vertices.end()));
                        it->second = c.vertices.back().get();
                    }
                    c.indices.push_back(
                        std::make_unique<std::vector<std::uint32_t>>(cmd.mesh.indices.begin(), cmd.mesh.indices.end()));
                    const std::vector<raster::Float4>& v = *it->second;
                    c.batch->draw(raster::MeshView{std::span<const raster::Float4>(v.data(), cmd.mesh.vertices.size()),
                                                   *c.indices.back()},
                                  cmd.state);
                    break;
                }
            }
        }
        c.emulator = r.value();
        captured.push_back(std::move(c));
        return r;
    }
    std::string name() const override { return "capture"; }

    std::vector<CapturedBatch> captured;

   private:
    std::unique_ptr<cullide::QueryDevice> emu_;
    std::size_t min_;
};

}  // namespace

TEST_CASE("llvmpipe over-counts a query of a long batch: a glFlush every 64 queries restores the exact answers") {
    // Before the first OSMesa context of this process: llvmpipe reads it when it makes its screen.
    REQUIRE(setenv("LP_NUM_THREADS", "0", 1) == 0);
    cullide::SceneOptions so;
    so.scale = 1.0;
    so.mesh_dir = "";
    auto scene = cullide::make_scene("cylinders", so);
    REQUIRE(scene.ok());
    const cullide::Frame objects = scene.value()->frame(0);

    CaptureDevice capture(1000);
    cullide::RunOptions o;
    o.method = cullide::Method::QCullideGL;
    o.resolution = 1024;
    o.device = &capture;
    auto frame = cullide::process_frame(objects, o);
    REQUIRE(frame.ok());
    REQUIRE(capture.captured.size() >= 2);

    auto gl = cullide_oracle::OsmesaDevice::create(1024, 1024, raster::DepthFormat::D24);
    REQUIRE(gl.ok());
    std::uint64_t queries = 0, passed = 0, wrong_whole = 0;
    for (std::size_t b = 0; b < capture.captured.size(); ++b) {
        const CapturedBatch& c = capture.captured[b];
        CAPTURE(b);
        gl.value()->set_bounded_scenes(true);
        gl.value()->clear(1.0);
        auto bounded = gl.value()->run(*c.batch);
        REQUIRE(bounded.ok());
        CHECK(bounded.value() == c.emulator);  // bounded scenes: bit for bit the emulator

        gl.value()->set_bounded_scenes(false);
        gl.value()->clear(1.0);
        auto whole = gl.value()->run(*c.batch);
        REQUIRE(whole.ok());
        REQUIRE(whole.value().size() == c.emulator.size());
        for (std::size_t q = 0; q < c.emulator.size(); ++q) {
            queries += 1;
            passed += c.emulator[q] != 0 ? 1 : 0;
            if (whole.value()[q] == c.emulator[q]) continue;
            ++wrong_whole;
            CAPTURE(q);
            // Every disagreement seen is llvmpipe counting samples that no draw of the query has.
            CHECK(whole.value()[q] > c.emulator[q]);
        }
    }
    MESSAGE("queries " << queries << ", passing " << passed << ", wrong as one stream " << wrong_whole);
    CHECK(passed > queries / 10);  // the passes decide something
    // The fault itself (Mesa 22.3.6 llvmpipe). If this fails, the installed Mesa no longer has it:
    // update docs/raster-known-differences.md and this test (the bounded-scene checks stay).
    CHECK(wrong_whole >= 1);
}
