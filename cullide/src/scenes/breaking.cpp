// breaking.cpp: CULLIDE's breaking object (Govindaraju et al., Graphics Hardware 2003: a breaking
// dragon with the bunny falling through it), rebuilt procedurally: a bumpy spherical shell cut into
// kChunks pieces along seeded Voronoi cells (each triangle goes to the nearest of kChunks seed
// triangles), each piece a separate object, and a bumpy ball falling through it. The shell holds
// still until the ball reaches it, then the pieces drift apart, tumbling and dropping. The story
// replays every kPeriod frames.
#include <cmath>
#include <string>

#include "scene_math.h"
#include "scenes/scene_kit.h"

namespace cullide::scene_kit {

namespace {

constexpr std::int64_t kPeriod = 120;        // frames per replay
constexpr std::int64_t kBreakFrame = 24;     // pieces start moving (the ball touches the shell)
constexpr std::int64_t kShellTriangles = 100000;
constexpr std::int64_t kBallTriangles = 20000;
constexpr int kChunks = 40;
constexpr double kShellRadius = 1.5;
constexpr double kBallRadius = 0.45;
constexpr double kBallStartZ = 3.5;          // ball centre at frame 0
constexpr double kBallSpeed = 2.0;           // units per second, straight down through the centre
constexpr double kGravity = 1.0;             // the pieces' drop, units per second^2

struct Chunk {
    Mesh rest;
    Vec3 centre;       // vertex mean at rest: the pivot of its tumbling
    Vec3 direction;    // outward drift direction (unit)
    double speed = 0;  // units per second
    Vec3 spin_axis;
    double spin_rate = 0;  // radians per second
};

class BreakingScene final : public SceneGenerator {
   public:
    explicit BreakingScene(const SceneOptions& options) {
        det::SplitMix64 rng(det::stream_seed(options.seed, kPartBreaking, 0));
        const double phase_a = rng.uniform(0.0, det::kTwoPi);
        const double phase_b = rng.uniform(0.0, det::kTwoPi);
        const Mesh shell = make_blob(
            "shell", round_at_least(static_cast<double>(kShellTriangles) * options.scale, 2 * kChunks), [&](Vec3 d) {
                const double r = kShellRadius * (1.0 + 0.04 * det::det_sin(5.0 * d.x + phase_a) *
                                                           det::det_cos(4.0 * d.y + phase_b));
                return r * d;
            });
        const std::size_t n = shell.triangles.size();
        std::vector<Vec3> centroid(n);
        for (std::size_t t = 0; t < n; ++t) {
            const Tri& tri = shell.triangles[t];
            centroid[t] = (1.0 / 3.0) * ((shell.positions[tri[0]] + shell.positions[tri[1]]) + shell.positions[tri[2]]);
        }
        // Seeds: kChunks distinct triangles; each seed's own triangle is nearest to itself, so no
        // chunk is empty.
        std::vector<std::size_t> seeds;
        while (seeds.size() < static_cast<std::size_t>(kChunks)) {
            const auto s = static_cast<std::size_t>(rng.below(n));
            bool taken = false;
            for (std::size_t k : seeds) taken = taken || k == s;
            if (!taken) seeds.push_back(s);
        }
        std::vector<std::vector<std::size_t>> members(seeds.size());
        for (std::size_t t = 0; t < n; ++t) {
            std::size_t best = 0;
            double best_d = 0;
            for (std::size_t k = 0; k < seeds.size(); ++k) {
                const Vec3 d = centroid[t] - centroid[seeds[k]];
                const double dd = dot(d, d);
                if (k == 0 || dd < best_d) {
                    best = k;
                    best_d = dd;
                }
            }
            members[best].push_back(t);
        }
        for (std::size_t k = 0; k < seeds.size(); ++k) {
            Chunk c;
            c.rest.name = "chunk_" + std::to_string(k);
            c.rest.positions = shell.positions;
            for (std::size_t t : members[k]) c.rest.triangles.push_back(shell.triangles[t]);
            compact_vertices(c.rest);
            Vec3 sum;
            for (const Vec3& p : c.rest.positions) sum = sum + p;
            c.centre = (1.0 / static_cast<double>(c.rest.positions.size())) * sum;
            c.direction = normalized(centroid[seeds[k]]);
            c.speed = rng.uniform(0.3, 0.7);
            c.spin_axis = normalized({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.1, 1)});
            c.spin_rate = rng.uniform(-1.5, 1.5);
            chunks_.push_back(std::move(c));
        }
        ball_ = make_blob("ball", round_at_least(static_cast<double>(kBallTriangles) * options.scale, 8), [](Vec3 d) {
            const double r = kBallRadius * (1.0 + 0.08 * det::det_sin(6.0 * d.x) * det::det_sin(5.0 * d.y + 0.5));
            return r * d;
        });
        shell_triangles_ = n;
    }

    [[nodiscard]] std::string name() const override { return "breaking"; }
    [[nodiscard]] std::string description() const override {
        return "a shell of " + std::to_string(shell_triangles_) + " triangles broken into " +
               std::to_string(chunks_.size()) + " drifting pieces, a ball of " +
               std::to_string(ball_.triangles.size()) + " triangles falling through it; scale multiplies the "
               "triangle counts";
    }

    [[nodiscard]] Frame frame(int f) const override {
        std::int64_t g = f % kPeriod;
        if (g < 0) g += kPeriod;
        const double t = static_cast<double>(g) / kFramesPerSecond;
        const double since_break =
            g > kBreakFrame ? static_cast<double>(g - kBreakFrame) / kFramesPerSecond : 0.0;
        Frame out;
        out.reserve(chunks_.size() + 1);
        for (const Chunk& c : chunks_) {
            Mesh m = c.rest;
            const Rotation rot = rotation_about(c.spin_axis, c.spin_rate * since_break);
            const Vec3 drift =
                (c.speed * since_break) * c.direction + Vec3{0, 0, -0.5 * kGravity * since_break * since_break};
            // At rest the pieces must meet exactly along their seams: c + (p - c) is not p in floating
            // point, so the rest positions are used as they are until the break.
            if (since_break > 0) {
                for (Vec3& p : m.positions) p = (c.centre + apply(rot, p - c.centre)) + drift;
            }
            out.push_back(std::move(m));
        }
        Mesh ball = ball_;
        const Rotation spin = rotation_about({0.6, 0.0, 0.8}, 1.2 * t);
        const Vec3 at{0.05, -0.03, kBallStartZ - kBallSpeed * t};
        for (Vec3& p : ball.positions) p = apply(spin, p) + at;
        out.push_back(std::move(ball));
        return out;
    }

   private:
    std::vector<Chunk> chunks_;
    Mesh ball_;
    std::size_t shell_triangles_ = 0;
};

}  // namespace

std::unique_ptr<SceneGenerator> make_breaking(const SceneOptions& options) {
    return std::make_unique<BreakingScene>(options);
}

}  // namespace cullide::scene_kit
