// bunny_dragon.cpp: CULLIDE's bunny and dragon pair (Govindaraju et al., Graphics Hardware 2003)
// and R-CULLIDE's interpenetrating pair: the Stanford bunny passes through the dragon and back.
//
// The real meshes (stanford-bunny.obj, 69,451 triangles; dragon.obj, 100,000) are read once, when
// the generator is made, from SceneOptions::mesh_dir; a missing folder or file falls back to a
// procedural stand-in with the same triangle count, and a file that is present but does not parse
// makes make_scene fail with the reader's message. Both are normalised (centred on their box,
// largest side kDragonSize / kBunnySize) and kept; frames only move the bunny.
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

#include "cullide/mesh_io.h"
#include "scene_math.h"
#include "scenes/scene_kit.h"

namespace cullide::scene_kit {

namespace {

constexpr std::int64_t kPeriod = 120;  // frames for a pass there and back (apart at 0, centred at 30)
constexpr std::int64_t kBunnyTriangles = 69451;
constexpr std::int64_t kDragonTriangles = 100000;
constexpr double kDragonSize = 2.0;
constexpr double kBunnySize = 0.9;

struct Part {
    Mesh mesh;
    std::string origin;  // "file <path>" or "stand-in"
};

// Largest box side and box centre of a mesh with triangles.
void box_of(const Mesh& m, Vec3& centre, Vec3& extent) {
    const Aabb b = mesh_bounds(m);
    centre = 0.5 * (b.lo + b.hi);
    extent = b.hi - b.lo;
}

void normalise(Mesh& m, double size) {
    Vec3 centre, extent;
    box_of(m, centre, extent);
    double largest = extent.x > extent.y ? extent.x : extent.y;
    largest = largest > extent.z ? largest : extent.z;
    const double factor = largest > 0 ? size / largest : 1.0;
    for (Vec3& p : m.positions) p = factor * (p - centre);
}

// Keeps `keep` of the triangles, evenly spread over the file order, for scale < 1 (the real files
// have no level of detail; striding keeps the shape's outline at a lower density).
void thin_out(Mesh& m, std::int64_t keep) {
    const auto total = static_cast<std::int64_t>(m.triangles.size());
    if (keep >= total) return;
    std::vector<Tri> kept;
    kept.reserve(static_cast<std::size_t>(keep));
    for (std::int64_t j = 0; j < keep; ++j) kept.push_back(m.triangles[static_cast<std::size_t>(j * total / keep)]);
    m.triangles = std::move(kept);
    compact_vertices(m);
}

// The real mesh, nothing when the folder or file is absent, or the reader's error.
Result<std::optional<Mesh>> load_real(const std::string& dir, const std::string& file, const std::string& name) {
    if (dir.empty()) return std::optional<Mesh>{};
    const std::string path = (std::filesystem::path(dir) / file).string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return std::optional<Mesh>{};
    Result<std::vector<Mesh>> read = read_mesh_file(path);
    if (!read) return Error{"scene 'bunny-dragon': " + read.error().message};
    Mesh merged;
    merged.name = name;
    for (const Mesh& part : read.value()) {
        const auto base = static_cast<std::uint32_t>(merged.positions.size());
        merged.positions.insert(merged.positions.end(), part.positions.begin(), part.positions.end());
        for (const Tri& t : part.triangles) merged.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    if (merged.triangles.empty()) return Error{"scene 'bunny-dragon': " + path + ": has no triangles"};
    return std::optional<Mesh>{std::move(merged)};
}

Mesh bunny_stand_in(std::int64_t triangles) {
    return make_blob("bunny", triangles, [](Vec3 d) {
        const double r = 1.0 + 0.15 * det::det_sin(4.0 * d.x + 1.0) * det::det_cos(3.0 * d.y) +
                         0.1 * det::det_sin(6.0 * d.z);
        return r * Vec3{d.x, 0.85 * d.y, 0.9 * d.z};
    });
}

Mesh dragon_stand_in(std::int64_t triangles) {
    return make_blob("dragon", triangles, [](Vec3 d) {
        const double r = 1.0 + 0.1 * det::det_sin(7.0 * d.x) * det::det_cos(5.0 * d.z) +
                         0.08 * det::det_sin(9.0 * d.y + 2.0);
        return r * Vec3{d.x, 0.7 * d.y, 0.35 * d.z};
    });
}

Result<Part> make_part(const SceneOptions& options, const std::string& file, const std::string& name,
                       std::int64_t full_count, Mesh (*stand_in)(std::int64_t)) {
    const std::int64_t wanted = round_at_least(static_cast<double>(full_count) * options.scale, 8);
    Result<std::optional<Mesh>> real = load_real(options.mesh_dir, file, name);
    if (!real) return real.error();
    Part part;
    if (real.value()) {
        part.mesh = std::move(*real.value());
        thin_out(part.mesh, wanted);  // scale > 1 keeps the file as it is
        part.origin = "file " + (std::filesystem::path(options.mesh_dir) / file).string();
    } else {
        part.mesh = stand_in(wanted);
        part.origin = "stand-in";
    }
    return part;
}

class BunnyDragonScene final : public SceneGenerator {
   public:
    BunnyDragonScene(Part bunny, Part dragon) : bunny_(std::move(bunny)), dragon_(std::move(dragon)) {
        normalise(dragon_.mesh, kDragonSize);
        normalise(bunny_.mesh, kBunnySize);
        // The bunny travels along the dragon's thinnest box axis, through the box centre, from just
        // clear of one side to just clear of the other.
        Vec3 centre, extent;
        box_of(dragon_.mesh, centre, extent);
        axis_ = 0;
        for (int a = 1; a < 3; ++a) {
            if (extent[a] < extent[axis_]) axis_ = a;
        }
        travel_ = extent[axis_] / 2.0 + kBunnySize * 0.75;
    }

    [[nodiscard]] std::string name() const override { return "bunny-dragon"; }
    [[nodiscard]] std::string description() const override {
        return "bunny (" + std::to_string(bunny_.mesh.triangles.size()) + " triangles, " +
               bunny_.origin + ") passing through dragon (" + std::to_string(dragon_.mesh.triangles.size()) +
               " triangles, " + dragon_.origin + "); scale thins the triangles (real files are never refined)";
    }

    [[nodiscard]] Frame frame(int f) const override {
        Frame out;
        out.push_back(dragon_.mesh);
        Mesh bunny = bunny_.mesh;
        Vec3 shift;
        shift[axis_] = -travel_ * det::det_cos_cycle(f, kPeriod, 0.0);
        Vec3 spin_axis;
        spin_axis[axis_] = 1.0;
        const Rotation rot = rotation_about(spin_axis, 0.5 * det::det_sin_cycle(f, kPeriod, 0.0));
        for (Vec3& p : bunny.positions) p = apply(rot, p) + shift;
        out.push_back(std::move(bunny));
        return out;
    }

   private:
    Part bunny_, dragon_;
    int axis_ = 2;
    double travel_ = 1.0;
};

}  // namespace

Result<std::unique_ptr<SceneGenerator>> make_bunny_dragon(const SceneOptions& options) {
    Result<Part> bunny = make_part(options, "stanford-bunny.obj", "bunny", kBunnyTriangles, bunny_stand_in);
    if (!bunny) return bunny.error();
    Result<Part> dragon = make_part(options, "dragon.obj", "dragon", kDragonTriangles, dragon_stand_in);
    if (!dragon) return dragon.error();
    return std::unique_ptr<SceneGenerator>(
        std::make_unique<BunnyDragonScene>(std::move(bunny).value(), std::move(dragon).value()));
}

}  // namespace cullide::scene_kit
