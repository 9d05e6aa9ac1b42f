#include "narrowphase/closest_points_contact.h"

#include <algorithm>

namespace rubble::detail {

bool misstatesDistance(const Manifold& m, float bestSeparation, float size) {
    if (!(bestSeparation > kClosestPointsMinimumGap * size)) return false;
    if (m.pointCount == 0) return true;  // every clipped point lay beyond the margin, the closest ones off the face
    float deepest = m.points[0].depth;
    for (int p = 1; p < m.pointCount; ++p) deepest = std::max(deepest, m.points[p].depth);
    return deepest < -(bestSeparation * (1 + kClosestPointsRelativeTolerance) + kClosestPointsAbsoluteTolerance * size);
}

bool contactAtClosestPoints(const GjkShape& a, const GjkShape& b, float margin, Manifold& out, Vec3& localA,
                            Vec3& localB) {
    const GjkResult g = gjkDistance(a, b);
    if (g.status != GjkStatus::Separated || g.distance > margin) return false;
    out.normal = g.normal;
    out.points[0].position = g.pointB;
    out.points[0].depth = -g.distance;
    out.pointCount = 1;
    localA = rotate(conjugate(a.pose.rotation), g.pointA - a.pose.position);
    localB = rotate(conjugate(b.pose.rotation), g.pointB - b.pose.position);
    return true;
}

}  // namespace rubble::detail
