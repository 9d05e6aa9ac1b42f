#pragma once
// The narrow-phase stage: candidate pairs from the broad phase become contact manifolds. The candidates are cut into
// fixed chunks that run in parallel; within a chunk the pairs are bucketed by shape-kind pair, and the buckets with a
// batched kernel (sphere-sphere, sphere-box, sphere-capsule, capsule-capsule, and box-box's axis tests and face
// clipping) run in SIMD lanes on pose data gathered lane-wide, the rest one pair at a time. Every pair gets its own
// speculative margin. A pair that has hardly moved since its manifolds were computed may get them again instead
// (manifold_reuse.h).
// The manifolds come out in the candidates' canonical order whatever the thread count.
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "broadphase/broadphase.h"
#include "contacts/contacts.h"
#include "narrowphase/manifold.h"
#include "narrowphase/manifold_reuse.h"
#include "narrowphase/pair_kernels.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;
struct HullAdjacency;

/// Per shape slot, what job building and the batched kernels read (SoA, for SIMD gathers); refreshed every run.
struct ShapeTables {
    std::vector<ShapeKind> kind;
    /// Box: half extents; sphere: (radius, 0, 0); capsule: (radius, half height, 0).
    std::vector<float> sizeX, sizeY, sizeZ;
    std::vector<float> reach;  ///< rotationReach (src/bounds/bounds.h)
};

/// Each moving body's pose and motion as two rows of eight floats (simd/transpose.h), copied from the SoA storage at
/// the start of every run. A pair reads two cache lines per body instead of one per field, and a SIMD batch of
/// pairs takes each side in two row transposes instead of sixteen gathers.
struct MovingRows {
    /// Per body: centre of mass x y z, orientation x y z w, local centre of mass x (the shape origin is the centre of
    /// mass less the rotated local centre).
    AlignedVector<float> pose;
    /// Per body: linear velocity x y z, angular velocity x y z, local centre of mass y z.
    AlignedVector<float> motion;
};

/// What the stage needs besides the pairs.
struct NarrowPhaseParams {
    float margin = 0.02f;     ///< WorldSettings::contactMargin: points are reported this far apart even at rest
    float dt = 1.0f / 60.0f;  ///< the step the contacts must cover (see speculative margins below)
    /// WorldSettings::manifoldReuseDistance: a pair whose shapes moved less than this relative to each other since
    /// its manifolds were computed gets them again, moved with its bodies (narrowphase/manifold_reuse.h); 0: never.
    float reuseDistance = 0;
};

class NarrowPhaseStage {
public:
    /// Manifolds for every candidate pair within its speculative margin: points with depth >= -m, where for a pair
    /// of bodies A and B
    ///     m = margin + |vB - vA| dt + min(|wA| dt, 2) reachA + min(|wB| dt, 2) reachB
    /// bounds how far their surfaces can approach each other during the step (reach: rotationReach of the body's
    /// shape, src/bounds/bounds.h, which the broad phase's boxes are grown by as well; static bodies have no velocity).
    /// A resting pair keeps the plain margin; a fast approach gets its points before the bodies meet, so the solver can
    /// stop it in time.
    void run(const CandidatePairs& candidates, const BodyStorage& storage, const std::vector<Shape>& shapes,
             const NarrowPhaseParams& params, TaskPool& pool, Contacts& out);
    /// The same with dt = 0: every pair gets the fixed margin (for callers that place bodies by hand).
    void run(const CandidatePairs& candidates, const BodyStorage& storage, const std::vector<Shape>& shapes,
             float margin, TaskPool& pool, Contacts& out) {
        run(candidates, storage, shapes, NarrowPhaseParams{margin, 0.0f}, pool, out);
    }
    /// Manifolds of the last run that were reused rather than computed.
    std::uint32_t reusedManifolds() const { return reusedManifolds_; }

    NarrowPhaseStage();
    ~NarrowPhaseStage();
    NarrowPhaseStage(const NarrowPhaseStage&) = delete;
    NarrowPhaseStage& operator=(const NarrowPhaseStage&) = delete;

    static constexpr std::uint32_t kNoReuse = ~0u;
    struct Job {
        ContactPair pair;
        PairKernel kernel = PairKernel::Count;  // always set when the job is made
        /// A body against a mesh: the job stands for the triangles CandidatePairs::meshTriangles[firstTriangle,
        /// firstTriangle + triangles) (pair.triangle is the first). 0 triangles: a pair of bodies.
        std::uint32_t firstTriangle = 0, triangles = 0;
        /// A reused manifold (of a pair of bodies), or a body's reused manifolds against a mesh (`triangles` of them):
        /// index in Chunk::reuses. kNoReuse: computed.
        std::uint32_t reuse = kNoReuse;
        /// A run of triangles: where its touching triangles went in Chunk::meshPairs.
        std::uint32_t firstOutput = 0, outputCount = 0;
    };
    /// Manifolds of the chunk's reuse cache to move with their bodies: the motions of the manifolds' A and B since.
    struct Reuse {
        PoseChange a, b;
        std::uint32_t firstStored = 0, count = 0;
    };
    /// A candidate computed this step whose manifolds go into its reuse entry: its jobs.
    struct PendingEntry {
        std::uint32_t entry = 0, firstBody = 0, jobBegin = 0, jobEnd = 0;
    };
    /// One parallel chunk of the candidates (fixed boundaries, in canonical order), kept from step to step so that a
    /// step allocates nothing once sizes settle. Its jobs are the pairs of bodies, then the runs of triangles (the
    /// candidates' order); the pairs of bodies get one manifold per job, the triangles only their touching ones.
    struct Chunk {
        std::vector<Job> jobs;
        std::vector<Manifold> manifolds;     ///< per job that is a pair of bodies (slots of triangle jobs unused)
        std::vector<ContactPair> meshPairs;  ///< the touching triangles of the runs, in order
        std::vector<Manifold> meshManifolds;
        std::vector<Reuse> reuses;
        std::vector<PendingEntry> pending;
        std::uint32_t touching = 0;  ///< manifolds with at least one point
        std::uint32_t points = 0;
        std::uint32_t reused = 0;  ///< manifolds moved rather than computed
        std::size_t offset = 0;    ///< where its touching manifolds go in the output
    };
    struct Scratch;

private:
    void prepareShapes(const std::vector<Shape>& shapes);
    void prepareRows(const MovingBodies& bodies, TaskPool& pool);
    void runChunk(Chunk& chunk, Scratch& scratch, const BodyStorage& storage, const std::vector<Shape>& shapes,
                  const std::vector<std::uint32_t>& meshTriangles, const NarrowPhaseParams& params,
                  const ManifoldReuse::ChunkCache* cache) const;
    /// The manifolds just computed for the chunk's pending entries go into their entries.
    static void keepComputed(Chunk& chunk, ManifoldReuse::ChunkCache& cache, const BodyStorage& storage,
                             const std::vector<Shape>& shapes);

    std::vector<Chunk> chunks_;
    ManifoldReuse reuse_;
    std::uint32_t reusedManifolds_ = 0;
    /// Per worker: index lists and SoA lanes of the batched kernels.
    std::vector<std::unique_ptr<Scratch>> scratch_;
    ShapeTables tables_;
    MovingRows rows_;
    /// Per shape slot: the hull whose adjacency is known to be in hullAdjacency_ (a cheap check per step).
    std::vector<const ConvexHull*> knownHull_;
    /// Edge-face adjacency of every hull met so far (Gauss-map pruning needs it), built before the parallel work.
    /// Each entry keeps its hull alive, so a hull's address cannot be reused by another while it is a key.
    struct HullEntry {
        std::shared_ptr<const ConvexHull> hull;
        std::unique_ptr<HullAdjacency> adjacency;
    };
    std::unordered_map<const ConvexHull*, HullEntry> hullAdjacency_;
};

}  // namespace rubble::detail
