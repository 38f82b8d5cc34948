// cullide/tri_tri.h: exact triangle-triangle intersection.
//
// Decides whether two closed triangles (given by double-precision vertices) share a point, and how.
// Every sign is exact: a floating-point filter, with an exact expansion-arithmetic fallback when the
// filter cannot decide (see predicates.h). No epsilon, no dependence on scene scale.
// Algorithm: Guigue & Devillers, "Fast and robust triangle-triangle overlap test using orientation
// predicates" (JGT 2003, corrected version), extended to degenerate triangles (segments, points).
#pragma once

#include "cullide/mesh.h"

namespace cullide {

// How two closed triangles meet. Definitions (docs/conventions.md):
//  Disjoint        no common point.
//  Touching        a common point, but neither of the two cases below.
//  Crossing        not coplanar, and they interpenetrate: the common segment has positive length
//                  and each triangle has vertices strictly on both sides of the other's plane.
//  CoplanarOverlap both in one plane and the common part has positive area.
// Degenerate triangles (zero area) can only be Disjoint or Touching.
enum class TriRelation : unsigned char { Disjoint, Touching, Crossing, CoplanarOverlap };

[[nodiscard]] const char* to_string(TriRelation r);

// The relation of triangles (a0, a1, a2) and (b0, b1, b2). Exact for every input whose coordinates
// are each 0 or of magnitude in [2^-300, 2^300] (predicates.h: then products of three differences
// neither overflow nor lose bits to underflow; see docs/conventions.md). Outside that range the
// answer is not guaranteed: use tri_tri_relation_checked on untrusted data. Symmetric in the two
// triangles and invariant under any permutation of either's vertices.
[[nodiscard]] TriRelation tri_tri_relation(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                                           const Vec3& b1, const Vec3& b2);

// tri_tri_relation after checking the range above; the error names the vertex (a0..b2), the
// coordinate and the limit, e.g. "vertex b1.z = inf is outside the exact range ...".
[[nodiscard]] Result<TriRelation> tri_tri_relation_checked(const Vec3& a0, const Vec3& a1, const Vec3& a2,
                                                           const Vec3& b0, const Vec3& b1, const Vec3& b2);

// True when the closed triangles share a point (relation != Disjoint); may be faster.
[[nodiscard]] bool tri_tri_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                                     const Vec3& b1, const Vec3& b2);

}  // namespace cullide
