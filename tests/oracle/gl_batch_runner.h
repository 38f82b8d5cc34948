// gl_batch_runner.h: the OpenGL 4.5 core work that the real-GL oracles share (osmesa_device.h: Mesa
// llvmpipe through OSMesa; egl_device.h: any driver through EGL, e.g. NVIDIA's). A pass-through
// vertex shader, one depth-only FBO of the requested format, each raster::CommandBatch issued as
// GL commands, queries read back at the end and depth read back with exact bits. It knows nothing
// of contexts: every call needs the owner's context current.
//
// gl_batch_runner.cpp is compiled into each GL oracle library, so that its gl* calls bind to that
// library's GL (libOSMesa exports its own; EGL's go through libOpenGL). No program links both.
// Test and benchmark code only: never linked into a library. No GL header leaks from here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace cullide_oracle {

class GlBatchRunner {
   public:
    // glGetQueryObjectui64v, which the owner resolves (libOSMesa does not export it).
    using GetQueryU64 = void (*)(unsigned query, unsigned pname, std::uint64_t* value);

    // Builds the program, buffers and FBO in the current context; fails with a message when a
    // shader does not compile, the FBO is incomplete or its depth has another number of bits.
    [[nodiscard]] static raster::Result<std::unique_ptr<GlBatchRunner>> create(int width, int height,
                                                                            raster::DepthFormat format,
                                                                            GetQueryU64 get_query_u64);
    // Deletes the GL objects: call with the context current, before the context goes.
    void destroy();

    void clear(double depth);
    // See OsmesaDevice::run: every command in order, queries read at the end; with bounded scenes a
    // glFlush goes before a glBeginQuery once kQueriesPerFlush queries or kTrianglesPerFlush
    // triangles were issued since the last one.
    [[nodiscard]] raster::Result<raster::QueryResults> run(const raster::CommandBatch& batch, bool bounded_scenes);
    static constexpr int kQueriesPerFlush = 64;
    static constexpr std::size_t kTrianglesPerFlush = 16384;
    [[nodiscard]] std::vector<std::uint32_t> read_depth();
    void finish();
    [[nodiscard]] std::string renderer() const;

   private:
    GlBatchRunner() = default;
    int width_ = 0, height_ = 0;
    raster::DepthFormat format_ = raster::DepthFormat::D24;
    GetQueryU64 get_query_u64_ = nullptr;
    unsigned fbo_ = 0, depth_rb_ = 0, program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0;
};

}  // namespace cullide_oracle
