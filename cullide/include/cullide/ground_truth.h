// cullide/ground_truth.h: the exact reference every culling method is measured against.
//
// All colliding triangle pairs of a frame: closed triangles that share at least one point (touching
// counts), decided by the exact test of tri_tri.h after a conservative box prefilter (closed boxes, no
// padding, so the prefilter can never drop a pair the exact test would accept).
#pragma once

#include <compare>
#include <cstdint>
#include <span>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide {

// One colliding triangle pair, in canonical form: object_a < object_b, or, for a self pair,
// object_a == object_b and triangle_a < triangle_b. Lists of pairs are sorted and unique.
struct TrianglePair {
    std::uint32_t object_a = 0, triangle_a = 0, object_b = 0, triangle_b = 0;
    friend auto operator<=>(const TrianglePair&, const TrianglePair&) = default;
};

// Two objects with at least one colliding triangle pair (a < b, or a == b for self-collision).
struct ObjectPair {
    std::uint32_t a = 0, b = 0;
    friend auto operator<=>(const ObjectPair&, const ObjectPair&) = default;
};

struct ExactOptions {
    // Also report pairs inside one object. Two triangles of one object that share a vertex are
    // adjacent, never colliding; vertices with identical coordinates count as one vertex (welding,
    // docs/conventions.md), so unwelded seams are not reported.
    bool self = false;
    // Worker threads, 0 = all hardware threads. The result does not depend on it.
    int threads = 0;
};

struct ExactStats {
    std::uint64_t triangles = 0;          // triangles in the frame
    std::uint64_t candidate_triangles = 0;  // triangles in some task: box meets the common box of an
                                            // overlapping object pair (all triangles with self)
    std::uint64_t box_pairs = 0;          // triangle pairs whose boxes overlap (sent to the exact test)
    std::uint64_t adjacent_skipped = 0;   // self pairs with overlapping boxes skipped as adjacent
};

// Every colliding triangle pair, sorted. Fails, naming the object and element, on invalid meshes
// and on coordinates outside the exact predicates' range (predicates.h: 0 or 2^-300..2^300 in
// magnitude), where an exact answer could not be promised.
[[nodiscard]] Result<std::vector<TrianglePair>> exact_pairs(std::span<const Mesh> objects,
                                                            const ExactOptions& options = {},
                                                            ExactStats* stats = nullptr);

// Fails, naming the object, vertex and coordinate, when a coordinate is outside the exact
// predicates' range. Every method checks it (they all end in the exact test).
[[nodiscard]] Status validate_exact_range(std::span<const Mesh> objects);

// The object pairs of a sorted triangle-pair list, sorted and unique.
[[nodiscard]] std::vector<ObjectPair> object_pairs(std::span<const TrianglePair> pairs);

// Welded vertex ids of one mesh: equal ids exactly when positions compare equal (so -0.0 == 0.0;
// a position with a NaN coordinate equals no other). Ids are dense, numbered in order of first
// appearance in the vertex list.
[[nodiscard]] std::vector<std::uint32_t> weld_vertices(const Mesh& mesh);

}  // namespace cullide
