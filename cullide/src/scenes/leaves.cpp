// leaves.cpp: R-CULLIDE's tree and falling leaves (Govindaraju, Lin & Manocha, VRST 2004: a tree of
// more than 40K triangles and 150 falling leaves). The tree is one object: a trunk and three levels
// of branches as tapered tubes, with small curved leaves attached to the twigs; it sways gently
// (vertices shifted in proportion to height squared). The falling leaves are separate small curved
// patches that flutter, tumble and curl as they drop from above the canopy to the ground, each on
// its own cycle.
#include <cmath>
#include <string>

#include "scene_math.h"
#include "scenes/scene_kit.h"

namespace cullide::scene_kit {

namespace {

constexpr std::int64_t kPeriod = 600;   // frames (20 s) of every cycle in this scene
constexpr int kLeaves100 = 150;         // falling leaves at scale 1
constexpr int kTwigLeaves100 = 40;      // leaves attached to each twig at scale 1
constexpr double kTrunkHeight = 4.0;
constexpr double kTreeHeight = 6.5;     // for the sway profile
constexpr double kFallTop = 8.0;        // falling leaves start here ...
constexpr double kFallBottom = 0.0;     // ... and end here
constexpr double kCanopyRadius = 3.2;   // falling leaves start above this disc

struct Level {
    int children;       // per parent
    int around, rings;  // tube resolution at scale 1
    double length, r0, r1;
};
// Trunk, branches, boughs, twigs.
constexpr Level kLevels[4] = {
    {1, 16, 24, kTrunkHeight, 0.25, 0.12},
    {6, 12, 16, 2.0, 0.10, 0.05},
    {5, 10, 10, 1.0, 0.045, 0.02},
    {4, 8, 8, 0.5, 0.02, 0.01},
};

struct FallingLeaf {
    double x0, y0;
    std::int64_t fall_cycles, fall_offset;
    std::int64_t spin[3];
    double angle0[3];
    std::int64_t flutter_freq, curl_freq;
    double flutter_phase, curl_phase;
};

// Adds a tapered open tube from `base` along unit `dir`.
void append_tube(Mesh& mesh, Vec3 base, Vec3 dir, const Level& level, int around, int rings) {
    const Rotation frame = rotation_to(dir);
    append_grid(mesh, around, rings, true, false, [&](int i, int j) {
        const double s = static_cast<double>(j) / rings;
        const double r = level.r0 + (level.r1 - level.r0) * s;
        double sa = 0, ca = 0;
        det::det_sincos(det::kTwoPi * (static_cast<double>(i) / around), sa, ca);
        return base + apply(frame, Vec3{r * ca, r * sa, level.length * s});
    });
}

// A curved leaf patch: length along local x, width along y, curled up in z by `curl` at its ends.
Vec3 leaf_point(int i, int j, int cols, int rows, double length, double width, double curl) {
    const double u = static_cast<double>(i) / cols - 0.5;
    const double v = static_cast<double>(j) / rows - 0.5;
    return {u * length, v * width, curl * ((4.0 * u * u) + v * v)};
}

class LeavesScene final : public SceneGenerator {
   public:
    explicit LeavesScene(const SceneOptions& options) {
        const double q = std::sqrt(options.scale);
        const int twig_leaves = static_cast<int>(round_at_least(kTwigLeaves100 * options.scale, 1));
        leaves_ = static_cast<int>(round_at_least(kLeaves100 * options.scale, 1));
        det::SplitMix64 rng(det::stream_seed(options.seed, kPartLeaves, 0));
        tree_.name = "tree";
        struct Stem {
            Vec3 base, dir;
        };
        std::vector<Stem> parents{{{0, 0, 0}, {0, 0, 1}}};
        for (int level = 0; level < 4; ++level) {
            const Level& lv = kLevels[level];
            const int around = static_cast<int>(round_at_least(lv.around * q, 3));
            const int rings = static_cast<int>(round_at_least(lv.rings * q, 1));
            std::vector<Stem> made;
            for (const Stem& parent : parents) {
                for (int c = 0; c < lv.children; ++c) {
                    Stem s = parent;
                    if (level > 0) {
                        const double parent_len = kLevels[level - 1].length;
                        const double lo = level == 1 ? 0.45 : 0.3;
                        s.base = parent.base + (parent_len * rng.uniform(lo, 0.95)) * parent.dir;
                        // Around the parent, evenly with jitter, tilted out and a little up.
                        const Rotation pf = rotation_to(parent.dir);
                        double sa = 0, ca = 0;
                        det::det_sincos(det::kTwoPi * ((c + rng.uniform(0.0, 0.5)) / lv.children), sa, ca);
                        const Vec3 out_dir = ca * pf.u + sa * pf.v;
                        const double lean = level == 1 ? rng.uniform(0.5, 0.9) : rng.uniform(0.7, 1.2);
                        s.dir = normalized((parent.dir + lean * out_dir) + Vec3{0, 0, 0.35});
                    }
                    append_tube(tree_, s.base, s.dir, lv, around, rings);
                    made.push_back(s);
                }
            }
            parents = std::move(made);
        }
        // Leaves on the twigs, at their base point on the twig's axis, pointing out and up.
        for (const Stem& twig : parents) {
            const Rotation tf = rotation_to(twig.dir);
            for (int k = 0; k < twig_leaves; ++k) {
                const Vec3 at = twig.base + (kLevels[3].length * rng.uniform(0.2, 1.0)) * twig.dir;
                const double yaw = rng.uniform(0.0, det::kTwoPi);
                double sy = 0, cy = 0;
                det::det_sincos(yaw, sy, cy);
                const Vec3 out_dir = normalized((cy * tf.u + sy * tf.v) + 0.4 * twig.dir);
                const Rotation lf = rotation_to(out_dir);
                const double curl = rng.uniform(0.0, 0.03);
                // Leaf length runs along lf.w (outward), width along lf.u.
                append_grid(tree_, 2, 1, false, false, [&](int i, int j) {
                    const Vec3 p = leaf_point(i, j, 2, 1, 0.18, 0.1, curl);
                    return at + apply(lf, Vec3{p.y, p.z, p.x + 0.09});
                });
            }
        }
        for (int i = 0; i < leaves_; ++i) {
            det::SplitMix64 lr(det::stream_seed(options.seed, kPartLeaves, static_cast<std::uint64_t>(i) + 1));
            FallingLeaf l{};
            const double radius = kCanopyRadius * std::sqrt(lr.uniform01());
            double sa = 0, ca = 0;
            det::det_sincos(lr.uniform(0.0, det::kTwoPi), sa, ca);
            l.x0 = radius * ca;
            l.y0 = radius * sa;
            l.fall_cycles = lr.between(2, 4);
            l.fall_offset = lr.between(0, kPeriod - 1);
            for (int a = 0; a < 3; ++a) {
                l.spin[a] = lr.between(-12, 12);
                l.angle0[a] = lr.uniform(0.0, det::kTwoPi);
            }
            l.flutter_freq = lr.between(8, 20);
            l.curl_freq = lr.between(10, 30);
            l.flutter_phase = lr.uniform(0.0, det::kTwoPi);
            l.curl_phase = lr.uniform(0.0, det::kTwoPi);
            falling_.push_back(l);
        }
        sway_phase_ = rng.uniform(0.0, det::kTwoPi);
    }

    [[nodiscard]] std::string name() const override { return "leaves"; }
    [[nodiscard]] std::string description() const override {
        return "a swaying tree of " + std::to_string(tree_.triangles.size()) + " triangles and " +
               std::to_string(leaves_) + " falling leaves x 16 triangles (R-CULLIDE); scale multiplies the "
               "falling and attached leaf counts (tube resolution by its square root)";
    }

    [[nodiscard]] Frame frame(int f) const override {
        Frame out;
        out.reserve(falling_.size() + 1);
        Mesh tree = tree_;
        const double sway_x = 0.12 * det::det_sin_cycle(3LL * f, kPeriod, sway_phase_);
        const double sway_y = 0.07 * det::det_sin_cycle(5LL * f, kPeriod, sway_phase_ + 1.0);
        for (Vec3& p : tree.positions) {
            const double h = p.z / kTreeHeight;
            p = p + Vec3{sway_x * h * h, sway_y * h * h, 0.0};
        }
        out.push_back(std::move(tree));
        for (std::size_t i = 0; i < falling_.size(); ++i) {
            const FallingLeaf& l = falling_[i];
            std::int64_t m = (l.fall_cycles * f + l.fall_offset) % kPeriod;
            if (m < 0) m += kPeriod;
            const double fall = static_cast<double>(m) / kPeriod;
            const Vec3 centre{l.x0 + 0.3 * det::det_sin_cycle(l.flutter_freq * f, kPeriod, l.flutter_phase),
                              l.y0 + 0.3 * det::det_cos_cycle(l.flutter_freq * f, kPeriod, l.flutter_phase),
                              kFallTop - (kFallTop - kFallBottom) * fall};
            double ang[3];
            for (int a = 0; a < 3; ++a) {
                const std::int64_t s = (l.spin[a] * f) % kPeriod;
                ang[a] = l.angle0[a] + det::kTwoPi * (static_cast<double>(s) / kPeriod);
            }
            const Rotation rot = rotation_from_angles(ang[0], ang[1], ang[2]);
            const double curl = 0.06 * det::det_sin_cycle(l.curl_freq * f, kPeriod, l.curl_phase);
            Mesh leaf;
            leaf.name = "leaf_" + std::to_string(i);
            append_grid(leaf, 4, 2, false, false, [&](int a, int b) {
                return centre + apply(rot, leaf_point(a, b, 4, 2, 0.3, 0.2, curl));
            });
            out.push_back(std::move(leaf));
        }
        return out;
    }

   private:
    Mesh tree_;
    int leaves_ = 0;
    std::vector<FallingLeaf> falling_;
    double sway_phase_ = 0;
};

}  // namespace

std::unique_ptr<SceneGenerator> make_leaves(const SceneOptions& options) {
    return std::make_unique<LeavesScene>(options);
}

}  // namespace cullide::scene_kit
