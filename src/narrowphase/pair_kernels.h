#pragma once
// The narrow phase's dispatch: which kernel a pair of shape kinds goes to, and how that kernel runs (in SIMD lanes
// over a batch of pairs, one pair at a time, or over a run of mesh triangles). One table, read wherever a job is
// built or run (narrowphase_stage.cpp).
#include <cassert>
#include <cstdint>

#include "shapes/shape.h"

namespace rubble::detail {

inline constexpr int kShapeKindCount = static_cast<int>(ShapeKind::Heightfield) + 1;

/// Shape-pair kinds that have a kernel. The lower ShapeKind comes first.
enum class PairKernel : std::uint8_t {
    SphereSphere,
    SphereBox,
    SphereCapsule,
    BoxBox,
    CapsuleCapsule,
    SphereHull,
    BoxCapsule,
    BoxHull,
    CapsuleHull,
    HullHull,
    SphereTriangle,
    CapsuleTriangle,
    BoxTriangle,
    HullTriangle,
    Count
};

/// Kernels that run in SIMD lanes over a batch of pairs (narrowphase_stage.cpp, collideBatched).
enum class BatchedKernel : std::uint8_t { SphereSphere, SphereBox, SphereCapsule, CapsuleCapsule, BoxBox, Count };

namespace pair_table {
using K = PairKernel;
/// [lower kind][upper kind]. Only a sphere, box, capsule or hull is ever the lower side (compounds are split into
/// their children, meshes and heightfields are static-only and always the upper side); Count marks what never meets.
inline constexpr PairKernel kKernelOf[kShapeKindCount][kShapeKindCount] = {
    //  Sphere         Box           Capsule            ConvexHull      Compound  TriangleMesh        Heightfield
    {K::SphereSphere, K::SphereBox, K::SphereCapsule, K::SphereHull, K::Count, K::SphereTriangle, K::SphereTriangle},
    {K::Count, K::BoxBox, K::BoxCapsule, K::BoxHull, K::Count, K::BoxTriangle, K::BoxTriangle},
    {K::Count, K::Count, K::CapsuleCapsule, K::CapsuleHull, K::Count, K::CapsuleTriangle, K::CapsuleTriangle},
    {K::Count, K::Count, K::Count, K::HullHull, K::Count, K::HullTriangle, K::HullTriangle},
    {K::Count, K::Count, K::Count, K::Count, K::Count, K::Count, K::Count},
    {K::Count, K::Count, K::Count, K::Count, K::Count, K::Count, K::Count},
    {K::Count, K::Count, K::Count, K::Count, K::Count, K::Count, K::Count},
};

using B = BatchedKernel;
/// Per kernel: the SIMD batch it runs in, or Count for one pair (or one triangle run) at a time.
inline constexpr BatchedKernel kBatchedOf[static_cast<int>(PairKernel::Count)] = {
    B::SphereSphere, B::SphereBox, B::SphereCapsule, B::BoxBox, B::CapsuleCapsule, B::Count, B::Count,
    B::Count,        B::Count,     B::Count,         B::Count,  B::Count,          B::Count, B::Count,
};
}  // namespace pair_table

/// The kernel for two shape kinds given in ascending order. Every pair that can reach the narrow phase has one.
inline PairKernel pairKernel(ShapeKind lower, ShapeKind upper) {
    const PairKernel k = pair_table::kKernelOf[static_cast<int>(lower)][static_cast<int>(upper)];
    assert(k != PairKernel::Count);
    return k;
}

/// The SIMD batch a kernel runs in, or BatchedKernel::Count.
inline BatchedKernel batchedKernel(PairKernel kernel) { return pair_table::kBatchedOf[static_cast<int>(kernel)]; }

}  // namespace rubble::detail
