// osmesa_device.cpp: see osmesa_device.h. The GL work is gl_batch_runner.cpp's; here is only the
// OSMesa context. Facts about OSMesa 22.3.6 used here are in ../shared/docs/toolchain.md section 2
// (do not link libGL; glGetQueryObjectui64v only through OSMesaGetProcAddress).
#include "osmesa_device.h"

#include <GL/osmesa.h>

#include "gl_batch_runner.h"

namespace cullide_oracle {

struct OsmesaDevice::Impl {
    OSMesaContext ctx = nullptr;
    std::vector<unsigned char> window;  // OSMesa needs a colour buffer to make the context current
    std::unique_ptr<GlBatchRunner> gl;

    void make_current() { OSMesaMakeCurrent(ctx, window.data(), GL_UNSIGNED_BYTE, 4, 4); }
};

raster::Result<std::unique_ptr<OsmesaDevice>> OsmesaDevice::create(int width, int height, raster::DepthFormat format) {
    std::unique_ptr<OsmesaDevice> d(new OsmesaDevice());
    d->impl_ = std::make_unique<Impl>();
    d->width_ = width;
    d->height_ = height;
    d->format_ = format;
    Impl& g = *d->impl_;
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_STENCIL_BITS, 0,
                           OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 4,
                           OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    g.ctx = OSMesaCreateContextAttribs(attribs, nullptr);
    if (g.ctx == nullptr) return raster::Error{"OSMesaCreateContextAttribs (core 4.5) failed"};
    g.window.assign(4 * 4 * 4, 0);
    if (!OSMesaMakeCurrent(g.ctx, g.window.data(), GL_UNSIGNED_BYTE, 4, 4))
        return raster::Error{"OSMesaMakeCurrent failed"};
    // libOSMesa does not export glGetQueryObjectui64v; its entry point is reachable this way.
    auto get_query_u64 = reinterpret_cast<GlBatchRunner::GetQueryU64>(OSMesaGetProcAddress("glGetQueryObjectui64v"));
    auto gl = GlBatchRunner::create(width, height, format, get_query_u64);
    if (!gl.ok()) return gl.error();
    g.gl = std::move(gl.value());
    return d;
}

OsmesaDevice::~OsmesaDevice() {
    if (impl_ && impl_->ctx) {
        impl_->make_current();
        if (impl_->gl) impl_->gl->destroy();
        OSMesaDestroyContext(impl_->ctx);
    }
}

void OsmesaDevice::clear(double depth) {
    impl_->make_current();
    impl_->gl->clear(depth);
}

raster::Result<raster::QueryResults> OsmesaDevice::run(const raster::CommandBatch& batch) {
    if (batch.rules() != raster::RasterRules::GlLlvmpipe)
        return raster::Error{"osmesa device: the batch is recorded for the Vulkan rules, not GL's"};
    impl_->make_current();
    return impl_->gl->run(batch, bounded_scenes_);
}

std::vector<std::uint32_t> OsmesaDevice::read_depth() {
    impl_->make_current();
    return impl_->gl->read_depth();
}

void OsmesaDevice::finish() {
    impl_->make_current();
    impl_->gl->finish();
}

std::string OsmesaDevice::renderer() const {
    impl_->make_current();
    return impl_->gl->renderer();
}

}  // namespace cullide_oracle
