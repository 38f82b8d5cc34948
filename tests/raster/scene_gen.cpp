// scene_gen.cpp: see scene_gen.h.
#include "scene_gen.h"

namespace raster_test {

namespace {
constexpr raster::DepthFunc kFuncs[] = {raster::DepthFunc::Never,   raster::DepthFunc::Less,
                                        raster::DepthFunc::Equal,   raster::DepthFunc::LEqual,
                                        raster::DepthFunc::Greater, raster::DepthFunc::NotEqual,
                                        raster::DepthFunc::GEqual,  raster::DepthFunc::Always};

// Window coordinate -> NDC for a viewport starting at 0 of size n (exact for dyadic inputs).
float to_ndc(float w, int n) { return w * (2.0f / static_cast<float>(n)) - 1.0f; }
}  // namespace

raster::Float4 random_vertex(SplitMix64& rng, int width, int height, int flavour) {
    raster::Float4 v;
    switch (flavour) {
        case 0:  // anywhere, some off-screen, some crossing near/far
            v = {rng.uniform(-1.3f, 1.3f), rng.uniform(-1.3f, 1.3f), rng.uniform(-1.2f, 1.2f), 1.0f};
            break;
        case 1: {  // on pixel centres
            const float x = static_cast<float>(rng.below(static_cast<std::uint32_t>(width))) + 0.5f;
            const float y = static_cast<float>(rng.below(static_cast<std::uint32_t>(height))) + 0.5f;
            v = {to_ndc(x, width), to_ndc(y, height), rng.uniform(-0.9f, 0.9f), 1.0f};
            break;
        }
        case 2: {  // on the 1/256 grid, or half a grid step off it (snapping ties)
            const float x = static_cast<float>(rng.below(static_cast<std::uint32_t>(width) * 256u)) / 256.0f +
                            (rng.chance(30) ? 1.0f / 512.0f : 0.0f);
            const float y = static_cast<float>(rng.below(static_cast<std::uint32_t>(height) * 256u)) / 256.0f;
            v = {to_ndc(x, width), to_ndc(y, height), rng.uniform(-0.9f, 0.9f), 1.0f};
            break;
        }
        case 3: {  // perspective: a random w, sometimes behind the eye (w < 0)
            const float w = rng.chance(10) ? rng.uniform(-1.0f, -0.1f) : rng.uniform(0.2f, 4.0f);
            v = {rng.uniform(-1.2f, 1.2f) * w, rng.uniform(-1.2f, 1.2f) * w, rng.uniform(-1.3f, 1.3f) * w, w};
            break;
        }
        default:  // on integer pixel corners (edges through centres on half-integer slopes)
            v = {to_ndc(static_cast<float>(rng.below(static_cast<std::uint32_t>(width) + 1)), width),
                 to_ndc(static_cast<float>(rng.below(static_cast<std::uint32_t>(height) + 1)), height),
                 rng.uniform(-0.9f, 0.9f), 1.0f};
            break;
    }
    return v;
}

void build_scene(Scene& scene, SplitMix64& rng, const SceneOptions& o) {
    scene.batch = raster::CommandBatch(o.width, o.height, o.rules);
    scene.vertices.clear();
    scene.indices.clear();
    scene.clear_depth = rng.chance(80) ? 1.0 : static_cast<double>(rng.uniform(0.0f, 1.0f));
    scene.query_count = 0;
    for (int obj = 0; obj < o.objects; ++obj) {
        auto& vs = scene.vertices.emplace_back();
        auto& is = scene.indices.emplace_back();
        const int flavour = static_cast<int>(rng.below(5));
        const std::uint32_t shape = rng.below(10);
        if (shape < 5) {  // one triangle
            for (int k = 0; k < 3; ++k) vs.push_back(random_vertex(rng, o.width, o.height, flavour));
            if (rng.chance(15)) {  // sliver: third vertex near the first
                vs[2] = vs[0];
                vs[2].x += rng.uniform(-0.01f, 0.01f) * vs[2].w;
                vs[2].y += rng.uniform(-0.01f, 0.01f) * vs[2].w;
            }
            is = {0, 1, 2};
        } else if (shape < 8) {  // a fan of triangles sharing edges (watertightness, shared edges)
            const int n = 3 + static_cast<int>(rng.below(5));
            const raster::Float4 centre = random_vertex(rng, o.width, o.height, flavour);
            vs.push_back(centre);
            for (int k = 0; k < n; ++k) vs.push_back(random_vertex(rng, o.width, o.height, flavour));
            for (int k = 0; k < n; ++k) {
                is.push_back(0);
                is.push_back(1 + static_cast<std::uint32_t>(k));
                is.push_back(1 + static_cast<std::uint32_t>((k + 1) % n));
            }
        } else {  // a small grid mesh (a height field), quads split in two
            const int gx = 2 + static_cast<int>(rng.below(4)), gy = 2 + static_cast<int>(rng.below(4));
            const float x0 = rng.uniform(-1.2f, 0.8f), y0 = rng.uniform(-1.2f, 0.8f);
            const float sx = rng.uniform(0.01f, 0.3f), sy = rng.uniform(0.01f, 0.3f);
            for (int j = 0; j <= gy; ++j)
                for (int i = 0; i <= gx; ++i)
                    vs.push_back({x0 + sx * static_cast<float>(i), y0 + sy * static_cast<float>(j),
                                  rng.uniform(-1.1f, 1.1f), 1.0f});
            for (int j = 0; j < gy; ++j)
                for (int i = 0; i < gx; ++i) {
                    const auto a = static_cast<std::uint32_t>(j * (gx + 1) + i);
                    const auto b = a + 1, c = a + static_cast<std::uint32_t>(gx + 1), d = c + 1;
                    is.insert(is.end(), {a, b, d, a, d, c});
                }
        }
        if (o.rules == raster::RasterRules::Vulkan)
            for (raster::Float4& v : vs) v.z = (v.z + v.w) * 0.5f;
        const raster::MeshView mesh{vs, is};
        raster::DrawState query_state;
        query_state.depth_func = rng.chance(50) ? raster::DepthFunc::GEqual : kFuncs[rng.below(8)];
        query_state.depth_write = rng.chance(15);
        if (o.allow_cull && rng.chance(25)) {
            query_state.cull_face = rng.chance(50) ? raster::CullFace::Back : raster::CullFace::Front;
            query_state.front_face = rng.chance(50) ? raster::FrontFace::CCW : raster::FrontFace::CW;
        }
        if (o.allow_viewport && rng.chance(10)) {
            const int w = 1 + static_cast<int>(rng.below(static_cast<std::uint32_t>(o.width)));
            const int h = 1 + static_cast<int>(rng.below(static_cast<std::uint32_t>(o.height)));
            query_state.viewport = raster::Viewport{static_cast<int>(rng.below(static_cast<std::uint32_t>(o.width))) - w / 2,
                                                    static_cast<int>(rng.below(static_cast<std::uint32_t>(o.height))) - h / 2, w, h};
        }
        scene.batch.begin_query(rng.chance(20) ? raster::QueryKind::AnySamplesPassed : raster::QueryKind::SamplesPassed);
        scene.batch.draw(mesh, query_state);
        scene.batch.end_query();
        ++scene.query_count;
        if (rng.chance(70)) {  // then draw it (CULLIDE: query GEQUAL mask off, then draw LEQUAL mask on)
            raster::DrawState draw_state = query_state;
            draw_state.depth_func = rng.chance(60) ? raster::DepthFunc::LEqual : kFuncs[rng.below(8)];
            draw_state.depth_write = true;
            if (rng.chance(30)) {  // with a query of its own: equal-depth ties under any function
                scene.batch.begin_query(raster::QueryKind::SamplesPassed);
                scene.batch.draw(mesh, draw_state);
                scene.batch.end_query();
                ++scene.query_count;
            } else {
                scene.batch.draw(mesh, draw_state);
            }
        }
    }
}

}  // namespace raster_test
