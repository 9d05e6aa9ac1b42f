// World::shapeGeometry: a built shape handed to renderers, hull faces fanned into triangles, heightfields expanded
// into the triangles the collision code uses, so that what is drawn is what collides.
#include "rubble/shape_geometry.h"

#include "broadphase/static_bvh.h"
#include "rubble/world.h"
#include "world/world_impl.h"

namespace rubble {

namespace {

ShapeGeometry geometryOf(const detail::Shape& shape) {
    ShapeGeometry g;
    g.boundsMin = shape.localBounds.min;
    g.boundsMax = shape.localBounds.max;
    switch (shape.kind) {
        case detail::ShapeKind::Sphere:
            g.type = ShapeType::Sphere;
            g.radius = shape.radius;
            break;
        case detail::ShapeKind::Box:
            g.type = ShapeType::Box;
            g.halfExtents = shape.halfExtents;
            break;
        case detail::ShapeKind::Capsule:
            g.type = ShapeType::Capsule;
            g.radius = shape.radius;
            g.halfHeight = shape.halfHeight;
            break;
        case detail::ShapeKind::ConvexHull: {
            g.type = ShapeType::ConvexHull;
            const detail::ConvexHull& hull = *shape.hull;
            g.vertices = hull.vertices;
            for (std::uint32_t f = 0; f < hull.faceCount(); ++f) {
                const std::uint32_t begin = hull.faceStart[f], end = hull.faceStart[f + 1];
                // Faces are convex polygons, so a fan from the first vertex covers them.
                for (std::uint32_t k = begin + 1; k + 1 < end; ++k)
                    g.indices.insert(g.indices.end(),
                                     {hull.faceVertices[begin], hull.faceVertices[k], hull.faceVertices[k + 1]});
            }
            break;
        }
        case detail::ShapeKind::Compound:
            g.type = ShapeType::Compound;
            g.children.reserve(shape.children.size());
            for (const detail::CompoundChild& child : shape.children)
                g.children.push_back({geometryOf(*child.shape), child.local});
            break;
        case detail::ShapeKind::TriangleMesh:
            g.type = ShapeType::TriangleMesh;
            g.vertices = shape.mesh->vertices;
            g.indices = shape.mesh->indices;
            break;
        case detail::ShapeKind::Heightfield: {
            g.type = ShapeType::Heightfield;
            const detail::Heightfield& field = *shape.heightfield;
            const std::uint32_t count = detail::heightfieldTriangleCount(field);
            g.vertices.reserve(3 * static_cast<std::size_t>(count));
            g.indices.reserve(3 * static_cast<std::size_t>(count));
            for (std::uint32_t t = 0; t < count; ++t)
                for (const Vec3& v : detail::heightfieldTriangle(field, t)) {
                    g.indices.push_back(static_cast<std::uint32_t>(g.vertices.size()));
                    g.vertices.push_back(v);
                }
            break;
        }
    }
    return g;
}

}  // namespace

ShapeGeometry World::shapeGeometry(ShapeId id) const { return geometryOf(impl_->shapeOf(id, "World::shapeGeometry")); }

}  // namespace rubble
