// A chunk's candidates into jobs: each candidate either gets its manifolds of an earlier step again (when its bodies
// have hardly moved and its pair is recycled: manifold_reuse.h) or becomes jobs to compute, one per pair of shapes (a
// compound's children are split) or one per body's run of mesh triangles, with its reuse entry pending until they are
// computed.
#if defined(__GNUC__) && !defined(__clang__)
// GCC 12's SLP vectoriser fuses the alternating a*b - c / a*b + c lanes of the quaternion product (poseChange) into
// vfmsubadd even under -ffp-contract=off: the reuse test would then round differently from one build level to
// another. (Before the includes, so every inline function in this file gets the same options.)
#pragma GCC optimize("no-tree-slp-vectorize")
#endif
#include <algorithm>

#include "narrowphase/narrowphase_stage.h"
#include "narrowphase/pair_kernels.h"
#include "narrowphase/speculative_margin.h"

namespace rubble::detail {
namespace {

class JobBuilder {
public:
    JobBuilder(NarrowChunk& chunk, const CandidatePairs& candidates, const BodyStorage& storage,
               const std::vector<Shape>& shapes, const ShapeTables& tables, const MovingRows& rows,
               const NarrowPhaseParams& params, ManifoldReuse& reuse, ManifoldReuse::ChunkCache* cache)
        : chunk_(chunk),
          candidates_(candidates),
          storage_(storage),
          shapes_(shapes),
          tables_(tables),
          rows_(rows),
          params_(params),
          reuse_(reuse),
          cache_(cache),
          finder_(reuse) {}

    /// A candidate: reused, or its jobs made and its reuse entry (if it gets one) pending. `run`: for a body against
    /// a mesh, the index of its first triangle in meshTriangles, and `runLength` the number of its triangles; else ~0u.
    void add(ManifoldReuse::Section section, std::uint32_t first, std::uint32_t second, bool secondStatic,
             std::uint32_t run = ~0u, std::uint32_t runLength = 0) {
        const std::size_t pendingBefore = chunk_.pending.size();
        lastHint_ = {};
        if (cache_ && reuseOrKeep(section, first, second, secondStatic)) return;
        addJobs(first, false, second, secondStatic, run, runLength);
        // Closes the pending entry reuseOrKeep opened for the candidate whose jobs were just made; a candidate of one
        // job takes the SAT hint its entry kept.
        if (chunk_.pending.size() > pendingBefore) {
            PendingEntry& pending = chunk_.pending.back();
            pending.jobEnd = static_cast<std::uint32_t>(chunk_.jobs.size());
            if (pending.jobEnd - pending.jobBegin == 1) chunk_.jobs[pending.jobBegin].hint = lastHint_;
        }
    }

private:
    /// A candidate: its manifolds again if its pair is recycled and its bodies have hardly moved (true: no jobs are
    /// made), else, for a recycled pair, an entry that takes this step's manifolds (pending until they are made).
    bool reuseOrKeep(ManifoldReuse::Section section, std::uint32_t first, std::uint32_t second, bool secondStatic) {
        const MovingBodies& m = storage_.moving;
        const StaticBodies& st = storage_.statics;
        const std::uint32_t shape1 = m.shape[first], shape2 = secondStatic ? st.shape[second] : m.shape[second];
        if (!recycled(tables_.kind[shape1], tables_.kind[shape2])) return false;
        // Written in place (a whole Entry built on the stack and copied in stalls on store forwarding).
        const auto entryIndex = static_cast<std::uint32_t>(cache_->entries.size());
        ManifoldReuse::Entry& now = cache_->entries.emplace_back();
        now.order = ManifoldReuse::orderOf(section, first,
                                           section == ManifoldReuse::Section::Moving ? second : st.slot[second]);
        now.shapeFirst = shape1, now.shapeSecond = shape2;
        // The bodies' slots and generations (the slot map is read at random): compared only when bodies were
        // added or removed since last step, else taken over with a reused entry.
        const auto identify = [&] {
            const std::uint32_t slot1 = m.slot[first], slot2 = secondStatic ? st.slot[second] : m.slot[second];
            now.slots = (std::uint64_t{slot1} << 32) | slot2;
            now.generations = (std::uint64_t{storage_.idAt(slot1).generation} << 32) | storage_.idAt(slot2).generation;
        };
        const bool sameBodies = reuse_.sameBodies();
        if (!sameBodies) identify();
        const auto movingPose = [&](std::uint32_t i) {
            const float* pose = rowOf(rows_.pose, i);
            return BodyPose{{pose[kComX], pose[kComY], pose[kComZ]},
                            {pose[kRotX], pose[kRotY], pose[kRotZ], pose[kRotW]}};
        };
        now.first = movingPose(first);
        if (secondStatic)
            now.second = {{st.px[second], st.py[second], st.pz[second]},
                          {st.qx[second], st.qy[second], st.qz[second], st.qw[second]}};
        else
            now.second = movingPose(second);
        const ContactPair asPair{first, second, false, secondStatic};
        now.margin =
            speculativeMargin<float>(params_.margin, params_.dt, motionOf(storage_, rows_, tables_, asPair, false),
                                     motionOf(storage_, rows_, tables_, asPair, true));
        const ManifoldReuse::Finder::Found found = finder_.find(now.order);
        if (found.entry != nullptr && found.entry->shapeFirst == shape1 && found.entry->shapeSecond == shape2 &&
            (sameBodies || (found.entry->slots == now.slots && found.entry->generations == now.generations))) {
            const ManifoldReuse::Entry& then = *found.entry;
            lastHint_ = then.hint;
            const PoseChange change1 = poseChange(then.first, now.first);
            const PoseChange change2 = poseChange(then.second, now.second);
            const float moved = relativeDisplacement(change1, change2, tables_.reach[shape1]);
            // Points the old margin left out were further apart than it, and can have closed by `moved`
            // since: the surfaces must not be able to close the rest in this step.
            if (moved <= params_.reuseDistance && now.margin - params_.margin + moved < then.margin &&
                turnedLittle(change1) && turnedLittle(change2)) {
                // Kept as computed then, under this step's order.
                const std::uint64_t order = now.order;
                const auto firstStored = static_cast<std::uint32_t>(cache_->stored.size());
                now = then;
                now.order = order;
                now.firstStored = firstStored;
                cache_->stored.insert(cache_->stored.end(), found.stored, found.stored + then.storedCount);
                const auto addReuse = [&](const ContactPair& pair, std::uint32_t triangles, bool swapped,
                                          std::uint32_t stored, std::uint32_t count) {
                    PairJob& job = chunk_.jobs.emplace_back();
                    job.pair = pair;
                    job.triangles = triangles;
                    job.reuse = static_cast<std::uint32_t>(chunk_.reuses.size());
                    ReusedManifolds& r = chunk_.reuses.emplace_back();
                    r.a = swapped ? change2 : change1;
                    r.b = swapped ? change1 : change2;
                    r.firstStored = stored, r.count = count;
                };
                if (then.storedCount == 0) return true;
                if (section == ManifoldReuse::Section::Mesh) {
                    const ManifoldReuse::Stored& s = *found.stored;
                    addReuse({first, second, false, true, s.triangle, s.childA, s.childB}, then.storedCount, false,
                             firstStored, then.storedCount);
                    return true;
                }
                for (std::uint32_t k = 0; k < then.storedCount; ++k) {
                    const ManifoldReuse::Stored& s = found.stored[k];
                    addReuse(s.swapped
                                 ? ContactPair{second, first, secondStatic, false, s.triangle, s.childA, s.childB}
                                 : ContactPair{first, second, false, secondStatic, s.triangle, s.childA, s.childB},
                             0, s.swapped, firstStored + k, 1);
                }
                return true;
            }
        }
        if (sameBodies) identify();
        const auto jobsNow = static_cast<std::uint32_t>(chunk_.jobs.size());
        chunk_.pending.push_back({entryIndex, first, jobsNow, jobsNow});
        return false;
    }

    /// A is the body whose shape kind is lower, so each kernel sees its shapes in its own argument order.
    /// Compounds expand into one job per child (per child pair for two compounds), in child order; a compound's child
    /// gets the whole run of triangles.
    void addJobs(std::uint32_t first, bool firstStatic, std::uint32_t second, bool secondStatic, std::uint32_t run,
                 std::uint32_t runLength) {
        const std::uint32_t triangle = run == ~0u ? ~0u : candidates_.meshTriangles[run];
        const std::uint32_t runStart = run == ~0u ? 0u : run;
        const std::uint32_t shape1 = firstStatic ? storage_.statics.shape[first] : storage_.moving.shape[first];
        const std::uint32_t shape2 = secondStatic ? storage_.statics.shape[second] : storage_.moving.shape[second];
        const ShapeKind kind1 = tables_.kind[shape1], kind2 = tables_.kind[shape2];
        const auto addJob = [&](ShapeKind k1, ShapeKind k2, std::uint16_t child1, std::uint16_t child2) {
            PairJob& job = chunk_.jobs.emplace_back();
            if (k2 < k1) {
                job.pair = {second, first, secondStatic, firstStatic, triangle, child2, child1};
                job.kernel = pairKernel(k2, k1);
            } else {
                job.pair = {first, second, firstStatic, secondStatic, triangle, child1, child2};
                job.kernel = pairKernel(k1, k2);
            }
            job.firstTriangle = runStart, job.triangles = runLength;
        };
        if (kind1 != ShapeKind::Compound && kind2 != ShapeKind::Compound) {
            addJob(kind1, kind2, kNoChild, kNoChild);
            return;
        }
        const Shape& s1 = shapes_[shape1];
        const Shape& s2 = shapes_[shape2];
        const bool compound1 = kind1 == ShapeKind::Compound, compound2 = kind2 == ShapeKind::Compound;
        const std::size_t n1 = compound1 ? s1.children.size() : 1, n2 = compound2 ? s2.children.size() : 1;
        for (std::size_t c1 = 0; c1 < n1; ++c1)
            for (std::size_t c2 = 0; c2 < n2; ++c2)
                addJob(compound1 ? s1.children[c1].shape->kind : kind1, compound2 ? s2.children[c2].shape->kind : kind2,
                       compound1 ? static_cast<std::uint16_t>(c1) : kNoChild,
                       compound2 ? static_cast<std::uint16_t>(c2) : kNoChild);
    }

    NarrowChunk& chunk_;
    const CandidatePairs& candidates_;
    const BodyStorage& storage_;
    const std::vector<Shape>& shapes_;
    const ShapeTables& tables_;
    const MovingRows& rows_;
    const NarrowPhaseParams& params_;
    const ManifoldReuse& reuse_;
    ManifoldReuse::ChunkCache* cache_;
    ManifoldReuse::Finder finder_;
    SatHint lastHint_;  ///< the hint of the entry reuseOrKeep found for the current candidate
};

}  // namespace

void NarrowPhaseStage::buildJobs(NarrowChunk& chunk, std::size_t begin, std::size_t end,
                                 const CandidatePairs& candidates, const BodyStorage& storage,
                                 const std::vector<Shape>& shapes, const NarrowPhaseParams& params,
                                 ManifoldReuse::ChunkCache* cache) {
    chunk.jobs.clear();
    chunk.reuses.clear();
    chunk.pending.clear();
    JobBuilder builder(chunk, candidates, storage, shapes, tables_, rows_, params, reuse_, cache);
    const std::size_t movingCount = candidates.moving.size(), staticCount = candidates.statics.size();
    for (std::size_t u = begin; u < std::min(end, movingCount); ++u) {
        const BodyPair& p = candidates.moving[u];
        builder.add(ManifoldReuse::Section::Moving, p.a, p.b, false);
    }
    for (std::size_t u = std::max(begin, movingCount); u < std::min(end, movingCount + staticCount); ++u) {
        const BodyPair& p = candidates.statics[u - movingCount];
        builder.add(ManifoldReuse::Section::Static, p.a, p.b, true);
    }
    // A body against a mesh (always B): one job for each run of its triangles that starts in the chunk, the whole
    // run, so that the run's manifolds can be merged (mesh_manifolds.h) and are reused or kept whole. Mesh pairs hold
    // consecutive runs of meshTriangles, so the pair of the chunk's first triangle is found once and then followed.
    if (end <= movingCount + staticCount) return;
    const auto first =
        static_cast<std::uint32_t>(std::max(begin, movingCount + staticCount) - movingCount - staticCount);
    auto mesh = std::upper_bound(candidates.meshes.begin(), candidates.meshes.end(), first,
                                 [](std::uint32_t t, const MeshPair& m) { return t < m.firstTriangle; }) -
                1;
    const auto last = static_cast<std::uint32_t>(end - movingCount - staticCount);
    // A run that started in an earlier chunk is that chunk's.
    auto t = mesh->firstTriangle < first ? mesh->firstTriangle + mesh->triangleCount : first;
    for (; t < last; ++mesh) {
        const std::uint32_t runEnd = mesh->firstTriangle + mesh->triangleCount;
        if (t >= runEnd) continue;
        builder.add(ManifoldReuse::Section::Mesh, mesh->moving, mesh->staticBody, true, t, runEnd - t);
        t = runEnd;
    }
}

}  // namespace rubble::detail
