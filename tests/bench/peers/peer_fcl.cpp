// tests/bench/peers/peer_fcl.cpp: FCL 0.7 (BSD-3) as a peer: one BVHModel per object (OBBRSS or AABB),
// refitted with beginUpdateModel/updateSubModel/endUpdateModel, objects paired by FCL's
// DynamicAABBTreeCollisionManager, triangle pairs from fcl::collide with contacts disabled (one
// Contact per triangle pair, b1/b2 the triangle indices; FCL's own double-precision triangle test).
#include <fcl/fcl.h>

#include "peer.h"

namespace peers {
namespace {

template <class BV>
class FclPeer final : public Peer {
   public:
    explicit FclPeer(const char* label) : label_(label) {}
    std::string name() const override { return label_; }
    std::string narrow_phase() const override { return "FCL triangle test (double; not exact)"; }

    void build(const std::vector<cullide::Mesh>& objects) override {
        models_.clear();
        objs_.clear();
        ids_.clear();
        manager_ = std::make_unique<fcl::DynamicAABBTreeCollisionManager<double>>();
        std::vector<fcl::CollisionObject<double>*> raw;
        for (std::size_t o = 0; o < objects.size(); ++o) {
            auto model = std::make_shared<fcl::BVHModel<BV>>();
            model->beginModel(static_cast<int>(objects[o].triangles.size()), static_cast<int>(objects[o].positions.size()));
            model->addSubModel(points(objects[o]), tris(objects[o]));
            model->endModel();
            models_.push_back(model);
            objs_.push_back(std::make_unique<fcl::CollisionObject<double>>(model));
        }
        ids_.resize(objs_.size());
        for (std::size_t o = 0; o < objs_.size(); ++o) {
            ids_[o] = static_cast<std::uint32_t>(o);
            objs_[o]->setUserData(&ids_[o]);
            objs_[o]->computeAABB();
            raw.push_back(objs_[o].get());
        }
        manager_->registerObjects(raw);
        manager_->setup();
    }

    void refit(const std::vector<cullide::Mesh>& objects) override {
        for (std::size_t o = 0; o < objects.size(); ++o) {
            models_[o]->beginUpdateModel();
            models_[o]->updateSubModel(points(objects[o]));
            models_[o]->endUpdateModel(true, true);
            // endUpdateModel refits the tree but leaves the model's local box as it was: without this
            // the object's box (and so the broad phase) stays at the previous frame and pairs are lost.
            models_[o]->computeLocalAABB();
            objs_[o]->computeAABB();
        }
        manager_->update();
    }

    std::vector<cullide::TrianglePair> query() override {
        Data d;
        manager_->collide(&d, &callback);
        return std::move(d.pairs);
    }

   private:
    struct Data {
        std::vector<cullide::TrianglePair> pairs;
    };
    static bool callback(fcl::CollisionObject<double>* a, fcl::CollisionObject<double>* b, void* data) {
        auto* d = static_cast<Data*>(data);
        // Every triangle pair: a contact cap far above any pair count, contacts (points) off.
        fcl::CollisionRequest<double> request(std::numeric_limits<int>::max() / 2, false);
        fcl::CollisionResult<double> result;
        fcl::collide(a, b, request, result);
        const std::uint32_t ia = *static_cast<std::uint32_t*>(a->getUserData());
        const std::uint32_t ib = *static_cast<std::uint32_t*>(b->getUserData());
        for (std::size_t i = 0; i < result.numContacts(); ++i) {
            const fcl::Contact<double>& c = result.getContact(i);
            // b1 indexes a's triangles, b2 b's (mesh-mesh keeps the argument order; for AABB models
            // c.o1 points to FCL's world-space copy of a's model, not to a's geometry).
            d->pairs.push_back(make_pair(ia, static_cast<std::uint32_t>(c.b1), ib, static_cast<std::uint32_t>(c.b2)));
        }
        return false;  // never stop early
    }
    static std::vector<fcl::Vector3<double>> points(const cullide::Mesh& m) {
        std::vector<fcl::Vector3<double>> p;
        p.reserve(m.positions.size());
        for (const cullide::Vec3& v : m.positions) p.emplace_back(v.x, v.y, v.z);
        return p;
    }
    static std::vector<fcl::Triangle> tris(const cullide::Mesh& m) {
        std::vector<fcl::Triangle> t;
        t.reserve(m.triangles.size());
        for (const cullide::Tri& x : m.triangles) t.emplace_back(x[0], x[1], x[2]);
        return t;
    }

    std::string label_;
    std::vector<std::shared_ptr<fcl::BVHModel<BV>>> models_;
    std::vector<std::unique_ptr<fcl::CollisionObject<double>>> objs_;
    std::vector<std::uint32_t> ids_;
    std::unique_ptr<fcl::DynamicAABBTreeCollisionManager<double>> manager_;
};

}  // namespace

std::unique_ptr<Peer> make_fcl(bool obbrss, int /*threads: FCL is single-threaded*/) {
    if (obbrss) return std::make_unique<FclPeer<fcl::OBBRSS<double>>>("fcl-obbrss");
    return std::make_unique<FclPeer<fcl::AABB<double>>>("fcl-aabb");
}

}  // namespace peers
