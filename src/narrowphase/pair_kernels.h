#pragma once
// The narrow phase's dispatch: which kernel a pair of shape kinds goes to, and how that kernel runs: one pair at a
// time, over a body's run of mesh triangles, or in SIMD lanes over a batch of pairs. Two tables, read wherever a job
// is built or run: kinds to kernel here, kernel to its functions in pair_kernels.cpp.
#include <cassert>
#include <cstdint>

#include "shapes/shape.h"

namespace rubble::detail {

struct Posed;
struct Manifold;
struct TriangleRun;
struct TriangleScratch;
struct NarrowChunk;
struct SatHint;
class HullAdjacencies;

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

/// Kernels that run in SIMD lanes over a batch of pairs (batched_pairs.h).
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
}  // namespace pair_table

/// The kernel for two shape kinds given in ascending order. Every pair that can reach the narrow phase has one.
inline PairKernel pairKernel(ShapeKind lower, ShapeKind upper) {
    const PairKernel k = pair_table::kKernelOf[static_cast<int>(lower)][static_cast<int>(upper)];
    assert(k != PairKernel::Count);
    return k;
}

/// Shape A against shape B (A's kind the lower), within `margin`: fills `out` (pointCount 0 when apart). The
/// polytope kernels read and rewrite `hint` and may build a contact from its feature within `featureDrift`
/// (hull_pairs.h); the others leave both alone.
using PairFunction = void (*)(const Posed& a, const Posed& b, float margin, float featureDrift,
                              const HullAdjacencies& hulls, SatHint& hint, Manifold& out);
/// Body A against a run of mesh triangles (triangle_runs.h).
using TriangleRunFunction = void (*)(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                                     NarrowChunk& chunk);

/// How a kernel runs. A pair of convex shapes has a one-pair function; a triangle kernel has only its run function.
struct PairKernelRow {
    PairKernel kernel;
    PairFunction pair;                ///< one pair at a time, or null
    TriangleRunFunction triangleRun;  ///< a body against a run of triangles, or null
    /// The SIMD batch the stage runs the kernel's pairs in (instead of `pair`), or Count.
    BatchedKernel batched;
};

/// One row per PairKernel, in its order (pair_kernels.cpp).
extern const PairKernelRow kPairKernelRows[static_cast<int>(PairKernel::Count)];

inline const PairKernelRow& kernelRow(PairKernel kernel) { return kPairKernelRows[static_cast<int>(kernel)]; }

/// Whether a pair's contacts are recycled (manifold_reuse.h): all but those between spheres and capsules. Their SIMD
/// kernels cost less than the lookup and the copies (S4's narrow phase took 0.94 ms instead of 0.60 with them), and
/// their one point on the line between the cores is what recycling would keep anyway, give or take the turn.
inline bool recycled(ShapeKind first, ShapeKind second) {
    const auto round = [](ShapeKind k) { return k == ShapeKind::Sphere || k == ShapeKind::Capsule; };
    return !(round(first) && round(second));
}

}  // namespace rubble::detail
