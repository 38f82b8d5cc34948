// embree_interference.h: an independent interference check by ray casting (Embree 3), an oracle of
// the tests and benchmarks; never linked into a library. No Embree header leaks from here.
//
// Method: every edge of every triangle is cast as a segment (a ray from its first endpoint, direction
// the edge vector, t in [0, 1]) against one Embree scene that holds each object as one triangle
// geometry (geomID = object index, primID = triangle index). Every hit along the segment is kept,
// not only the first: a context filter function records the hit and rejects it, so traversal goes
// on. A pair (edge's triangle, hit triangle) is reported in canonical form. Since every object's
// edges are cast against every other object, each pair of objects is tested in both directions.
//
// Why it finds crossings: when two closed, non-coplanar triangles cross, each end of their common
// segment lies on an edge of one of them, so some edge of one passes through the other. Touching
// and coplanar contacts are where it may differ from the exact method (docs/embree-oracle.md):
// an edge lying in the other triangle's plane is never hit (Embree's ray-triangle test divides by
// the ray's component along the normal), and contacts at an edge's end or the other triangle's
// boundary are decided in float arithmetic.
//
// Precision: Embree works in float. Each double coordinate is rounded to the nearest float (relative
// error <= 2^-24, about 6e-8 of the coordinate's magnitude), so pairs whose overlap or gap is
// smaller than that may flip; the ray's end point is pf + 1 * float(qf - pf), within a float ulp of
// qf. The scene is built with RTC_SCENE_FLAG_ROBUST (watertight ray-triangle test, conservative box
// tests).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide_oracle {

struct EmbreeOptions {
    // Also report pairs inside one object, with exact_pairs' adjacency rule: two triangles of one
    // object that share a welded vertex (cullide::weld_vertices: equal coordinates) are never a pair.
    bool self = false;
    // Threads of the Embree device (BVH build) and of the ray loop; 0 = Embree's default and all
    // hardware threads. The result does not depend on it (hits are sorted and made unique).
    int threads = 0;
};

struct EmbreeStats {
    std::uint64_t rays = 0;               // edges cast (3 per triangle, less zero-length ones)
    std::uint64_t zero_length_edges = 0;  // edges whose float end points coincide: not cast
    std::uint64_t hits_recorded = 0;      // filter calls that recorded a pair (before dedupe)
    double build_seconds = 0;             // device + scene build (wall clock)
    double cast_seconds = 0;              // the ray loop (wall clock)
};

// The triangle pairs found by edge casting, sorted and unique, canonical as cullide::TrianglePair.
// Fails, naming object and vertex, on invalid meshes (cullide::validate_scene) and on coordinates
// that do not fit a float; fails with Embree's error code and message when Embree does.
[[nodiscard]] cullide::Result<std::vector<cullide::TrianglePair>> embree_pairs(
    std::span<const cullide::Mesh> objects, const EmbreeOptions& options = {}, EmbreeStats* stats = nullptr);

// The rounding embree_pairs applies to every coordinate (nearest float), as doubles: a check can run
// the exact test on the coordinates Embree actually saw.
[[nodiscard]] cullide::Vec3 round_to_float(const cullide::Vec3& p);

}  // namespace cullide_oracle
