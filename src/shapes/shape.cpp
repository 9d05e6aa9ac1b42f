// buildShape: the one gate every ShapeDef passes before the engine sees it. Validation happens here so that no
// later stage has to distrust a Shape; the heavy work (hulls, mesh grids, mass integration) lives in the
// neighbouring files.
#include "shapes/shape.h"
#include "world/validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "broadphase/static_bvh.h"
#include "rubble/error.h"
#include "rubble/limits.h"
#include "shapes/mesh_adjacency.h"

namespace rubble::detail {

namespace {

/// A radius or half extent: within the sizes whose mass, inertia and contacts float arithmetic carries.
void requireSize(const char* def, const char* field, float value) {
    requireFinite(def, field, value);
    if (!(value >= limits::kMinShapeSize && value <= limits::kMaxShapeSize))
        fail(def, std::string(field) + " must be in [" + formatNumber(limits::kMinShapeSize) + ", " +
                      formatNumber(limits::kMaxShapeSize) + "] m (got " + formatNumber(value) + "; docs/limits.md)");
}

Aabb emptyAabb() {
    const float inf = std::numeric_limits<float>::infinity();
    return {{inf, inf, inf}, {-inf, -inf, -inf}};
}

void grow(Aabb& box, Vec3 p) {
    box.min = {std::min(box.min.x, p.x), std::min(box.min.y, p.y), std::min(box.min.z, p.z)};
    box.max = {std::max(box.max.x, p.x), std::max(box.max.y, p.y), std::max(box.max.z, p.z)};
}

// Bounds of a compound child in the compound frame. Each kind uses its exact extreme points, so compounds do not
// carry the slack of rotating a box around a box.
Aabb childBounds(const Shape& child, const Transform& t) {
    Aabb box = emptyAabb();
    switch (child.kind) {
        case ShapeKind::Sphere: {
            const Vec3 r{child.radius, child.radius, child.radius};
            box = {t.position - r, t.position + r};
            break;
        }
        case ShapeKind::Capsule: {
            const Vec3 r{child.radius, child.radius, child.radius};
            for (float s : {-1.0f, 1.0f}) {
                const Vec3 end = apply(t, {0, s * child.halfHeight, 0});
                grow(box, end - r);
                grow(box, end + r);
            }
            break;
        }
        case ShapeKind::Box:
            for (int i = 0; i < 8; ++i) {
                const Vec3 h = child.halfExtents;
                grow(box, apply(t, {i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z}));
            }
            break;
        case ShapeKind::ConvexHull:
            for (Vec3 v : child.hull->vertices) grow(box, apply(t, v));
            break;
        default:
            break;  // compounds never hold compounds, meshes or heightfields
    }
    return box;
}

struct Builder {
    Shape operator()(const SphereDef& def) const {
        requireSize("SphereDef", "radius", def.radius);
        Shape s;
        s.kind = ShapeKind::Sphere;
        s.radius = def.radius;
        const Vec3 r{def.radius, def.radius, def.radius};
        s.localBounds = {-r, r};
        return s;
    }

    Shape operator()(const BoxDef& def) const {
        requireSize("BoxDef", "halfExtents.x", def.halfExtents.x);
        requireSize("BoxDef", "halfExtents.y", def.halfExtents.y);
        requireSize("BoxDef", "halfExtents.z", def.halfExtents.z);
        Shape s;
        s.kind = ShapeKind::Box;
        s.halfExtents = def.halfExtents;
        s.localBounds = {-def.halfExtents, def.halfExtents};
        return s;
    }

    Shape operator()(const CapsuleDef& def) const {
        requireSize("CapsuleDef", "radius", def.radius);
        requireFinite("CapsuleDef", "halfHeight", def.halfHeight);
        // A zero half-height is a sphere written as a capsule; allowed so tools can shrink capsules freely.
        if (!(def.halfHeight >= 0 && def.halfHeight <= limits::kMaxShapeSize))
            fail("CapsuleDef", "halfHeight must be in [0, " + formatNumber(limits::kMaxShapeSize) + "] m (got " +
                                   formatNumber(def.halfHeight) + "; docs/limits.md)");
        Shape s;
        s.kind = ShapeKind::Capsule;
        s.radius = def.radius;
        s.halfHeight = def.halfHeight;
        const Vec3 e{def.radius, def.radius + def.halfHeight, def.radius};
        s.localBounds = {-e, e};
        return s;
    }

    Shape operator()(const ConvexHullDef& def) const {
        Shape s;
        s.kind = ShapeKind::ConvexHull;
        auto hull = std::make_shared<ConvexHull>(buildConvexHull(def.points));
        s.localBounds = emptyAabb();
        for (Vec3 v : hull->vertices) grow(s.localBounds, v);
        // What the narrow phase can represent: contact clipping holds two faces' sides, and features are numbered
        // in 16 bits.
        if (hull->vertices.size() > limits::kMaxHullVertices)
            fail("ConvexHullDef", "the hull has " + std::to_string(hull->vertices.size()) + " vertices, more than " +
                                      std::to_string(limits::kMaxHullVertices) + " (docs/limits.md)");
        for (std::uint32_t f = 0; f < hull->faceCount(); ++f) {
            const std::uint32_t sides = hull->faceStart[f + 1] - hull->faceStart[f];
            if (sides > limits::kMaxHullFaceSides)
                fail("ConvexHullDef", "a face of the hull has " + std::to_string(sides) + " sides, more than " +
                                          std::to_string(limits::kMaxHullFaceSides) +
                                          " (docs/limits.md): use fewer points around its rim");
        }
        const Vec3 half = (s.localBounds.max - s.localBounds.min) * 0.5f;
        const float extent = std::max({half.x, half.y, half.z});
        const float reach =
            std::max({std::abs(s.localBounds.min.x), std::abs(s.localBounds.min.y), std::abs(s.localBounds.min.z),
                      s.localBounds.max.x, s.localBounds.max.y, s.localBounds.max.z});
        if (extent < limits::kMinShapeSize || reach > limits::kMaxShapeSize)
            fail("ConvexHullDef", "the hull's half extent " + formatNumber(extent) + " m and reach from its origin " +
                                      formatNumber(reach) + " m must lie in [" + formatNumber(limits::kMinShapeSize) +
                                      ", " + formatNumber(limits::kMaxShapeSize) + "] m (docs/limits.md)");
        s.hull = std::move(hull);
        return s;
    }

    Shape operator()(const CompoundDef& def) const {
        if (def.children.empty()) fail("CompoundDef", "children is empty: a compound needs at least one child");
        if (def.children.size() > limits::kMaxCompoundChildren)
            fail("CompoundDef", "children has " + std::to_string(def.children.size()) + " shapes, more than " +
                                    std::to_string(limits::kMaxCompoundChildren) +
                                    " (contacts name a child in 16 bits; docs/limits.md)");
        Shape s;
        s.kind = ShapeKind::Compound;
        s.localBounds = emptyAabb();
        for (std::size_t i = 0; i < def.children.size(); ++i) {
            const CompoundChildDef& c = def.children[i];
            const std::string where = "CompoundDef: children[" + std::to_string(i) + "]";
            Shape child;
            try {
                child = std::visit(*this, c.shape);
            } catch (const Error& e) {
                throw Error(where + ": " + e.what());
            }
            if (!isFinite(c.local.position))
                throw Error(where + ": local.position is not finite " + describe(c.local.position));
            // A child beyond the coordinate limit puts the compound's centre of mass, and so the body, beyond it.
            if (!withinCoordinateLimit(c.local.position))
                throw Error(where + ": local.position " + describe(c.local.position) + " lies farther than " +
                            formatNumber(limits::kMaxCoordinate) + " m from the compound's origin on an axis " +
                            "(docs/limits.md)");
            const Quat q = c.local.rotation;
            if (!isFinite(q))
                throw Error(where + ": local.rotation is not finite (" + formatNumber(q.x) + ", " + formatNumber(q.y) +
                            ", " + formatNumber(q.z) + ", " + formatNumber(q.w) + ")");
            const double len = std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z + double(q.w) * q.w);
            if (!(len > 1e-6)) throw Error(where + ": local.rotation is a zero quaternion: it must be a rotation");
            // Hand-typed or parsed quaternions are rarely exactly unit; normalising is harmless, while leaving
            // them would scale the child.
            Transform local = c.local;
            local.rotation = {float(q.x / len), float(q.y / len), float(q.z / len), float(q.w / len)};
            child.unitMass = unitMassProperties(child);
            const Aabb b = childBounds(child, local);
            grow(s.localBounds, b.min);
            grow(s.localBounds, b.max);
            s.children.push_back({std::make_shared<const Shape>(std::move(child)), local});
        }
        return s;
    }

    Shape operator()(const TriangleMeshDef& def) const {
        const std::uint64_t triangles = def.indices.size() / 3;
        if (triangles > limits::kMaxMeshTriangles)
            fail("TriangleMeshDef", "indices make " + std::to_string(triangles) + " triangles, more than " +
                                        std::to_string(limits::kMaxMeshTriangles) + " (docs/limits.md)");
        for (std::size_t i = 0; i < def.vertices.size(); ++i) {
            const Vec3 v = def.vertices[i];
            if (!isFinite(v)) continue;  // buildTriangleMesh names it
            if (!withinCoordinateLimit(v))
                fail("TriangleMeshDef", "vertices[" + std::to_string(i) + "] " + describe(v) + " lies farther than " +
                                            formatNumber(limits::kMaxCoordinate) +
                                            " m from the origin on an axis (docs/limits.md)");
        }
        Shape s;
        s.kind = ShapeKind::TriangleMesh;
        auto mesh = std::make_shared<TriangleMesh>(buildTriangleMesh(def));
        mesh->activeEdges = buildMeshAdjacency(*mesh).activeEdges;
        s.localBounds = mesh->bounds;
        s.mesh = std::move(mesh);
        return s;
    }

    Shape operator()(const HeightfieldDef& def) const {
        Shape s;
        s.kind = ShapeKind::Heightfield;
        auto field = std::make_shared<Heightfield>(buildHeightfield(def));
        Aabb b = emptyAabb();
        for (float h : field->heights) {
            b.min.y = std::min(b.min.y, h);
            b.max.y = std::max(b.max.y, h);
        }
        b.min.x = 0;
        b.min.z = 0;
        b.max.x = float(field->columns - 1) * field->spacingX;
        b.max.z = float(field->rows - 1) * field->spacingZ;
        s.localBounds = b;
        s.heightfield = std::move(field);
        return s;
    }
};

}  // namespace

Shape buildShape(const ShapeDef& def) {
    Shape s = std::visit(Builder{}, def);
    s.unitMass = unitMassProperties(s);
    if (!s.staticOnly()) s.unitPrincipal = principalAxes(s.unitMass.inertia);
    return s;
}

std::array<Vec3, 3> triangleOf(const Shape& shape, std::uint32_t t) {
    if (shape.kind == ShapeKind::Heightfield) return heightfieldTriangle(*shape.heightfield, t);
    const std::uint32_t* index = &shape.mesh->indices[3 * std::size_t(t)];
    return {shape.mesh->vertices[index[0]], shape.mesh->vertices[index[1]], shape.mesh->vertices[index[2]]};
}

std::optional<float> surfaceHeightAt(const Shape& shape, float x, float z) {
    if (shape.kind == ShapeKind::TriangleMesh && shape.mesh) return meshHeightAt(*shape.mesh, x, z);
    if (shape.kind == ShapeKind::Heightfield && shape.heightfield) return heightfieldHeightAt(*shape.heightfield, x, z);
    return std::nullopt;
}

}  // namespace rubble::detail
