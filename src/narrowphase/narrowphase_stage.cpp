#include "narrowphase/narrowphase_stage.h"

#include <algorithm>

#include "core/parallel.h"
#include "narrowphase/batched_pairs.h"
#include "narrowphase/pair_kernels.h"
#include "narrowphase/speculative_margin.h"
#include "narrowphase/triangle_runs.h"

namespace rubble::detail {
namespace {

/// Candidates per parallel task: enough work to amortise a task, small enough for two threads to balance.
constexpr std::size_t kChunk = 256;
/// Chunks per task when their results are copied to the output.
constexpr std::size_t kMergeChunks = 8;

}  // namespace

struct NarrowPhaseStage::Scratch {
    BatchScratch batch;
    TriangleScratch triangles;
};

NarrowPhaseStage::NarrowPhaseStage() = default;
NarrowPhaseStage::~NarrowPhaseStage() = default;

void NarrowPhaseStage::run(const CandidatePairs& candidates, const BodyStorage& storage,
                           const std::vector<Shape>& shapes, const NarrowPhaseParams& params, TaskPool& pool,
                           Contacts& out) {
    tables_.prepare(shapes);
    hulls_.prepare(shapes);
    rows_.write(storage.moving, candidates, pool);
    while (scratch_.size() < static_cast<std::size_t>(pool.threadCount()))
        scratch_.push_back(std::make_unique<Scratch>());

    // One index space over the candidates in canonical order: moving pairs, moving-static pairs, then every
    // triangle the broad phase handed over (so a body on a mesh spreads over chunks like any other work).
    const std::size_t units = candidates.moving.size() + candidates.statics.size() + candidates.meshTriangles.size();
    const std::size_t chunkCount = TaskPool::chunkCount(units, kChunk);
    if (chunks_.size() < chunkCount) chunks_.resize(chunkCount);
    const bool reuse = params.reuseDistance > 0;
    if (reuse)
        reuse_.begin(chunkCount, storage.layoutChanges());
    else
        reuse_.clear();

    pool.forChunks(units, kChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int worker) {
        NarrowChunk& chunk = chunks_[c];
        ManifoldReuse::ChunkCache* cache = reuse ? &reuse_.current(c) : nullptr;
        buildJobs(chunk, begin, end, candidates, storage, shapes, params, cache);
        runChunk(chunk, *scratch_[static_cast<std::size_t>(worker)], storage, shapes, candidates.meshTriangles, params,
                 cache);
        if (cache) keepComputed(chunk, *cache, storage, shapes);
    });

    // Each chunk's touching jobs go to the output at the offset its predecessors leave: canonical order on any
    // number of threads, one copy per manifold, and no output element constructed only to be overwritten.
    if (reuse) reuse_.finish();
    std::size_t total = 0;
    std::uint32_t points = 0;
    reusedManifolds_ = 0;
    for (std::size_t c = 0; c < chunkCount; ++c) {
        chunks_[c].offset = total;
        total += chunks_[c].touching;
        points += chunks_[c].points;
        reusedManifolds_ += chunks_[c].reused;
    }
    out.pairs.resize(total);
    out.manifolds.resize(total);
    out.pointCount = points;
    pool.forChunks(chunkCount, kMergeChunks, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t c = begin; c < end; ++c) {
            const NarrowChunk& chunk = chunks_[c];
            std::size_t o = chunk.offset;
            for (std::size_t j = 0; j < chunk.jobs.size() && chunk.jobs[j].triangles == 0; ++j) {
                if (chunk.manifolds[j].pointCount == 0) continue;
                out.pairs[o] = chunk.jobs[j].pair;
                out.manifolds[o] = chunk.manifolds[j];
                ++o;
            }
            for (std::size_t k = 0; k < chunk.meshPairs.size(); ++k, ++o) {
                out.pairs[o] = chunk.meshPairs[k];
                out.manifolds[o] = chunk.meshManifolds[k];
            }
        }
    });
}

void NarrowPhaseStage::runChunk(NarrowChunk& chunk, Scratch& scratch, const BodyStorage& storage,
                                const std::vector<Shape>& shapes, const std::vector<std::uint32_t>& meshTriangles,
                                const NarrowPhaseParams& params, const ManifoldReuse::ChunkCache* cache) const {
    const std::size_t n = chunk.jobs.size();
    if (chunk.manifolds.size() < n) chunk.manifolds.resize(n);
    chunk.meshPairs.clear();
    chunk.meshManifolds.clear();
    std::uint32_t reused = 0;
    for (auto& list : scratch.batch.jobs) list.clear();
    // Reused manifolds are moved with their bodies; pairs with a batched kernel are collected for it; every other
    // pair runs here, one at a time, with its own speculative margin, and so does each body's run of mesh triangles
    // (its poses and margin worked out once).
    MeshSide mesh;
    for (std::uint32_t j = 0; j < n; ++j) {
        PairJob& job = chunk.jobs[j];
        if (job.reuse != kNoReuse) {
            const ReusedManifolds& r = chunk.reuses[job.reuse];
            const ManifoldReuse::Stored* stored = cache->stored.data() + r.firstStored;
            reused += r.count;
            if (job.triangles == 0) {
                moveManifold(stored->manifold, r.a, r.b, stored->radiusA, stored->radiusB, chunk.manifolds[j]);
                continue;
            }
            for (std::uint32_t k = 0; k < r.count; ++k) {
                ContactPair pair = job.pair;
                pair.triangle = stored[k].triangle, pair.childA = stored[k].childA, pair.childB = stored[k].childB;
                chunk.meshPairs.push_back(pair);
                moveManifold(stored[k].manifold, r.a, r.b, stored[k].radiusA, stored[k].radiusB,
                             chunk.meshManifolds.emplace_back());
            }
            continue;
        }
        // A computed manifold anchors both bodies at its points (its slot may hold an older, recycled one).
        if (job.triangles == 0) chunk.manifolds[j].shiftA = Vec3{};
        const PairKernelRow& kernel = kernelRow(job.kernel);
        if (kernel.batched != BatchedKernel::Count) {
            scratch.batch.jobs[static_cast<int>(kernel.batched)].push_back(j);
            continue;
        }
        const ContactPair& p = job.pair;
        const float margin =
            speculativeMargin<float>(params.margin, params.dt, motionOf(storage, rows_, tables_, p, false),
                                     motionOf(storage, rows_, tables_, p, true));
        const Posed a = posedSide(storage, rows_, shapes, p, false);
        const Posed b = posedSide(storage, rows_, shapes, p, true);
        if (job.triangles == 0) {
            Manifold& out = chunk.manifolds[j];
            out.pointCount = 0;
            kernel.pair(a, b, margin, params.featureDrift, hulls_, job.hint, out);
            continue;
        }
        mesh.prepare(a, b);
        prefetchTriangles(chunk, j, meshTriangles, mesh);
        job.firstOutput = static_cast<std::uint32_t>(chunk.meshPairs.size());
        kernel.triangleRun({a, mesh, meshTriangles.data() + job.firstTriangle, job.triangles, margin, job.pair}, hulls_,
                           scratch.triangles, chunk);
        job.outputCount = static_cast<std::uint32_t>(chunk.meshPairs.size()) - job.firstOutput;
    }
    const BatchSources sources{storage, rows_, shapes, tables_, params.margin, params.dt};
    for (int kernel = 0; kernel < static_cast<int>(BatchedKernel::Count); ++kernel)
        if (!scratch.batch.jobs[kernel].empty())
            collideBatched(static_cast<BatchedKernel>(kernel), chunk, scratch.batch, sources);

    // Counted in locals: the compiler cannot keep the chunk's fields in registers across the loop.
    std::uint32_t touching = static_cast<std::uint32_t>(chunk.meshManifolds.size()), points = 0;
    for (std::size_t j = 0; j < n && chunk.jobs[j].triangles == 0; ++j) {
        const int count = chunk.manifolds[j].pointCount;
        touching += count > 0 ? 1u : 0u;
        points += static_cast<std::uint32_t>(count);
    }
    for (const Manifold& m : chunk.meshManifolds) points += static_cast<std::uint32_t>(m.pointCount);
    chunk.touching = touching;
    chunk.points = points;
    chunk.reused = reused;
}

void NarrowPhaseStage::keepComputed(NarrowChunk& chunk, ManifoldReuse::ChunkCache& cache, const BodyStorage& storage,
                                    const std::vector<Shape>& shapes) {
    auto keep = [&](const Manifold& m, const ContactPair& pair, bool swapped) {
        ManifoldReuse::Stored& s = cache.stored.emplace_back();
        s.manifold = m;
        s.radiusA = roundingOf(sideShape(storage, shapes, pair, false));
        s.radiusB = roundingOf(sideShape(storage, shapes, pair, true));
        s.triangle = pair.triangle, s.childA = pair.childA, s.childB = pair.childB, s.swapped = swapped;
    };
    for (const PendingEntry& p : chunk.pending) {
        ManifoldReuse::Entry& entry = cache.entries[p.entry];
        entry.firstStored = static_cast<std::uint32_t>(cache.stored.size());
        entry.hint = p.jobEnd - p.jobBegin == 1 ? chunk.jobs[p.jobBegin].hint : SatHint{};
        for (std::uint32_t j = p.jobBegin; j < p.jobEnd; ++j) {
            const PairJob& job = chunk.jobs[j];
            if (job.triangles == 0) {
                if (chunk.manifolds[j].pointCount > 0)
                    keep(chunk.manifolds[j], job.pair, job.pair.aStatic || job.pair.a != p.firstBody);
                continue;
            }
            for (std::uint32_t k = job.firstOutput; k < job.firstOutput + job.outputCount; ++k)
                keep(chunk.meshManifolds[k], chunk.meshPairs[k], false);
        }
        entry.storedCount = static_cast<std::uint32_t>(cache.stored.size()) - entry.firstStored;
    }
}

}  // namespace rubble::detail
