// scenes.cpp: the scene registry, option checks and the frame digest. The scenes themselves are in
// scenes/*.cpp, one file per scene (docs/scenes.md describes each).
#include "cullide/scenes.h"

#include <bit>
#include <charconv>
#include <cmath>
#include <system_error>

#include "scenes/scene_kit.h"

namespace cullide {

namespace {

std::string format_double(double v) {
    char buf[64];
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof(buf), v);
    return r.ec == std::errc() ? std::string(buf, r.ptr) : std::string("?");
}

std::string joined_names() {
    std::string out;
    for (const std::string& n : scene_names()) out += (out.empty() ? "" : ", ") + n;
    return out;
}

}  // namespace

std::vector<std::string> scene_names() { return {"cylinders", "tori", "bunny-dragon", "breaking", "leaves", "cloth"}; }

Result<std::unique_ptr<SceneGenerator>> make_scene(const std::string& name, const SceneOptions& options) {
    if (!(std::isfinite(options.scale) && options.scale > 0.0 && options.scale <= kMaxSceneScale)) {
        return Error{"scene option scale = " + format_double(options.scale) +
                     " is out of range: it must be finite, > 0 and <= 100"};
    }
    if (name == "cylinders") return scene_kit::make_cylinders(options);
    if (name == "tori") return scene_kit::make_tori(options);
    if (name == "bunny-dragon") return scene_kit::make_bunny_dragon(options);
    if (name == "breaking") return scene_kit::make_breaking(options);
    if (name == "leaves") return scene_kit::make_leaves(options);
    if (name == "cloth") return scene_kit::make_cloth(options);
    return Error{"unknown scene '" + name + "' (valid: " + joined_names() + ")"};
}

std::uint64_t frame_digest(const Frame& frame) {
    constexpr std::uint64_t kPrime = 0x100000001B3ULL;
    std::uint64_t h = 0xCBF29CE484222325ULL;
    auto eat = [&](std::uint64_t v, int bytes) {
        for (int b = 0; b < bytes; ++b) {
            h ^= (v >> (8 * b)) & 0xFFu;
            h *= kPrime;
        }
    };
    eat(frame.size(), 8);
    for (const Mesh& m : frame) {
        eat(m.positions.size(), 8);
        for (const Vec3& p : m.positions) {
            eat(std::bit_cast<std::uint64_t>(p.x), 8);
            eat(std::bit_cast<std::uint64_t>(p.y), 8);
            eat(std::bit_cast<std::uint64_t>(p.z), 8);
        }
        eat(m.triangles.size(), 8);
        for (const Tri& t : m.triangles) {
            for (std::uint32_t v : t) eat(v, 4);
        }
    }
    return h;
}

}  // namespace cullide
