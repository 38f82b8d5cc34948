// cloth.cpp: Quick-CULLIDE's cloth self-collision workload (Govindaraju, Lin & Manocha, IEEE VR 2005:
// cloth of tens of thousands of triangles), made procedural: one square sheet (a regular grid, two
// triangles per cell) whose flap folds over onto the rest around a rounded crease. The fold angle
// swings from 0 (flat, frame 0) past 180 degrees (frame kPeriod/2), so the rippled flap first comes
// within a few hundredths of the base (near contacts) and then dips through it (self-intersections),
// and unfolds again. A small ball (the collider) bobs under the sheet and pokes through it at the top
// of its stroke.
#include <cmath>
#include <string>

#include "scene_math.h"
#include "scenes/scene_kit.h"

namespace cullide::scene_kit {

namespace {

constexpr std::int64_t kPeriod = 120;       // frames per fold and unfold
constexpr int kCells100 = 100;              // cells per side at scale 1: 2 * 100 * 100 = 20,000
constexpr std::int64_t kBallTriangles100 = 800;
constexpr double kSide = 2.0;               // the sheet spans [0, 2] x [0, 2] at rest
constexpr double kCrease = 1.1;             // fold line x = kCrease; the flap is x > kCrease
constexpr double kBendRadius = 0.025;       // radius of the rounded crease
constexpr double kOverFold = 0.3;           // radians past 180 degrees at the deepest fold
constexpr double kFlapRipple = 0.03;        // ripple amplitude on the flap, along its normal
constexpr double kBaseRipple = 0.008;
constexpr double kBallRadius = 0.22;

class ClothScene final : public SceneGenerator {
   public:
    explicit ClothScene(const SceneOptions& options) {
        cells_ = static_cast<int>(round_at_least(kCells100 * std::sqrt(options.scale), 4));
        det::SplitMix64 rng(det::stream_seed(options.seed, kPartCloth, 0));
        ripple_phase_ = rng.uniform(0.0, det::kTwoPi);
        ripple_waves_ = static_cast<int>(rng.between(2, 4));
        bob_phase_ = rng.uniform(0.0, det::kTwoPi);
        ball_ = make_blob("collider", round_at_least(static_cast<double>(kBallTriangles100) * options.scale, 8),
                          [](Vec3 d) { return kBallRadius * d; });
    }

    [[nodiscard]] std::string name() const override { return "cloth"; }
    [[nodiscard]] std::string description() const override {
        return "one " + std::to_string(2 * cells_ * cells_) +
               "-triangle sheet folding onto itself (self-collision, Q-CULLIDE) over a bobbing ball of " +
               std::to_string(ball_.triangles.size()) + " triangles; scale multiplies the triangle counts";
    }

    [[nodiscard]] Frame frame(int f) const override {
        const double theta = (det::kPi + kOverFold) * (0.5 - 0.5 * det::det_cos_cycle(f, kPeriod, 0.0));
        const double ripple_shift = det::kTwoPi * 0.25 * det::det_sin_cycle(f, kPeriod, 0.0);
        double st = 0, ct = 0;
        det::det_sincos(theta, st, ct);
        const double arc = kBendRadius * theta;
        Frame out;
        Mesh cloth;
        cloth.name = "cloth";
        cloth.positions.reserve(static_cast<std::size_t>(cells_ + 1) * static_cast<std::size_t>(cells_ + 1));
        append_grid(cloth, cells_, cells_, false, false, [&](int i, int j) {
            const double x = kSide * (static_cast<double>(i) / cells_);
            const double y = kSide * (static_cast<double>(j) / cells_);
            const double wave = det::det_sin(det::kTwoPi * ripple_waves_ * (y / kSide) + ripple_phase_ + ripple_shift);
            if (x <= kCrease) {
                double sb = 0, cb = 0;
                det::det_sincos(det::kPi * (x / kCrease), sb, cb);
                return Vec3{x, y, kBaseRipple * wave * sb};
            }
            // Along the flap: distance d from the crease; on the rounded crease while d <= arc, then
            // straight on along the crease's end tangent. (px, pz) and the unit normal (nx, nz) are
            // in the x-z plane.
            const double d = x - kCrease;
            double px = 0, pz = 0, nx = 0, nz = 0;
            if (d <= arc) {
                double sa = 0, ca = 0;
                det::det_sincos(d / kBendRadius, sa, ca);
                px = kCrease + kBendRadius * sa;
                pz = kBendRadius * (1.0 - ca);
                nx = -sa;
                nz = ca;
            } else {
                px = (kCrease + kBendRadius * st) + (d - arc) * ct;
                pz = kBendRadius * (1.0 - ct) + (d - arc) * st;
                nx = -st;
                nz = ct;
            }
            // The ripple grows from the crease outwards, so the crease itself stays smooth.
            const double grow = d / (kSide - kCrease);
            const double r = kFlapRipple * wave * grow;
            return Vec3{px + r * nx, y, pz + r * nz};
        });
        out.push_back(std::move(cloth));
        Mesh ball = ball_;
        const Vec3 at{0.55, 1.0, -kBallRadius - 0.02 + 0.06 * det::det_sin_cycle(3LL * f, kPeriod, bob_phase_)};
        for (Vec3& p : ball.positions) p = p + at;
        out.push_back(std::move(ball));
        return out;
    }

   private:
    int cells_ = 0;
    double ripple_phase_ = 0;
    int ripple_waves_ = 2;
    double bob_phase_ = 0;
    Mesh ball_;
};

}  // namespace

std::unique_ptr<SceneGenerator> make_cloth(const SceneOptions& options) { return std::make_unique<ClothScene>(options); }

}  // namespace cullide::scene_kit
