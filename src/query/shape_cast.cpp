// Sweeps and overlaps of one shape pair. See shape_cast.h for why conservative advancement on GJK is safe.
#include "query/shape_cast.h"

#include <cmath>

#include "query/ray_cast.h"

namespace rubble::detail {
namespace {

/// Flat contacts converge in one or two advances and curved ones in a handful (a grazing contact quarters its gap with
/// each). A sweep still approaching after this many is reported as a hit where it stands: every advance is safe, so
/// that is never past the contact, while a miss could let a caller move through it.
constexpr int kMaxAdvances = 32;

/// p lies in the closed triangle (a, b, c) of unit normal n (p is in the triangle's plane).
bool insideTriangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c, Vec3 n) {
    return dot(cross(b - a, p - a), n) >= 0 && dot(cross(c - b, p - b), n) >= 0 && dot(cross(a - c, p - c), n) >= 0;
}

}  // namespace

SweepResult sweepConvex(const GjkShape& moving, Vec3 dir, float maxT, const GjkShape& target, SweepHit& hit) {
    // Work relative to the moving shape's start: the steps along the sweep must not be rounded away by a position
    // 10 km from the origin, where a float cannot resolve less than a millimetre.
    const Vec3 base = moving.pose.position;
    GjkShape a = moving;
    GjkShape b = target;
    b.pose.position = target.pose.position - base;
    GjkSettings settings;
    GjkResult previous;
    float t = 0;
    for (int advance = 0; advance < kMaxAdvances; ++advance) {
        a.pose.position = dir * t;
        const GjkResult g = gjkDistance(a, b, settings);
        if (g.status != GjkStatus::Separated) {
            if (t == 0) return SweepResult::StartsInside;
            // An advance cannot overshoot but for rounding (GJK calls cores within 1e-6 m touching): the contact
            // is here, and the last separated step knows its normal.
            hit = {t, previous.pointB + base, -previous.normal};
            return SweepResult::Hit;
        }
        const float closing = dot(g.normal, dir);
        // The gap does not shrink now, so it never will (it is convex in t): a shape resting on another and pushed
        // along it does not hit it.
        if (!(closing > 0)) return SweepResult::Miss;
        if (g.distance <= kSweepTolerance) {
            // The remaining gap closed at the current rate: still never past the contact, by convexity.
            hit = {std::fmin(t + g.distance / closing, maxT), g.pointB + base, -g.normal};
            return SweepResult::Hit;
        }
        // Aim half the tolerance short, so that a flat contact ends inside the band with a valid normal rather than
        // exactly touching, where GJK cannot tell the normal.
        t += (g.distance - 0.5f * kSweepTolerance) / closing;
        if (!(t <= maxT)) return SweepResult::Miss;
        settings.initialDirection = g.normal;
        previous = g;
    }
    hit = {t, previous.pointB + base, -previous.normal};
    return SweepResult::Hit;
}

Vec3 closestPointOnTriangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    // Voronoi regions of the vertices, then the edges, then the face (Ericson, Real-Time Collision Detection 5.1.5).
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const float denom = va + vb + vc;
    if (!(denom > 0)) {  // collinear: nearest of the three edges
        Vec3 best = a;
        float bestD = INFINITY;
        const Vec3 ends[3][2] = {{a, b}, {b, c}, {c, a}};
        for (const auto& e : ends) {
            const Vec3 d = e[1] - e[0];
            const float dd = dot(d, d);
            const float s = dd > 0 ? std::fmin(std::fmax(dot(p - e[0], d) / dd, 0.0f), 1.0f) : 0.0f;
            const Vec3 q = e[0] + d * s;
            if (dot(p - q, p - q) < bestD) bestD = dot(p - q, p - q), best = q;
        }
        return best;
    }
    const float v = vb / denom, w = vc / denom;
    return a + ab * v + ac * w;
}

SweepResult sweepSphereTriangle(Vec3 center, float radius, Vec3 dir, float maxT, Vec3 a, Vec3 b, Vec3 c, bool backFaces,
                                SweepHit& hit) {
    if (degenerateTriangle(a, b, c)) return SweepResult::Miss;
    const Vec3 n = normalized(cross(b - a, c - a));
    const float facing = dot(n, dir);
    if (facing >= 0 && !backFaces) return SweepResult::Miss;
    const Vec3 gap = center - closestPointOnTriangle(center, a, b, c);
    if (dot(gap, gap) < radius * radius) return SweepResult::StartsInside;

    // The face: the sphere meets the plane first where its centre is `radius` away from it. If that point of
    // contact lies in the triangle it is the first contact with any of it; if the plane is only met beyond maxT,
    // nothing of the triangle can be met earlier.
    const float side = dot(n, center - a);
    const float s = side >= 0 ? 1.0f : -1.0f;
    const float approach = s * facing;
    if (approach < 0 && s * side > radius) {
        const float t = (s * side - radius) / -approach;
        if (!(t <= maxT)) return SweepResult::Miss;
        const Vec3 p = center + dir * t - n * (s * radius);
        if (insideTriangle(p, a, b, c, n)) {
            hit = {t, p, n * s};
            return SweepResult::Hit;
        }
    }
    // Edges as capsules (whose end caps are the vertex spheres): the first one entered.
    bool found = false;
    float best = maxT;
    SurfaceHit edgeHit;
    const Vec3 ends[3][2] = {{a, b}, {b, c}, {c, a}};
    for (const auto& e : ends) {
        SurfaceHit h;
        const RayResult r = rayCapsule(e[0], e[1], radius, Ray{center, dir, best}, h);
        if (r == RayResult::StartsInside) return SweepResult::StartsInside;  // rounding at the closest-point test
        if (r == RayResult::Hit && (!found || h.t < best)) best = h.t, edgeHit = h, found = true;
    }
    if (!found) return SweepResult::Miss;
    hit = {edgeHit.t, center + dir * edgeHit.t - edgeHit.normal * radius, edgeHit.normal};
    return SweepResult::Hit;
}

GjkShape gjkTriangle(const Vec3 (&vertices)[3], const Transform& pose) {
    GjkShape g;
    g.core = GjkShape::Core::Points;
    g.points = vertices;
    g.pointCount = 3;
    g.pose = pose;
    return g;
}

bool overlapConvex(const GjkShape& a, const GjkShape& b) { return gjkDistance(a, b).status != GjkStatus::Separated; }

}  // namespace rubble::detail
