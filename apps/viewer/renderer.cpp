// The viewer's OpenGL renderer (see renderer.h).
#include "renderer.h"

#include <cmath>
#include <cstddef>

#include "gl_util.h"

namespace rubble::viewer {

namespace {

constexpr const char* kSolidVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 iPosition;
layout(location = 3) in vec4 iRotation;
layout(location = 4) in vec3 iScale;
layout(location = 5) in vec4 iColor;
uniform mat4 uViewProjection;
out vec3 vWorld;
out vec3 vNormal;
out vec4 vColor;
vec3 rotate(vec4 q, vec3 v) {
    vec3 t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}
void main() {
    vWorld = rotate(iRotation, aPosition * iScale) + iPosition;
    // Normals take the inverse scale, so scaled spheres and cylinders stay lit as their true surfaces.
    vNormal = rotate(iRotation, aNormal / iScale);
    vColor = iColor;
    gl_Position = uViewProjection * vec4(vWorld, 1.0);
}
)";

constexpr const char* kSolidFragment = R"(#version 330 core
in vec3 vWorld;
in vec3 vNormal;
in vec4 vColor;
uniform vec3 uEye;
uniform vec3 uLight;
uniform vec3 uFog;
out vec4 fragColor;
void main() {
    vec3 n = normalize(vNormal);
    if (!gl_FrontFacing) n = -n;  // meshes are one-sided surfaces; light their back as well
    vec3 base = vColor.rgb;
    if (vColor.a < 1.0 && n.y > 0.7) {  // the checker marks out floors, not walls
        float cell = mod(floor(vWorld.x) + floor(vWorld.z), 2.0);
        base *= 1.0 - (1.0 - vColor.a) * cell;
    }
    // A key light and a weaker fill from the opposite side, so faces turned from the key keep their shape.
    float diffuse = max(dot(n, uLight), 0.0) + 0.3 * max(dot(n, -vec3(uLight.x, 0.0, uLight.z)), 0.0);
    vec3 ambient = mix(vec3(0.28, 0.26, 0.24), vec3(0.42, 0.46, 0.52), 0.5 + 0.5 * n.y);
    vec3 toEye = normalize(uEye - vWorld);
    float specular = pow(max(dot(reflect(-uLight, n), toEye), 0.0), 32.0) * 0.25;
    vec3 color = base * (ambient + 0.75 * diffuse) + vec3(specular);
    float fog = 1.0 - exp(-max(length(uEye - vWorld) - 40.0, 0.0) * 0.004);
    fragColor = vec4(mix(color, uFog, fog), 1.0);
}
)";

constexpr const char* kLineVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec4 aColor;
uniform mat4 uViewProjection;
out vec4 vColor;
void main() {
    vColor = aColor;
    gl_Position = uViewProjection * vec4(aPosition, 1.0);
    gl_Position.z -= 0.0005 * gl_Position.w;  // a little towards the eye, so lines on surfaces stay visible
}
)";

constexpr const char* kLineFragment = R"(#version 330 core
in vec4 vColor;
out vec4 fragColor;
void main() { fragColor = vColor; }
)";

void instanceAttribute(GLuint location, GLint size, std::size_t offset) {
    glEnableVertexAttribArray(location);
    glVertexAttribPointer(location, size, GL_FLOAT, GL_FALSE, sizeof(Instance), reinterpret_cast<void*>(offset));
    glVertexAttribDivisor(location, 1);
}

}  // namespace

Renderer::Renderer() {
    solidProgram_ = buildProgram("solid", kSolidVertex, kSolidFragment);
    solidViewProjection_ = glGetUniformLocation(solidProgram_, "uViewProjection");
    solidEye_ = glGetUniformLocation(solidProgram_, "uEye");
    solidLight_ = glGetUniformLocation(solidProgram_, "uLight");
    solidFog_ = glGetUniformLocation(solidProgram_, "uFog");
    lineProgram_ = buildProgram("line", kLineVertex, kLineFragment);
    lineViewProjection_ = glGetUniformLocation(lineProgram_, "uViewProjection");

    primitives_[static_cast<int>(PrimitiveMesh::Sphere)] = upload(unitSphere(24, 14));
    primitives_[static_cast<int>(PrimitiveMesh::Box)] = upload(unitBox());
    primitives_[static_cast<int>(PrimitiveMesh::Cylinder)] = upload(unitCylinder(24));

    glGenVertexArrays(1, &lineVao_);
    glGenBuffers(1, &lineBuffer_);
    glBindVertexArray(lineVao_);
    glBindBuffer(GL_ARRAY_BUFFER, lineBuffer_);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex), reinterpret_cast<void*>(0));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(LineVertex),
                          reinterpret_cast<void*>(offsetof(LineVertex, color)));
    glBindVertexArray(0);
}

Renderer::~Renderer() {
    auto release = [](GpuMesh& m) {
        glDeleteVertexArrays(1, &m.vao);
        const GLuint buffers[] = {m.vertexBuffer, m.indexBuffer, m.instanceBuffer};
        glDeleteBuffers(3, buffers);
    };
    for (GpuMesh& m : primitives_) release(m);
    for (GpuMesh& m : meshes_) release(m);
    glDeleteVertexArrays(1, &lineVao_);
    glDeleteBuffers(1, &lineBuffer_);
    glDeleteProgram(solidProgram_);
    glDeleteProgram(lineProgram_);
}

Renderer::GpuMesh Renderer::upload(const MeshData& mesh) {
    GpuMesh m;
    m.indexCount = static_cast<GLsizei>(mesh.indices.size());
    glGenVertexArrays(1, &m.vao);
    glGenBuffers(1, &m.vertexBuffer);
    glGenBuffers(1, &m.indexBuffer);
    glGenBuffers(1, &m.instanceBuffer);
    glBindVertexArray(m.vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.vertexBuffer);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.vertices.size() * sizeof(MeshVertex)),
                 mesh.vertices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex), reinterpret_cast<void*>(0));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          reinterpret_cast<void*>(offsetof(MeshVertex, normal)));
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.indexBuffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(std::uint32_t)),
                 mesh.indices.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, m.instanceBuffer);
    instanceAttribute(2, 3, offsetof(Instance, position));
    instanceAttribute(3, 4, offsetof(Instance, rotation));
    instanceAttribute(4, 3, offsetof(Instance, scale));
    instanceAttribute(5, 4, offsetof(Instance, color));
    glBindVertexArray(0);
    return m;
}

void Renderer::uploadMeshes(const ShapeLibrary& library) {
    for (std::size_t i = meshes_.size(); i < library.meshes().size(); ++i)
        meshes_.push_back(upload(library.meshes()[i]));
}

void Renderer::drawInstanced(const GpuMesh& mesh, const std::vector<Instance>& instances) {
    if (instances.empty() || mesh.indexCount == 0) return;
    glBindVertexArray(mesh.vao);
    glBindBuffer(GL_ARRAY_BUFFER, mesh.instanceBuffer);
    // Re-specifying the store each frame lets the driver hand out fresh memory instead of waiting on the GPU.
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(instances.size() * sizeof(Instance)), instances.data(),
                 GL_STREAM_DRAW);
    glDrawElementsInstanced(GL_TRIANGLES, mesh.indexCount, GL_UNSIGNED_INT, nullptr,
                            static_cast<GLsizei>(instances.size()));
    ++stats_.drawCalls;
    stats_.instances += instances.size();
    stats_.triangles += instances.size() * static_cast<std::size_t>(mesh.indexCount / 3);
}

void Renderer::draw(const InstanceLists& instances, const std::vector<const DebugLines*>& lines,
                    const Mat4& viewProjection, Vec3 eye, int width, int height) {
    stats_ = {};
    glViewport(0, 0, width, height);
    glClearColor(kClearColor[0], kClearColor[1], kClearColor[2], 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);  // meshes are seen from both sides; closed primitives cost little more

    glUseProgram(solidProgram_);
    glUniformMatrix4fv(solidViewProjection_, 1, GL_FALSE, viewProjection.data());
    glUniform3f(solidEye_, eye.x, eye.y, eye.z);
    const Vec3 light = Vec3{0.45f, 0.8f, 0.35f} / length(Vec3{0.45f, 0.8f, 0.35f});
    glUniform3f(solidLight_, light.x, light.y, light.z);
    glUniform3f(solidFog_, kClearColor[0], kClearColor[1], kClearColor[2]);
    for (int p = 0; p < static_cast<int>(PrimitiveMesh::Count); ++p)
        drawInstanced(primitives_[p], instances.primitives[p]);
    for (std::size_t m = 0; m < meshes_.size() && m < instances.meshes.size(); ++m)
        drawInstanced(meshes_[m], instances.meshes[m]);

    lineVertices_.clear();
    for (const DebugLines* batch : lines) {
        if (!batch) continue;
        for (std::size_t l = 0; l < batch->lineCount(); ++l) {
            const DebugColor c = batch->colors[l];
            for (int end = 0; end < 2; ++end) {
                const Vec3 p = batch->points[2 * l + end];
                lineVertices_.push_back({{p.x, p.y, p.z}, {c.r, c.g, c.b, c.a}});
            }
        }
    }
    if (!lineVertices_.empty()) {
        glUseProgram(lineProgram_);
        glUniformMatrix4fv(lineViewProjection_, 1, GL_FALSE, viewProjection.data());
        glBindVertexArray(lineVao_);
        glBindBuffer(GL_ARRAY_BUFFER, lineBuffer_);
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(lineVertices_.size() * sizeof(LineVertex)),
                     lineVertices_.data(), GL_STREAM_DRAW);
        glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(lineVertices_.size()));
        ++stats_.drawCalls;
        stats_.lines = lineVertices_.size() / 2;
    }
    glBindVertexArray(0);
    glUseProgram(0);
}

}  // namespace rubble::viewer
