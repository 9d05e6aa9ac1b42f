#include "shapes/shape_extents.h"

#include <algorithm>
#include <cmath>

namespace rubble::detail {
namespace {

Aabb transformedBox(const Aabb& local, const Transform& pose) {
    const Vec3 center = (local.min + local.max) * 0.5f, half = (local.max - local.min) * 0.5f;
    const Vec3 c = apply(pose, center);
    const Vec3 ax = rotate(pose.rotation, {1, 0, 0}), ay = rotate(pose.rotation, {0, 1, 0}),
               az = rotate(pose.rotation, {0, 0, 1});
    const Vec3 e{std::fabs(ax.x) * half.x + std::fabs(ay.x) * half.y + std::fabs(az.x) * half.z,
                 std::fabs(ax.y) * half.x + std::fabs(ay.y) * half.y + std::fabs(az.y) * half.z,
                 std::fabs(ax.z) * half.x + std::fabs(ay.z) * half.y + std::fabs(az.z) * half.z};
    return {c - e, c + e};
}

Aabb pointsBounds(const std::vector<Vec3>& points, const Transform& pose) {
    Aabb box{apply(pose, points.front()), apply(pose, points.front())};
    for (const Vec3& p : points) {
        const Vec3 w = apply(pose, p);
        box.min = {std::min(box.min.x, w.x), std::min(box.min.y, w.y), std::min(box.min.z, w.z)};
        box.max = {std::max(box.max.x, w.x), std::max(box.max.y, w.y), std::max(box.max.z, w.z)};
    }
    return box;
}

Aabb merge(const Aabb& a, const Aabb& b) {
    return {{std::min(a.min.x, b.min.x), std::min(a.min.y, b.min.y), std::min(a.min.z, b.min.z)},
            {std::max(a.max.x, b.max.x), std::max(a.max.y, b.max.y), std::max(a.max.z, b.max.z)}};
}

Transform compose(const Transform& outer, const Transform& inner) {
    return {apply(outer, inner.position), outer.rotation * inner.rotation};
}

}  // namespace

ShapeBoundsInfo shapeBoundsInfo(const Shape& shape) {
    const Aabb& box = shape.localBounds;
    const Vec3 center = (box.min + box.max) * 0.5f, half = (box.max - box.min) * 0.5f;
    const Vec3 relative = center - shape.unitMass.centerOfMass;
    float radius = length(half);  // the box's own bounding sphere; tighter for round shapes below
    switch (shape.kind) {
        case ShapeKind::Sphere:
            radius = shape.radius;
            break;
        case ShapeKind::Capsule:
            radius = shape.radius + shape.halfHeight;
            break;
        case ShapeKind::ConvexHull: {
            float r2 = 0;
            for (const Vec3& v : shape.hull->vertices) r2 = std::max(r2, dot(v - center, v - center));
            radius = std::sqrt(r2);
            break;
        }
        default:
            break;
    }
    // Rounding in the kernel's rotation must not shrink a box below the shape: pad by a few ulps of the size.
    const float pad = 4e-7f * (length(half) + length(relative));
    return {relative.x,   relative.y,   relative.z,           half.x + pad,      half.y + pad,
            half.z + pad, radius + pad, rotationReach(shape), innerExtent(shape)};
}

namespace {

float innerExtentAbout(const Shape& s, Vec3 center) {
    switch (s.kind) {
        case ShapeKind::Sphere:
        case ShapeKind::Capsule:
            return s.radius;
        case ShapeKind::Box:
            return std::min({s.halfExtents.x, s.halfExtents.y, s.halfExtents.z});
        case ShapeKind::ConvexHull: {
            float inner = INFINITY;
            for (std::uint32_t f = 0; f < s.hull->faceCount(); ++f)
                inner = std::min(inner, s.hull->faceOffsets[f] - dot(s.hull->faceNormals[f], center));
            return std::max(inner, 0.0f);
        }
        case ShapeKind::Compound: {
            float inner = INFINITY;
            for (const CompoundChild& c : s.children)
                inner = std::min(inner, innerExtentAbout(*c.shape, applyInverse(c.local, center)));
            return inner;
        }
        case ShapeKind::TriangleMesh:
        case ShapeKind::Heightfield:
            break;
    }
    return 0.0f;
}

}  // namespace

float innerExtent(const Shape& shape) { return innerExtentAbout(shape, shape.unitMass.centerOfMass); }

float rotationReach(const Shape& shape) {
    const Vec3 com = shape.unitMass.centerOfMass;
    switch (shape.kind) {
        case ShapeKind::Sphere:
            return length(com);
        case ShapeKind::Capsule:
            return length(com) + shape.halfHeight;
        case ShapeKind::Box:
            return length(com) + length(shape.halfExtents);
        case ShapeKind::ConvexHull:
        case ShapeKind::Compound: {
            const Aabb& box = shape.localBounds;
            return length((box.min + box.max) * 0.5f - com) + length((box.max - box.min) * 0.5f);
        }
        case ShapeKind::TriangleMesh:
        case ShapeKind::Heightfield:
            break;
    }
    return 0.0f;
}

Aabb worldBounds(const Shape& shape, const Transform& pose) {
    switch (shape.kind) {
        case ShapeKind::Sphere: {
            const Vec3 r{shape.radius, shape.radius, shape.radius};
            return {pose.position - r, pose.position + r};
        }
        case ShapeKind::Capsule: {
            const Vec3 axis = rotate(pose.rotation, {0, shape.halfHeight, 0});
            const Vec3 r{shape.radius, shape.radius, shape.radius};
            const Vec3 a = pose.position + axis, b = pose.position - axis;
            return {Vec3{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)} - r,
                    Vec3{std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)} + r};
        }
        case ShapeKind::ConvexHull:
            return pointsBounds(shape.hull->vertices, pose);
        case ShapeKind::TriangleMesh:
            return pointsBounds(shape.mesh->vertices, pose);
        case ShapeKind::Compound: {
            Aabb box = worldBounds(*shape.children.front().shape, compose(pose, shape.children.front().local));
            for (const CompoundChild& child : shape.children)
                box = merge(box, worldBounds(*child.shape, compose(pose, child.local)));
            return box;
        }
        case ShapeKind::Box:
        case ShapeKind::Heightfield:
            break;
    }
    return transformedBox(shape.localBounds, pose);
}

}  // namespace rubble::detail
