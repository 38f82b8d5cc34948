// tests/bench/peers/peer_cgal.cpp: CGAL 5.5 (Box_intersection_d is GPL-3.0-or-later: a benchmark
// peer only, never linked into the libraries) as a peer: CGAL::box_self_intersection_d
// (Zomorodian-Edelsbrunner streamed segment tree, closed boxes) over every triangle's box, boxes of
// one object skipped, the rest decided by cullide's exact test. No tree survives a frame, so "build"
// is making the boxes and there is no refit (refit_is_rebuild).
#include <CGAL/box_intersection_d.h>

#include <algorithm>

#include "peer.h"

namespace peers {
namespace {

using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint64_t>;

class CgalPeer final : public Peer {
   public:
    std::string name() const override { return "cgal-box-d"; }
    std::string narrow_phase() const override { return "box_intersection_d + our exact test"; }
    bool refit_is_rebuild() const override { return true; }

    void build(const std::vector<cullide::Mesh>& objects) override {
        objects_ = &objects;
        boxes_.clear();
        for (std::size_t o = 0; o < objects.size(); ++o) {
            const cullide::Mesh& m = objects[o];
            for (std::size_t t = 0; t < m.triangles.size(); ++t) {
                double lo[3], hi[3];
                for (int a = 0; a < 3; ++a) {
                    lo[a] = hi[a] = m.positions[m.triangles[t][0]][a];
                    for (int k = 1; k < 3; ++k) {
                        const double v = m.positions[m.triangles[t][static_cast<std::size_t>(k)]][a];
                        lo[a] = std::min(lo[a], v);
                        hi[a] = std::max(hi[a], v);
                    }
                }
                boxes_.emplace_back(lo, hi, (static_cast<std::uint64_t>(o) << 32) | t);
            }
        }
    }
    void refit(const std::vector<cullide::Mesh>& objects) override { build(objects); }

    std::vector<cullide::TrianglePair> query() override {
        std::vector<cullide::TrianglePair> out;
        const std::vector<cullide::Mesh>& objs = *objects_;
        auto cb = [&](const Box& a, const Box& b) {
            const auto oa = static_cast<std::uint32_t>(a.info() >> 32), ob = static_cast<std::uint32_t>(b.info() >> 32);
            if (oa == ob) return;
            const auto ta = static_cast<std::uint32_t>(a.info()), tb = static_cast<std::uint32_t>(b.info());
            if (exact_pair(objs, oa, ta, ob, tb)) out.push_back(make_pair(oa, ta, ob, tb));
        };
        // box_self_intersection_d reorders its input: work on a copy so query() can repeat.
        std::vector<Box> work = boxes_;
        CGAL::box_self_intersection_d(work.begin(), work.end(), cb);
        return out;
    }

   private:
    const std::vector<cullide::Mesh>* objects_ = nullptr;
    std::vector<Box> boxes_;
};

}  // namespace

std::unique_ptr<Peer> make_cgal(int /*threads: sequential box_intersection_d*/) { return std::make_unique<CgalPeer>(); }

}  // namespace peers
