// Meshes and instance lists of the viewer (see shape_meshes.h).
#include "shape_meshes.h"

#include <cmath>
#include <numbers>

#include "rubble/runtime.h"

namespace rubble::viewer {

namespace {

Transform compose(const Transform& outer, const Transform& inner) {
    return {apply(outer, inner.position), outer.rotation * inner.rotation};
}

void addQuad(MeshData& mesh, Vec3 a, Vec3 b, Vec3 c, Vec3 d, Vec3 normal) {
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    for (Vec3 p : {a, b, c, d}) mesh.vertices.push_back({p, normal});
    mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

Instance makeInstance(const Transform& pose, Vec3 scale, Rgba color) {
    return {{pose.position.x, pose.position.y, pose.position.z},
            {pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w},
            {scale.x, scale.y, scale.z},
            {color.r, color.g, color.b, color.a}};
}

}  // namespace

MeshData unitSphere(int slices, int stacks) {
    MeshData mesh;
    const float pi = std::numbers::pi_v<float>;
    for (int i = 0; i <= stacks; ++i) {
        const float theta = pi * static_cast<float>(i) / static_cast<float>(stacks);  // from the +y pole
        for (int j = 0; j <= slices; ++j) {
            const float phi = 2 * pi * static_cast<float>(j) / static_cast<float>(slices);
            const Vec3 p{std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi)};
            mesh.vertices.push_back({p, p});
        }
    }
    const auto row = static_cast<std::uint32_t>(slices + 1);
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(stacks); ++i)
        for (std::uint32_t j = 0; j < static_cast<std::uint32_t>(slices); ++j) {
            const std::uint32_t a = i * row + j, b = a + row, c = b + 1, d = a + 1;
            // Pole rows would make zero-area triangles; leave them out.
            if (i != 0) mesh.indices.insert(mesh.indices.end(), {a, b, d});
            if (i + 1 != static_cast<std::uint32_t>(stacks)) mesh.indices.insert(mesh.indices.end(), {d, b, c});
        }
    return mesh;
}

MeshData unitBox() {
    MeshData mesh;
    for (int axis = 0; axis < 3; ++axis)
        for (float sign : {-1.0f, 1.0f}) {
            Vec3 n{}, u{}, v{};
            n[axis] = sign;
            u[(axis + 1) % 3] = 1;
            v[(axis + 2) % 3] = 1;
            // u x v = +axis; for the negative face swap them so every face winds counter-clockwise from outside.
            if (sign < 0) std::swap(u, v);
            addQuad(mesh, n - u - v, n + u - v, n + u + v, n - u + v, n);
        }
    return mesh;
}

MeshData unitCylinder(int slices) {
    MeshData mesh;
    const float pi = std::numbers::pi_v<float>;
    for (int j = 0; j < slices; ++j) {
        const float a0 = 2 * pi * static_cast<float>(j) / static_cast<float>(slices);
        const float a1 = 2 * pi * static_cast<float>(j + 1) / static_cast<float>(slices);
        const Vec3 n0{std::sin(a0), 0, std::cos(a0)}, n1{std::sin(a1), 0, std::cos(a1)};
        const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
        mesh.vertices.push_back({n0 + Vec3{0, -1, 0}, n0});
        mesh.vertices.push_back({n1 + Vec3{0, -1, 0}, n1});
        mesh.vertices.push_back({n1 + Vec3{0, 1, 0}, n1});
        mesh.vertices.push_back({n0 + Vec3{0, 1, 0}, n0});
        mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    return mesh;
}

MeshData flatShaded(const std::vector<Vec3>& vertices, const std::vector<std::uint32_t>& indices) {
    MeshData mesh;
    mesh.vertices.reserve(indices.size());
    mesh.indices.reserve(indices.size());
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
        const Vec3 a = vertices[indices[t]], b = vertices[indices[t + 1]], c = vertices[indices[t + 2]];
        const Vec3 n = cross(b - a, c - a);
        const float len = length(n);
        if (!(len > 0)) continue;
        for (Vec3 p : {a, b, c}) {
            mesh.indices.push_back(static_cast<std::uint32_t>(mesh.vertices.size()));
            mesh.vertices.push_back({p, n / len});
        }
    }
    return mesh;
}

std::size_t InstanceLists::instanceCount() const {
    std::size_t n = 0;
    for (const auto& list : primitives) n += list.size();
    for (const auto& list : meshes) n += list.size();
    return n;
}

void InstanceLists::clear() {
    for (auto& list : primitives) list.clear();
    for (auto& list : meshes) list.clear();
}

void ShapeLibrary::addParts(const ShapeGeometry& g, const Transform& local, std::vector<Part>& parts) {
    switch (g.type) {
        case ShapeType::Sphere:
            parts.push_back({false, PrimitiveMesh::Sphere, 0, local, {g.radius, g.radius, g.radius}});
            break;
        case ShapeType::Box:
            parts.push_back({false, PrimitiveMesh::Box, 0, local, g.halfExtents});
            break;
        case ShapeType::Capsule: {
            parts.push_back({false, PrimitiveMesh::Cylinder, 0, local, {g.radius, g.halfHeight, g.radius}});
            for (float side : {-1.0f, 1.0f}) {
                const Transform cap{apply(local, {0, side * g.halfHeight, 0}), local.rotation};
                parts.push_back({false, PrimitiveMesh::Sphere, 0, cap, {g.radius, g.radius, g.radius}});
            }
            break;
        }
        case ShapeType::Compound:
            for (const ShapeGeometryChild& child : g.children)
                addParts(child.geometry, compose(local, child.local), parts);
            break;
        case ShapeType::ConvexHull:
        case ShapeType::TriangleMesh:
        case ShapeType::Heightfield:
            parts.push_back(
                {true, PrimitiveMesh::Sphere, static_cast<std::uint32_t>(meshes_.size()), local, {1, 1, 1}});
            meshes_.push_back(flatShaded(g.vertices, g.indices));
            break;
    }
}

void ShapeLibrary::add(std::uint32_t shapeIndex, const ShapeGeometry& geometry) {
    if (shapeIndex >= entries_.size()) entries_.resize(shapeIndex + 1);
    Entry& e = entries_[shapeIndex];
    e.present = true;
    e.type = geometry.type;
    e.boundsMin = geometry.boundsMin;
    e.boundsMax = geometry.boundsMax;
    e.parts.clear();
    addParts(geometry, Transform{}, e.parts);
}

bool ShapeLibrary::has(std::uint32_t shapeIndex) const {
    return shapeIndex < entries_.size() && entries_[shapeIndex].present;
}
ShapeType ShapeLibrary::type(std::uint32_t shapeIndex) const { return entries_.at(shapeIndex).type; }
const std::vector<ShapeLibrary::Part>& ShapeLibrary::parts(std::uint32_t shapeIndex) const {
    return entries_.at(shapeIndex).parts;
}
Vec3 ShapeLibrary::boundsMin(std::uint32_t shapeIndex) const { return entries_.at(shapeIndex).boundsMin; }
Vec3 ShapeLibrary::boundsMax(std::uint32_t shapeIndex) const { return entries_.at(shapeIndex).boundsMax; }

std::uint32_t collectInstances(const RenderFrame& frame, const ShapeLibrary& library, const BodyColor& color,
                               InstanceLists& out) {
    out.clear();
    out.meshes.resize(library.meshes().size());
    std::uint32_t unknown = 0;
    for (std::uint32_t slot = 0; slot < frame.slotCount(); ++slot) {
        if (frame.generation[slot] == 0) continue;
        const std::uint32_t shape = frame.shape[slot];
        if (!library.has(shape)) {
            ++unknown;
            continue;
        }
        const Rgba rgba = color(slot, library.type(shape));
        const Transform pose = frame.transform(slot);
        for (const ShapeLibrary::Part& part : library.parts(shape)) {
            const Instance instance = makeInstance(compose(pose, part.local), part.scale, rgba);
            if (part.isMesh)
                out.meshes[part.mesh].push_back(instance);
            else
                out.primitives[static_cast<int>(part.primitive)].push_back(instance);
        }
    }
    return unknown;
}

}  // namespace rubble::viewer
