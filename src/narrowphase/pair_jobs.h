#pragma once
// The narrow phase's unit of work: a job is a pair of shapes for one kernel (a compound's child pairs are one job
// each) or a body's run of mesh triangles, computed or carried over from an earlier step. A chunk holds the jobs of
// a fixed slice of the candidates and what they produced.
#include <cstdint>
#include <vector>

#include "contacts/contacts.h"
#include "narrowphase/hull_pairs.h"
#include "narrowphase/manifold.h"
#include "narrowphase/manifold_reuse.h"
#include "narrowphase/pair_kernels.h"

namespace rubble::detail {

inline constexpr std::uint32_t kNoReuse = ~0u;

struct PairJob {
    ContactPair pair;
    PairKernel kernel = PairKernel::Count;  // always set when the job is made
    /// A body against a mesh: the job stands for the triangles CandidatePairs::meshTriangles[firstTriangle,
    /// firstTriangle + triangles) (pair.triangle is the first). 0 triangles: a pair of bodies.
    std::uint32_t firstTriangle = 0, triangles = 0;
    /// A reused manifold (of a pair of bodies), or a body's reused manifolds against a mesh (`triangles` of them):
    /// index in NarrowChunk::reuses. kNoReuse: computed.
    std::uint32_t reuse = kNoReuse;
    /// A run of triangles: where its touching triangles went in NarrowChunk::meshPairs.
    std::uint32_t firstOutput = 0, outputCount = 0;
    /// The polytope kernels' SAT hint: from the pair's reuse entry, and back into it (hull_pairs.h).
    SatHint hint;
};

/// Manifolds of the chunk's reuse cache to move with their bodies: the motions of the manifolds' A and B since.
struct ReusedManifolds {
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
struct NarrowChunk {
    std::vector<PairJob> jobs;
    std::vector<Manifold> manifolds;     ///< per job that is a pair of bodies (slots of triangle jobs unused)
    std::vector<ContactPair> meshPairs;  ///< the touching triangles of the runs, in order
    std::vector<Manifold> meshManifolds;
    std::vector<ReusedManifolds> reuses;
    std::vector<PendingEntry> pending;
    std::uint32_t touching = 0;  ///< manifolds with at least one point
    std::uint32_t points = 0;
    std::uint32_t reused = 0;  ///< manifolds moved rather than computed
    std::size_t offset = 0;    ///< where its touching manifolds go in the output
};

}  // namespace rubble::detail
