// raster/types.h: the GL-state enums and small value types of the raster library.
// Conventions: raster/raster.h.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

namespace raster {

// Per side, in pixels. Keeps 16.8 fixed-point products inside 64 bits (see raster.h).
inline constexpr int kMaxTargetSize = 16384;

// Largest |x|, |y|, |z| the exact-bounds mode accepts in clip space (2^100: far beyond any view,
// small enough that no product in its clipping can overflow a double).
inline constexpr double kMaxExactBoundsCoordinate = 1267650600228229401496703205376.0;

enum class DepthFormat : std::uint8_t { D16, D24, D32F };

// GL depth functions (glDepthFunc), compared as incoming <op> stored.
enum class DepthFunc : std::uint8_t { Never, Less, Equal, LEqual, Greater, NotEqual, GEqual, Always };

enum class CullFace : std::uint8_t { None, Front, Back };   // glCullFace (None = GL_CULL_FACE off)
enum class FrontFace : std::uint8_t { CCW, CW };           // glFrontFace

// How coverage and depth are decided (docs/raster.md, docs/reliable-raster.md).
//  GLExact:     pixel-centre sampling exactly as llvmpipe (float input, bit-identical to OSMesa).
//  ExactBounds: conservative (R-CULLIDE's reliable rasterization, done in the emulator): every pixel
//               whose closed square meets the closed triangle is covered, with a depth interval
//               [zmin, zmax] bounding the triangle over that square, quantized outward. A draw with
//               depth_write tests and writes zmin; a draw without tests zmax. Orthographic (w = 1)
//               input only; double input through CommandBatch::draw(MeshViewD, ...).
enum class RasterMode : std::uint8_t { GLExact, ExactBounds };

// Whose rasterization rules GL-exact draws follow (raster/raster.h lists both sets), chosen per
// batch (CommandBatch). The batch's clip coordinates must be recorded for the same API (Vulkan:
// 0 <= z <= w). Exact-bounds draws are conservative and follow GL's conventions under both.
//  GlLlvmpipe: OpenGL on Mesa llvmpipe (OSMesa 22.3.6), bit-identical; the default.
//  Vulkan:     Vulkan's rules as Mesa lavapipe 22.3.6 implements them, bit-identical.
enum class RasterRules : std::uint8_t { GlLlvmpipe, Vulkan };

enum class QueryKind : std::uint8_t { SamplesPassed, AnySamplesPassed };

// glViewport(x, y, width, height) in pixels.
struct Viewport {
    int x = 0;
    int y = 0;
    int width = 0;
    int height = 0;
};

// A clip-space vertex (x, y, z, w), as gl_Position: Float4 for GL-exact input, Double4 (double
// precision, w must be 1) for the exact-bounds mode. One template, so the two cannot drift apart.
template <class T>
struct Vertex4 {
    T x = 0;
    T y = 0;
    T z = 0;
    T w = 1;
};
using Float4 = Vertex4<float>;
using Double4 = Vertex4<double>;

// Non-owning view of an indexed triangle mesh in clip space; three indices per triangle. The
// spans must stay valid until the batch that holds the view has been executed. MeshView holds
// Float4 vertices; MeshViewD double ones (clip space, orthographic: w = 1), same lifetime rule.
template <class Vertex>
struct IndexedMeshView {
    std::span<const Vertex> vertices;
    std::span<const std::uint32_t> indices;
};
using MeshView = IndexedMeshView<Float4>;
using MeshViewD = IndexedMeshView<Double4>;

// The GL state one draw runs under. GL_DEPTH_TEST is always on (use DepthFunc::Always for "no test").
struct DrawState {
    DepthFunc depth_func = DepthFunc::Less;
    bool depth_write = true;                 // glDepthMask
    CullFace cull_face = CullFace::None;
    FrontFace front_face = FrontFace::CCW;
    std::optional<Viewport> viewport;        // nullopt: the whole target
    RasterMode mode = RasterMode::GLExact;
};

}  // namespace raster
