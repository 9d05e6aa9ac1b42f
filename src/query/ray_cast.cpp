// Exact ray tests per shape kind. Quadratics take their small root as c / (-b + sqrt(disc)), which loses no bits
// when the origin is close to the surface, and measure the discriminant through a cross product, which loses none
// when the origin is far away (the textbook b^2 - ac subtracts two huge, nearly equal numbers there).
#include "query/ray_cast.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "shapes/shape.h"

namespace rubble::detail {
namespace {

float component(Vec3 v, int axis) { return v[axis]; }

/// Clips the ray against half-spaces dot(n, x) <= offset (the faces of a box or hull) one at a time.
class PlaneClipper {
public:
    explicit PlaneClipper(float maxT) : exit_(maxT) {}

    /// nd = dot(n, dir); gap = offset - dot(n, origin), > 0 when the origin is strictly inside this half-space.
    void add(float nd, float gap, int plane) {
        if (empty_) return;
        if (!(gap > 0)) strictlyInside_ = false;
        if (nd == 0) {
            if (gap < 0) empty_ = true;  // parallel and outside: never enters
            return;
        }
        const float t = gap / nd;
        if (nd < 0) {
            // Entering through this plane. Equal entries (the ray meets an edge) keep the first plane: deterministic.
            if (t >= enter_ && (plane_ < 0 || t > enter_)) enter_ = t, plane_ = plane;
        } else if (t < exit_) {
            exit_ = t;
        }
        if (enter_ > exit_) empty_ = true;
    }

    /// Planes must all have been added. `normalOf(plane)` gives the outward normal of the entry plane.
    template <class NormalOf>
    RayResult finish(const Ray& ray, NormalOf&& normalOf, SurfaceHit& hit) const {
        if (empty_) return RayResult::Miss;
        if (strictlyInside_) {
            hit = {0, -ray.dir};
            return RayResult::StartsInside;
        }
        if (plane_ < 0) return RayResult::Miss;  // on the surface, heading out
        hit = {std::max(enter_, 0.0f), normalOf(plane_)};
        return RayResult::Hit;
    }

private:
    float enter_ = 0, exit_;
    int plane_ = -1;
    bool strictlyInside_ = true;
    bool empty_ = false;
};

/// Smaller root of t^2 a + 2 b t + c = 0 for b < 0 (approaching), c > 0 (outside), disc = b^2 - a c >= 0.
float smallRoot(float a, float b, float c, float disc) {
    const float q = -b + std::sqrt(disc);
    return q > 0 ? c / q : (a > 0 ? -b / a : 0.0f);
}

}  // namespace

Ray toLocal(const Transform& pose, const Ray& ray) {
    const Quat inverse = conjugate(pose.rotation);
    return {rotate(inverse, ray.origin - pose.position), rotate(inverse, ray.dir), ray.maxT};
}

RayResult raySphere(Vec3 center, float radius, const Ray& ray, SurfaceHit& hit) {
    const Vec3 m = ray.origin - center;
    const float b = dot(m, ray.dir);
    const float c = dot(m, m) - radius * radius;
    if (c < 0) {
        hit = {0, -ray.dir};
        return RayResult::StartsInside;
    }
    if (b >= 0) return RayResult::Miss;  // outside or on the surface, and not heading in
    const Vec3 perpendicular = m - ray.dir * b;
    const float disc = radius * radius - dot(perpendicular, perpendicular);
    if (disc < 0) return RayResult::Miss;
    const float t = smallRoot(1, b, c, disc);
    if (!(t <= ray.maxT)) return RayResult::Miss;
    hit = {t, normalized(m + ray.dir * t)};
    return RayResult::Hit;
}

RayResult rayCapsule(Vec3 p0, Vec3 p1, float radius, const Ray& ray, SurfaceHit& hit) {
    const Vec3 axis = p1 - p0;
    const float axisLength2 = dot(axis, axis);
    const Vec3 m = ray.origin - p0;
    const float along = axisLength2 > 0 ? std::clamp(dot(m, axis) / axisLength2, 0.0f, 1.0f) : 0.0f;
    const Vec3 offset = m - axis * along;
    if (dot(offset, offset) < radius * radius) {
        hit = {0, -ray.dir};
        return RayResult::StartsInside;
    }
    // The capsule is the union of the cylinder and two spheres, and the origin is outside all three: the first
    // entry into the union is the first entry into any of them.
    float best = ray.maxT;
    bool found = false;
    if (axisLength2 > 0) {
        const Vec3 dirPerp = ray.dir - axis * (dot(ray.dir, axis) / axisLength2);
        const Vec3 mPerp = m - axis * (dot(m, axis) / axisLength2);
        const float a = dot(dirPerp, dirPerp);
        const float b = dot(mPerp, dirPerp);
        // a == 0: parallel to the axis, only the caps can be met. b >= 0: not approaching the axis.
        if (a > 1e-12f && b < 0) {
            const Vec3 crossed = cross(mPerp, dirPerp);
            const float disc = a * radius * radius - dot(crossed, crossed);
            const float c = dot(mPerp, mPerp) - radius * radius;
            if (disc >= 0 && c >= 0) {
                const float t = smallRoot(a, b, c, disc);
                const float s = dot(m + ray.dir * t, axis) / axisLength2;
                if (t <= best && s >= 0 && s <= 1) {
                    best = t;
                    found = true;
                    hit = {t, normalized(mPerp + dirPerp * t)};
                }
            }
        }
    }
    for (const Vec3 cap : {p0, p1}) {
        SurfaceHit h;
        const Ray limited{ray.origin, ray.dir, best};
        if (raySphere(cap, radius, limited, h) == RayResult::Hit && (!found || h.t < best)) {
            best = h.t;
            found = true;
            hit = h;
        }
    }
    return found ? RayResult::Hit : RayResult::Miss;
}

RayResult rayBox(Vec3 half, const Ray& ray, SurfaceHit& hit) {
    PlaneClipper clip(ray.maxT);
    for (int axis = 0; axis < 3; ++axis) {
        const float d = component(ray.dir, axis), o = component(ray.origin, axis), h = component(half, axis);
        clip.add(d, h - o, 2 * axis);
        clip.add(-d, h + o, 2 * axis + 1);
    }
    return clip.finish(
        ray,
        [](int plane) {
            Vec3 n;
            n[plane / 2] = (plane & 1) ? -1.0f : 1.0f;
            return n;
        },
        hit);
}

RayResult rayHull(const ConvexHull& hull, const Ray& ray, SurfaceHit& hit) {
    PlaneClipper clip(ray.maxT);
    for (std::uint32_t f = 0; f < hull.faceCount(); ++f) {
        const Vec3 n = hull.faceNormals[f];
        clip.add(dot(n, ray.dir), hull.faceOffsets[f] - dot(n, ray.origin), int(f));
    }
    return clip.finish(
        ray, [&](int plane) { return hull.faceNormals[std::size_t(plane)]; }, hit);
}

RayResult rayConvex(const Shape& shape, const Ray& ray, SurfaceHit& hit) {
    switch (shape.kind) {
        case ShapeKind::Sphere:
            return raySphere({}, shape.radius, ray, hit);
        case ShapeKind::Box:
            return rayBox(shape.halfExtents, ray, hit);
        case ShapeKind::Capsule:
            return rayCapsule({0, -shape.halfHeight, 0}, {0, shape.halfHeight, 0}, shape.radius, ray, hit);
        case ShapeKind::ConvexHull:
            return rayHull(*shape.hull, ray, hit);
        default:
            return RayResult::Miss;
    }
}

bool degenerateTriangle(Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 e1 = b - a, e2 = c - a;
    const Vec3 n = cross(e1, e2);
    // sin^2 of the angle at a below 1e-12: collinear to float precision (or a zero edge, or NaN).
    return !(dot(n, n) > 1e-12f * dot(e1, e1) * dot(e2, e2));
}

bool rayTriangle(const Ray& ray, Vec3 a, Vec3 b, Vec3 c, bool backFaces, SurfaceHit& hit) {
    if (degenerateTriangle(a, b, c)) return false;
    const Vec3 n = cross(b - a, c - a);
    const float facing = dot(n, ray.dir);
    if (facing == 0 || (facing > 0 && !backFaces)) return false;

    // Shear the triangle into a frame where the ray is the +z axis through the origin; the 2D edge functions there
    // are computed the same way (up to sign) for both triangles of a shared edge, which is what makes it watertight.
    int kz = 0;
    if (std::fabs(ray.dir.y) > std::fabs(component(ray.dir, kz))) kz = 1;
    if (std::fabs(ray.dir.z) > std::fabs(component(ray.dir, kz))) kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (component(ray.dir, kz) < 0) std::swap(kx, ky);
    const float dz = component(ray.dir, kz);
    const float sx = component(ray.dir, kx) / dz, sy = component(ray.dir, ky) / dz, sz = 1.0f / dz;

    const Vec3 A = a - ray.origin, B = b - ray.origin, C = c - ray.origin;
    const float ax = component(A, kx) - sx * component(A, kz), ay = component(A, ky) - sy * component(A, kz);
    const float bx = component(B, kx) - sx * component(B, kz), by = component(B, ky) - sy * component(B, kz);
    const float cx = component(C, kx) - sx * component(C, kz), cy = component(C, ky) - sy * component(C, kz);
    float u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
    if (u == 0 || v == 0 || w == 0) {  // on an edge in float: decide it in double, as both neighbours will
        u = float(double(cx) * by - double(cy) * bx);
        v = float(double(ax) * cy - double(ay) * cx);
        w = float(double(bx) * ay - double(by) * ax);
    }
    if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return false;
    const float det = u + v + w;
    if (det == 0) return false;
    const float az = sz * component(A, kz), bz = sz * component(B, kz), cz = sz * component(C, kz);
    const float t = (u * az + v * bz + w * cz) / det;
    if (!(t >= 0 && t <= ray.maxT)) return false;
    const Vec3 unit = normalized(n);
    hit = {t, facing < 0 ? unit : -unit};
    return true;
}

}  // namespace rubble::detail
