// cylinders.cpp: CULLIDE's environment 1 (Govindaraju et al., Graphics Hardware 2003): 100 deforming
// open cylinders of 200 triangles each moving randomly in a room.
//
// Each cylinder is a bent tube (a parabolic centre line whose curvature oscillates) that wanders on
// a Lissajous path of two harmonics per axis and tumbles at constant angular rates. Every frequency
// is an integer number of cycles per kPeriod frames, so frame f is a closed formula of f mod
// kPeriod (the motion loops seamlessly) and arguments of det_sin never grow.
#include <string>

#include "scene_math.h"
#include "scenes/scene_kit.h"

namespace cullide::scene_kit {

namespace {

constexpr std::int64_t kPeriod = 600;       // frames (20 s) before the motion repeats
constexpr int kAround = 10;                 // vertices around a tube
constexpr int kRings = 10;                  // bands along it: 2 * 10 * 10 = 200 triangles
constexpr double kRoomSide100 = 12.0;       // room side for 100 cylinders
constexpr double kHalfLength = 1.0;         // half the tube length
constexpr double kRadius = 0.15;
constexpr double kMaxBend = 0.3;            // tip offset of the parabola at full bend

struct CylinderParams {
    double amp[3][2];       // per axis, two harmonics: amplitude (fraction of the free half-room)
    std::int64_t freq[3][2];
    double phase[3][2];
    double angle0[3];       // yaw, pitch, roll at f = 0
    std::int64_t spin[3];   // whole turns per period
    std::int64_t bend_freq;
    double bend_phase;
};

class CylindersScene final : public SceneGenerator {
   public:
    explicit CylindersScene(const SceneOptions& options) {
        count_ = static_cast<int>(round_at_least(100.0 * options.scale, 1));
        // Keep the density of the 100-cylinder room: the side grows with the cube root of the count.
        room_ = kRoomSide100 * det::det_cbrt(static_cast<double>(count_) / 100.0);
        params_.reserve(static_cast<std::size_t>(count_));
        for (int i = 0; i < count_; ++i) {
            det::SplitMix64 rng(det::stream_seed(options.seed, kPartCylinders, static_cast<std::uint64_t>(i)));
            CylinderParams p{};
            for (int a = 0; a < 3; ++a) {
                const double w = rng.uniform(0.55, 0.8);
                p.amp[a][0] = w;
                p.amp[a][1] = 1.0 - w;
                p.freq[a][0] = rng.between(1, 3);
                p.freq[a][1] = rng.between(3, 7);
                p.phase[a][0] = rng.uniform(0.0, det::kTwoPi);
                p.phase[a][1] = rng.uniform(0.0, det::kTwoPi);
                p.angle0[a] = rng.uniform(0.0, det::kTwoPi);
                p.spin[a] = rng.between(-4, 4);
            }
            p.bend_freq = rng.between(6, 14);
            p.bend_phase = rng.uniform(0.0, det::kTwoPi);
            params_.push_back(p);
        }
    }

    [[nodiscard]] std::string name() const override { return "cylinders"; }
    [[nodiscard]] std::string description() const override {
        return std::to_string(count_) + " bending open cylinders x 200 triangles (" +
               std::to_string(count_ * 200) + ") moving randomly in a room (CULLIDE env. 1); scale multiplies "
               "the cylinder count";
    }

    [[nodiscard]] Frame frame(int f) const override {
        Frame out;
        out.reserve(params_.size());
        const double free_half = room_ / 2.0 - (kHalfLength + kMaxBend + kRadius);
        for (std::size_t i = 0; i < params_.size(); ++i) {
            const CylinderParams& p = params_[i];
            Vec3 centre;
            for (int a = 0; a < 3; ++a) {
                const double s0 = det::det_sin_cycle(p.freq[a][0] * f, kPeriod, p.phase[a][0]);
                const double s1 = det::det_sin_cycle(p.freq[a][1] * f, kPeriod, p.phase[a][1]);
                centre[a] = room_ / 2.0 + free_half * (p.amp[a][0] * s0 + p.amp[a][1] * s1);
            }
            double ang[3];
            for (int a = 0; a < 3; ++a) {
                std::int64_t m = (p.spin[a] * f) % kPeriod;
                ang[a] = p.angle0[a] + det::kTwoPi * (static_cast<double>(m) / static_cast<double>(kPeriod));
            }
            const Rotation rot = rotation_from_angles(ang[0], ang[1], ang[2]);
            // Curvature k of the centre line x = k (s^2 - h^2/3), z = s (zero mean offset, so bending
            // does not shift the tube's middle).
            const double bend = kMaxBend * det::det_sin_cycle(p.bend_freq * f, kPeriod, p.bend_phase);
            const double k = bend / (kHalfLength * kHalfLength);
            Mesh m;
            m.name = "cylinder_" + std::to_string(i);
            m.positions.reserve(static_cast<std::size_t>(kAround * (kRings + 1)));
            append_grid(m, kAround, kRings, true, false, [&](int ia, int jr) {
                const double s = -kHalfLength + 2.0 * kHalfLength * (static_cast<double>(jr) / kRings);
                const Vec3 axis_point{k * (s * s - kHalfLength * kHalfLength / 3.0), 0.0, s};
                // Cross-section perpendicular to the tangent (2 k s, 0, 1).
                const Vec3 normal = normalized({1.0, 0.0, -2.0 * k * s});
                const Vec3 binormal{0.0, 1.0, 0.0};
                double sa = 0, ca = 0;
                det::det_sincos(det::kTwoPi * (static_cast<double>(ia) / kAround), sa, ca);
                const Vec3 local = axis_point + kRadius * (ca * normal + sa * binormal);
                return centre + apply(rot, local);
            });
            out.push_back(std::move(m));
        }
        return out;
    }

   private:
    int count_ = 0;
    double room_ = 0;
    std::vector<CylinderParams> params_;
};

}  // namespace

std::unique_ptr<SceneGenerator> make_cylinders(const SceneOptions& options) {
    return std::make_unique<CylindersScene>(options);
}

}  // namespace cullide::scene_kit
