#pragma once
// What the renderer draws, prepared without OpenGL: unit meshes of the primitives (sphere, box, the cylinder of
// capsules), flat-shaded meshes of hulls, static meshes and heightfields, and per frame the instance lists (one per
// primitive kind, one per mesh) made from the runtime's interpolated RenderFrame.
#include <cstdint>
#include <functional>
#include <vector>

#include "rubble/math.h"
#include "rubble/shape_geometry.h"

namespace rubble {
struct RenderFrame;
}

namespace rubble::viewer {

struct MeshVertex {
    Vec3 position;
    Vec3 normal;
};

/// Indexed triangles, counter-clockwise seen from outside.
struct MeshData {
    std::vector<MeshVertex> vertices;
    std::vector<std::uint32_t> indices;
};

/// Radius 1, smooth normals; `slices` around y, `stacks` from pole to pole.
MeshData unitSphere(int slices, int stacks);
/// Half extents 1, one flat face per side.
MeshData unitBox();
/// Radius 1, half height 1 along y, open at both ends (capsules close it with sphere caps).
MeshData unitCylinder(int slices);
/// Triangles with one normal per face (vertices are repeated per triangle). Degenerate triangles are dropped.
MeshData flatShaded(const std::vector<Vec3>& vertices, const std::vector<std::uint32_t>& indices);

/// Per-instance data of an instanced draw: the shader computes rotate(rotation, scale * p) + position, and turns
/// normals by the inverse scale.
struct Instance {
    float position[3];
    float rotation[4];  ///< quaternion x, y, z, w
    float scale[3];
    float color[4];  ///< rgb; a < 1 mixes in a 1 m checker pattern of strength 1 - a (static ground)
};

enum class PrimitiveMesh : std::uint8_t { Sphere, Box, Cylinder, Count };

/// Instances of one frame: one list per primitive mesh and one per shape mesh (ShapeLibrary::meshes()).
struct InstanceLists {
    std::vector<Instance> primitives[static_cast<int>(PrimitiveMesh::Count)];
    std::vector<std::vector<Instance>> meshes;
    std::size_t instanceCount() const;
    void clear();
};

struct Rgba {
    float r = 1, g = 1, b = 1, a = 1;
};

/// Shapes of one world as drawable parts, by ShapeId::index (what snapshots carry).
class ShapeLibrary {
public:
    /// One piece of a shape: a scaled primitive mesh or a shape mesh, at a pose in the shape's frame.
    struct Part {
        bool isMesh = false;
        PrimitiveMesh primitive = PrimitiveMesh::Sphere;
        std::uint32_t mesh = 0;  ///< index into meshes() when isMesh
        Transform local;
        Vec3 scale{1, 1, 1};
    };

    /// Adds the shape with this index (again: replaces it). Hulls, meshes and heightfields get a mesh each.
    void add(std::uint32_t shapeIndex, const ShapeGeometry& geometry);
    bool has(std::uint32_t shapeIndex) const;
    ShapeType type(std::uint32_t shapeIndex) const;
    const std::vector<Part>& parts(std::uint32_t shapeIndex) const;
    const std::vector<MeshData>& meshes() const { return meshes_; }
    /// Local bounding box, for picking feedback and framing the camera.
    Vec3 boundsMin(std::uint32_t shapeIndex) const;
    Vec3 boundsMax(std::uint32_t shapeIndex) const;

private:
    struct Entry {
        bool present = false;
        ShapeType type = ShapeType::Sphere;
        std::vector<Part> parts;
        Vec3 boundsMin, boundsMax;
    };
    void addParts(const ShapeGeometry& geometry, const Transform& local, std::vector<Part>& parts);
    std::vector<Entry> entries_;
    std::vector<MeshData> meshes_;
};

/// Colour of the body in `slot` of the frame, given its shape's type.
using BodyColor = std::function<Rgba(std::uint32_t slot, ShapeType type)>;

/// Fills `out` with an instance per part of every live body of `frame` whose shape the library knows; returns how
/// many bodies had a shape it does not know (they are not drawn).
std::uint32_t collectInstances(const RenderFrame& frame, const ShapeLibrary& library, const BodyColor& color,
                               InstanceLists& out);

}  // namespace rubble::viewer
