#include "narrowphase/pair_kernels.h"

#include "narrowphase/box_box.h"
#include "narrowphase/convex_pairs.h"
#include "narrowphase/hull_adjacencies.h"
#include "narrowphase/hull_pairs.h"
#include "narrowphase/pair_sides.h"
#include "narrowphase/triangle_runs.h"

namespace rubble::detail {
namespace {

// The one-pair kernels in one signature. The box-hull and hull-hull SAT keeps its hint (hull_pairs.h); the capsule
// and sphere kernels against hulls find their contact by GJK on the cores and take none.

void spheres(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies&, SatHint&, Manifold& out) {
    collideSpheres(a.pose.position, a.shape->radius, b.pose.position, b.shape->radius, margin, out);
}

void sphereBox(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies&, SatHint&, Manifold& out) {
    collideSphereBox(a.pose.position, a.shape->radius, b.pose, b.shape->halfExtents, margin, out);
}

void sphereCapsule(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies&, SatHint&,
                   Manifold& out) {
    collideSphereCapsule(a.pose.position, a.shape->radius, segmentOf(b), margin, out);
}

void boxes(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies&, SatHint&, Manifold& out) {
    collideBoxes(a.pose, a.shape->halfExtents, b.pose, b.shape->halfExtents, margin, out);
}

void capsules(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies&, SatHint&, Manifold& out) {
    collideCapsules(segmentOf(a), segmentOf(b), margin, out);
}

/// A sphere is a capsule whose segment has no length.
void sphereHull(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies& hulls, SatHint&,
                Manifold& out) {
    const ConvexHull& hull = *b.shape->hull;
    collideCapsuleHull({a.pose.position, {}, a.shape->radius}, hull, hulls.of(hull), b.pose, margin, out);
}

/// The capsule-box kernel sees the capsule as A; the table's order has the box first. Same contact seen from the
/// other body: the normal turns round and the points move across the overlap onto the capsule.
void boxCapsule(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies&, SatHint&, Manifold& out) {
    collideCapsuleBox(segmentOf(b), a.pose, a.shape->halfExtents, margin, out);
    for (int p = 0; p < out.pointCount; ++p) out.points[p].position += out.normal * out.points[p].depth;
    out.normal = -out.normal;
}

void boxHull(const Posed& a, const Posed& b, float margin, float featureDrift, const HullAdjacencies& hulls,
             SatHint& hint, Manifold& out) {
    const ConvexHull& hull = *b.shape->hull;
    collideBoxHull(a.pose, a.shape->halfExtents, hull, hulls.of(hull), b.pose, margin, out, &hint, featureDrift);
}

void capsuleHull(const Posed& a, const Posed& b, float margin, float, const HullAdjacencies& hulls, SatHint&,
                 Manifold& out) {
    const ConvexHull& hull = *b.shape->hull;
    collideCapsuleHull(segmentOf(a), hull, hulls.of(hull), b.pose, margin, out);
}

void hulls(const Posed& a, const Posed& b, float margin, float featureDrift, const HullAdjacencies& adjacency,
           SatHint& hint, Manifold& out) {
    const ConvexHull &hullA = *a.shape->hull, &hullB = *b.shape->hull;
    collideHulls(hullA, adjacency.of(hullA), a.pose, hullB, adjacency.of(hullB), b.pose, margin, out, &hint,
                 featureDrift);
}

using K = PairKernel;
using B = BatchedKernel;
constexpr TriangleRunFunction kNoRun = nullptr;
constexpr PairFunction kNoPair = nullptr;

}  // namespace

constexpr PairKernelRow kPairKernelRows[static_cast<int>(PairKernel::Count)] = {
    {K::SphereSphere, spheres, kNoRun, B::SphereSphere},
    {K::SphereBox, sphereBox, kNoRun, B::SphereBox},
    {K::SphereCapsule, sphereCapsule, kNoRun, B::SphereCapsule},
    {K::BoxBox, boxes, kNoRun, B::BoxBox},
    {K::CapsuleCapsule, capsules, kNoRun, B::CapsuleCapsule},
    {K::SphereHull, sphereHull, kNoRun, B::Count},
    {K::BoxCapsule, boxCapsule, kNoRun, B::Count},
    {K::BoxHull, boxHull, kNoRun, B::Count},
    {K::CapsuleHull, capsuleHull, kNoRun, B::Count},
    {K::HullHull, hulls, kNoRun, B::Count},
    {K::SphereTriangle, kNoPair, collideSphereTriangleRun, B::Count},
    {K::CapsuleTriangle, kNoPair, collideCapsuleTriangleRun, B::Count},
    {K::BoxTriangle, kNoPair, collideBoxTriangleRun, B::Count},
    {K::HullTriangle, kNoPair, collideHullTriangleRun, B::Count},
};

namespace {
constexpr bool rowsInOrder() {
    for (int k = 0; k < static_cast<int>(PairKernel::Count); ++k)
        if (static_cast<int>(kPairKernelRows[k].kernel) != k) return false;
    return true;
}
}  // namespace
static_assert(rowsInOrder(), "kPairKernelRows[k] is kernel k's row");

}  // namespace rubble::detail
