#pragma once
// The narrow-phase stage: candidate pairs from the broad phase become contact manifolds. The candidates are cut into
// fixed chunks that run in parallel; within a chunk the pairs are bucketed by shape-kind pair, and the buckets with a
// batched kernel (sphere-sphere, sphere-box, sphere-capsule, capsule-capsule, and box-box's axis tests and face
// clipping) run in SIMD lanes on pose data gathered lane-wide, the rest one pair at a time. Every pair gets its own
// speculative margin. A pair that has hardly moved since its manifolds were computed may get them again instead
// (manifold_reuse.h).
// The manifolds come out in the candidates' canonical order whatever the thread count.
//
// Here: the chunks, the order of the work and the output. Building a chunk's jobs and deciding on reuse:
// job_building.cpp; the kernels by pair kind: pair_kernels.h; their inputs: pair_sides.h and speculative_margin.h;
// the batched kernels' lanes: batched_pairs.h; the mesh triangle runs: triangle_runs.h.
#include <cstdint>
#include <memory>
#include <vector>

#include "broadphase/broadphase.h"
#include "contacts/contacts.h"
#include "narrowphase/hull_adjacencies.h"
#include "narrowphase/manifold.h"
#include "narrowphase/manifold_reuse.h"
#include "narrowphase/pair_jobs.h"
#include "narrowphase/pair_sides.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

/// What the stage needs besides the pairs.
struct NarrowPhaseParams {
    float margin = 0.02f;     ///< WorldSettings::contactMargin: points are reported this far apart even at rest
    float dt = 1.0f / 60.0f;  ///< the step the contacts must cover (see speculative margins below)
    /// WorldSettings::manifoldReuseDistance: a pair whose shapes moved less than this relative to each other since
    /// its manifolds were computed gets them again, moved with its bodies (narrowphase/manifold_reuse.h); 0: never.
    float reuseDistance = 0;
    /// WorldSettings::contactFeatureDrift: a touching pair of polytopes makes its contact from last step's feature
    /// while that feature's separation stays within this of what the search found (hull_pairs.h, SatHint); 0: never.
    float featureDrift = 0;
};

class NarrowPhaseStage {
public:
    /// Manifolds for every candidate pair within its speculative margin: points with depth >= -m, where for a pair
    /// of bodies A and B
    ///     m = margin + |vB - vA| dt + min(|wA| dt, 2) reachA + min(|wB| dt, 2) reachB
    /// bounds how far their surfaces can approach each other during the step (reach: rotationReach of the body's
    /// shape, shapes/shape_extents.h, which the broad phase's boxes are grown by as well; static bodies have no
    /// velocity). A resting pair keeps the plain margin; a fast approach gets its points before the bodies meet, so the
    /// solver can stop it in time.
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

private:
    struct Scratch;

    /// The jobs of candidates [begin, end) (of the one index space run() describes) into the chunk: manifolds to
    /// reuse, or pairs and triangle runs to compute, with their reuse entries pending (job_building.cpp).
    void buildJobs(NarrowChunk& chunk, std::size_t begin, std::size_t end, const CandidatePairs& candidates,
                   const BodyStorage& storage, const std::vector<Shape>& shapes, const NarrowPhaseParams& params,
                   ManifoldReuse::ChunkCache* cache);
    void runChunk(NarrowChunk& chunk, Scratch& scratch, const BodyStorage& storage, const std::vector<Shape>& shapes,
                  const std::vector<std::uint32_t>& meshTriangles, const NarrowPhaseParams& params,
                  const ManifoldReuse::ChunkCache* cache) const;
    /// The manifolds just computed for the chunk's pending entries go into their entries.
    static void keepComputed(NarrowChunk& chunk, ManifoldReuse::ChunkCache& cache, const BodyStorage& storage,
                             const std::vector<Shape>& shapes);

    std::vector<NarrowChunk> chunks_;
    ManifoldReuse reuse_;
    std::uint32_t reusedManifolds_ = 0;
    /// Per worker: the batched kernels' lists and lanes, the triangle runs' memory.
    std::vector<std::unique_ptr<Scratch>> scratch_;
    ShapeTables tables_;
    MovingRows rows_;
    HullAdjacencies hulls_;
};

}  // namespace rubble::detail
