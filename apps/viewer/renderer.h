#pragma once
// The OpenGL 3.3 core renderer: one instanced draw per primitive mesh (sphere, box, capsule cylinder) and per shape
// mesh (hulls, static meshes, heightfields; uploaded once), simple lighting with fog, and one draw for all debug
// lines.
#include <epoxy/gl.h>

#include <vector>

#include "camera.h"
#include "rubble/debug_draw.h"
#include "shape_meshes.h"

namespace rubble::viewer {

struct RenderStats {
    int drawCalls = 0;
    std::size_t instances = 0;
    std::size_t triangles = 0;
    std::size_t lines = 0;
};

class Renderer {
public:
    /// Needs a current OpenGL 3.3 core context; throws std::runtime_error when the shaders do not build.
    Renderer();
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// The background (and fog) colour.
    static constexpr float kClearColor[3] = {0.62f, 0.71f, 0.80f};

    /// Uploads the library's meshes that are not on the GPU yet (each mesh once).
    void uploadMeshes(const ShapeLibrary& library);
    /// Clears the bound framebuffer and draws the instances, then `lines` (when given) over them.
    void draw(const InstanceLists& instances, const std::vector<const DebugLines*>& lines, const Mat4& viewProjection,
              Vec3 eye, int width, int height);
    const RenderStats& stats() const { return stats_; }

private:
    struct GpuMesh {
        GLuint vao = 0, vertexBuffer = 0, indexBuffer = 0, instanceBuffer = 0;
        GLsizei indexCount = 0;
    };
    struct LineVertex {
        float position[3];
        unsigned char color[4];
    };
    GpuMesh upload(const MeshData& mesh);
    void drawInstanced(const GpuMesh& mesh, const std::vector<Instance>& instances);

    GLuint solidProgram_ = 0, lineProgram_ = 0;
    GLint solidViewProjection_ = -1, solidEye_ = -1, solidLight_ = -1, solidFog_ = -1;
    GLint lineViewProjection_ = -1;
    GpuMesh primitives_[static_cast<int>(PrimitiveMesh::Count)];
    std::vector<GpuMesh> meshes_;
    GLuint lineVao_ = 0, lineBuffer_ = 0;
    std::vector<LineVertex> lineVertices_;
    RenderStats stats_;
};

}  // namespace rubble::viewer
