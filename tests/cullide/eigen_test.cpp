// Tests of cullide/eigen.h: the Eigen front door returns process_frame's pairs and statistics pair for
// pair (built-in scenes, random cases, several methods, row- and column-major V and F, int, long and
// narrower or unsigned F, Maps and blocks), self_collide equals process_frame with self, and every
// error path gives its message verbatim.
#include "cullide/eigen.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/pipeline.h"
#include "cullide/scenes.h"
#include "test_rng.h"

using cullide::Mesh;
using cullide::Method;
using cullide::RunOptions;

namespace {

template <class Matrix>
Matrix vertices_of(const Mesh& m) {
    Matrix v(static_cast<Eigen::Index>(m.positions.size()), 3);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        for (int k = 0; k < 3; ++k) v(static_cast<Eigen::Index>(i), k) = m.positions[i][k];
    }
    return v;
}

template <class Matrix>
Matrix faces_of(const Mesh& m) {
    using Index = typename Matrix::Scalar;
    Matrix f(static_cast<Eigen::Index>(m.triangles.size()), 3);
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) f(static_cast<Eigen::Index>(i), k) = static_cast<Index>(m.triangles[i][k]);
    }
    return f;
}

using RowV = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using ColV = Eigen::MatrixXd;
using RowFLong = Eigen::Matrix<long, Eigen::Dynamic, 3, Eigen::RowMajor>;
using ColFInt = Eigen::MatrixXi;

cullide::FrameResult reference(const std::vector<Mesh>& objects, const RunOptions& options) {
    cullide::Result<cullide::FrameResult> r = cullide::process_frame(objects, options);
    if (!r) FAIL(r.error().message);
    return std::move(r).value();
}

// The front door's result equals process_frame's: pairs, object pairs, every count of the stats,
// and the matrix holds the same pairs row by row.
void check_same(const cullide::CollideResult& got, const cullide::FrameResult& want) {
    CHECK(got.frame.pairs == want.pairs);
    CHECK(got.frame.object_pairs == want.object_pairs);
    const cullide::FrameStats& a = got.frame.stats;
    const cullide::FrameStats& b = want.stats;
    CHECK(a.objects == b.objects);
    CHECK(a.triangles == b.triangles);
    CHECK(a.candidate_triangles == b.candidate_triangles);
    CHECK(a.exact_tests == b.exact_tests);
    CHECK(a.adjacent_skipped == b.adjacent_skipped);
    CHECK(a.pcs_boxes == b.pcs_boxes);
    CHECK(a.pcs_objects == b.pcs_objects);
    CHECK(a.pcs_subobjects == b.pcs_subobjects);
    CHECK(a.queries == b.queries);
    CHECK(a.triangles_rasterized == b.triangles_rasterized);
    CHECK(a.views.size() == b.views.size());
    REQUIRE(got.pairs.rows() == static_cast<Eigen::Index>(want.pairs.size()));
    for (std::size_t i = 0; i < want.pairs.size(); ++i) {
        const auto r = static_cast<Eigen::Index>(i);
        CHECK(got.pairs(r, 0) == static_cast<int>(want.pairs[i].object_a));
        CHECK(got.pairs(r, 1) == static_cast<int>(want.pairs[i].triangle_a));
        CHECK(got.pairs(r, 2) == static_cast<int>(want.pairs[i].object_b));
        CHECK(got.pairs(r, 3) == static_cast<int>(want.pairs[i].triangle_b));
    }
}

cullide::CollideResult ok(cullide::Result<cullide::CollideResult> r) {
    if (!r) FAIL(r.error().message);
    return std::move(r).value();
}

template <class R>
std::string error_of(const R& r) {
    REQUIRE_FALSE(r.ok());
    return r.error().message;
}

// A random triangle soup in [-1, 1]^3 with a few shared vertices (so indices repeat).
Mesh soup(test::Rng& rng, int triangles, const std::string& name) {
    Mesh m;
    m.name = name;
    const int vertices = triangles * 2 + 1;
    for (int i = 0; i < vertices; ++i) m.positions.push_back({rng.sym(), rng.sym(), rng.sym()});
    for (int t = 0; t < triangles; ++t) {
        m.triangles.push_back({static_cast<std::uint32_t>(rng.below(vertices)),
                               static_cast<std::uint32_t>(rng.below(vertices)),
                               static_cast<std::uint32_t>(rng.below(vertices))});
    }
    return m;
}

}  // namespace

TEST_CASE("the Eigen list form equals process_frame on every built-in scene for several methods") {
    cullide::SceneOptions so;
    so.scale = 0.05;
    const Method methods[] = {Method::Exact, Method::RCullide, Method::Cullide, Method::QCullide};
    std::size_t scenes_with_pairs = 0;
    for (const std::string& name : cullide::scene_names()) {
        auto scene = cullide::make_scene(name, so);
        REQUIRE(scene.ok());
        const std::vector<Mesh> objects = scene.value()->frame(2);
        // Row-major double V with long F for even objects, column-major V with int F for odd ones.
        std::vector<RowV> row_v;
        std::vector<RowFLong> row_f;
        std::vector<ColV> col_v;
        std::vector<ColFInt> col_f;
        for (const Mesh& m : objects) {
            row_v.push_back(vertices_of<RowV>(m));
            row_f.push_back(faces_of<RowFLong>(m));
            col_v.push_back(vertices_of<ColV>(m));
            col_f.push_back(faces_of<ColFInt>(m));
        }
        std::vector<cullide::EigenMeshRef> refs;
        for (std::size_t i = 0; i < objects.size(); ++i) {
            if (i % 2 == 0) refs.emplace_back(row_v[i], row_f[i], objects[i].name);
            else refs.emplace_back(col_v[i], col_f[i], objects[i].name);
        }
        for (Method method : methods) {
            CAPTURE(name);
            CAPTURE(cullide::to_string(method));
            RunOptions o;
            o.method = method;
            o.threads = 2;
            if (method == Method::Cullide) o.resolution = 128;
            const cullide::FrameResult want = reference(objects, o);
            check_same(ok(cullide::collide(refs, o)), want);
            if (method == Method::Exact && !want.pairs.empty()) ++scenes_with_pairs;
        }
        // The two-object form on the first two objects, both layouts.
        if (objects.size() >= 2) {
            CAPTURE(name);
            RunOptions o;
            o.threads = 1;
            const std::vector<Mesh> two = {objects[0], objects[1]};
            const cullide::FrameResult want = reference(two, o);
            check_same(ok(cullide::collide(row_v[0], row_f[0], col_v[1], col_f[1], o)), want);
            check_same(ok(cullide::collide(col_v[0], col_f[0], row_v[1], row_f[1], o)), want);
        }
    }
    // Not vacuous: cylinders, tori and breaking collide in this frame at this scale (bunny-dragon,
    // leaves and cloth have not met yet; they still check the stats and empty results).
    CHECK(scenes_with_pairs >= 3);
}

TEST_CASE("random cases: every storage order, index type, Map and block gives the exact pairs") {
    test::Rng rng(20261125);
    int rounds_with_pairs = 0;
    for (int round = 0; round < 12; ++round) {
        CAPTURE(round);
        const Mesh a = soup(rng, 4 + static_cast<int>(rng.below(40)), "a");
        const Mesh b = soup(rng, 4 + static_cast<int>(rng.below(40)), "b");
        const std::vector<Mesh> objects = {a, b};
        cullide::Result<std::vector<cullide::TrianglePair>> truth = cullide::exact_pairs(objects);
        REQUIRE(truth.ok());

        RunOptions o;
        o.threads = 1 + round % 3;
        o.method = round % 2 == 0 ? Method::Exact : Method::RCullide;
        const cullide::FrameResult want = reference(objects, o);
        CHECK(want.pairs == truth.value());
        rounds_with_pairs += want.pairs.empty() ? 0 : 1;

        const ColV va = vertices_of<ColV>(a);
        const RowV vb = vertices_of<RowV>(b);
        check_same(ok(cullide::collide(va, faces_of<ColFInt>(a), vb, faces_of<RowFLong>(b), o)), want);
        using RowFU32 = Eigen::Matrix<std::uint32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;
        using ColFI16 = Eigen::Matrix<std::int16_t, Eigen::Dynamic, Eigen::Dynamic>;
        using ColFU64 = Eigen::Matrix<std::uint64_t, Eigen::Dynamic, 3>;
        check_same(ok(cullide::collide(va, faces_of<RowFU32>(a), vb, faces_of<ColFU64>(b), o)), want);
        check_same(ok(cullide::collide(va.leftCols(3), faces_of<ColFI16>(a), vb, faces_of<ColFU64>(b).leftCols(3), o)),
                   want);

        // A Map over a flat row-major array (x y z per vertex, as numpy or a vertex buffer holds it)
        // and a block: the first three columns of a wider matrix, columns of a transposed 3 x m F.
        std::vector<double> flat;
        for (const cullide::Vec3& p : a.positions) flat.insert(flat.end(), {p.x, p.y, p.z});
        const Eigen::Map<const RowV> mapped(flat.data(), static_cast<Eigen::Index>(a.positions.size()), 3);
        Eigen::MatrixXd wide(vb.rows(), 5);
        wide.setConstant(std::numeric_limits<double>::quiet_NaN());
        wide.leftCols(3) = vb;
        const Eigen::MatrixXi ft = faces_of<ColFInt>(b).transpose();
        check_same(ok(cullide::collide(mapped, faces_of<ColFInt>(a), wide.leftCols(3), ft.transpose(), o)), want);
    }
    CHECK(rounds_with_pairs >= 6);
}

TEST_CASE("self_collide equals process_frame with self on, for the self-capable methods") {
    cullide::SceneOptions so;
    so.scale = 0.05;
    auto cloth = cullide::make_scene("cloth", so);
    REQUIRE(cloth.ok());
    test::Rng rng(7);
    std::vector<Mesh> cases = {cloth.value()->frame(5)[0], soup(rng, 60, "soup")};
    for (const Mesh& m : cases) {
        for (Method method : {Method::Exact, Method::QCullide, Method::QCullideGL, Method::Auto}) {
            CAPTURE(m.name);
            CAPTURE(cullide::to_string(method));
            RunOptions o;
            o.method = method;
            o.threads = 2;
            if (method == Method::QCullideGL) o.resolution = 128;
            RunOptions with_self = o;
            with_self.self = true;
            const cullide::FrameResult want = reference({m}, with_self);
            check_same(ok(cullide::self_collide(vertices_of<RowV>(m), faces_of<RowFLong>(m), o)), want);
            check_same(ok(cullide::self_collide(vertices_of<ColV>(m), faces_of<ColFInt>(m), o)), want);
        }
    }
    // The soup has self-intersections: the test is not vacuous.
    RunOptions o;
    o.method = Method::Exact;
    CHECK_FALSE(ok(cullide::self_collide(vertices_of<ColV>(cases[1]), faces_of<ColFInt>(cases[1]), o)).frame.pairs.empty());
}

TEST_CASE("bad V or F gives an error naming the object, the mesh, the element and the limit") {
    ColV v(3, 3);
    v << 0, 0, 0, 1, 0, 0, 0, 1, 0;
    ColFInt f(1, 3);
    f << 0, 1, 2;
    RunOptions o;
    o.method = Method::Exact;

    const ColV v2 = v.leftCols(2);
    CHECK(error_of(cullide::collide(v, f, v2, f, o)) ==
          "object 1: mesh 'mesh1': V has 2 columns (expected 3: x y z)");
    Eigen::MatrixXi f4(1, 4);
    f4 << 0, 1, 2, 0;
    CHECK(error_of(cullide::collide(v, f4, v, f, o)) ==
          "object 0: mesh 'mesh0': F has 4 columns (expected 3: the vertex indices of one triangle)");

    ColFInt neg(2, 3);
    neg << 0, 1, 2, 0, -1, 2;
    CHECK(error_of(cullide::collide(v, f, v, neg, o)) ==
          "object 1: mesh 'mesh1': triangle 1 vertex index -1 is negative (the vertex list has size 3)");
    ColFInt beyond(1, 3);
    beyond << 0, 3, 2;
    CHECK(error_of(cullide::collide(v, beyond, v, f, o)) ==
          "object 0: mesh 'mesh0': triangle 0 vertex index 3 is beyond the vertex list (size 3)");
    // Wider than Tri's uint32: refused before narrowing, with the same words.
    RowFLong huge(1, 3);
    huge << 0, 1, 4294967296L;
    CHECK(error_of(cullide::collide(v, f, v, huge, o)) ==
          "object 1: mesh 'mesh1': triangle 0 vertex index 4294967296 is beyond the vertex list (size 3)");
    Eigen::Matrix<std::uint64_t, Eigen::Dynamic, 3> uhuge(1, 3);
    uhuge << 0, 1, std::numeric_limits<std::uint64_t>::max();
    CHECK(error_of(cullide::collide(v, uhuge, v, f, o)) ==
          "object 0: mesh 'mesh0': triangle 0 vertex index 18446744073709551615 is beyond the vertex list (size 3)");

    ColV nan = v;
    nan(2, 1) = std::numeric_limits<double>::quiet_NaN();
    CHECK(error_of(cullide::collide(v, f, nan, f, o)) ==
          "object 1: mesh 'mesh1': vertex 2 has a non-finite coordinate");
    ColV inf = v;
    inf(0, 2) = -std::numeric_limits<double>::infinity();
    CHECK(error_of(cullide::self_collide(inf, f, o)) == "object 0: mesh 'mesh0': vertex 0 has a non-finite coordinate");
    const ColFInt none(0, 3);
    CHECK(error_of(cullide::collide(v, f, v, none, o)) == "object 1: mesh 'mesh1': has no triangles");

    // The list form names meshes as the caller does, else by position.
    CHECK(error_of(cullide::collide({{v, f, "floor"}, {v, f}, {v, neg, "robot arm"}}, o)) ==
          "object 2: mesh 'robot arm': triangle 1 vertex index -1 is negative (the vertex list has size 3)");
    CHECK(error_of(cullide::collide({{v, f, "floor"}, {nan, f}}, o)) ==
          "object 1: mesh 'mesh1': vertex 2 has a non-finite coordinate");

    // Options are process_frame's, with its messages: self-collision needs a method that has it.
    RunOptions rc;
    rc.method = cullide::Method::RCullide;
    CHECK(error_of(cullide::self_collide(v, f, rc)) ==
          "self-collision is not supported by method 'rcullide' (CULLIDE never tests an object against itself); "
          "use method 'qcullide', 'qcullide-gl' or 'exact'");
    RunOptions bad_threads;
    bad_threads.threads = -1;
    CHECK(error_of(cullide::collide(v, f, v, f, bad_threads)) == "threads must be >= 0 (got -1)");
}

TEST_CASE("the pair matrix is empty for no pairs and keeps the canonical order") {
    ColV v(3, 3);
    v << 0, 0, 0, 1, 0, 0, 0, 1, 0;
    ColFInt f(1, 3);
    f << 0, 1, 2;
    ColV far = v;
    far.col(2).setConstant(5.0);
    RunOptions o;
    o.method = Method::Exact;
    const cullide::CollideResult apart = ok(cullide::collide(v, f, far, f, o));
    CHECK(apart.pairs.rows() == 0);
    CHECK(apart.pairs.cols() == 4);
    // The same triangle twice: they touch (coplanar, equal).
    const cullide::CollideResult same = ok(cullide::collide(v, f, v, f, o));
    REQUIRE(same.pairs.rows() == 1);
    CHECK(same.pairs(0, 0) == 0);
    CHECK(same.pairs(0, 1) == 0);
    CHECK(same.pairs(0, 2) == 1);
    CHECK(same.pairs(0, 3) == 0);
}
