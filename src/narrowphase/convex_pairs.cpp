// Closed-form contact kernels. Each kernel is written once over a lane type F (simd::FloatW for full batches, float
// for tails, the *Scalar references and the per-pair Manifold functions) with selects instead of branches, so every
// form runs the same operations in the same order and agrees bit for bit (only + - * / sqrt min max select are used).
// Positions are computed relative to one of the bodies and only the final contact point adds the world position
// back, so pairs 10 km from the origin lose no more than the rounding of their own coordinates.
#if defined(__GNUC__) && !defined(__clang__)
// GCC's SLP vectoriser may fuse alternating +/- lanes even under -ffp-contract=off (see src/integrate/integrate.cpp),
// and its loop vectoriser would turn the scalar reference into a second SIMD path; the wide kernels are explicit SIMD.
#pragma GCC optimize("no-tree-slp-vectorize", "no-tree-loop-vectorize")
#endif
#include "narrowphase/convex_pairs.h"

#include "simd/simd.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::IntOf;
using simd::MaskOf;
using simd::QuatW;
using simd::Vec3W;

/// Squared centre distances below this (1e-12 m) have no usable direction: a fixed normal is taken instead.
constexpr float kMinDistanceSq = 1e-24f;
/// Squared segment lengths below this (1e-6 m) count as points.
constexpr float kMinSegmentSq = 1e-12f;
/// Parallel capsules give two points only when their projections overlap by more than this (squared, 1 mm).
constexpr float kMinOverlapSq = 1e-6f;

template <class F>
struct Contact {
    Vec3W<F> normal;
    Vec3W<F> p0, p1;
    F depth0, depth1;
    IntOf<F> feature0, feature1, count;
};

template <class F>
Vec3W<F> up() {
    return Vec3W<F>::broadcast(0.0f, 1.0f, 0.0f);
}

template <class F>
IntOf<F> selectInt(const MaskOf<F>& m, int a, int b) {
    return simd::select(m, IntOf<F>(a), IntOf<F>(b));
}

/// Sphere at a against sphere at b (any common origin): unit normal a->b (+y when coincident), distance, point on
/// b's surface.
template <class F>
void sphereSphere(const Vec3W<F>& a, const Vec3W<F>& b, const F& radiusB, Vec3W<F>& normal, F& distance,
                  Vec3W<F>& point) {
    const Vec3W<F> d = b - a;
    const F d2 = simd::dot(d, d);
    const auto ok = d2 > F(kMinDistanceSq);
    distance = simd::sqrt(d2);
    const F inv = F(1.0f) / simd::select(ok, distance, F(1.0f));
    normal = simd::select(ok, d * inv, up<F>());
    point = b - normal * radiusB;
}

/// Fills count and the second slot of a one-point contact.
template <class F>
void finishOnePoint(Contact<F>& c, const F& margin) {
    c.p1 = c.p0;
    c.depth1 = c.depth0;
    c.feature1 = c.feature0;
    c.count = selectInt<F>(c.depth0 >= -margin, 1, 0);
}

template <class F>
Contact<F> spheresKernel(const Vec3W<F>& cA, const F& rA, const Vec3W<F>& cB, const F& rB, const F& margin) {
    Contact<F> c;
    F distance;
    Vec3W<F> pointRel;
    // Relative to A: only the final point goes back to world coordinates.
    sphereSphere(Vec3W<F>::zero(), cB - cA, rB, c.normal, distance, pointRel);
    c.p0 = pointRel + cA;
    c.depth0 = rA + rB - distance;
    c.feature0 = IntOf<F>(0);
    finishOnePoint(c, margin);
    return c;
}

/// Segment feature of a clamped parameter in [-1, 1] or [0, 1]: 1 at the low end, 2 at the high end, 0 between.
template <class F>
IntOf<F> segmentFeature(const F& t, float low, float high) {
    return simd::select(t <= F(low), IntOf<F>(1), selectInt<F>(t >= F(high), 2, 0));
}

template <class F>
Contact<F> sphereCapsuleKernel(const Vec3W<F>& cA, const F& rA, const Vec3W<F>& cB, const Vec3W<F>& h, const F& rB,
                               const F& margin) {
    Contact<F> c;
    const Vec3W<F> rel = cA - cB;  // relative to the capsule centre
    const F hh = simd::dot(h, h);
    const F t = simd::clamp(simd::dot(rel, h) / simd::select(hh > F(0.0f), hh, F(1.0f)), F(-1.0f), F(1.0f));
    const Vec3W<F> onAxis = h * t;
    F distance;
    Vec3W<F> pointRel;
    sphereSphere(rel, onAxis, rB, c.normal, distance, pointRel);
    c.p0 = pointRel + cB;
    c.depth0 = rA + rB - distance;
    c.feature0 = segmentFeature(t, -1.0f, 1.0f);
    finishOnePoint(c, margin);
    return c;
}

/// Unit vector perpendicular to v, chosen from v alone (cross with the least aligned axis); +y for v = 0.
template <class F>
Vec3W<F> perpendicular(const Vec3W<F>& v) {
    const Vec3W<F> av = simd::abs(v);
    const auto useX = simd::andMask(av.x <= av.y, av.x <= av.z);
    const auto useY = simd::andMask(simd::notMask(useX), av.y <= av.z);
    const F zero(0.0f), one(1.0f);
    const Vec3W<F> axis{simd::select(useX, one, zero), simd::select(useY, one, zero),
                        simd::select(simd::orMask(useX, useY), zero, one)};
    const Vec3W<F> p = simd::cross(v, axis);
    const F p2 = simd::dot(p, p);
    const auto ok = p2 > F(kMinDistanceSq);
    return simd::select(ok, p / simd::sqrt(simd::select(ok, p2, one)), up<F>());
}

template <class F>
Contact<F> capsulesKernel(const Vec3W<F>& cA, const Vec3W<F>& hA, const F& rA, const Vec3W<F>& cB, const Vec3W<F>& hB,
                          const F& rB, const F& margin) {
    const F zero(0.0f), one(1.0f), two(2.0f);
    // Segments p1 + s d1 and p2 + t d2 (s, t in [0, 1]) relative to A's centre.
    const Vec3W<F> cAB = cB - cA;
    const Vec3W<F> p1 = -hA, d1 = hA * two;
    const Vec3W<F> p2 = cAB - hB, d2 = hB * two;
    const Vec3W<F> r = p1 - p2;
    const F a = simd::dot(d1, d1), e = simd::dot(d2, d2), f = simd::dot(d2, r);
    const F cc = simd::dot(d1, r), b = simd::dot(d1, d2);
    const auto aOk = a > F(kMinSegmentSq), eOk = e > F(kMinSegmentSq);
    const F safeA = simd::select(aOk, a, one), safeE = simd::select(eOk, e, one);

    // Ericson 5.1.9: closest points of two segments.
    const F denom = a * e - b * b;
    const auto parallel = denom <= F(kCapsuleParallelSine * kCapsuleParallelSine) * (a * e);
    const F sLine =
        simd::select(parallel, zero, simd::clamp((b * f - cc * e) / simd::select(parallel, one, denom), zero, one));
    const F tLine = (b * sLine + f) / safeE;
    const F sIfT0 = simd::clamp(-cc / safeA, zero, one);
    const F sIfT1 = simd::clamp((b - cc) / safeA, zero, one);
    F s = simd::select(tLine < zero, sIfT0, simd::select(tLine > one, sIfT1, sLine));
    F t = simd::clamp(tLine, zero, one);
    // Degenerate segments (capsules of zero half height are spheres).
    const F tIfPointA = simd::clamp(f / safeE, zero, one);
    s = simd::select(aOk, simd::select(eOk, s, sIfT0), zero);
    t = simd::select(eOk, simd::select(aOk, t, tIfPointA), zero);

    const Vec3W<F> onA = p1 + d1 * s, onB = p2 + d2 * t;
    const Vec3W<F> diff = onB - onA;
    const F dist2 = simd::dot(diff, diff);
    const auto apart = dist2 > F(kMinDistanceSq);
    const F dist = simd::sqrt(dist2);
    // Touching axes: the normal of the plane of both axes (oriented A->B), or for collinear axes any perpendicular.
    const Vec3W<F> axesNormal = simd::cross(d1, d2);
    const F an2 = simd::dot(axesNormal, axesNormal);
    const auto crossOk = simd::andMask(simd::notMask(parallel), an2 > F(kMinDistanceSq));
    const Vec3W<F> axesUnit = axesNormal / simd::sqrt(simd::select(crossOk, an2, one));
    const Vec3W<F> axesOriented = simd::select(simd::dot(axesUnit, cAB) < zero, -axesUnit, axesUnit);
    const Vec3W<F> fallback = simd::select(crossOk, axesOriented, perpendicular(simd::select(aOk, d1, d2)));
    Contact<F> c;
    c.normal = simd::select(apart, diff / simd::select(apart, dist, one), fallback);
    c.depth0 = rA + rB - dist;
    c.p0 = onB - c.normal * rB + cA;
    c.feature0 = segmentFeature(s, 0.0f, 1.0f) * IntOf<F>(4) + segmentFeature(t, 0.0f, 1.0f);

    // Nearly parallel with overlapping projections: two points at the ends of the overlap, measured along the
    // normal made perpendicular to A's axis.
    const F sB0 = -simd::dot(r, d1) / safeA;
    const F sB1 = simd::dot(d2 - r, d1) / safeA;
    const F lo = simd::max(zero, simd::min(sB0, sB1)), hi = simd::min(one, simd::max(sB0, sB1));
    const F span = hi - lo;
    const auto twoPoints =
        simd::andMask(simd::andMask(parallel, simd::andMask(aOk, eOk)), span * span * a > F(kMinOverlapSq));
    const Vec3W<F> radial = c.normal - d1 * (simd::dot(c.normal, d1) / safeA);
    const F radial2 = simd::dot(radial, radial);
    const auto radialOk = radial2 > F(kMinDistanceSq);
    const Vec3W<F> n2 = simd::select(radialOk, radial / simd::sqrt(simd::select(radialOk, radial2, one)), c.normal);
    const F dsB = simd::select(twoPoints, sB1 - sB0, one);
    const auto point = [&](const F& sA, Vec3W<F>& position, F& depth) {
        const F tB = simd::clamp((sA - sB0) / dsB, zero, one);
        const Vec3W<F> q = p2 + d2 * tB;
        const F sq = simd::clamp(simd::dot(q - p1, d1) / safeA, zero, one);
        const F sep = simd::dot(q - (p1 + d1 * sq), n2);
        depth = rA + rB - sep;
        position = q - n2 * rB + cA;
    };
    Vec3W<F> posLo, posHi;
    F depthLo, depthHi;
    point(lo, posLo, depthLo);
    point(hi, posHi, depthHi);
    const IntOf<F> featureLo = selectInt<F>(simd::min(sB0, sB1) <= zero, 16, 17);
    const IntOf<F> featureHi = selectInt<F>(simd::max(sB0, sB1) >= one, 32, 33);

    c.normal = simd::select(twoPoints, n2, c.normal);
    c.p1 = simd::select(twoPoints, posHi, c.p0);
    c.depth1 = simd::select(twoPoints, depthHi, c.depth0);
    c.feature1 = simd::select(twoPoints, featureHi, c.feature0);
    c.p0 = simd::select(twoPoints, posLo, c.p0);
    c.depth0 = simd::select(twoPoints, depthLo, c.depth0);
    c.feature0 = simd::select(twoPoints, featureLo, c.feature0);

    const auto ok0 = c.depth0 >= -margin;
    const auto ok1 = simd::andMask(twoPoints, c.depth1 >= -margin);
    const auto moveDown = simd::andMask(simd::notMask(ok0), ok1);
    c.p0 = simd::select(moveDown, c.p1, c.p0);
    c.depth0 = simd::select(moveDown, c.depth1, c.depth0);
    c.feature0 = simd::select(moveDown, c.feature1, c.feature0);
    c.count = selectInt<F>(ok0, 1, 0) + selectInt<F>(ok1, 1, 0);
    return c;
}

/// Box feature code of a local point: per axis 0 strictly inside, 1 on/below -h, 2 on/above +h, weighted 1, 3, 9.
template <class F>
IntOf<F> boxFeature(const Vec3W<F>& p, const Vec3W<F>& h) {
    const auto axis = [](const F& v, const F& e) {
        return simd::select(v >= e, IntOf<F>(2), selectInt<F>(v <= -e, 1, 0));
    };
    return axis(p.x, h.x) + axis(p.y, h.y) * IntOf<F>(3) + axis(p.z, h.z) * IntOf<F>(9);
}

template <class F>
Contact<F> sphereBoxKernel(const Vec3W<F>& cA, const F& rA, const Vec3W<F>& cB, const QuatW<F>& q, const Vec3W<F>& h,
                           const F& margin) {
    const F zero(0.0f), one(1.0f);
    const Vec3W<F> p = simd::rotateInverse(q, cA - cB);  // sphere centre in the box frame
    const Vec3W<F> clamped = simd::min(simd::max(p, -h), h);
    const Vec3W<F> diff = clamped - p;
    const F d2 = simd::dot(diff, diff);
    const auto outside = d2 > F(kMinDistanceSq);
    const F dist = simd::sqrt(d2);
    const Vec3W<F> nOutside = diff / simd::select(outside, dist, one);

    // Inside (or on the surface): the face of least penetration.
    const Vec3W<F> slack = h - simd::abs(p);
    const auto pickX = simd::andMask(slack.x <= slack.y, slack.x <= slack.z);
    const auto pickY = simd::andMask(simd::notMask(pickX), slack.y <= slack.z);
    const auto pickZ = simd::notMask(simd::orMask(pickX, pickY));
    const F minSlack = simd::select(pickX, slack.x, simd::select(pickY, slack.y, slack.z));
    const F sx = simd::select(p.x < zero, -one, one), sy = simd::select(p.y < zero, -one, one),
            sz = simd::select(p.z < zero, -one, one);
    // Normal A->B points into the box: against the outward normal of the face the centre leaves through.
    const Vec3W<F> nInside{simd::select(pickX, -sx, zero), simd::select(pickY, -sy, zero),
                           simd::select(pickZ, -sz, zero)};
    const Vec3W<F> onFace{simd::select(pickX, sx * h.x, p.x), simd::select(pickY, sy * h.y, p.y),
                          simd::select(pickZ, sz * h.z, p.z)};

    const Vec3W<F> localPoint = simd::select(outside, clamped, onFace);
    Contact<F> c;
    c.normal = simd::rotate(q, simd::select(outside, nOutside, nInside));
    c.p0 = simd::rotate(q, localPoint) + cB;
    c.depth0 = simd::select(outside, rA - dist, rA + minSlack);
    c.feature0 = boxFeature(localPoint, h);
    finishOnePoint(c, margin);
    return c;
}

// ---- SoA drivers ------------------------------------------------------------------------------------------------

template <class F>
void storeContact(const Contact<F>& c, const PairContacts& out, std::size_t i, bool second) {
    c.normal.store(out.nx, out.ny, out.nz, i);
    c.p0.store(out.px, out.py, out.pz, i);
    simd::store(out.depth + i, c.depth0);
    simd::store(reinterpret_cast<std::int32_t*>(out.feature) + i, c.feature0);
    simd::store(out.count + i, c.count);
    if (second) {
        c.p1.store(out.qx, out.qy, out.qz, i);
        simd::store(out.depth1 + i, c.depth1);
        simd::store(reinterpret_cast<std::int32_t*>(out.feature1) + i, c.feature1);
    }
}

/// Lanes [i, i + lanesOf<F>) of the batch's own margins, or the uniform one.
template <class F>
F marginAt(const float* margins, std::size_t i, float margin) {
    return margins != nullptr ? simd::load<F>(margins + i) : F(margin);
}

template <class F>
void spheresAt(const SpherePairs& in, std::size_t i, float margin, const PairContacts& out) {
    const auto c = spheresKernel(Vec3W<F>::load(in.ax, in.ay, in.az, i), simd::load<F>(in.ar + i),
                                 Vec3W<F>::load(in.bx, in.by, in.bz, i), simd::load<F>(in.br + i),
                                 marginAt<F>(in.margin, i, margin));
    storeContact(c, out, i, false);
}

template <class F>
void sphereCapsulesAt(const SphereCapsulePairs& in, std::size_t i, float margin, const PairContacts& out) {
    const auto c = sphereCapsuleKernel(Vec3W<F>::load(in.ax, in.ay, in.az, i), simd::load<F>(in.ar + i),
                                       Vec3W<F>::load(in.bx, in.by, in.bz, i), Vec3W<F>::load(in.hx, in.hy, in.hz, i),
                                       simd::load<F>(in.br + i), marginAt<F>(in.margin, i, margin));
    storeContact(c, out, i, false);
}

template <class F>
void capsulesAt(const CapsulePairs& in, std::size_t i, float margin, const PairContacts& out) {
    const auto c = capsulesKernel(Vec3W<F>::load(in.ax, in.ay, in.az, i), Vec3W<F>::load(in.ahx, in.ahy, in.ahz, i),
                                  simd::load<F>(in.ar + i), Vec3W<F>::load(in.bx, in.by, in.bz, i),
                                  Vec3W<F>::load(in.bhx, in.bhy, in.bhz, i), simd::load<F>(in.br + i),
                                  marginAt<F>(in.margin, i, margin));
    storeContact(c, out, i, true);
}

template <class F>
void sphereBoxesAt(const SphereBoxPairs& in, std::size_t i, float margin, const PairContacts& out) {
    const auto c =
        sphereBoxKernel(Vec3W<F>::load(in.ax, in.ay, in.az, i), simd::load<F>(in.ar + i),
                        Vec3W<F>::load(in.bx, in.by, in.bz, i), QuatW<F>::load(in.qx, in.qy, in.qz, in.qw, i),
                        Vec3W<F>::load(in.ex, in.ey, in.ez, i), marginAt<F>(in.margin, i, margin));
    storeContact(c, out, i, false);
}

/// Full batches in SIMD lanes from 0, then a scalar tail; or everything scalar. Flattened: the optimize pragma above
/// makes GCC's inliner give up on the kernels' helpers, and a wide kernel left as calls passes every Vec3W through
/// the stack (sphere-sphere ran at half speed that way); both forms get the whole kernel inlined into their loop.
template <auto wideAt, auto scalarAt, class Pairs>
RUBBLE_FLATTEN void run(const Pairs& in, std::size_t n, float margin, const PairContacts& out, bool wide) {
    std::size_t i = 0;
    if (wide)
        for (const std::size_t end = simd::roundDownToLanes<FloatW>(n); i < end; i += simd::kLanes)
            wideAt(in, i, margin, out);
    for (; i < n; ++i) scalarAt(in, i, margin, out);
}

Vec3W<float> wide1(Vec3 v) { return {v.x, v.y, v.z}; }
Vec3 narrow(const Vec3W<float>& v) { return {v.x, v.y, v.z}; }

int toManifold(const Contact<float>& c, Manifold& out) {
    out.normal = narrow(c.normal);
    out.pointCount = c.count;
    if (c.count > 0) out.points[0] = {narrow(c.p0), c.depth0, static_cast<std::uint32_t>(c.feature0)};
    if (c.count > 1) out.points[1] = {narrow(c.p1), c.depth1, static_cast<std::uint32_t>(c.feature1)};
    return c.count;
}

}  // namespace

CapsuleSegment capsuleSegmentOf(const Transform& pose, float halfHeight, float radius) {
    return {pose.position, rotate(pose.rotation, Vec3{0.0f, halfHeight, 0.0f}), radius};
}

int collideSpheres(Vec3 centerA, float radiusA, Vec3 centerB, float radiusB, float margin, Manifold& out) {
    return toManifold(spheresKernel<float>(wide1(centerA), radiusA, wide1(centerB), radiusB, margin), out);
}

int collideSphereCapsule(Vec3 centerA, float radiusA, const CapsuleSegment& b, float margin, Manifold& out) {
    return toManifold(
        sphereCapsuleKernel<float>(wide1(centerA), radiusA, wide1(b.center), wide1(b.halfAxis), b.radius, margin), out);
}

int collideCapsules(const CapsuleSegment& a, const CapsuleSegment& b, float margin, Manifold& out) {
    return toManifold(capsulesKernel<float>(wide1(a.center), wide1(a.halfAxis), a.radius, wide1(b.center),
                                            wide1(b.halfAxis), b.radius, margin),
                      out);
}

int collideSphereBox(Vec3 centerA, float radiusA, const Transform& boxPose, Vec3 halfExtents, float margin,
                     Manifold& out) {
    const Quat& q = boxPose.rotation;
    return toManifold(sphereBoxKernel<float>(wide1(centerA), radiusA, wide1(boxPose.position),
                                             QuatW<float>(q.x, q.y, q.z, q.w), wide1(halfExtents), margin),
                      out);
}

void collideSpheresBatch(const SpherePairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<spheresAt<FloatW>, spheresAt<float>>(in, n, margin, out, true);
}
void collideSphereCapsulesBatch(const SphereCapsulePairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<sphereCapsulesAt<FloatW>, sphereCapsulesAt<float>>(in, n, margin, out, true);
}
void collideCapsulesBatch(const CapsulePairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<capsulesAt<FloatW>, capsulesAt<float>>(in, n, margin, out, true);
}
void collideSphereBoxesBatch(const SphereBoxPairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<sphereBoxesAt<FloatW>, sphereBoxesAt<float>>(in, n, margin, out, true);
}

void collideSpheresBatchScalar(const SpherePairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<spheresAt<FloatW>, spheresAt<float>>(in, n, margin, out, false);
}
void collideSphereCapsulesBatchScalar(const SphereCapsulePairs& in, std::size_t n, float margin,
                                      const PairContacts& out) {
    run<sphereCapsulesAt<FloatW>, sphereCapsulesAt<float>>(in, n, margin, out, false);
}
void collideCapsulesBatchScalar(const CapsulePairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<capsulesAt<FloatW>, capsulesAt<float>>(in, n, margin, out, false);
}
void collideSphereBoxesBatchScalar(const SphereBoxPairs& in, std::size_t n, float margin, const PairContacts& out) {
    run<sphereBoxesAt<FloatW>, sphereBoxesAt<float>>(in, n, margin, out, false);
}

}  // namespace rubble::detail
