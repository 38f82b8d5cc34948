// tests/bench/peers/peer_bullet.cpp: Bullet 3.24 (zlib) GImpact as a peer. One btGImpactMeshShape per
// object over a float copy of its vertices (Debian's Bullet is single precision), margin 0 (the
// default margin inflates every box, ../shared/docs/peers.md section 4); refit = write the new
// vertices, postUpdate, updateBound (GImpact refits its quantized BVH). Object pairs by box overlap
// of the shapes' AABBs (all pairs: the scenes have at most a few hundred objects), triangle
// candidates by btGImpactQuantizedBvh::find_collision (float boxes: a touching pair can be lost),
// decided by GImpact's own clip-method test (a contact generator: it also reports penetrating pairs
// whose triangles do not meet), or, as bullet-gimpact-exact, by cullide's exact test.
#include <btBulletCollisionCommon.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/Gimpact/btGImpactQuantizedBvh.h>
#include <BulletCollision/Gimpact/btTriangleShapeEx.h>

#include "peer.h"

namespace peers {
namespace {

class BulletPeer final : public Peer {
   public:
    explicit BulletPeer(bool our_exact) : our_exact_(our_exact) {}
    std::string name() const override { return our_exact_ ? "bullet-gimpact-exact" : "bullet-gimpact"; }
    std::string narrow_phase() const override {
        return our_exact_ ? "GImpact candidates + our exact test" : "GImpact clip method (float; not exact)";
    }

    void build(const std::vector<cullide::Mesh>& objects) override {
        objects_ = &objects;
        parts_.clear();
        for (const cullide::Mesh& m : objects) {
            auto p = std::make_unique<Part>();
            copy_vertices(m, *p);
            p->indices.reserve(m.triangles.size() * 3);
            for (const cullide::Tri& t : m.triangles) {
                for (int k = 0; k < 3; ++k) p->indices.push_back(static_cast<int>(t[static_cast<std::size_t>(k)]));
            }
            p->array = std::make_unique<btTriangleIndexVertexArray>(
                static_cast<int>(m.triangles.size()), p->indices.data(), 3 * static_cast<int>(sizeof(int)),
                static_cast<int>(m.positions.size()), p->vertices.data(), 3 * static_cast<int>(sizeof(btScalar)));
            p->shape = std::make_unique<btGImpactMeshShape>(p->array.get());
            p->shape->setMargin(0);
            p->shape->updateBound();
            parts_.push_back(std::move(p));
        }
    }

    void refit(const std::vector<cullide::Mesh>& objects) override {
        objects_ = &objects;
        for (std::size_t o = 0; o < objects.size(); ++o) {
            copy_vertices(objects[o], *parts_[o]);
            parts_[o]->shape->postUpdate();
            parts_[o]->shape->updateBound();
        }
    }

    std::vector<cullide::TrianglePair> query() override {
        std::vector<cullide::TrianglePair> out;
        btTransform identity;
        identity.setIdentity();
        for (std::size_t i = 0; i < parts_.size(); ++i) {
            const btAABB& bi = box(i);
            for (std::size_t j = i + 1; j < parts_.size(); ++j) {
                if (!bi.has_collision(box(j))) continue;
                const btGImpactMeshShapePart* pi = parts_[i]->shape->getMeshPart(0);
                const btGImpactMeshShapePart* pj = parts_[j]->shape->getMeshPart(0);
                btPairSet candidates;
                btGImpactQuantizedBvh::find_collision(pi->getBoxSet(), identity, pj->getBoxSet(), identity, candidates);
                if (candidates.size() == 0) continue;
                pi->lockChildShapes();
                pj->lockChildShapes();
                btPrimitiveTriangle ta, tb;
                GIM_TRIANGLE_CONTACT contact;
                for (int k = 0; k < candidates.size(); ++k) {
                    if (our_exact_) {
                        const auto a = static_cast<std::uint32_t>(candidates[k].m_index1);
                        const auto b = static_cast<std::uint32_t>(candidates[k].m_index2);
                        if (exact_pair(*objects_, static_cast<std::uint32_t>(i), a, static_cast<std::uint32_t>(j), b)) {
                            out.push_back(make_pair(static_cast<std::uint32_t>(i), a, static_cast<std::uint32_t>(j), b));
                        }
                        continue;
                    }
                    pi->getPrimitiveTriangle(candidates[k].m_index1, ta);
                    pj->getPrimitiveTriangle(candidates[k].m_index2, tb);
                    ta.m_margin = 0;  // btPrimitiveTriangle defaults to 0.01 whatever the shape's margin
                    tb.m_margin = 0;
                    ta.buildTriPlane();
                    tb.buildTriPlane();
                    if (ta.overlap_test_conservative(tb) && ta.find_triangle_collision_clip_method(tb, contact)) {
                        out.push_back(make_pair(static_cast<std::uint32_t>(i),
                                                static_cast<std::uint32_t>(candidates[k].m_index1),
                                                static_cast<std::uint32_t>(j),
                                                static_cast<std::uint32_t>(candidates[k].m_index2)));
                    }
                }
                pi->unlockChildShapes();
                pj->unlockChildShapes();
            }
        }
        return out;
    }

   private:
    struct Part {
        std::vector<btScalar> vertices;
        std::vector<int> indices;
        std::unique_ptr<btTriangleIndexVertexArray> array;
        std::unique_ptr<btGImpactMeshShape> shape;
        btAABB aabb;
    };
    const btAABB& box(std::size_t i) {
        btAABB& b = parts_[i]->aabb;
        btTransform identity;
        identity.setIdentity();
        parts_[i]->shape->getAabb(identity, b.m_min, b.m_max);
        return b;
    }
    static void copy_vertices(const cullide::Mesh& m, Part& p) {
        p.vertices.resize(m.positions.size() * 3);
        for (std::size_t v = 0; v < m.positions.size(); ++v) {
            p.vertices[3 * v] = static_cast<btScalar>(m.positions[v].x);
            p.vertices[3 * v + 1] = static_cast<btScalar>(m.positions[v].y);
            p.vertices[3 * v + 2] = static_cast<btScalar>(m.positions[v].z);
        }
    }
    bool our_exact_;
    const std::vector<cullide::Mesh>* objects_ = nullptr;
    std::vector<std::unique_ptr<Part>> parts_;
};

}  // namespace

std::unique_ptr<Peer> make_bullet(bool our_exact, int /*threads: single-threaded here*/) {
    return std::make_unique<BulletPeer>(our_exact);
}

}  // namespace peers
