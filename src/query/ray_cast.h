#pragma once
// Exact ray tests against one shape, in whatever frame the caller put the ray and the shape in (usually the shape's
// local frame, so that bodies far from the origin keep their precision). Solid shapes are closed sets: a ray that
// starts strictly inside hits at t = 0 (when the caller asks for it); one that starts on the surface hits at t = 0
// with the surface normal if it heads inwards and misses if it heads outwards.
#include <cstdint>

#include "rubble/math.h"

namespace rubble::detail {

struct Shape;
struct ConvexHull;

/// A ray: origin, unit direction, and the stretch [0, maxT] it covers.
struct Ray {
    Vec3 origin;
    Vec3 dir;
    float maxT = 0;
};

/// Where a ray meets a surface: the parameter along the ray and the unit normal facing the ray.
struct SurfaceHit {
    float t = 0;
    Vec3 normal;
};

/// What a solid-shape test found.
enum class RayResult : std::uint8_t { Miss, Hit, StartsInside };

/// The ray in the frame whose pose in the ray's frame is `pose` (rigid, so t and distances are unchanged).
Ray toLocal(const Transform& pose, const Ray& ray);

/// First point of a solid sphere, box, capsule or hull (not a compound, mesh or heightfield) on the ray. A ray that
/// starts strictly inside gives StartsInside with t = 0 and normal = -dir.
RayResult rayConvex(const Shape& shape, const Ray& ray, SurfaceHit& hit);

RayResult raySphere(Vec3 center, float radius, const Ray& ray, SurfaceHit& hit);
/// Capsule around the segment p0-p1 (p0 == p1 is a sphere).
RayResult rayCapsule(Vec3 p0, Vec3 p1, float radius, const Ray& ray, SurfaceHit& hit);
RayResult rayBox(Vec3 halfExtents, const Ray& ray, SurfaceHit& hit);
RayResult rayHull(const ConvexHull& hull, const Ray& ray, SurfaceHit& hit);

/// Watertight ray-triangle test (Woop, Benthin and Wald 2013): a ray through an edge or vertex shared by triangles
/// of one mesh hits at least one of them, never slips between. Front faces (counter-clockwise seen from the ray)
/// only unless `backFaces`; the normal faces the ray either way. Zero-area triangles are never hit.
bool rayTriangle(const Ray& ray, Vec3 a, Vec3 b, Vec3 c, bool backFaces, SurfaceHit& hit);

/// True when the triangle has no area to float precision (its normal is not defined); queries skip such triangles.
bool degenerateTriangle(Vec3 a, Vec3 b, Vec3 c);

inline Vec3 normalized(Vec3 v) {
    const float len = length(v);
    return len > 0 ? v / len : v;
}

}  // namespace rubble::detail
