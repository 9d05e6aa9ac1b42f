// Triangle reach tests in SIMD lanes; the tests and their slack are documented in the header.
#include "narrowphase/triangle_reach.h"

#include <algorithm>

#include "simd/simd.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::MaskOf;
using simd::Vec3W;

/// Relative slack on the reach (or the box's margin), and on the size of the coordinates (see the header).
constexpr float kReachSlack = 1e-3f;
constexpr float kSizeSlack = 1e-5f;

template <class F>
struct Triangle {
    Vec3W<F> v[3];
};

template <class F>
Triangle<F> loadTriangle(const TriangleLanes& t, std::size_t i) {
    Triangle<F> tri;
    for (int k = 0; k < 3; ++k) tri.v[k] = Vec3W<F>::load(t.x[k], t.y[k], t.z[k], i);
    return tri;
}

template <class F>
F maxAbs(const Vec3W<F>& v) {
    return simd::max(simd::abs(v.x), simd::max(simd::abs(v.y), simd::abs(v.z)));
}

/// A segment p0 + t (p1 - p0) (a point when p1 = p0) with both ends beyond `limit` on the outer side of the plane
/// dot(n, x - o) = 0 (the scaled limit compared squared: dot(n, x - o) > limit |n|).
template <class F>
MaskOf<F> beyondPlane(const Vec3W<F>& n, const F& d0, const F& d1, const F& limit) {
    const F zero(0.0f);
    const F nearer = simd::min(d0, d1);
    return simd::andMask(nearer > zero, nearer * nearer > limit * limit * simd::dot(n, n));
}

/// A segment (ends p0, p1 relative to the triangle's first vertex) out of reach of the triangle (vertices relative to
/// the first: 0, b, c): beyond `reach` from its plane on one side, or beyond it outside one edge's side plane.
template <class F>
MaskOf<F> segmentOutOfReach(const Vec3W<F>& p0, const Vec3W<F>& p1, const Vec3W<F>& b, const Vec3W<F>& c,
                            const F& reach) {
    const Vec3W<F> n = cross(b, c);
    const F size = simd::max(simd::max(maxAbs(p0), maxAbs(p1)), simd::max(maxAbs(b), maxAbs(c)));
    const F limit = reach * F(1.0f + kReachSlack) + size * F(kSizeSlack);
    const F h0 = dot(n, p0), h1 = dot(n, p1);
    MaskOf<F> out = simd::orMask(beyondPlane(n, h0, h1, limit), beyondPlane(n, -h0, -h1, limit));
    // Edge e from vertex e to e + 1; its side plane's outward normal is edge x n (the triangle is counter-clockwise
    // about n, so it lies on the inner side).
    const Vec3W<F> zero = Vec3W<F>::zero();
    const Vec3W<F> from[3] = {zero, b, c}, to[3] = {b, c, zero};
    for (int e = 0; e < 3; ++e) {
        const Vec3W<F> side = cross(to[e] - from[e], n);
        out = simd::orMask(out, beyondPlane(side, dot(side, p0 - from[e]), dot(side, p1 - from[e]), limit));
    }
    return out;
}

template <class F>
void sphereAt(Vec3 center, float reach, const TriangleLanes& t, std::size_t i, bool* inReach) {
    const Triangle<F> tri = loadTriangle<F>(t, i);
    const Vec3W<F> p = Vec3W<F>::broadcast(center.x, center.y, center.z) - tri.v[0];
    simd::storeMask(inReach + i,
                    simd::notMask(segmentOutOfReach(p, p, tri.v[1] - tri.v[0], tri.v[2] - tri.v[0], F(reach))));
}

template <class F>
void capsuleAt(const CapsuleSegment& capsule, float reach, const TriangleLanes& t, std::size_t i, bool* inReach) {
    const Triangle<F> tri = loadTriangle<F>(t, i);
    const Vec3 s0 = capsule.center - capsule.halfAxis, s1 = capsule.center + capsule.halfAxis;
    const Vec3W<F> p0 = Vec3W<F>::broadcast(s0.x, s0.y, s0.z) - tri.v[0];
    const Vec3W<F> p1 = Vec3W<F>::broadcast(s1.x, s1.y, s1.z) - tri.v[0];
    simd::storeMask(inReach + i,
                    simd::notMask(segmentOutOfReach(p0, p1, tri.v[1] - tri.v[0], tri.v[2] - tri.v[0], F(reach))));
}

template <class F>
void boxAt(const TriangleBox& box, float margin, const TriangleLanes& t, std::size_t i, bool* inReach) {
    const Triangle<F> tri = loadTriangle<F>(t, i);
    const Vec3 c = box.pose.position, h = box.halfExtents;
    Vec3W<F> v[3];  // relative to the box centre
    for (int k = 0; k < 3; ++k) v[k] = tri.v[k] - Vec3W<F>::broadcast(c.x, c.y, c.z);
    const F size =
        simd::max(simd::max(maxAbs(v[0]), maxAbs(v[1])), simd::max(maxAbs(v[2]), F(std::max({h.x, h.y, h.z}))));
    const F limit = F(margin * (1.0f + kReachSlack)) + size * F(kSizeSlack);
    const F hk[3] = {F(h.x), F(h.y), F(h.z)};
    Vec3W<F> axis[3];  // the box axes in the world (columns of toWorld)
    for (int k = 0; k < 3; ++k) axis[k] = Vec3W<F>::broadcast(box.toWorld(0, k), box.toWorld(1, k), box.toWorld(2, k));
    // The triangle's plane (either side): |dot(n, v0)| - radius of the box along n beyond limit |n|.
    const Vec3W<F> n = cross(v[1] - v[0], v[2] - v[0]);
    const F radius =
        hk[0] * simd::abs(dot(n, axis[0])) + hk[1] * simd::abs(dot(n, axis[1])) + hk[2] * simd::abs(dot(n, axis[2]));
    const F gap = simd::abs(dot(n, v[0])) - radius;
    MaskOf<F> out = simd::andMask(gap > F(0.0f), gap * gap > limit * limit * dot(n, n));
    // The box's face axes: the whole triangle beyond a face by more than the limit.
    for (int k = 0; k < 3; ++k) {
        const F p0 = dot(axis[k], v[0]), p1 = dot(axis[k], v[1]), p2 = dot(axis[k], v[2]);
        const F lo = simd::min(p0, simd::min(p1, p2)), hi = simd::max(p0, simd::max(p1, p2));
        out = simd::orMask(out, simd::orMask(lo - hk[k] > limit, -hi - hk[k] > limit));
    }
    simd::storeMask(inReach + i, simd::notMask(out));
}

/// Full SIMD batches over the padded range, or every triangle one at a time.
template <class Wide, class Narrow>
void run(std::size_t n, bool wide, Wide wideAt, Narrow scalarAt) {
    if (wide)
        for (std::size_t i = 0; i < n; i += simd::kLanes) wideAt(i);
    else
        for (std::size_t i = 0; i < n; ++i) scalarAt(i);
}

void sphere(Vec3 center, float radius, float margin, const TriangleLanes& t, std::size_t n, bool* inReach, bool wide) {
    const float reach = radius + margin;
    run(
        n, wide, [&](std::size_t i) { sphereAt<FloatW>(center, reach, t, i, inReach); },
        [&](std::size_t i) { sphereAt<float>(center, reach, t, i, inReach); });
}

void capsule(const CapsuleSegment& c, float margin, const TriangleLanes& t, std::size_t n, bool* inReach, bool wide) {
    const float reach = c.radius + margin;
    run(
        n, wide, [&](std::size_t i) { capsuleAt<FloatW>(c, reach, t, i, inReach); },
        [&](std::size_t i) { capsuleAt<float>(c, reach, t, i, inReach); });
}

void box(const TriangleBox& b, float margin, const TriangleLanes& t, std::size_t n, bool* inReach, bool wide) {
    run(
        n, wide, [&](std::size_t i) { boxAt<FloatW>(b, margin, t, i, inReach); },
        [&](std::size_t i) { boxAt<float>(b, margin, t, i, inReach); });
}

}  // namespace

std::size_t triangleLanesPadded(std::size_t n) { return simd::roundUpToLanes<FloatW>(n); }

void sphereTrianglesInReach(Vec3 center, float radius, float margin, const TriangleLanes& tris, std::size_t n,
                            bool* inReach) {
    sphere(center, radius, margin, tris, n, inReach, true);
}
void capsuleTrianglesInReach(const CapsuleSegment& capsule_, float margin, const TriangleLanes& tris, std::size_t n,
                             bool* inReach) {
    capsule(capsule_, margin, tris, n, inReach, true);
}
void boxTrianglesInReach(const TriangleBox& box_, float margin, const TriangleLanes& tris, std::size_t n,
                         bool* inReach) {
    box(box_, margin, tris, n, inReach, true);
}

void sphereTrianglesInReachScalar(Vec3 center, float radius, float margin, const TriangleLanes& tris, std::size_t n,
                                  bool* inReach) {
    sphere(center, radius, margin, tris, n, inReach, false);
}
void capsuleTrianglesInReachScalar(const CapsuleSegment& capsule_, float margin, const TriangleLanes& tris,
                                   std::size_t n, bool* inReach) {
    capsule(capsule_, margin, tris, n, inReach, false);
}
void boxTrianglesInReachScalar(const TriangleBox& box_, float margin, const TriangleLanes& tris, std::size_t n,
                               bool* inReach) {
    box(box_, margin, tris, n, inReach, false);
}

}  // namespace rubble::detail
