// tests/bench/peers/peer_embree.cpp: Embree 3 (Apache-2.0) as a peer. rtcCollide needs scenes made of
// user geometry only (../shared/docs/peers.md section 2): one RTC_GEOMETRY_TYPE_USER geometry per
// object, one primitive per triangle, bounds from our double vertices rounded outward to float (so no
// touching pair is lost to rounding). rtcCollide(scene, scene) reports candidate pairs whose leaf
// boxes overlap, from several threads; pairs inside one object are dropped, the rest decided by
// cullide's exact test. Refit: re-commit the geometries and the scene with RTC_BUILD_QUALITY_REFIT
// (a hint only, per Embree's documentation).
#include <embree3/rtcore.h>

#include <cmath>
#include <mutex>
#include <string>

#include "peer.h"

namespace peers {
namespace {

class EmbreePeer final : public Peer {
   public:
    explicit EmbreePeer(int threads) {
        const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : "";
        device_ = rtcNewDevice(config.c_str());
    }
    ~EmbreePeer() override {
        release();
        if (device_) rtcReleaseDevice(device_);
    }
    EmbreePeer(const EmbreePeer&) = delete;
    EmbreePeer& operator=(const EmbreePeer&) = delete;

    std::string name() const override { return "embree-collide"; }
    std::string narrow_phase() const override { return "rtcCollide candidates + our exact test"; }

    void build(const std::vector<cullide::Mesh>& objects) override {
        release();
        objects_ = &objects;
        scene_ = rtcNewScene(device_);
        geometries_.clear();
        tags_.assign(objects.size(), Tag{});
        for (std::size_t o = 0; o < objects.size(); ++o) {
            tags_[o] = Tag{this, static_cast<std::uint32_t>(o)};
            RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
            rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(objects[o].triangles.size()));
            rtcSetGeometryUserData(g, &tags_[o]);
            rtcSetGeometryBoundsFunction(g, &bounds, &tags_[o]);
            rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(scene_, g, static_cast<unsigned>(o));
            geometries_.push_back(g);
        }
        rtcCommitScene(scene_);
    }

    void refit(const std::vector<cullide::Mesh>& objects) override {
        objects_ = &objects;
        for (RTCGeometry g : geometries_) rtcCommitGeometry(g);
        rtcCommitScene(scene_);
    }

    std::vector<cullide::TrianglePair> query() override {
        pairs_.clear();
        rtcCollide(scene_, scene_, &collide, this);
        return std::move(pairs_);
    }

   private:
    static float down(double v) {
        float f = static_cast<float>(v);
        return static_cast<double>(f) > v ? std::nextafter(f, -INFINITY) : f;
    }
    static float up(double v) {
        float f = static_cast<float>(v);
        return static_cast<double>(f) < v ? std::nextafter(f, INFINITY) : f;
    }
    static void bounds(const RTCBoundsFunctionArguments* args) {
        // The geometry id is not passed: each geometry's user data names its object.
        const auto* tag = static_cast<const Tag*>(args->geometryUserPtr);
        const cullide::Mesh& m = (*tag->self->objects_)[tag->object];
        const cullide::Tri& t = m.triangles[args->primID];
        cullide::Vec3 lo = m.positions[t[0]], hi = lo;
        for (int k = 1; k < 3; ++k) {
            const cullide::Vec3& p = m.positions[t[static_cast<std::size_t>(k)]];
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], p[a]);
                hi[a] = std::max(hi[a], p[a]);
            }
        }
        RTCBounds* b = args->bounds_o;
        b->lower_x = down(lo.x);
        b->lower_y = down(lo.y);
        b->lower_z = down(lo.z);
        b->upper_x = up(hi.x);
        b->upper_y = up(hi.y);
        b->upper_z = up(hi.z);
    }
    struct Tag {
        const EmbreePeer* self = nullptr;
        std::uint32_t object = 0;
    };

    static void collide(void* user, RTCCollision* collisions, unsigned int n) {
        auto* self = static_cast<EmbreePeer*>(user);
        std::vector<cullide::TrianglePair> local;
        for (unsigned i = 0; i < n; ++i) {
            const RTCCollision& c = collisions[i];
            // Both orders are reported: keep geomID0 < geomID1 only (drops self pairs too).
            if (c.geomID0 >= c.geomID1) continue;
            if (exact_pair(*self->objects_, c.geomID0, c.primID0, c.geomID1, c.primID1)) {
                local.push_back({c.geomID0, c.primID0, c.geomID1, c.primID1});
            }
        }
        if (local.empty()) return;
        std::lock_guard<std::mutex> lock(self->mutex_);
        self->pairs_.insert(self->pairs_.end(), local.begin(), local.end());
    }

    void release() {
        for (RTCGeometry g : geometries_) rtcReleaseGeometry(g);
        geometries_.clear();
        if (scene_) rtcReleaseScene(scene_);
        scene_ = nullptr;
    }

    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    std::vector<RTCGeometry> geometries_;
    std::vector<Tag> tags_;
    const std::vector<cullide::Mesh>* objects_ = nullptr;
    std::vector<cullide::TrianglePair> pairs_;
    std::mutex mutex_;
};

}  // namespace

std::unique_ptr<Peer> make_embree(int threads) { return std::make_unique<EmbreePeer>(threads); }

}  // namespace peers
