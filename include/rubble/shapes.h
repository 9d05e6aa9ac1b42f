#pragma once
// Shape definitions. A shape is created once in a world (World::createShape) and shared by any number of bodies.
// Sizes are in metres; every shape's local frame has y up.
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "rubble/math.h"

namespace rubble {

/// Sphere centred on the local origin.
struct SphereDef {
    float radius = 0.5f;
};

/// Box centred on the local origin, axis-aligned in the local frame.
struct BoxDef {
    Vec3 halfExtents{0.5f, 0.5f, 0.5f};
};

/// Capsule along the local y axis: a cylinder of half-height `halfHeight` capped by two hemispheres.
struct CapsuleDef {
    float radius = 0.5f;
    float halfHeight = 0.5f;
};

/// Convex hull of a point cloud. Duplicate, interior and coplanar points are allowed; the cloud must span a volume.
struct ConvexHullDef {
    std::vector<Vec3> points;
};

/// A primitive placed inside a compound.
struct CompoundChildDef {
    std::variant<SphereDef, BoxDef, CapsuleDef, ConvexHullDef> shape;
    Transform local;  ///< pose of the child in the compound's frame
};

/// Rigid union of primitives. Mass properties follow from the children (parallel-axis theorem).
struct CompoundDef {
    std::vector<CompoundChildDef> children;
};

/// Triangle mesh for static bodies only. Triangles are counter-clockwise seen from the front (outward) side.
/// Zero-area triangles are kept (later stages must cope with them); indices must be in range.
struct TriangleMeshDef {
    std::vector<Vec3> vertices;
    std::vector<std::uint32_t> indices;  ///< three per triangle
};

/// Regular height grid for static bodies only: heights[row * columns + column] is the height (local y) at
/// x = column * spacing.x, z = row * spacing.z (local frame, origin at the first sample).
struct HeightfieldDef {
    std::uint32_t rows = 0;
    std::uint32_t columns = 0;
    std::vector<float> heights;
    Vec3 spacing{1, 1, 1};  ///< x and z: sample spacing; y: height scale
};

using ShapeDef =
    std::variant<SphereDef, BoxDef, CapsuleDef, ConvexHullDef, CompoundDef, TriangleMeshDef, HeightfieldDef>;

/// Reads a Wavefront OBJ file (v and f lines; polygons are fan-triangulated; v/vt/vn and negative indices are
/// accepted). Throws rubble::Error naming the file and line on malformed input.
TriangleMeshDef loadObj(const std::string& path);
/// Same, from OBJ text in memory (a mesh from an archive or a network message); `sourceName` stands for the file in
/// messages.
TriangleMeshDef parseObj(std::string_view text, const std::string& sourceName);

/// Mass properties of a solid of the given shape and density.
struct MassProperties {
    float mass = 0;
    Vec3 centerOfMass;            ///< in the shape's local frame
    Mat3 inertia = Mat3::zero();  ///< inertia tensor about the centre of mass, in the shape's local frame
};

/// Mass properties of `shape` at `density` (kg/m^3). Throws rubble::Error for static-only shapes
/// (meshes, heightfields) and for invalid definitions.
MassProperties computeMassProperties(const ShapeDef& shape, float density);

}  // namespace rubble
