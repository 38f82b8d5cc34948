// gl_batch_runner.cpp: see gl_batch_runner.h. Facts about Mesa 22.3.6's GL used here are in
// ../shared/docs/toolchain.md section 2 (GL_GLEXT_PROTOTYPES, glFinish before reading back).
#define GL_GLEXT_PROTOTYPES 1
#include "gl_batch_runner.h"

#include "batch_geometry.h"

#include <GL/gl.h>
#include <GL/glext.h>


namespace cullide_oracle {

namespace {

GLuint compile(GLenum type, const char* src, std::string& log) {
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char buf[1024] = {};
        glGetShaderInfoLog(s, sizeof buf, nullptr, buf);
        log = buf;
    }
    return s;
}

GLenum gl_func(raster::DepthFunc f) {
    switch (f) {
        case raster::DepthFunc::Never: return GL_NEVER;
        case raster::DepthFunc::Less: return GL_LESS;
        case raster::DepthFunc::Equal: return GL_EQUAL;
        case raster::DepthFunc::LEqual: return GL_LEQUAL;
        case raster::DepthFunc::Greater: return GL_GREATER;
        case raster::DepthFunc::NotEqual: return GL_NOTEQUAL;
        case raster::DepthFunc::GEqual: return GL_GEQUAL;
        case raster::DepthFunc::Always: return GL_ALWAYS;
    }
    return GL_LESS;
}

}  // namespace

raster::Result<std::unique_ptr<GlBatchRunner>> GlBatchRunner::create(int width, int height, raster::DepthFormat format,
                                                                  GetQueryU64 get_query_u64) {
    if (get_query_u64 == nullptr) return raster::Error{"glGetQueryObjectui64v is not available"};
    std::unique_ptr<GlBatchRunner> g(new GlBatchRunner());
    g->width_ = width;
    g->height_ = height;
    g->format_ = format;
    g->get_query_u64_ = get_query_u64;
    std::string log;
    const char* vs = "#version 330 core\nlayout(location = 0) in vec4 p;\nvoid main() { gl_Position = p; }\n";
    const char* fs = "#version 330 core\nvoid main() {}\n";
    GLuint v = compile(GL_VERTEX_SHADER, vs, log);
    GLuint f = compile(GL_FRAGMENT_SHADER, fs, log);
    if (!log.empty()) return raster::Error{"shader compile failed: " + log};
    g->program_ = glCreateProgram();
    glAttachShader(g->program_, v);
    glAttachShader(g->program_, f);
    glLinkProgram(g->program_);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint linked = 0;
    glGetProgramiv(g->program_, GL_LINK_STATUS, &linked);
    if (!linked) return raster::Error{"program link failed"};
    glUseProgram(g->program_);

    glGenVertexArrays(1, &g->vao_);
    glBindVertexArray(g->vao_);
    glGenBuffers(1, &g->vbo_);
    glGenBuffers(1, &g->ibo_);
    glBindBuffer(GL_ARRAY_BUFFER, g->vbo_);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ibo_);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 16, nullptr);

    const GLenum internal = format == raster::DepthFormat::D16   ? GL_DEPTH_COMPONENT16
                            : format == raster::DepthFormat::D24 ? GL_DEPTH_COMPONENT24
                                                                 : GL_DEPTH_COMPONENT32F;
    glGenRenderbuffers(1, &g->depth_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, g->depth_rb_);
    glRenderbufferStorage(GL_RENDERBUFFER, internal, width, height);
    glGenFramebuffers(1, &g->fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, g->depth_rb_);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return raster::Error{"depth-only FBO is incomplete"};
    GLint bits = 0;
    glGetFramebufferAttachmentParameteriv(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE,
                                          &bits);
    const int want = format == raster::DepthFormat::D16 ? 16 : format == raster::DepthFormat::D24 ? 24 : 32;
    if (bits != want) return raster::Error{"depth attachment has " + std::to_string(bits) + " bits, wanted " +
                                           std::to_string(want)};
    glEnable(GL_DEPTH_TEST);
    glDisable(GL_MULTISAMPLE);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    if (glGetError() != GL_NO_ERROR) return raster::Error{"GL error during setup"};
    g->clear(1.0);
    return g;
}

void GlBatchRunner::destroy() {
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(1, &depth_rb_);
    glDeleteBuffers(1, &vbo_);
    glDeleteBuffers(1, &ibo_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
    fbo_ = depth_rb_ = vbo_ = ibo_ = vao_ = program_ = 0;
}

void GlBatchRunner::clear(double depth) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glDepthMask(GL_TRUE);
    glClearDepth(depth);
    glClear(GL_DEPTH_BUFFER_BIT);
}

raster::Result<raster::QueryResults> GlBatchRunner::run(const raster::CommandBatch& batch, bool bounded_scenes) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    const BatchGeometry geometry(batch);
    const auto& verts = geometry.vertices;
    const auto& idx = geometry.indices;
    const auto& ranges = geometry.draws;
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(verts.size() * sizeof(raster::Float4)), verts.data(),
                 GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * 4), idx.data(), GL_STREAM_DRAW);

    const auto& kinds = batch.query_kinds();
    std::vector<GLuint> ids(kinds.size());
    if (!ids.empty()) glGenQueries(static_cast<GLsizei>(ids.size()), ids.data());
    GLenum active_target = 0;
    std::size_t draw = 0;
    int queries_since_flush = 0;
    std::size_t triangles_since_flush = 0;
    // See bounded_scenes in the header: a flush before a query begins, whenever the scene llvmpipe
    // is filling may be large, so that binning a query's begin and end never meets a full scene.
    // Only between queries: a flush inside a query would take the path under suspicion.
    auto bound_scene = [&] {
        if (!bounded_scenes) return;
        if (queries_since_flush < kQueriesPerFlush && triangles_since_flush < kTrianglesPerFlush) return;
        glFlush();
        queries_since_flush = 0;
        triangles_since_flush = 0;
    };
    for (const auto& c : batch.commands()) {
        switch (c.kind) {
            case raster::Command::Kind::BeginQuery:
                bound_scene();
                ++queries_since_flush;
                active_target = kinds[c.query] == raster::QueryKind::SamplesPassed ? GL_SAMPLES_PASSED
                                                                                 : GL_ANY_SAMPLES_PASSED;
                glBeginQuery(active_target, ids[c.query]);
                break;
            case raster::Command::Kind::EndQuery:
                glEndQuery(active_target);
                break;
            case raster::Command::Kind::Draw: {
                const raster::DrawState& s = c.state;
                glDepthFunc(gl_func(s.depth_func));
                glDepthMask(s.depth_write ? GL_TRUE : GL_FALSE);
                if (s.cull_face == raster::CullFace::None) {
                    glDisable(GL_CULL_FACE);
                } else {
                    glEnable(GL_CULL_FACE);
                    glCullFace(s.cull_face == raster::CullFace::Front ? GL_FRONT : GL_BACK);
                }
                glFrontFace(s.front_face == raster::FrontFace::CCW ? GL_CCW : GL_CW);
                const raster::Viewport vp = s.viewport ? *s.viewport : raster::Viewport{0, 0, width_, height_};
                glViewport(vp.x, vp.y, vp.width, vp.height);
                const BatchGeometry::Range& r = ranges[draw++];
                triangles_since_flush += r.count / 3;
                if (r.count > 0)
                    glDrawElementsBaseVertex(GL_TRIANGLES, static_cast<GLsizei>(r.count), GL_UNSIGNED_INT,
                                             reinterpret_cast<const void*>(r.first_index * 4),
                                             static_cast<GLint>(r.base_vertex));
                break;
            }
        }
    }
    raster::QueryResults out(kinds.size(), 0);
    for (std::size_t q = 0; q < ids.size(); ++q) {
        GLuint64 v = 0;
        get_query_u64_(ids[q], GL_QUERY_RESULT, &v);
        out[q] = v;
    }
    if (!ids.empty()) glDeleteQueries(static_cast<GLsizei>(ids.size()), ids.data());
    if (GLenum e = glGetError(); e != GL_NO_ERROR) return raster::Error{"GL error " + std::to_string(e) + " in run"};
    return out;
}

std::vector<std::uint32_t> GlBatchRunner::read_depth() {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFinish();
    const std::size_t n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
    std::vector<std::uint32_t> out(n);
    if (format_ == raster::DepthFormat::D32F) {
        glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, out.data());
    } else if (format_ == raster::DepthFormat::D16) {
        std::vector<std::uint16_t> s(n);
        glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_UNSIGNED_SHORT, s.data());
        for (std::size_t i = 0; i < n; ++i) out[i] = s[i];
    } else {
        // GL_UNSIGNED_INT scales the 24-bit value to 32 bits; its top 24 bits are the stored value.
        glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, out.data());
        for (auto& v : out) v >>= 8;
    }
    return out;
}

void GlBatchRunner::finish() { glFinish(); }

std::string GlBatchRunner::renderer() const {
    const auto* s = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    std::string r = s ? s : "";
    if (v) r += std::string(", ") + v;
    return r;
}

}  // namespace cullide_oracle
