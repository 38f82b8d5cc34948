// tests/bench/peers/peer.h: one collision library as peers_bench drives it (benchmarks only).
//
// A peer is built on a frame (all its objects), refitted to a later frame of the same scene (same
// topology, moved vertices) and queried for the colliding triangle pairs between different objects.
// Pairs come back canonical (ground_truth.h: object_a < object_b) but may be unsorted or repeated;
// peers_bench sorts, dedupes and compares them with exact_pairs.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/tri_tri.h"

namespace peers {

class Peer {
   public:
    virtual ~Peer() = default;
    [[nodiscard]] virtual std::string name() const = 0;
    // How the peer decides a pair (for the report): e.g. "FCL tri-tri (double)", "our exact test".
    [[nodiscard]] virtual std::string narrow_phase() const = 0;
    // Builds every structure from scratch for these objects.
    virtual void build(const std::vector<cullide::Mesh>& objects) = 0;
    // Moves to new vertex positions (same objects, same triangles): the peer's refit path, or a
    // rebuild where it has none (then refit_is_rebuild() is true).
    virtual void refit(const std::vector<cullide::Mesh>& objects) = 0;
    [[nodiscard]] virtual bool refit_is_rebuild() const { return false; }
    // Colliding triangle pairs between different objects of the last build/refit.
    [[nodiscard]] virtual std::vector<cullide::TrianglePair> query() = 0;
};

// Factories: nullptr when the peer was not built in (its library was not found).
std::unique_ptr<Peer> make_fcl(bool obbrss, int threads);
std::unique_ptr<Peer> make_bullet(bool our_exact, int threads);
std::unique_ptr<Peer> make_embree(int threads);
std::unique_ptr<Peer> make_cgal(int threads);

// The exact test of cullide on one candidate triangle pair (closed triangles, touching counts).
inline bool exact_pair(const std::vector<cullide::Mesh>& objects, std::uint32_t oa, std::uint32_t ta,
                       std::uint32_t ob, std::uint32_t tb) {
    const cullide::Mesh& a = objects[oa];
    const cullide::Mesh& b = objects[ob];
    const cullide::Tri& x = a.triangles[ta];
    const cullide::Tri& y = b.triangles[tb];
    return cullide::tri_tri_intersect(a.positions[x[0]], a.positions[x[1]], a.positions[x[2]], b.positions[y[0]],
                                      b.positions[y[1]], b.positions[y[2]]);
}

// Canonical pair (object_a < object_b).
inline cullide::TrianglePair make_pair(std::uint32_t oa, std::uint32_t ta, std::uint32_t ob, std::uint32_t tb) {
    if (oa > ob) return {ob, tb, oa, ta};
    return {oa, ta, ob, tb};
}

}  // namespace peers
