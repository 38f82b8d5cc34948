// egl_device.cpp: see egl_device.h. EGL only makes the context; gl_batch_runner.cpp does the GL.
#include "egl_device.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>

#include <cctype>
#include <cstring>

#include "gl_batch_runner.h"

namespace cullide_oracle {

struct EglDevice::Impl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    EGLSurface surface = EGL_NO_SURFACE;
    std::unique_ptr<GlBatchRunner> gl;
    std::string renderer;

    // Makes a current OpenGL 4.5 core context on `dpy` (display, context, surface and renderer set),
    // or says why not; release() undoes what was made either way.
    std::string open(EGLDisplay dpy);
    void make_current() const { eglMakeCurrent(display, surface, surface, context); }
    void release() {
        if (context == EGL_NO_CONTEXT) return;
        make_current();
        if (gl) gl->destroy();
        gl.reset();
        eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
        eglDestroyContext(display, context);
        context = EGL_NO_CONTEXT;
        surface = EGL_NO_SURFACE;
        // The display stays initialized: another EglDevice on the same EGL device shares it.
    }
};

namespace {

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

bool has_extension(const char* list, const char* name) {
    if (list == nullptr) return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    return false;
}

}  // namespace

std::string EglDevice::Impl::open(EGLDisplay dpy) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(dpy, &major, &minor)) return "eglInitialize failed";
    if (!eglBindAPI(EGL_OPENGL_API)) return "eglBindAPI(EGL_OPENGL_API) failed";
    const bool surfaceless = has_extension(eglQueryString(dpy, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context");
    const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                     surfaceless ? 0 : EGL_PBUFFER_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    if (!eglChooseConfig(dpy, config_attribs, &config, 1, &configs) || configs < 1)
        return "no EGL config renders OpenGL";
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    display = dpy;
    context = eglCreateContext(dpy, config, EGL_NO_CONTEXT, context_attribs);
    if (context == EGL_NO_CONTEXT) return "eglCreateContext (OpenGL 4.5 core) failed";
    if (!surfaceless) {
        const EGLint pbuffer_attribs[] = {EGL_WIDTH, 4, EGL_HEIGHT, 4, EGL_NONE};
        surface = eglCreatePbufferSurface(dpy, config, pbuffer_attribs);
        if (surface == EGL_NO_SURFACE) return "eglCreatePbufferSurface failed";
    }
    if (!eglMakeCurrent(dpy, surface, surface, context)) return "eglMakeCurrent failed";
    const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    renderer = r ? r : "";
    return {};
}

raster::Result<std::unique_ptr<EglDevice>> EglDevice::create(int width, int height, raster::DepthFormat format,
                                                             const std::string& device) {
    if (width < 1 || height < 1 || width > raster::kMaxTargetSize || height > raster::kMaxTargetSize)
        return raster::Error{"egl device: bad target size"};
    std::unique_ptr<EglDevice> d(new EglDevice());
    d->width_ = width;
    d->height_ = height;

    // Every EGL device first (the way to a GPU without a window), then the default display.
    std::vector<EGLDisplay> displays;
    const auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    const auto platform_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (query_devices != nullptr && platform_display != nullptr) {
        EGLDeviceEXT devices[16];
        EGLint n = 0;
        if (query_devices(16, devices, &n))
            for (EGLint i = 0; i < n; ++i) {
                EGLDisplay dpy = platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
                if (dpy != EGL_NO_DISPLAY) displays.push_back(dpy);
            }
    }
    if (EGLDisplay dpy = eglGetDisplay(EGL_DEFAULT_DISPLAY); dpy != EGL_NO_DISPLAY) displays.push_back(dpy);

    const std::string wanted = lower(device);
    std::string seen;
    for (EGLDisplay dpy : displays) {
        auto impl = std::make_unique<Impl>();
        const std::string why = impl->open(dpy);
        if (!why.empty()) {
            seen += (seen.empty() ? "" : "; ") + why;
            impl->release();
            continue;
        }
        seen += (seen.empty() ? "" : "; ") + impl->renderer;
        if (!wanted.empty() && lower(impl->renderer).find(wanted) == std::string::npos) {
            impl->release();
            continue;
        }
        auto get_query_u64 =
            reinterpret_cast<GlBatchRunner::GetQueryU64>(eglGetProcAddress("glGetQueryObjectui64v"));
        auto gl = GlBatchRunner::create(width, height, format, get_query_u64);
        if (!gl.ok()) {
            impl->release();
            return raster::Error{"egl device (" + impl->renderer + "): " + gl.error().message};
        }
        impl->gl = std::move(gl.value());
        d->impl_ = std::move(impl);
        return d;
    }
    return raster::Error{"egl device: no OpenGL 4.5 core context" +
                         (wanted.empty() ? std::string() : " whose renderer contains '" + device + "'") +
                         " (tried: " + (seen.empty() ? std::string("no EGL display") : seen) + ")"};
}

EglDevice::~EglDevice() {
    if (impl_) impl_->release();
}

void EglDevice::clear(double depth) {
    impl_->make_current();
    impl_->gl->clear(depth);
}

raster::Result<raster::QueryResults> EglDevice::run(const raster::CommandBatch& batch) {
    if (batch.rules() != raster::RasterRules::GlLlvmpipe)
        return raster::Error{"egl device: the batch is recorded for the Vulkan rules, not GL's"};
    impl_->make_current();
    return impl_->gl->run(batch, bounded_scenes_);
}

std::vector<std::uint32_t> EglDevice::read_depth() {
    impl_->make_current();
    return impl_->gl->read_depth();
}

void EglDevice::finish() {
    impl_->make_current();
    impl_->gl->finish();
}

std::string EglDevice::renderer() const {
    impl_->make_current();
    return impl_->gl->renderer();
}

}  // namespace cullide_oracle
