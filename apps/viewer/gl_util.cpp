// OpenGL helpers of the viewer (see gl_util.h).
#include "gl_util.h"

#include <stb_image_write.h>

#include <cstring>
#include <stdexcept>

namespace rubble::viewer {

namespace {

GLuint compile(const char* name, GLenum kind, const char* source) {
    const GLuint shader = glCreateShader(kind);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048] = {};
        glGetShaderInfoLog(shader, sizeof log, nullptr, log);
        glDeleteShader(shader);
        throw std::runtime_error(std::string(name) + (kind == GL_VERTEX_SHADER ? " vertex" : " fragment") +
                                 " shader does not compile: " + log);
    }
    return shader;
}

}  // namespace

GLuint buildProgram(const char* name, const char* vertexSource, const char* fragmentSource) {
    const GLuint vs = compile(name, GL_VERTEX_SHADER, vertexSource);
    const GLuint fs = compile(name, GL_FRAGMENT_SHADER, fragmentSource);
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[2048] = {};
        glGetProgramInfoLog(program, sizeof log, nullptr, log);
        glDeleteProgram(program);
        throw std::runtime_error(std::string(name) + " program does not link: " + log);
    }
    return program;
}

OffscreenTarget::OffscreenTarget(int width, int height, int samples) : width_(width), height_(height) {
    glGenRenderbuffers(1, &msColor_);
    glBindRenderbuffer(GL_RENDERBUFFER, msColor_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
    glGenRenderbuffers(1, &msDepth_);
    glBindRenderbuffer(GL_RENDERBUFFER, msDepth_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
    glGenFramebuffers(1, &msFramebuffer_);
    glBindFramebuffer(GL_FRAMEBUFFER, msFramebuffer_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msColor_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msDepth_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw std::runtime_error("the offscreen framebuffer is incomplete (" + std::to_string(width) + "x" +
                                 std::to_string(height) + ", " + std::to_string(samples) + " samples)");

    glGenRenderbuffers(1, &resolveColor_);
    glBindRenderbuffer(GL_RENDERBUFFER, resolveColor_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glGenFramebuffers(1, &resolveFramebuffer_);
    glBindFramebuffer(GL_FRAMEBUFFER, resolveFramebuffer_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolveColor_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw std::runtime_error("the resolve framebuffer is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

OffscreenTarget::~OffscreenTarget() {
    glDeleteFramebuffers(1, &msFramebuffer_);
    glDeleteFramebuffers(1, &resolveFramebuffer_);
    const GLuint buffers[] = {msColor_, msDepth_, resolveColor_};
    glDeleteRenderbuffers(3, buffers);
}

void OffscreenTarget::bind() const { glBindFramebuffer(GL_FRAMEBUFFER, msFramebuffer_); }

std::vector<unsigned char> OffscreenTarget::readPixels() const {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, msFramebuffer_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolveFramebuffer_);
    glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, resolveFramebuffer_);
    std::vector<unsigned char> pixels = readFramebuffer(width_, height_);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return pixels;
}

std::vector<unsigned char> readFramebuffer(int width, int height) {
    const std::size_t row = static_cast<std::size_t>(width) * 4;
    std::vector<unsigned char> pixels(row * static_cast<std::size_t>(height));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    // OpenGL's first row is the bottom one; images start at the top.
    std::vector<unsigned char> swap(row);
    for (int y = 0; y < height / 2; ++y) {
        unsigned char* top = pixels.data() + static_cast<std::size_t>(y) * row;
        unsigned char* bottom = pixels.data() + static_cast<std::size_t>(height - 1 - y) * row;
        std::memcpy(swap.data(), top, row);
        std::memcpy(top, bottom, row);
        std::memcpy(bottom, swap.data(), row);
    }
    return pixels;
}

void writePng(const std::string& path, int width, int height, const std::vector<unsigned char>& rgba) {
    if (!stbi_write_png(path.c_str(), width, height, 4, rgba.data(), width * 4))
        throw std::runtime_error("cannot write the screenshot '" + path + "'");
}

}  // namespace rubble::viewer
