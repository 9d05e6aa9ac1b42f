#pragma once
// Small OpenGL 3.3 core helpers: shader programs, an offscreen multisampled framebuffer and PNG screenshots.
#include <epoxy/gl.h>

#include <string>
#include <vector>

namespace rubble::viewer {

/// Compiles and links a vertex + fragment program; throws std::runtime_error with the driver's log on failure.
GLuint buildProgram(const char* name, const char* vertexSource, const char* fragmentSource);

/// An offscreen target: a multisampled colour + depth framebuffer resolved into a plain one for reading back.
class OffscreenTarget {
public:
    OffscreenTarget(int width, int height, int samples);
    ~OffscreenTarget();
    OffscreenTarget(const OffscreenTarget&) = delete;
    OffscreenTarget& operator=(const OffscreenTarget&) = delete;

    /// Binds the multisampled framebuffer for drawing.
    void bind() const;
    /// Resolves the samples and returns the image as RGBA rows, top row first.
    std::vector<unsigned char> readPixels() const;
    int width() const { return width_; }
    int height() const { return height_; }

private:
    int width_, height_;
    GLuint msFramebuffer_ = 0, msColor_ = 0, msDepth_ = 0;
    GLuint resolveFramebuffer_ = 0, resolveColor_ = 0;
};

/// Reads the currently bound read framebuffer (RGBA, top row first).
std::vector<unsigned char> readFramebuffer(int width, int height);

/// Writes RGBA rows (top row first) as a PNG; throws std::runtime_error when the file cannot be written.
void writePng(const std::string& path, int width, int height, const std::vector<unsigned char>& rgba);

}  // namespace rubble::viewer
