#include "broadphase/broadphase_stage.h"

#include <algorithm>
#include <cmath>

#include "broadphase/multi_resolution_grid.h"
#include "broadphase/radix_sort.h"
#include "broadphase/static_bvh.h"
#include "broadphase/sweep_and_prune.h"
#include "parallel.h"

namespace rubble::detail {
namespace {

/// SAP meets about this many boxes per body along its sweep axis before the grid is cheaper. Measured with
/// `rubble run --broadphase sap|grid --steps 100` on the standard scenes, whose estimates are S1 189, S2 95,
/// S3 73-101, S4 540, S5 66-78, S6 69: the grid is faster on S1 (by 12%), S2 (25%), S4, S5 (10%) and S6 (1.3 against
/// 2.3 ms at one thread: its pyramids fill both horizontal axes, and a sweep along one meets every row), and even
/// with SAP on S3 while its bodies fall. So the grid is the default from well below them; SAP keeps the sparse and
/// the long thin worlds, where its kept order makes a step's sort nearly free.
constexpr float kSweepCandidatesForGrid = 40.0f;
/// The choice only flips when the estimate crosses the threshold by this factor, so that a scene near the
/// threshold does not throw away SAP's temporal coherence every other step.
constexpr float kHysteresis = 1.5f;
/// Scenes change slowly: `auto` looks again every this many steps, or sooner when the body count moves by 1/8.
constexpr std::uint32_t kStepsBetweenChoices = 16;
constexpr std::uint32_t kChoiceChunk = 16384;

struct AxisSums {
    double sum[3] = {}, sumSquares[3] = {}, width[3] = {};
};

}  // namespace

BroadPhaseChoice chooseBroadPhase(const Bounds& b, BroadPhaseKind current, TaskPool& pool) {
    const std::uint32_t n = b.size();
    BroadPhaseChoice choice;
    choice.kind = current == BroadPhaseKind::Auto ? BroadPhaseKind::SweepAndPrune : current;
    if (n < 2) return choice;
    const float* lo[3] = {b.minX.data(), b.minY.data(), b.minZ.data()};
    const float* hi[3] = {b.maxX.data(), b.maxY.data(), b.maxZ.data()};
    std::vector<AxisSums> chunks(TaskPool::chunkCount(n, kChoiceChunk));
    pool.forChunks(n, kChoiceChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        AxisSums& s = chunks[chunk];
        for (int axis = 0; axis < 3; ++axis)
            for (std::size_t i = begin; i < end; ++i) {
                const double c = 0.5 * (double(lo[axis][i]) + double(hi[axis][i]));
                s.sum[axis] += c;
                s.sumSquares[axis] += c * c;
                s.width[axis] += double(hi[axis][i]) - double(lo[axis][i]);
            }
    });
    double sum[3] = {}, sumSquares[3] = {}, width[3] = {};
    for (const AxisSums& s : chunks)
        for (int axis = 0; axis < 3; ++axis)
            sum[axis] += s.sum[axis], sumSquares[axis] += s.sumSquares[axis], width[axis] += s.width[axis];
    int best = 0;
    double bestVariance = -1;
    for (int axis = 0; axis < 3; ++axis) {
        const double mean = sum[axis] / n;
        const double variance = std::max(0.0, sumSquares[axis] / n - mean * mean);
        if (variance > bestVariance) bestVariance = variance, best = axis;
    }
    // Centres spread over about sqrt(12 variance) for a uniform spread; a box meets the others whose intervals
    // overlap its own, about n * (2 mean width) / spread of them, half of which the sweep visits.
    const double spread = std::sqrt(12.0 * bestVariance);
    const double meanWidth = width[best] / n;
    choice.sweepCandidatesPerBody = spread > 0 ? static_cast<float>(n * meanWidth / spread) : static_cast<float>(n);
    const float threshold =
        current == BroadPhaseKind::Grid ? kSweepCandidatesForGrid / kHysteresis : kSweepCandidatesForGrid * kHysteresis;
    choice.kind = choice.sweepCandidatesPerBody > threshold ? BroadPhaseKind::Grid : BroadPhaseKind::SweepAndPrune;
    return choice;
}

BroadPhaseStage::BroadPhaseStage()
    : sap_(std::make_unique<SweepAndPrune>()),
      grid_(std::make_unique<MultiResolutionGrid>()),
      bvh_(std::make_unique<StaticBvh>()) {}

BroadPhaseStage::~BroadPhaseStage() = default;

void BroadPhaseStage::staticAdded(std::uint32_t slot) {
    pendingAdds_.push_back(slot);
    filtersDirty_ = true;
}

void BroadPhaseStage::staticRemoved(std::uint32_t slot) {
    // A body added and removed between the same two steps never reaches the tree.
    const auto pending = std::find(pendingAdds_.begin(), pendingAdds_.end(), slot);
    if (pending != pendingAdds_.end())
        pendingAdds_.erase(pending);
    else
        pendingRemoves_.push_back(slot);
    filtersDirty_ = true;
}

std::uint32_t BroadPhaseStage::staticPrimitiveCount() const { return bvh_->primitiveCount(); }

const StaticBvh& BroadPhaseStage::staticBvh(const BodyStorage& storage, const std::vector<Shape>& shapes,
                                            TaskPool& pool) {
    applyStaticEdits(storage, shapes, pool);
    bvh_->commit(pool);
    return *bvh_;
}

void BroadPhaseStage::applyStaticEdits(const BodyStorage& storage, const std::vector<Shape>& shapes, TaskPool& pool) {
    for (std::uint32_t slot : pendingRemoves_) bvh_->remove(slot);
    pendingRemoves_.clear();
    if (!pendingAdds_.empty()) {
        std::vector<StaticPrimitive> primitives;
        const StaticBodies& s = storage.statics;
        for (std::uint32_t slot : pendingAdds_) {
            const std::uint32_t i = storage.slots()[slot].dense;
            const Transform pose{{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}};
            appendStaticPrimitives(shapes[s.shape[i]], pose, slot, primitives);
        }
        pendingAdds_.clear();
        // The first time, one SAH build over everything; later additions go through the BVH's edit path.
        if (bvh_->empty())
            bvh_->build(std::move(primitives), pool);
        else
            bvh_->insert(primitives);
    }
    if (filtersDirty_) {
        const auto& slots = storage.slots();
        staticCategory_.assign(slots.size(), 0);
        staticMask_.assign(slots.size(), 0);
        for (std::uint32_t i = 0; i < storage.statics.size(); ++i) {
            const std::uint32_t slot = storage.statics.slot[i];
            staticCategory_[slot] = storage.statics.filterCategory[i];
            staticMask_[slot] = storage.statics.filterMask[i];
        }
        filtersDirty_ = false;
    }
}

void BroadPhaseStage::findPairs(const Bounds& moving, const BodyStorage& storage, const std::vector<Shape>& shapes,
                                BroadPhaseKind requested, TaskPool& pool, CandidatePairs& out) {
    out.clear();
    const MovingBodies& bodies = storage.moving;
    PairFilter filter;
    filter.category = bodies.filterCategory.data();
    filter.mask = bodies.filterMask.data();
    filter.flags = bodies.flags.data();
    filter.asleepBit = kFlagAsleep;

    BroadPhaseKind kind = requested;
    if (requested == BroadPhaseKind::Auto) {
        const std::uint32_t n = moving.size();
        const bool countMoved = n > countAtChoice_ + countAtChoice_ / 8 || n < countAtChoice_ - countAtChoice_ / 8;
        if (stepsSinceChoice_ == 0 || stepsSinceChoice_ >= kStepsBetweenChoices || countMoved) {
            lastChoice_ = chooseBroadPhase(moving, lastKind_, pool).kind;
            stepsSinceChoice_ = 0;
            countAtChoice_ = n;
        }
        ++stepsSinceChoice_;
        kind = lastChoice_;
    }
    if (kind == BroadPhaseKind::Grid) {
        grid_->findPairs(moving, filter, pool, out.moving);
    } else {
        sap_->findPairs(moving, bodies.slot.data(), static_cast<std::uint32_t>(storage.slots().size()), filter, pool,
                        out.moving);
    }
    // A switch loses SAP's kept order; it is rebuilt from scratch the next time SAP runs.
    if (kind != lastKind_ && lastKind_ == BroadPhaseKind::SweepAndPrune) sap_->reset();
    lastKind_ = kind;
    sortPairs(out.moving, pool);

    applyStaticEdits(storage, shapes, pool);
    if (!bvh_->empty() && moving.size() > 0) {
        StaticQueryFilter staticFilter;
        staticFilter.moving = filter;
        staticFilter.staticCategory = staticCategory_.data();
        staticFilter.staticMask = staticMask_.data();
        bvh_->query(moving, staticFilter, pool, out.statics, out.meshes, out.meshTriangles);
        // The BVH speaks in stable slots; the narrow phase wants dense rows of StaticBodies.
        const auto& slots = storage.slots();
        for (BodyPair& p : out.statics) p.b = slots[p.b].dense;
        for (MeshPair& p : out.meshes) p.staticBody = slots[p.staticBody].dense;
    }
}

}  // namespace rubble::detail
