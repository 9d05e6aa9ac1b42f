// Triangle reach tests in SIMD lanes; the tests and their slack are documented in the header.
#include "narrowphase/triangle_reach.h"

#include <algorithm>
#include <cmath>

#include "simd/simd.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::MaskOf;
using simd::Vec3W;

/// Relative slack on the reach, and on the size of the coordinates (see the header).
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

/// Whether every coordinate is finite (a sum of them is not when one is infinite or NaN, or when they overflow: then
/// the triangle is left to the kernel, which is always safe).
template <class F>
simd::MaskOf<F> finite(const Triangle<F>& t) {
    const Vec3W<F> sum = t.v[0] + t.v[1] + t.v[2];
    return simd::isFinite(sum.x + sum.y + sum.z);
}

/// inReach for the lanes from their out-of-reach mask: non-finite triangles always stay in.
template <class F>
void storeInReach(bool* inReach, const simd::MaskOf<F>& out, const Triangle<F>& t) {
    simd::storeMask(inReach, simd::notMask(simd::andMask(out, finite(t))));
}

template <class F>
F maxAbs(const Vec3W<F>& v) {
    return simd::max(simd::abs(v.x), simd::max(simd::abs(v.y), simd::abs(v.z)));
}

/// Squared distance from p to the triangle (0, b, c): the closest point by Voronoi regions (Ericson, RTCD 5.1.5, as
/// closestOnTriangle in triangle_pairs.cpp), every region computed and the first that holds selected.
template <class F>
F pointTriangleDistance2(const Vec3W<F>& p, const Vec3W<F>& b, const Vec3W<F>& c) {
    const F zero(0.0f);
    const Vec3W<F> bp = p - b, cp = p - c;
    const F d1 = dot(b, p), d2 = dot(c, p), d3 = dot(b, bp), d4 = dot(c, bp), d5 = dot(b, cp), d6 = dot(c, cp);
    const F vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    // From the face inwards to the first region, so that the earliest region that holds is the one kept.
    const F inv = F(1.0f) / (va + vb + vc);
    Vec3W<F> q = b * (vb * inv) + c * (vc * inv);
    const F u = d4 - d3, w = d5 - d6;
    q = simd::select(simd::andMask(va <= zero, simd::andMask(u >= zero, w >= zero)), b + (c - b) * (u / (u + w)), q);
    q = simd::select(simd::andMask(vb <= zero, simd::andMask(d2 >= zero, d6 <= zero)), c * (d2 / (d2 - d6)), q);
    q = simd::select(simd::andMask(d6 >= zero, d5 <= d6), c, q);
    q = simd::select(simd::andMask(vc <= zero, simd::andMask(d1 >= zero, d3 <= zero)), b * (d1 / (d1 - d3)), q);
    q = simd::select(simd::andMask(d3 >= zero, d4 <= d3), b, q);
    q = simd::select(simd::andMask(d1 <= zero, d2 <= zero), Vec3W<F>::zero(), q);
    const Vec3W<F> d = q - p;
    return dot(d, d);
}

/// Squared distance between segments p + s d and q + t e, s, t in [0, 1] (Ericson, RTCD 5.1.9, branch-free; e is a
/// triangle edge, never of zero length here, and a segment of zero length takes s = 0).
template <class F>
F segmentSegmentDistance2(const Vec3W<F>& p, const Vec3W<F>& d, const Vec3W<F>& q, const Vec3W<F>& e) {
    const F zero(0.0f), one(1.0f);
    const Vec3W<F> r = p - q;
    const F a = dot(d, d), ee = dot(e, e), f = dot(e, r), c = dot(d, r), b = dot(d, e);
    const F denom = a * ee - b * b;
    auto clamp01 = [&](const F& x) { return simd::min(simd::max(x, zero), one); };
    const simd::MaskOf<F> point = a <= F(1e-12f);
    F s = simd::select(denom > zero, clamp01((b * f - c * ee) / denom), zero);
    s = simd::select(point, zero, s);
    F t = (b * s + f) / ee;
    const simd::MaskOf<F> below = t<zero, above = t> one;
    s = simd::select(below, clamp01(-c / a), simd::select(above, clamp01((b - c) / a), s));
    s = simd::select(point, zero, s);
    t = clamp01(t);
    const Vec3W<F> between = (p + d * s) - (q + e * t);
    return dot(between, between);
}

/// The size the slack scales with: the largest coordinate of the inputs (relative to the triangle's first vertex).
template <class F>
F sizeOf(const Vec3W<F>& p0, const Vec3W<F>& p1, const Vec3W<F>& b, const Vec3W<F>& c) {
    return simd::max(simd::max(maxAbs(p0), maxAbs(p1)), simd::max(maxAbs(b), maxAbs(c)));
}

/// Whether the squared distance d2 exceeds the reach with the header's slack. NaN never does.
template <class F>
simd::MaskOf<F> beyond(const F& d2, const F& reach, const F& size) {
    const F limit = reach * F(1.0f + kReachSlack) + size * F(kSizeSlack);
    return d2 > limit * limit;
}

template <class F>
void sphereAt(Vec3 center, float reach, const TriangleLanes& t, std::size_t i, bool* inReach) {
    const Triangle<F> tri = loadTriangle<F>(t, i);
    const Vec3W<F> p = Vec3W<F>::broadcast(center.x, center.y, center.z) - tri.v[0];
    const Vec3W<F> b = tri.v[1] - tri.v[0], c = tri.v[2] - tri.v[0];
    storeInReach<F>(inReach + i, beyond(pointTriangleDistance2(p, b, c), F(reach), sizeOf(p, p, b, c)), tri);
}

/// The segment's distance from the triangle is the least of: its ends' distances from the triangle, its distances
/// from the three edges, and, where it crosses the triangle's plane, the crossing point's distance (zero when that
/// point is inside). Each is the distance of a segment point from a triangle point, and the closest pair is among
/// them.
template <class F>
void capsuleAt(const CapsuleSegment& capsule, float reach, const TriangleLanes& t, std::size_t i, bool* inReach) {
    const Triangle<F> tri = loadTriangle<F>(t, i);
    const Vec3 s0 = capsule.center - capsule.halfAxis, s1 = capsule.center + capsule.halfAxis;
    const Vec3W<F> p0 = Vec3W<F>::broadcast(s0.x, s0.y, s0.z) - tri.v[0];
    const Vec3W<F> p1 = Vec3W<F>::broadcast(s1.x, s1.y, s1.z) - tri.v[0];
    const Vec3W<F> b = tri.v[1] - tri.v[0], c = tri.v[2] - tri.v[0], d = p1 - p0;
    F d2 = simd::min(pointTriangleDistance2(p0, b, c), pointTriangleDistance2(p1, b, c));
    const Vec3W<F> zero = Vec3W<F>::zero();
    d2 = simd::min(d2, segmentSegmentDistance2(p0, d, zero, b));
    d2 = simd::min(d2, segmentSegmentDistance2(p0, d, b, c - b));
    d2 = simd::min(d2, segmentSegmentDistance2(p0, d, c, zero - c));
    const Vec3W<F> n = cross(b, c);
    const F h0 = dot(n, p0), h1 = dot(n, p1), fzero(0.0f);
    const simd::MaskOf<F> crosses =
        simd::orMask(simd::andMask(h0<fzero, h1> fzero), simd::andMask(h0 > fzero, h1 < fzero));
    const Vec3W<F> x = p0 + d * (h0 / (h0 - h1));
    d2 = simd::select(crosses, simd::min(d2, pointTriangleDistance2(x, b, c)), d2);
    storeInReach<F>(inReach + i, beyond(d2, F(reach), sizeOf(p0, p1, b, c)), tri);
}

/// Full SIMD batches over the padded range, or every triangle one at a time.
template <class Wide, class Narrow>
void run(std::size_t n, bool wide, Wide wideAt, Narrow scalarAt) {
    if (wide)
        for (std::size_t i = 0; i < n; i += simd::kLanes) wideAt(i);
    else
        for (std::size_t i = 0; i < n; ++i) scalarAt(i);
}

/// A body with a non-finite value leaves every triangle to the kernels.
bool allIn(bool finiteBody, std::size_t n, bool wide, bool* inReach) {
    if (finiteBody) return false;
    std::fill(inReach, inReach + (wide ? triangleLanesPadded(n) : n), true);
    return true;
}

void sphere(Vec3 center, float radius, float margin, const TriangleLanes& t, std::size_t n, bool* inReach, bool wide) {
    const float reach = radius + margin;
    if (allIn(isFinite(center) && std::isfinite(reach), n, wide, inReach)) return;
    run(
        n, wide, [&](std::size_t i) { sphereAt<FloatW>(center, reach, t, i, inReach); },
        [&](std::size_t i) { sphereAt<float>(center, reach, t, i, inReach); });
}

void capsule(const CapsuleSegment& c, float margin, const TriangleLanes& t, std::size_t n, bool* inReach, bool wide) {
    const float reach = c.radius + margin;
    if (allIn(isFinite(c.center) && isFinite(c.halfAxis) && std::isfinite(reach), n, wide, inReach)) return;
    run(
        n, wide, [&](std::size_t i) { capsuleAt<FloatW>(c, reach, t, i, inReach); },
        [&](std::size_t i) { capsuleAt<float>(c, reach, t, i, inReach); });
}

}  // namespace

void sphereTrianglesInReach(Vec3 center, float radius, float margin, const TriangleLanes& tris, std::size_t n,
                            bool* inReach) {
    sphere(center, radius, margin, tris, n, inReach, true);
}
void capsuleTrianglesInReach(const CapsuleSegment& capsule_, float margin, const TriangleLanes& tris, std::size_t n,
                             bool* inReach) {
    capsule(capsule_, margin, tris, n, inReach, true);
}

void sphereTrianglesInReachScalar(Vec3 center, float radius, float margin, const TriangleLanes& tris, std::size_t n,
                                  bool* inReach) {
    sphere(center, radius, margin, tris, n, inReach, false);
}
void capsuleTrianglesInReachScalar(const CapsuleSegment& capsule_, float margin, const TriangleLanes& tris,
                                   std::size_t n, bool* inReach) {
    capsule(capsule_, margin, tris, n, inReach, false);
}

}  // namespace rubble::detail
