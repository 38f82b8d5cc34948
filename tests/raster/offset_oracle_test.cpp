// offset_oracle_test.cpp: R-CULLIDE's offset boxes are ordinary triangles, so the GL-exact mode and
// real GL (Mesa llvmpipe via OSMesa) must give the same query counts and depth buffers for them,
// bit for bit, in every format: the paper's construction runs on either.
#include <doctest/doctest.h>

#include <cstdint>
#include <deque>
#include <vector>

#include "osmesa_device.h"
#include "raster/raster.h"
#include "test_rng.h"

TEST_CASE("Offset boxes give identical results in the GL-exact mode and in OSMesa") {
    test::Rng rng(777);
    std::size_t queries = 0, mismatched_queries = 0, mismatched_pixels = 0, passed_total = 0;
    for (const auto f : {raster::DepthFormat::D16, raster::DepthFormat::D24, raster::DepthFormat::D32F}) {
        const int w = 96, h = 80;
        auto dev = cullide_oracle::OsmesaDevice::create(w, h, f);
        REQUIRE_MESSAGE(dev.ok(), (dev.ok() ? "" : dev.error().message));
        for (int scene = 0; scene < 8; ++scene) {
            CAPTURE(static_cast<int>(f));
            CAPTURE(scene);
            const auto axis = static_cast<raster::Axis>(scene % 3);
            auto view = raster::make_ortho_view(axis, {0, 0, 0}, {10, 10, 10}, w, h, f);
            REQUIRE(view.ok());
            // Objects: small clusters of triangles; per object either per-triangle boxes or a UOBB.
            std::deque<raster::OffsetMesh> meshes;
            raster::CommandBatch batch(w, h);
            for (int o = 0; o < 30; ++o) {
                const raster::Double3 c{rng.uniform(1, 9), rng.uniform(1, 9), rng.uniform(1, 9)};
                std::vector<raster::Double3> pts;
                std::vector<std::uint32_t> idx;
                for (int k = 0; k < 9; ++k) {
                    pts.push_back(
                        {c.x + rng.uniform(-1, 1), c.y + rng.uniform(-1, 1), c.z + rng.uniform(-1, 1)});
                    idx.push_back(static_cast<std::uint32_t>(k));
                }
                auto m = (o % 2 == 0) ? raster::triangle_offset_boxes(view.value(), pts, idx)
                                      : raster::object_offset_obbs(view.value(), pts, idx, 2);
                REQUIRE(m.ok());
                meshes.push_back(std::move(m.value()));
                raster::DrawState q;
                q.cull_face = raster::CullFace::Front;  // far faces
                q.depth_func = raster::DepthFunc::GEqual;
                q.depth_write = false;
                batch.begin_query(raster::QueryKind::SamplesPassed);
                batch.draw(meshes.back().view(), q);
                batch.end_query();
                raster::DrawState d;
                d.cull_face = raster::CullFace::Back;  // near faces
                d.depth_func = raster::DepthFunc::LEqual;
                batch.draw(meshes.back().view(), d);
            }
            dev.value()->clear(1.0);
            auto gl = dev.value()->run(batch);
            REQUIRE_MESSAGE(gl.ok(), (gl.ok() ? "" : gl.error().message));
            const auto gl_depth = dev.value()->read_depth();
            auto target = raster::DepthTarget::create(w, h, f);
            REQUIRE(target.ok());
            auto ours = raster::execute(target.value(), batch, raster::ExecuteOptions{2});
            REQUIRE(ours.ok());
            REQUIRE(ours.value().size() == gl.value().size());
            for (std::size_t q = 0; q < ours.value().size(); ++q) {
                ++queries;
                passed_total += ours.value()[q];
                if (ours.value()[q] != gl.value()[q]) ++mismatched_queries;
            }
            const auto mine = target.value().values();
            for (std::size_t i = 0; i < mine.size(); ++i)
                if (mine[i] != gl_depth[i]) ++mismatched_pixels;
        }
    }
    MESSAGE("offset boxes vs OSMesa: " << queries << " queries, " << mismatched_queries << " query and "
                                       << mismatched_pixels << " pixel differences");
    CHECK(passed_total > 0);
    CHECK(mismatched_queries == 0);
    CHECK(mismatched_pixels == 0);
}
