#pragma once
// The narrow-phase stage: candidate pairs from the broad phase become contact manifolds. Pairs are bucketed by
// shape-kind pair; each bucket runs one kernel over its pairs in parallel chunks (sphere-sphere in SIMD lanes),
// and the manifolds come out in the candidates' canonical order whatever the thread count.
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "body_storage.h"
#include "broadphase/broadphase.h"
#include "narrowphase/manifold.h"
#include "shapes/shape.h"

namespace rubble::detail {

class TaskPool;
struct HullAdjacency;

inline constexpr std::uint16_t kNoChild = 0xFFFF;

/// The two bodies of a manifold, in the order the kernel saw them: A has the lower ShapeKind, so the normal
/// points from A to B. Each side is a dense index into MovingBodies, or into StaticBodies when flagged static;
/// for a compound, `childA` / `childB` name the child whose shape made the contact.
struct ContactPair {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    bool aStatic = false;
    bool bStatic = false;
    /// For a body against a static mesh or heightfield (B): the triangle; ~0u otherwise.
    std::uint32_t triangle = ~0u;
    std::uint16_t childA = kNoChild;
    std::uint16_t childB = kNoChild;
};

/// The stage's output: one manifold (with at least one point) per touching or nearly touching pair.
struct Contacts {
    std::vector<ContactPair> pairs;
    std::vector<Manifold> manifolds;
    std::uint32_t pointCount = 0;
    /// Candidate pairs (or compound child pairs) whose shape kinds have no kernel yet (hull-triangle). They are
    /// counted here and shown by the runner, never silently treated as apart.
    std::uint32_t unsupportedPairs = 0;

    void clear() {
        pairs.clear();
        manifolds.clear();
        pointCount = 0;
        unsupportedPairs = 0;
    }
};

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
    Unsupported,
    Count
};

/// The kernel for two shape kinds given in ascending order.
PairKernel pairKernel(ShapeKind lower, ShapeKind upper);

class NarrowPhaseStage {
public:
    /// Manifolds for every candidate pair within `margin` (speculative points included).
    void run(const CandidatePairs& candidates, const BodyStorage& storage, const std::vector<Shape>& shapes,
             float margin, TaskPool& pool, Contacts& out);

    NarrowPhaseStage();
    ~NarrowPhaseStage();

private:
    struct Job {
        ContactPair pair;
        PairKernel kernel = PairKernel::Unsupported;
    };
    std::vector<Job> jobs_;
    /// Edge-face adjacency of every hull met so far (Gauss-map pruning needs it), built before the parallel work.
    /// Each entry keeps its hull alive, so a hull's address cannot be reused by another while it is a key.
    struct HullEntry {
        std::shared_ptr<const ConvexHull> hull;
        std::unique_ptr<HullAdjacency> adjacency;
    };
    std::unordered_map<const ConvexHull*, HullEntry> hullAdjacency_;
    std::vector<Manifold> perJob_;
    std::vector<std::uint32_t> bucket_[static_cast<int>(PairKernel::Count)];
    // SoA scratch for the batched sphere-sphere kernel.
    std::vector<float> sphereIn_[8], sphereOut_[7];
    std::vector<std::uint32_t> sphereFeature_;
    std::vector<std::int32_t> sphereCount_;
};

}  // namespace rubble::detail
