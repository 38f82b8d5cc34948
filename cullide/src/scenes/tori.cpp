// tori.cpp: CULLIDE's deforming tori (Govindaraju et al., Graphics Hardware 2003, plotted only):
// kTori tori of 20,000 triangles each. Their centres sit on a ring that breathes in and out, so
// neighbours interpenetrate for part of the period and are apart for the rest; each torus tumbles,
// its major radius pulses and a wave runs around its tube (minor radius modulated).
#include <array>
#include <cmath>
#include <string>

#include "scene_math.h"
#include "scenes/scene_kit.h"

namespace cullide::scene_kit {

namespace {

constexpr std::int64_t kPeriod = 240;  // frames (8 s)
constexpr int kTori = 6;
constexpr int kCells100 = 100;         // cells per direction at scale 1: 2 * 100 * 100 = 20,000
constexpr double kMajor = 1.0;
constexpr double kMinor = 0.3;
constexpr double kRingMean = 1.9;      // distance of the centres from the scene axis (= neighbour gap)
constexpr double kRingSwing = 0.8;

struct TorusParams {
    double angle0[3];
    std::int64_t spin[3];
    std::int64_t pulse_freq, wave_freq, lift_freq;
    double pulse_phase, wave_phase, lift_phase;
    int lobes;
};

class ToriScene final : public SceneGenerator {
   public:
    explicit ToriScene(const SceneOptions& options) {
        cells_ = static_cast<int>(round_at_least(kCells100 * std::sqrt(options.scale), 3));
        det::SplitMix64 ring_rng(det::stream_seed(options.seed, kPartTori, 1000));
        ring_phase_ = ring_rng.uniform(0.0, det::kTwoPi);
        for (int i = 0; i < kTori; ++i) {
            det::SplitMix64 rng(det::stream_seed(options.seed, kPartTori, static_cast<std::uint64_t>(i)));
            TorusParams& p = params_[static_cast<std::size_t>(i)];
            for (int a = 0; a < 3; ++a) {
                p.angle0[a] = rng.uniform(0.0, det::kTwoPi);
                p.spin[a] = rng.between(-2, 2);
            }
            p.pulse_freq = rng.between(2, 5);
            p.wave_freq = rng.between(3, 8);
            p.lift_freq = rng.between(1, 3);
            p.pulse_phase = rng.uniform(0.0, det::kTwoPi);
            p.wave_phase = rng.uniform(0.0, det::kTwoPi);
            p.lift_phase = rng.uniform(0.0, det::kTwoPi);
            p.lobes = static_cast<int>(rng.between(2, 5));
        }
    }

    [[nodiscard]] std::string name() const override { return "tori"; }
    [[nodiscard]] std::string description() const override {
        const int tris = 2 * cells_ * cells_;
        return std::to_string(kTori) + " deforming tori x " + std::to_string(tris) + " triangles (" +
               std::to_string(kTori * tris) + "), meeting and parting on a breathing ring; scale multiplies the "
               "triangles per torus";
    }

    [[nodiscard]] Frame frame(int f) const override {
        Frame out;
        const double ring = kRingMean + kRingSwing * det::det_sin_cycle(f, kPeriod, ring_phase_);
        for (int i = 0; i < kTori; ++i) {
            const TorusParams& p = params_[static_cast<std::size_t>(i)];
            double sc = 0, cc = 0;
            det::det_sincos(det::kTwoPi * (static_cast<double>(i) / kTori), sc, cc);
            const Vec3 centre{ring * cc, ring * sc, 0.4 * det::det_sin_cycle(p.lift_freq * f, kPeriod, p.lift_phase)};
            double ang[3];
            for (int a = 0; a < 3; ++a) {
                const std::int64_t m = (p.spin[a] * f) % kPeriod;
                ang[a] = p.angle0[a] + det::kTwoPi * (static_cast<double>(m) / static_cast<double>(kPeriod));
            }
            const Rotation rot = rotation_from_angles(ang[0], ang[1], ang[2]);
            const double major = kMajor * (1.0 + 0.08 * det::det_sin_cycle(p.pulse_freq * f, kPeriod, p.pulse_phase));
            const std::int64_t wave_m = (p.wave_freq * f) % kPeriod;
            const double wave = p.wave_phase + det::kTwoPi * (static_cast<double>(wave_m) / kPeriod);
            Mesh m;
            m.name = "torus_" + std::to_string(i);
            m.positions.reserve(static_cast<std::size_t>(cells_) * static_cast<std::size_t>(cells_));
            append_grid(m, cells_, cells_, true, true, [&](int iu, int iv) {
                double su = 0, cu = 0, sv = 0, cv = 0;
                const double u = det::kTwoPi * (static_cast<double>(iu) / cells_);
                det::det_sincos(u, su, cu);
                det::det_sincos(det::kTwoPi * (static_cast<double>(iv) / cells_), sv, cv);
                const double minor = kMinor * (1.0 + 0.2 * det::det_sin(p.lobes * u + wave) * cv);
                const double rr = major + minor * cv;
                return centre + apply(rot, Vec3{rr * cu, rr * su, minor * sv});
            });
            out.push_back(std::move(m));
        }
        return out;
    }

   private:
    int cells_ = 0;
    double ring_phase_ = 0;
    std::array<TorusParams, kTori> params_{};
};

}  // namespace

std::unique_ptr<SceneGenerator> make_tori(const SceneOptions& options) { return std::make_unique<ToriScene>(options); }

}  // namespace cullide::scene_kit
