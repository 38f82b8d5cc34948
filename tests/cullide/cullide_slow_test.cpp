// Long checks of the CULLIDE pipeline (LABELS slow): real meshes and the built-in scenes at the
// papers' scale. The reliable methods must report exactly the ground truth; cullide's misses are
// reported per resolution (never hidden) and must never include a false pair.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh_io.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "pipeline_test_util.h"

namespace {

using cullide::Method;
using cullide::TrianglePair;

using test::misses;
using test::run;
using test::truth;

}  // namespace

TEST_CASE("every built-in scene at full scale: reliable modes exact, cullide's misses reported") {
    for (const std::string& name : cullide::scene_names()) {
        cullide::SceneOptions so;
        so.mesh_dir = CULLIDE_SHARED_MESH_DIR;
        auto scene = cullide::make_scene(name, so);
        REQUIRE(scene.ok());
        const cullide::Frame objects = scene.value()->frame(2);
        const auto exact = truth(objects);
        {
            CAPTURE(name);
            CHECK(run(objects, Method::Auto, 0).pairs == exact);  // the default, at the papers' sizes
        }
        for (int resolution : {256, 1024}) {
            CAPTURE(name);
            CAPTURE(resolution);
            CHECK(run(objects, Method::RCullide, resolution).pairs == exact);
            CHECK(run(objects, Method::RCullideOffset, resolution).pairs == exact);
            const std::size_t missed = misses(run(objects, Method::Cullide, resolution).pairs, exact);
            MESSAGE(name << ", resolution " << resolution << ": cullide missed " << missed << " of " << exact.size());
        }
    }
}

TEST_CASE("two interpenetrating real bunnies: reliable modes exact, cullide's misses reported") {
    const std::filesystem::path path = std::filesystem::path(CULLIDE_SHARED_MESH_DIR) / "stanford-bunny.obj";
    if (!std::filesystem::exists(path)) {
        MESSAGE("skipped: " << path.string() << " is absent");
        return;
    }
    auto meshes = cullide::read_mesh_file(path.string());
    REQUIRE(meshes.ok());
    REQUIRE(meshes.value().size() == 1);
    cullide::Mesh a = meshes.value()[0];
    const cullide::Aabb box = cullide::mesh_bounds(a);
    cullide::Mesh b = a;
    b.name = "bunny 2";
    const double shift = 0.3 * (box.hi.x - box.lo.x);  // R-CULLIDE's two interpenetrating bunnies
    for (cullide::Vec3& p : b.positions) p = p + cullide::Vec3{shift, 0.1 * shift, 0.05 * shift};
    const std::vector<cullide::Mesh> objects{a, b};
    const auto exact = truth(objects);
    REQUIRE(exact.size() > 10);
    for (int resolution : {128, 512}) {
        CAPTURE(resolution);
        CHECK(run(objects, Method::RCullide, resolution).pairs == exact);
        CHECK(run(objects, Method::RCullideOffset, resolution).pairs == exact);
        const std::size_t missed = misses(run(objects, Method::Cullide, resolution).pairs, exact);
        MESSAGE("bunnies, resolution " << resolution << ": cullide missed " << missed << " of " << exact.size());
    }
}
