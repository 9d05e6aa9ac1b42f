#pragma once
// Closed-form contact kernels for the round shapes and for sphere-box: sphere-sphere, sphere-capsule,
// capsule-capsule and sphere-box. Each exists as
//  - a per-pair function that fills a Manifold (normal A->B, points on B's surface, depth > 0 penetrating,
//    depth <= 0 speculative within `margin`, stable feature ids), and
//  - a batched function over SoA pair arrays, run in SIMD lanes with a scalar tail, plus its *Scalar twin
//    (the same kernel instantiated for float) that tests and benchmarks compare against.
// Both forms run one kernel template (convex_pairs.cpp), so they agree bit for bit.
//
// Pair order follows ShapeKind order (Sphere < Box < Capsule): A is the sphere in sphere-box and sphere-capsule.
#include <cstddef>
#include <cstdint>

#include "narrowphase/manifold.h"
#include "rubble/math.h"

namespace rubble::detail {

/// A capsule in world space: the segment centre -/+ halfAxis swept by radius. For a capsule shape of half height
/// h posed by T: center = T.position, halfAxis = rotate(T.rotation, (0, h, 0)).
struct CapsuleSegment {
    Vec3 center;
    Vec3 halfAxis;
    float radius = 0;
};

CapsuleSegment capsuleSegmentOf(const Transform& pose, float halfHeight, float radius);

// ---- Feature ids ------------------------------------------------------------------------------------------------
// Sphere-sphere: 0. Sphere-capsule: the capsule segment feature (0 interior, 1 end at center - halfAxis, 2 end at
// center + halfAxis). Capsule-capsule, one point: segA * 4 + segB with the same segment codes; parallel pair, two
// points: 16 + (0 when the end of the overlap comes from A's segment, 1 from B's) for the low end, 32 + ... for the
// high end. Sphere-box: the box feature under the contact point, sum over axes i of code_i * 3^i with code 0 strictly
// between the faces, 1 on the -h face, 2 on the +h face (so faces, edges and vertices each get their own id).

/// Sphere A against sphere B. Coincident centres give the normal +y. Returns the point count (0 or 1).
int collideSpheres(Vec3 centerA, float radiusA, Vec3 centerB, float radiusB, float margin, Manifold& out);

/// Sphere A against capsule B. A centre on the capsule's axis takes the normal +y.
int collideSphereCapsule(Vec3 centerA, float radiusA, const CapsuleSegment& b, float margin, Manifold& out);

/// Capsule A against capsule B (Ericson 5.1.9 closest points). Nearly parallel segments (sine of the angle below
/// kCapsuleParallelSine) whose projections overlap give two points at the ends of the overlap, so a capsule
/// lying along another does not rock. Returns 0, 1 or 2.
int collideCapsules(const CapsuleSegment& a, const CapsuleSegment& b, float margin, Manifold& out);

/// Sphere A against box B (half extents, posed by boxPose). Centre outside: closest point on the box. Centre
/// inside or on the surface: pushed out through the face of least penetration (ties go to x, then y, then z, and
/// to the + face when the centre is on the mid-plane).
int collideSphereBox(Vec3 centerA, float radiusA, const Transform& boxPose, Vec3 halfExtents, float margin,
                     Manifold& out);

inline constexpr float kCapsuleParallelSine = 0.01f;

// ---- Batched SoA forms ------------------------------------------------------------------------------------------

// Every batch may carry its own margin per pair (`margin`, n entries; the stage's speculative margins); when it is
// null the kernels use the `margin` argument for every pair.

/// Sphere-sphere pairs: A centres and radii, B centres and radii (n entries each).
struct SpherePairs {
    const float *ax, *ay, *az, *ar;
    const float *bx, *by, *bz, *br;
    const float* margin = nullptr;
};

/// Sphere A against capsule B.
struct SphereCapsulePairs {
    const float *ax, *ay, *az, *ar;
    const float *bx, *by, *bz;  ///< capsule centre
    const float *hx, *hy, *hz;  ///< capsule half axis (world)
    const float* br;
    const float* margin = nullptr;
};

/// Capsule A against capsule B.
struct CapsulePairs {
    const float *ax, *ay, *az, *ahx, *ahy, *ahz, *ar;
    const float *bx, *by, *bz, *bhx, *bhy, *bhz, *br;
    const float* margin = nullptr;
};

/// Sphere A against box B (centre, unit quaternion, half extents).
struct SphereBoxPairs {
    const float *ax, *ay, *az, *ar;
    const float *bx, *by, *bz;
    const float *qx, *qy, *qz, *qw;
    const float *ex, *ey, *ez;
    const float* margin = nullptr;
};

/// Per-pair results: normal, point 0 (and point 1 for capsule pairs; others leave those arrays untouched, they may
/// be null), depth and feature per point, and the number of points within the margin (0, 1, 2). When only the
/// second of two points is within the margin it is moved to slot 0.
struct PairContacts {
    float *nx, *ny, *nz;
    float *px, *py, *pz, *depth;
    std::uint32_t* feature;
    std::int32_t* count;
    float *qx = nullptr, *qy = nullptr, *qz = nullptr, *depth1 = nullptr;
    std::uint32_t* feature1 = nullptr;
};

/// Pairs [0, n): full SIMD batches, then a scalar tail.
void collideSpheresBatch(const SpherePairs& in, std::size_t n, float margin, const PairContacts& out);
void collideSphereCapsulesBatch(const SphereCapsulePairs& in, std::size_t n, float margin, const PairContacts& out);
void collideCapsulesBatch(const CapsulePairs& in, std::size_t n, float margin, const PairContacts& out);
void collideSphereBoxesBatch(const SphereBoxPairs& in, std::size_t n, float margin, const PairContacts& out);

/// The same kernels, one pair at a time (the scalar reference).
void collideSpheresBatchScalar(const SpherePairs& in, std::size_t n, float margin, const PairContacts& out);
void collideSphereCapsulesBatchScalar(const SphereCapsulePairs& in, std::size_t n, float margin,
                                      const PairContacts& out);
void collideCapsulesBatchScalar(const CapsulePairs& in, std::size_t n, float margin, const PairContacts& out);
void collideSphereBoxesBatchScalar(const SphereBoxPairs& in, std::size_t n, float margin, const PairContacts& out);

}  // namespace rubble::detail
