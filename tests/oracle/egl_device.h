// egl_device.h: a real-GL oracle through EGL, for any driver that EGL can reach without a window:
// Mesa's llvmpipe (EGL's software device) on a CPU-only machine, NVIDIA's GL on a machine with
// its driver. The GL work is OsmesaDevice's (gl_batch_runner.h: OpenGL 4.5 core, a pass-through
// vertex shader, a depth-only FBO, exact read-back), so on llvmpipe the two devices must give the
// same bits; tests/raster/driver_report.cpp compares any of them with the emulator.
// Test and benchmark code only: never linked into a library, and never into a program that links
// the OSMesa oracle (both export the gl* entry points). No EGL or GL header leaks from here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raster/raster.h"

namespace cullide_oracle {

class GlBatchRunner;

class EglDevice {
   public:
    // One OpenGL 4.5 core context on an EGL device (EGL_EXT_platform_device; the default display
    // as a fallback), surfaceless where EGL_KHR_surfaceless_context allows, else on a 4 x 4 pbuffer,
    // with a width x height depth-only FBO. `device`, when not empty, picks the first context whose
    // GL_RENDERER contains it (case-insensitive), e.g. "NVIDIA" or "llvmpipe"; the error then lists
    // the renderers there are. Cleared to depth 1.0.
    [[nodiscard]] static raster::Result<std::unique_ptr<EglDevice>> create(int width, int height,
                                                                        raster::DepthFormat format,
                                                                        const std::string& device = {});
    ~EglDevice();
    EglDevice(const EglDevice&) = delete;
    EglDevice& operator=(const EglDevice&) = delete;

    void clear(double depth);
    // As OsmesaDevice::run (GL rules only; bounded scenes on by default, which changes no result
    // under the GL rules and keeps llvmpipe off its whole-batch fault).
    [[nodiscard]] raster::Result<raster::QueryResults> run(const raster::CommandBatch& batch);
    void set_bounded_scenes(bool on) { bounded_scenes_ = on; }
    [[nodiscard]] std::vector<std::uint32_t> read_depth();
    void finish();

    // GL_RENDERER and GL_VERSION, e.g. "NVIDIA H200/PCIe/SSE2, 4.5.0 NVIDIA 580.159.04".
    [[nodiscard]] std::string renderer() const;
    [[nodiscard]] int width() const { return width_; }
    [[nodiscard]] int height() const { return height_; }

   private:
    EglDevice() = default;
    struct Impl;
    std::unique_ptr<Impl> impl_;
    int width_ = 0;
    int height_ = 0;
    bool bounded_scenes_ = true;
};

}  // namespace cullide_oracle
