// cullide/eigen.h: the front door for meshes held as libigl-style Eigen matrices.
//
//   V: n x 3 double, one vertex per row (x y z).     F: m x 3 integers, one triangle per row,
//   0-based vertex indices into V (libigl's convention).
//
// collide(V1, F1, V2, F2, options), collide({{V1, F1}, {V2, F2}, ...}, options) and
// self_collide(V, F, options) run one frame through process_frame (cullide/pipeline.h) and return
// its result unchanged, plus the pairs as an m x 4 int matrix. Objects are numbered in argument order
// and triangles by F's row, so a pair names (object, row of F, object, row of F).
//
// Header only: the compiled library does not use Eigen. Link the CMake target cullide::eigen
// (cullide::cullide + Eigen3::Eigen) to use this header.
//
// What is copied, and why. Mesh (cullide/mesh.h) owns its positions and triangles in std::vectors,
// and every method takes Meshes, so each V and F is copied once, element by element, straight from
// the caller's storage into the Mesh: V into Mesh::positions (doubles unchanged, bit for bit), F into
// Mesh::triangles (each index range-checked and narrowed to uint32). Nothing else is copied: the
// matrices are read in place through Eigen's coefficient access, whatever their storage order,
// strides or index type (row-major, column-major, Map, Ref, blocks, int, long, unsigned ...). That is
// why the parameters are Eigen::MatrixBase templates and not Eigen::Ref<const Eigen::MatrixXd>: a Ref
// to a column-major double matrix binds a row-major matrix (or an int F to an index type it does not
// match) by first copying it into a hidden temporary, a second copy. "Without copying where the layout
// allows" is not possible with the present Mesh even for row-major n x 3 doubles, whose bytes equal
// Mesh::positions' layout: the vector must own them. The result's pairs are moved out of
// process_frame, not copied; the int matrix is built from them (one row per pair). Measured cost of
// the copy (docs/eigen.md): about 3 ns per triangle, 0.5 to 1.5 % of a 1-thread rcullide frame on the
// built-in scenes with contact, up to about a quarter of a frame the box stage ends at once.
//
// Errors name the object (its position in the argument list), the mesh name ("mesh<i>" unless the
// caller names it) and the element, worded as validate_mesh and the file readers word them:
//   object 1: mesh 'mesh1': F has 4 columns (expected 3: the vertex indices of one triangle)
//   object 0: mesh 'mesh0': V has 2 columns (expected 3: x y z)
//   object 0: mesh 'mesh0': triangle 5 vertex index -1 is negative (the vertex list has size 8)
//   object 0: mesh 'mesh0': triangle 5 vertex index 8 is beyond the vertex list (size 8)
//   object 0: mesh 'mesh0': vertex 3 has a non-finite coordinate
//   object 0: mesh 'mesh0': has no triangles
// Checked in this order: column counts, indices a uint32 cannot hold (negative, >= 2^32), then
// process_frame's own validation (no triangles, non-finite positions, indices beyond V, the exact
// predicates' range, the options). A failed call changes nothing the caller can see.
//
// Determinism: unchanged. The positions reach the methods as the very doubles of V, so every call
// returns the same bits as process_frame on the same meshes (and as the CLI on the same data), for
// any thread count, storage order and index type (tests/cullide/eigen_test.cpp checks this pair for
// pair against process_frame and exact_pairs).
//
// Lifetimes: the functions read V and F during the call only. EigenMeshRef (the list form) refers to
// the caller's matrices without owning them: they must outlive the collide call; a braced list
// written in the call itself is always fine.
#pragma once

#include <Eigen/Core>

#include <climits>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/pipeline.h"
#include "cullide/result.h"

namespace cullide {

// Colliding triangle pairs, one per row: object_a, triangle_a, object_b, triangle_b (the order and
// canonical form of TrianglePair: rows sorted, object_a <= object_b).
using PairMatrix = Eigen::Matrix<int, Eigen::Dynamic, 4>;

struct CollideResult {
    FrameResult frame;  // exactly what process_frame returns: pairs, object_pairs, stats
    PairMatrix pairs;   // frame.pairs as a matrix
};

namespace eigen_detail {

template <class DerivedV, class DerivedF>
constexpr void check_types() {
    static_assert(std::is_same_v<typename DerivedV::Scalar, double>,
                  "cullide: V must hold double (the positions are kept bit for bit; convert with .cast<double>())");
    static_assert(std::is_integral_v<typename DerivedF::Scalar> && !std::is_same_v<typename DerivedF::Scalar, bool>,
                  "cullide: F must hold an integer type (0-based vertex indices)");
    static_assert(DerivedV::ColsAtCompileTime == Eigen::Dynamic || DerivedV::ColsAtCompileTime == 3,
                  "cullide: V must have 3 columns (x y z)");
    static_assert(DerivedF::ColsAtCompileTime == Eigen::Dynamic || DerivedF::ColsAtCompileTime == 3,
                  "cullide: F must have 3 columns (one triangle per row)");
}

// Copies V and F into `mesh` (whose name is set): the one copy of the front door. Checks what the
// Mesh cannot represent; the rest is left to process_frame's validate_scene.
template <class DerivedV, class DerivedF>
Status copy_into_mesh(const Eigen::MatrixBase<DerivedV>& V, const Eigen::MatrixBase<DerivedF>& F, Mesh& mesh) {
    check_types<DerivedV, DerivedF>();
    using Index = typename DerivedF::Scalar;
    const std::string who = "mesh '" + mesh.name + "'";
    if (V.cols() != 3) {
        return Error{who + ": V has " + std::to_string(V.cols()) + " columns (expected 3: x y z)"};
    }
    if (F.cols() != 3) {
        return Error{who + ": F has " + std::to_string(F.cols()) +
                     " columns (expected 3: the vertex indices of one triangle)"};
    }
    // The pair matrix holds int triangle numbers.
    if (F.rows() > INT_MAX) {
        return Error{who + ": F has " + std::to_string(F.rows()) + " rows (limit " + std::to_string(INT_MAX) + ")"};
    }
    const DerivedV& v = V.derived();
    const DerivedF& f = F.derived();
    mesh.positions.resize(static_cast<std::size_t>(v.rows()));
    for (Eigen::Index i = 0; i < v.rows(); ++i) {
        mesh.positions[static_cast<std::size_t>(i)] = Vec3{v.coeff(i, 0), v.coeff(i, 1), v.coeff(i, 2)};
    }
    mesh.triangles.resize(static_cast<std::size_t>(f.rows()));
    for (Eigen::Index i = 0; i < f.rows(); ++i) {
        Tri& t = mesh.triangles[static_cast<std::size_t>(i)];
        for (Eigen::Index k = 0; k < 3; ++k) {
            const Index index = f.coeff(i, k);
            if constexpr (std::is_signed_v<Index>) {
                if (index < 0) return vertex_index_error(mesh, static_cast<std::size_t>(i), std::int64_t{index});
            }
            const auto wide = static_cast<std::uint64_t>(index);
            if (wide > UINT32_MAX) return vertex_index_error(mesh, static_cast<std::size_t>(i), wide);
            t[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(wide);
        }
    }
    return {};
}

}  // namespace eigen_detail

// One mesh of the list form: a non-owning reference to the caller's V and F (any types accepted by
// collide(V1, F1, V2, F2, ...)). They must outlive the collide call that reads them. `name` appears
// in messages; empty means "mesh<i>", i its position in the list.
class EigenMeshRef {
 public:
    template <class DerivedV, class DerivedF>
    EigenMeshRef(const Eigen::MatrixBase<DerivedV>& V, const Eigen::MatrixBase<DerivedF>& F, std::string name = {})
        : v_(&V.derived()), f_(&F.derived()), name_(std::move(name)), copy_(&copy<DerivedV, DerivedF>) {
        eigen_detail::check_types<DerivedV, DerivedF>();
    }

    // Copies the referenced matrices into `mesh` (eigen_detail::copy_into_mesh).
    [[nodiscard]] Status copy_into(Mesh& mesh) const { return copy_(v_, f_, mesh); }
    [[nodiscard]] const std::string& name() const { return name_; }

 private:
    template <class DerivedV, class DerivedF>
    static Status copy(const void* v, const void* f, Mesh& mesh) {
        return eigen_detail::copy_into_mesh(*static_cast<const DerivedV*>(v), *static_cast<const DerivedF*>(f), mesh);
    }

    const void* v_;
    const void* f_;
    std::string name_;
    Status (*copy_)(const void*, const void*, Mesh&);
};

// The pairs of a frame as an m x 4 matrix (object_a, triangle_a, object_b, triangle_b per row).
// Indices fit: the front door refuses more than INT_MAX triangles per object or objects.
[[nodiscard]] inline PairMatrix pair_matrix(std::span<const TrianglePair> pairs) {
    PairMatrix m(static_cast<Eigen::Index>(pairs.size()), 4);
    for (std::size_t i = 0; i < pairs.size(); ++i) {
        const TrianglePair& p = pairs[i];
        const auto r = static_cast<Eigen::Index>(i);
        m(r, 0) = static_cast<int>(p.object_a);
        m(r, 1) = static_cast<int>(p.triangle_a);
        m(r, 2) = static_cast<int>(p.object_b);
        m(r, 3) = static_cast<int>(p.triangle_b);
    }
    return m;
}

// The meshes of the list, copied (once each), named, checked as described at the top.
[[nodiscard]] inline Result<std::vector<Mesh>> to_meshes(std::span<const EigenMeshRef> meshes) {
    if (meshes.size() > INT_MAX) return Error{"too many objects (limit " + std::to_string(INT_MAX) + ")"};
    std::vector<Mesh> out(meshes.size());
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        out[i].name = meshes[i].name().empty() ? "mesh" + std::to_string(i) : meshes[i].name();
        if (Status s = meshes[i].copy_into(out[i]); !s) {
            return Error{"object " + std::to_string(i) + ": " + s.error().message};
        }
    }
    return out;
}

// Runs process_frame on the given meshes; the result holds its FrameResult and the pair matrix.
[[nodiscard]] inline Result<CollideResult> collide(std::span<const EigenMeshRef> meshes, const RunOptions& options) {
    Result<std::vector<Mesh>> objects = to_meshes(meshes);
    if (!objects) return objects.error();
    Result<FrameResult> frame = process_frame(objects.value(), options);
    if (!frame) return frame.error();
    CollideResult result{std::move(frame).value(), {}};
    result.pairs = pair_matrix(result.frame.pairs);
    return result;
}

[[nodiscard]] inline Result<CollideResult> collide(std::initializer_list<EigenMeshRef> meshes,
                                                   const RunOptions& options) {
    return collide(std::span<const EigenMeshRef>(meshes.begin(), meshes.size()), options);
}

// Two objects: mesh0 = (V1, F1), mesh1 = (V2, F2). Pairs inside one object are reported only when
// options.self is set (and the method supports it, as for process_frame).
template <class DerivedV1, class DerivedF1, class DerivedV2, class DerivedF2>
[[nodiscard]] Result<CollideResult> collide(const Eigen::MatrixBase<DerivedV1>& V1, const Eigen::MatrixBase<DerivedF1>& F1,
                                            const Eigen::MatrixBase<DerivedV2>& V2, const Eigen::MatrixBase<DerivedF2>& F2,
                                            const RunOptions& options) {
    const EigenMeshRef meshes[] = {{V1, F1}, {V2, F2}};
    return collide(std::span<const EigenMeshRef>(meshes), options);
}

// One object against itself: process_frame with options.self forced on. The method must support
// self-collision (exact, qcullide, qcullide-gl, and auto, RunOptions' default, which runs exact
// then); the CULLIDE methods do not, and process_frame's error says so.
template <class DerivedV, class DerivedF>
[[nodiscard]] Result<CollideResult> self_collide(const Eigen::MatrixBase<DerivedV>& V, const Eigen::MatrixBase<DerivedF>& F,
                                                 RunOptions options) {
    options.self = true;
    const EigenMeshRef meshes[] = {{V, F}};
    return collide(std::span<const EigenMeshRef>(meshes), options);
}

}  // namespace cullide
