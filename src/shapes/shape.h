#pragma once
// Built shapes as the engine keeps them. A Shape is made from a public ShapeDef by buildShape, which validates the
// definition, computes hulls and unit-density mass properties once, so that body creation is cheap.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rubble/math.h"
#include "rubble/shapes.h"

namespace rubble::detail {

enum class ShapeKind : std::uint8_t { Sphere, Box, Capsule, ConvexHull, Compound, TriangleMesh, Heightfield };

struct Aabb {
    Vec3 min, max;
};

/// Convex polyhedron with polygonal faces (coplanar triangles merged).
struct ConvexHull {
    std::vector<Vec3> vertices;
    std::vector<std::uint32_t> faceVertices;  ///< counter-clockwise seen from outside, faces back to back
    std::vector<std::uint32_t> faceStart;     ///< face f uses faceVertices[faceStart[f] .. faceStart[f+1])
    std::vector<Vec3> faceNormals;            ///< outward unit normals
    std::vector<float> faceOffsets;           ///< plane: dot(normal, p) = offset
    std::vector<std::uint32_t> edges;         ///< unique edges as vertex index pairs
    std::uint32_t faceCount() const { return static_cast<std::uint32_t>(faceNormals.size()); }
};

struct TriangleMesh {
    std::vector<Vec3> vertices;
    std::vector<std::uint32_t> indices;  ///< three per triangle
    /// Uniform grid over the xz bounds of the triangles, for height look-ups: cell -> triangle indices.
    Aabb bounds;
    float cellSize = 1;
    std::uint32_t cellsX = 0, cellsZ = 0;
    std::vector<std::uint32_t> cellStart;  ///< size cellsX * cellsZ + 1
    std::vector<std::uint32_t> cellTriangles;
    /// Per triangle, bit e set when its edge e (vertex e to e + 1) is a boundary or convex edge. Contacts on the
    /// other (flat or concave) edges take the face normal, so bodies slide over internal edges without bumps.
    std::vector<std::uint8_t> activeEdges;
    std::uint32_t triangleCount() const { return static_cast<std::uint32_t>(indices.size() / 3); }
};

struct Heightfield {
    std::uint32_t rows = 0, columns = 0;
    std::vector<float> heights;  ///< already multiplied by the y scale
    float spacingX = 1, spacingZ = 1;
};

/// Principal moments and the rotation that takes the principal frame to the shape frame:
/// inertia = R diag(moments) R^T. R is a proper rotation.
struct PrincipalInertia {
    Vec3 moments;
    Quat rotation;
};
struct Shape;

struct CompoundChild {
    std::shared_ptr<const Shape> shape;  ///< a primitive or hull, never a compound, mesh or heightfield
    Transform local;
};

struct Shape {
    ShapeKind kind = ShapeKind::Sphere;
    float radius = 0;      ///< sphere, capsule
    float halfHeight = 0;  ///< capsule (along local y)
    Vec3 halfExtents;      ///< box
    std::shared_ptr<const ConvexHull> hull;
    std::vector<CompoundChild> children;
    std::shared_ptr<const TriangleMesh> mesh;
    std::shared_ptr<const Heightfield> heightfield;

    Aabb localBounds;         ///< bounds in the local frame
    MassProperties unitMass;  ///< at density 1; zero for static-only shapes
    /// Principal axes of unitMass.inertia, computed once: density scales the moments, never the axes.
    PrincipalInertia unitPrincipal;
    bool staticOnly() const { return kind == ShapeKind::TriangleMesh || kind == ShapeKind::Heightfield; }
};

/// Validates `def` and builds the shape. Throws rubble::Error naming the field and the problem
/// (non-finite numbers, non-positive sizes, too few or coplanar hull points, indices out of range, ...).
Shape buildShape(const ShapeDef& def);

/// Mass properties scaled from unit density.
MassProperties scaleMass(const MassProperties& unit, float density);

PrincipalInertia principalAxes(const Mat3& inertia);

/// The three vertices of triangle t of a triangle mesh or heightfield, in the shape's frame.
std::array<Vec3, 3> triangleOf(const Shape& shape, std::uint32_t t);

/// Height (local y) of the highest surface of a triangle mesh or heightfield at local (x, z); empty when
/// (x, z) is outside the shape or the shape has no surface there.
std::optional<float> surfaceHeightAt(const Shape& shape, float x, float z);

/// Numbers as error messages show them: "-1", "0.5", "nan", "(nan, 0, 1)".

// ---- Building blocks of buildShape, exposed for tests, benchmarks and later stages. ----

/// Convex hull of `points` (merged polygonal faces, only hull vertices kept). Throws rubble::Error whose
/// message starts with "ConvexHullDef: " for too few, non-finite, coincident, collinear or coplanar points.
ConvexHull buildConvexHull(const std::vector<Vec3>& points);

/// Validated mesh with its height look-up grid. Throws rubble::Error ("TriangleMeshDef: ...").
TriangleMesh buildTriangleMesh(const TriangleMeshDef& def);

/// Validated heightfield (heights scaled by spacing.y). Throws rubble::Error ("HeightfieldDef: ...").
Heightfield buildHeightfield(const HeightfieldDef& def);

/// Unit-density mass properties of a solid hull (polyhedral integration in double precision).
MassProperties hullMassProperties(const ConvexHull& hull);

/// Unit-density mass properties of a built primitive, hull or compound; zero for static-only shapes.
MassProperties unitMassProperties(const Shape& shape);

/// Height of triangle (a, b, c) above (x, z) when its xz projection contains the point (tiny tolerance);
/// empty for vertical or degenerate triangles. Meshes and heightfields both use it, so they agree.
std::optional<float> triangleHeightAt(Vec3 a, Vec3 b, Vec3 c, float x, float z);

std::optional<float> meshHeightAt(const TriangleMesh& mesh, float x, float z);
std::optional<float> heightfieldHeightAt(const Heightfield& field, float x, float z);

// Heightfield triangle numbering (the static tree, the narrow phase, debug draw and the mesh adjacency all use it):
// the cell at row r (z) and column c (x) is split along its (x0, z0)-(x1, z1) diagonal into triangle
// 2 * (r * (columns - 1) + c) + k, k = 0: (p00, p01, p11) and k = 1: (p00, p11, p10), where p<dx><dz> is the sample
// at column c + dx, row r + dz. Both are counter-clockwise seen from +y, the split and order of heightfieldHeightAt
// and of generated terrains.

/// The sample at (row, column) in the shape frame.
inline Vec3 heightfieldSample(const Heightfield& field, std::uint32_t row, std::uint32_t column) {
    return Vec3{float(column) * field.spacingX, field.heights[std::size_t(row) * field.columns + column],
                float(row) * field.spacingZ};
}
/// Number of triangles of a heightfield: 2 (rows - 1) (columns - 1).
std::uint32_t heightfieldTriangleCount(const Heightfield& field);
/// Vertices of a heightfield triangle in the shape frame.
std::array<Vec3, 3> heightfieldTriangle(const Heightfield& field, std::uint32_t triangle);

}  // namespace rubble::detail
