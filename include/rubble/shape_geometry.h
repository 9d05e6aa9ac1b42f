#pragma once
// Shapes as a renderer sees them: the primitives' sizes, and the triangles of hulls, meshes and heightfields in the
// shape's local frame, read back from a world (World::shapeGeometry) after the engine built them.
#include <cstdint>
#include <vector>

#include "rubble/math.h"

namespace rubble {

/// Kinds of shape, in ShapeDef's order.
enum class ShapeType : std::uint8_t { Sphere, Box, Capsule, ConvexHull, Compound, TriangleMesh, Heightfield };

struct ShapeGeometryChild;

/// What a renderer needs to draw one shape.
struct ShapeGeometry {
    ShapeType type = ShapeType::Sphere;
    float radius = 0;      ///< sphere, capsule
    float halfHeight = 0;  ///< capsule, along local y
    Vec3 halfExtents;      ///< box
    /// Hulls, meshes and heightfields: triangles in the local frame, three indices each, counter-clockwise seen from
    /// the front (hull faces are fanned from their first vertex; heightfields face +y, split as RayHit::triangle
    /// describes). Empty for the other kinds.
    std::vector<Vec3> vertices;
    std::vector<std::uint32_t> indices;
    std::vector<ShapeGeometryChild> children;  ///< compounds: their primitives and hulls
    Vec3 boundsMin, boundsMax;                 ///< local bounding box
};

struct ShapeGeometryChild {
    ShapeGeometry geometry;
    Transform local;  ///< pose of the child in the compound's frame
};

}  // namespace rubble
