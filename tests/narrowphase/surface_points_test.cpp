// Contact points on both surfaces: a manifold point p (on B's side) with depth d along the normal n (A to B) names
// two points, p on B's surface and p + d n on A's (the two that the depth measures between). For capsule-box pairs
// (a tilted capsule resting on or sunk into a box's face, and random poses) and for hull-hull pairs whose contact is
// edge against edge, both must lie within 1 mm of their body's surface, measured by an exact distance written for
// this test in double (point to segment for the capsule, point to each face polygon for boxes and hulls).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "narrowphase/convex_pairs.h"
#include "narrowphase/hull_pairs.h"
#include "shapes/shape.h"
#include "support/random_poses.h"
#include "support/test_shapes.h"

namespace rubble::detail {
namespace {

constexpr double kTolerance = 1e-3;  // m, the bound

struct D3 {
    double x, y, z;
};
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dotd(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 crossd(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }

/// A posed point in double: rotation by the (normalised) quaternion, then translation.
D3 place(const Transform& t, Vec3 v) {
    const double n = std::sqrt(double(t.rotation.x) * t.rotation.x + double(t.rotation.y) * t.rotation.y +
                               double(t.rotation.z) * t.rotation.z + double(t.rotation.w) * t.rotation.w);
    const D3 u{t.rotation.x / n, t.rotation.y / n, t.rotation.z / n};
    const double w = t.rotation.w / n;
    const D3 p = d3(v);
    const D3 c = crossd(u, p) * 2.0;
    return p + c * w + crossd(u, c) + d3(t.position);
}

/// Distance from p to triangle (a, b, c) (Ericson 5.1.5, in double).
double pointTriangle(D3 p, D3 a, D3 b, D3 c) {
    const D3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dotd(ab, ap), d2 = dotd(ac, ap);
    const auto dist = [&](D3 q) {
        const D3 d = p - q;
        return std::sqrt(dotd(d, d));
    };
    if (d1 <= 0 && d2 <= 0) return dist(a);
    const D3 bp = p - b;
    const double d3v = dotd(ab, bp), d4 = dotd(ac, bp);
    if (d3v >= 0 && d4 <= d3v) return dist(b);
    const double vc = d1 * d4 - d3v * d2;
    if (vc <= 0 && d1 >= 0 && d3v <= 0) return dist(a + ab * (d1 / (d1 - d3v)));
    const D3 cp = p - c;
    const double d5 = dotd(ab, cp), d6 = dotd(ac, cp);
    if (d6 >= 0 && d5 <= d6) return dist(c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return dist(a + ac * (d2 / (d2 - d6)));
    const double va = d3v * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3v) >= 0 && (d5 - d6) >= 0)
        return dist(b + (c - b) * ((d4 - d3v) / ((d4 - d3v) + (d5 - d6))));
    const double denom = 1.0 / (va + vb + vc);
    return dist(a + ab * (vb * denom) + ac * (vc * denom));
}

/// Distance from p to the surface of a posed convex hull: the nearest of its face polygons.
double toHullSurface(const ConvexHull& hull, const Transform& pose, Vec3 point) {
    const D3 p = d3(point);
    double best = INFINITY;
    for (std::uint32_t f = 0; f + 1 < hull.faceStart.size(); ++f) {
        const std::uint32_t first = hull.faceStart[f], end = hull.faceStart[f + 1];
        const D3 a = place(pose, hull.vertices[hull.faceVertices[first]]);
        for (std::uint32_t k = first + 1; k + 1 < end; ++k)
            best = std::min(best, pointTriangle(p, a, place(pose, hull.vertices[hull.faceVertices[k]]),
                                                place(pose, hull.vertices[hull.faceVertices[k + 1]])));
    }
    return best;
}

/// Distance from p to the surface of a capsule: its distance from the segment, less the radius, in magnitude.
double toCapsuleSurface(const CapsuleSegment& c, Vec3 point) {
    const D3 p = d3(point), s0 = d3(c.center) - d3(c.halfAxis), axis = d3(c.halfAxis) * 2.0;
    const double len2 = dotd(axis, axis);
    const double t = len2 > 0 ? std::clamp(dotd(p - s0, axis) / len2, 0.0, 1.0) : 0.0;
    const D3 d = p - (s0 + axis * t);
    return std::fabs(std::sqrt(dotd(d, d)) - c.radius);
}

/// Largest distance of any point pair of `m` from its surfaces (A: p + d n, B: p), given the two distance functions.
template <class ToA, class ToB>
double worstOffSurface(const Manifold& m, int count, ToA&& toA, ToB&& toB) {
    double worst = 0;
    for (int k = 0; k < count; ++k) {
        const ContactPoint& p = m.points[k];
        worst = std::max(worst, toB(p.position));
        worst = std::max(worst, toA(p.position + m.normal * p.depth));
    }
    return worst;
}

TEST(SurfacePoints, CapsuleBoxPointsLieOnBothSurfaces) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(-1, 1);
    const Vec3 half{0.6f, 0.4f, 0.5f};
    const ConvexHull boxHull = buildConvexHull(rubble::test::boxCorners(half));
    int checked = 0;
    double worst = 0;
    for (int i = 0; i < 4000; ++i) {
        const Transform box{{u(rng), u(rng), u(rng)}, rubble::test::randomRotation(rng)};
        const float radius = 0.1f + 0.1f * (u(rng) + 1), halfHeight = 0.5f * (u(rng) + 1);
        Transform capsulePose;
        if (i % 2 == 0) {
            // Tilted over the top face (local +y), its lowest point within 5 cm of the face either way.
            const Quat tilt = Quat::fromAxisAngle({u(rng), 0, u(rng)}, 1.5f * u(rng));
            const Vec3 axisLocal = rotate(tilt, {0, 1, 0});
            const float lowest = halfHeight * std::fabs(axisLocal.y) + radius;
            const Vec3 local{0.5f * half.x * u(rng), half.y + lowest + 0.05f * u(rng), 0.5f * half.z * u(rng)};
            capsulePose = {apply(box, local), box.rotation * tilt};
        } else {
            capsulePose = {apply(box, {u(rng), u(rng), u(rng)}), rubble::test::randomRotation(rng)};
        }
        const CapsuleSegment capsule = capsuleSegmentOf(capsulePose, halfHeight, radius);
        Manifold m;
        if (!collideCapsuleBox(capsule, box, half, 0.02f, m)) continue;
        const double off = worstOffSurface(
            m, m.pointCount, [&](Vec3 p) { return toCapsuleSurface(capsule, p); },
            [&](Vec3 p) { return toHullSurface(boxHull, box, p); });
        worst = std::max(worst, off);
        EXPECT_LT(off, kTolerance) << i;
        ++checked;
    }
    EXPECT_GT(checked, 1500);
    std::printf("capsule-box: %d manifolds, worst point %.3g m off its surface\n", checked, worst);
}

TEST(SurfacePoints, HullHullEdgeEdgePointsLieOnBothSurfaces) {
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<ConvexHull> hulls;
    for (int k = 0; k < 8; ++k) hulls.push_back(buildConvexHull(rubble::test::randomHullCloud(rng, 10 + 4 * k, 0.5f)));
    int edgeEdge = 0;
    double worst = 0;
    for (int i = 0; i < 20000 && edgeEdge < 600; ++i) {
        const ConvexHull& a = hulls[i % hulls.size()];
        const ConvexHull& b = hulls[(i / 3) % hulls.size()];
        const Transform poseA{{0, 0, 0}, rubble::test::randomRotation(rng)};
        const Transform poseB{Vec3{u(rng), u(rng), u(rng)} * 0.9f, rubble::test::randomRotation(rng)};
        Manifold m;
        if (!collideHulls(a, poseA, b, poseB, 0.02f, m) || m.pointCount == 0) continue;
        if ((m.points[0].feature >> 30) != 2) continue;  // edge against edge only
        ++edgeEdge;
        const double off = worstOffSurface(
            m, m.pointCount, [&](Vec3 p) { return toHullSurface(a, poseA, p); },
            [&](Vec3 p) { return toHullSurface(b, poseB, p); });
        worst = std::max(worst, off);
        EXPECT_LT(off, kTolerance) << i;
    }
    EXPECT_GT(edgeEdge, 200);
    std::printf("hull-hull edge-edge: %d manifolds, worst point %.3g m off its surface\n", edgeEdge, worst);
}

}  // namespace
}  // namespace rubble::detail
