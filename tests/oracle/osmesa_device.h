// osmesa_device.h: the real-GL oracle of the raster tests and benchmarks (Mesa llvmpipe through
// OSMesa). It runs a raster::CommandBatch through OpenGL 4.5 core with the same clip-space floats
// (a pass-through vertex shader, so no GPU-side matrix multiply) into an FBO whose only attachment
// is a depth renderbuffer of the requested format, and reads results back with exact bits. The GL
// work is gl_batch_runner.h's, shared with the EGL device (egl_device.h).
// Test and benchmark code only: never linked into a library. No OSMesa header leaks from here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace cullide_oracle {

class OsmesaDevice {
   public:
    // One GL context with a width x height depth-only FBO. Fails with a message when OSMesa cannot
    // create the context or the FBO is incomplete.
    [[nodiscard]] static raster::Result<std::unique_ptr<OsmesaDevice>> create(int width, int height,
                                                                           raster::DepthFormat format);
    ~OsmesaDevice();
    OsmesaDevice(const OsmesaDevice&) = delete;
    OsmesaDevice& operator=(const OsmesaDevice&) = delete;

    // glClearDepth(depth); glClear(GL_DEPTH_BUFFER_BIT) with the depth mask on.
    void clear(double depth);
    // Fails unless the batch is recorded for RasterRules::GlLlvmpipe. Issues every command (all queries first, results read at the end, so GL can batch), then
    // returns the query results indexed like the batch's queries (0/1 for any-samples queries).
    // With bounded scenes (the default) a glFlush goes before a glBeginQuery once
    // GlBatchRunner::kQueriesPerFlush queries or kTrianglesPerFlush triangles were issued since the last one:
    // llvmpipe (Mesa 22.3) over-counts a query now and then in one long stream of queries, most
    // likely when its binned scene fills up while a query's begin/end is binned
    // (docs/raster-known-differences.md, "Whole batches"); tests/oracle/llvmpipe_scene_test.cpp
    // shows it with bounded scenes off. glFlush changes no result under the GL rules, so this only
    // keeps llvmpipe off its faulty path.
    [[nodiscard]] raster::Result<raster::QueryResults> run(const raster::CommandBatch& batch);
    void set_bounded_scenes(bool on) { bounded_scenes_ = on; }
    [[nodiscard]] bool bounded_scenes() const { return bounded_scenes_; }
    // The depth buffer, row 0 at the bottom, in raster::DepthTarget's encoding.
    [[nodiscard]] std::vector<std::uint32_t> read_depth();
    // Waits for the GL work issued so far (for timing).
    void finish();

    [[nodiscard]] std::string renderer() const;
    [[nodiscard]] int width() const { return width_; }
    [[nodiscard]] int height() const { return height_; }

   private:
    OsmesaDevice() = default;
    struct Impl;
    std::unique_ptr<Impl> impl_;
    int width_ = 0;
    int height_ = 0;
    raster::DepthFormat format_ = raster::DepthFormat::D24;
    bool bounded_scenes_ = true;
};

}  // namespace cullide_oracle
