#include "broadphase/broadphase_stage.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "broadphase/multi_resolution_grid.h"
#include "broadphase/radix_sort.h"
#include "broadphase/static_bvh.h"
#include "broadphase/sweep_and_prune.h"
#include "core/parallel.h"
#include "storage/flag_scan.h"

namespace rubble::detail {
namespace {

/// SAP meets about this many boxes per body along its sweep axis before the grid is cheaper: the estimate `auto`
/// starts from (BroadPhaseTimer then measures). It was set with `rubble run --broadphase sap|grid --steps 100` on the
/// standard scenes, whose estimates are S1 189, S2 95, S3 73-101, S4 540, S5 66-78, S6 69; the grid was faster on
/// all of them then. Measured again since (600 steps, sorting and SAP's sweep faster), SAP is faster on S1 (0.54
/// against 0.61 ms at one thread), S2 (1.30 against 1.50) and S3 (1.22 against 1.33), the grid on S5 (0.53 against
/// 0.62) and S6 (1.11 against 1.29): the estimate cannot tell them apart, so the measurement decides.
constexpr float kSweepCandidatesForGrid = 40.0f;
/// The choice only flips when the estimate crosses the threshold by this factor, so that a scene near the
/// threshold does not throw away SAP's temporal coherence every other step.
constexpr float kHysteresis = 1.5f;
/// An estimate this factor or more from the threshold is decisive: no trial of the other algorithm. The standard
/// scenes where measuring decides lie within 5x of it (S1 189, S2 95, S3 73-101, S5 66-78, S6 69); S4 lies at 540.
constexpr float kDecisiveFactor = 8.0f;
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
    choice.decisive = choice.sweepCandidatesPerBody >= kSweepCandidatesForGrid * kDecisiveFactor ||
                      choice.sweepCandidatesPerBody <= kSweepCandidatesForGrid / kDecisiveFactor;
    return choice;
}

BroadPhaseKind BroadPhaseTimer::next(std::optional<BroadPhaseKind> estimate, bool mayTry) {
    if (estimate && (*estimate != inUse_ || samples_ == 0)) {
        inUse_ = *estimate;
        samples_ = 0;
        stepsSinceTrial_ = 0;
        trialStep_ = 0;
    }
    if (mayTry && trialStep_ == 0 && samples_ >= kTrialSteps && stepsSinceTrial_ >= kTrialPeriod) trialStep_ = 1;
    return trialStep_ > 0 ? other(inUse_) : inUse_;
}

void BroadPhaseTimer::record(double ms) {
    if (trialStep_ == 0) {
        // A running average that forgets within a few dozen steps: scenes settle, and piles spread.
        averageMs_ = samples_ == 0 ? ms : 0.9 * averageMs_ + 0.1 * ms;
        ++samples_;
        ++stepsSinceTrial_;
        return;
    }
    trialMs_[trialStep_ - 1] = ms;
    if (++trialStep_ <= kTrialSteps) return;
    double* measured = trialMs_ + kTrialWarmup;
    const std::uint32_t count = kTrialSteps - kTrialWarmup;
    std::nth_element(measured, measured + count / 2, measured + count);
    if (measured[count / 2] < 0.9 * averageMs_) {
        inUse_ = other(inUse_);
        averageMs_ = measured[count / 2];
        samples_ = 1;
    }
    trialStep_ = 0;
    stepsSinceTrial_ = 0;
}

BroadPhaseStage::BroadPhaseStage()
    : sap_(std::make_unique<SweepAndPrune>()),
      grid_(std::make_unique<MultiResolutionGrid>()),
      bvh_(std::make_unique<StaticBvh>()),
      sleepers_(std::make_unique<StaticBvh>()) {}

BroadPhaseStage::~BroadPhaseStage() = default;

void BroadPhaseStage::staticAdded(std::uint32_t slot, const BodyStorage& storage, const std::vector<Shape>& shapes,
                                  TaskPool& pool) {
    const StaticBodies& s = storage.statics;
    const std::uint32_t i = storage.slots()[slot].dense;
    const Transform pose{{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}};
    addedPrimitives_.clear();
    appendStaticPrimitives(shapes[s.shape[i]], pose, slot, addedPrimitives_);
    bvh_->insert(addedPrimitives_, pool);
    staticFilterChanged(slot, s.filterCategory[i], s.filterMask[i]);
}

void BroadPhaseStage::staticRemoved(std::uint32_t slot) { bvh_->remove(slot); }

void BroadPhaseStage::staticFilterChanged(std::uint32_t slot, std::uint32_t category, std::uint32_t mask) {
    if (slot >= staticCategory_.size()) {
        const std::size_t size = std::max(std::size_t(slot) + 1, 2 * staticCategory_.size());
        staticCategory_.resize(size, 0);
        staticMask_.resize(size, 0);
    }
    staticCategory_[slot] = category;
    staticMask_[slot] = mask;
}

const std::uint32_t* BroadPhaseStage::movingInCellOrder(const BodyStorage& storage) {
    if (lastKind_ != BroadPhaseKind::Grid || layoutAtLastCall_ != storage.layoutChanges()) return nullptr;
    const AlignedVector<std::uint32_t>& cells = grid_->boxesInCellOrder();
    const std::uint32_t n = storage.moving.size();
    if (!lastSearchWasAwakeOnly_) return cells.size() == n ? cells.data() : nullptr;
    // The grid saw the awake rows of the last call: they go first, in its cell order, and the sleepers of that call
    // after them in their present order, so that the awake rows of a world that sleeps are packed together.
    if (cells.size() != awake_.size()) return nullptr;
    cellOrder_.resize(n);
    std::size_t at = 0;
    for (const std::uint32_t k : cells) cellOrder_[at++] = awake_[k];
    std::size_t next = 0;  // awake_ ascends: the rows missing from it are the sleepers
    for (std::uint32_t i = 0; i < n; ++i) {
        if (next < awake_.size() && awake_[next] == i) {
            ++next;
            continue;
        }
        cellOrder_[at++] = i;
    }
    return cellOrder_.data();
}

std::uint32_t BroadPhaseStage::staticPrimitiveCount() const { return bvh_->primitiveCount(); }

BroadPhaseStage::StepInProgress::StepInProgress(BroadPhaseStage& stage, bool takesEveryCore)
    : bvh_(takesEveryCore ? stage.bvh_.get() : nullptr), sleepers_(takesEveryCore ? stage.sleepers_.get() : nullptr) {
    if (bvh_ != nullptr) bvh_->stepBegins(), sleepers_->stepBegins();
}

BroadPhaseStage::StepInProgress::~StepInProgress() {
    if (bvh_ != nullptr) bvh_->stepEnds(), sleepers_->stepEnds();
}

const StaticBvh& BroadPhaseStage::staticBvh(TaskPool& pool) {
    bvh_->commit(pool);
    return *bvh_;
}

void BroadPhaseStage::syncSleepers(const Bounds& moving, const BodyStorage& storage, SleepChanges changes,
                                   TaskPool& pool) {
    const auto& slots = storage.slots();
    if (sleeperSlot_.size() < slots.size()) sleeperSlot_.resize(slots.size(), 0);
    changedSlots_.clear();
    if (changes.all) {
        for (std::uint32_t slot = 0; slot < slots.size(); ++slot) changedSlots_.push_back(slot);
    } else {
        changedSlots_.assign(changes.slots.begin(), changes.slots.end());
        std::sort(changedSlots_.begin(), changedSlots_.end());
        changedSlots_.erase(std::unique(changedSlots_.begin(), changedSlots_.end()), changedSlots_.end());
    }
    fellAsleep_.clear();
    for (const std::uint32_t slot : changedSlots_) {
        // Every change of a body's pose, shape or filter wakes it first, so a sleeper's box holds while it sleeps;
        // one that slept again may have moved in between, so its box is taken anew.
        if (sleeperSlot_[slot]) {
            sleepers_->remove(slot);
            sleeperSlot_[slot] = 0;
            --sleeperCount_;
        }
        const std::uint32_t i = storage.sleepingRow(slot);
        if (i == ~0u) continue;
        const Aabb box{{moving.minX[i], moving.minY[i], moving.minZ[i]},
                       {moving.maxX[i], moving.maxY[i], moving.maxZ[i]}};
        fellAsleep_.push_back({box, slot, kWholeBody});
        sleeperSlot_[slot] = 1;
        ++sleeperCount_;
    }
    // Inside the step: a quick build (a field that falls asleep at once, 250,000 spheres: 165 ms with the SAH);
    // the background merges rebuild it with the SAH.
    if (!fellAsleep_.empty()) sleepers_->insert(fellAsleep_, pool, StaticBvh::BuildQuality::Quick);
}

void BroadPhaseStage::gatherAwake(const Bounds& moving, const MovingBodies& bodies, TaskPool& pool) {
    constexpr std::size_t kGatherChunk = 16384;
    const std::uint32_t n = moving.size();
    const std::size_t chunks = TaskPool::chunkCount(n, kGatherChunk);
    chunkAwake_.assign(chunks + 1, 0);
    pool.forChunks(n, kGatherChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        chunkAwake_[c + 1] =
            static_cast<std::uint32_t>(end - begin - countWith(bodies.flags.data() + begin, end - begin, kFlagAsleep));
    });
    for (std::size_t c = 0; c < chunks; ++c) chunkAwake_[c + 1] += chunkAwake_[c];
    const std::uint32_t awake = chunkAwake_[chunks];
    awake_.resize(awake);
    awakeBounds_.resize(awake);
    awakeCategory_.resize(awake);
    awakeMask_.resize(awake);
    awakeSlot_.resize(awake);
    pool.forChunks(n, kGatherChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t at = chunkAwake_[c];
        for (std::size_t i = begin; (i = nextWithout(bodies.flags.data(), i, end, kFlagAsleep)) < end; ++i) {
            awake_[at] = static_cast<std::uint32_t>(i);
            awakeBounds_.minX[at] = moving.minX[i], awakeBounds_.minY[at] = moving.minY[i];
            awakeBounds_.minZ[at] = moving.minZ[i], awakeBounds_.maxX[at] = moving.maxX[i];
            awakeBounds_.maxY[at] = moving.maxY[i], awakeBounds_.maxZ[at] = moving.maxZ[i];
            awakeCategory_[at] = bodies.filterCategory[i];
            awakeMask_[at] = bodies.filterMask[i];
            awakeSlot_[at] = bodies.slot[i];
            ++at;
        }
    });
}

void BroadPhaseStage::findSleeperPairs(const BodyStorage& storage, const PairFilter& filter,
                                       const PairFilter& awakeFilter, TaskPool& pool, CandidatePairs& out) {
    // The awake rows look for sleepers; the filter bits of both sides are read here, in dense order.
    StaticQueryFilter sleeperFilter;
    sleeperFilter.moving = awakeFilter;
    sleepers_->query(awakeBounds_, sleeperFilter, pool, sleeperPairs_, sleeperMeshes_, sleeperTriangles_);
    out.droppedMoving += sleepers_->droppedHits();
    const auto& slots = storage.slots();
    for (const BodyPair& p : sleeperPairs_) {
        const std::uint32_t awake = awake_[p.a], sleeper = slots[p.b].dense;
        if (filter.accepts(awake, sleeper)) out.moving.push_back({std::min(awake, sleeper), std::max(awake, sleeper)});
    }
}

void BroadPhaseStage::findPairs(const Bounds& moving, const BodyStorage& storage, BroadPhaseKind requested,
                                SleepChanges sleepChanges, TaskPool& pool, CandidatePairs& out) {
    out.clear();
    const MovingBodies& bodies = storage.moving;
    PairFilter filter;
    filter.category = bodies.filterCategory.data();
    filter.mask = bodies.filterMask.data();
    filter.flags = bodies.flags.data();
    filter.asleepBit = kFlagAsleep;

    syncSleepers(moving, storage, sleepChanges, pool);
    // With sleepers in their tree, SAP or the grid see the awake bodies only: a pair of two sleepers is never kept,
    // and awake against asleep comes from the tree.
    const bool awakeOnly = sleeperCount_ > 0;
    const Bounds* searched = &moving;
    PairFilter searchFilter = filter;
    const std::uint32_t* searchSlots = bodies.slot.data();
    if (awakeOnly) {
        gatherAwake(moving, bodies, pool);
        searched = &awakeBounds_;
        searchFilter = PairFilter{awakeCategory_.data(), awakeMask_.data(), nullptr, 0};
        searchSlots = awakeSlot_.data();
    }

    BroadPhaseKind kind = requested;
    if (requested == BroadPhaseKind::Auto) {
        const std::uint32_t n = searched->size();
        const bool countMoved =
            n > countAtEstimate_ + countAtEstimate_ / 8 || n < countAtEstimate_ - countAtEstimate_ / 8;
        std::optional<BroadPhaseKind> estimate;
        // The estimate is also renewed every trial period, since a world's spread changes (a rain becomes a pile):
        // a renewed estimate is followed only when decisive, else the clock keeps deciding.
        if (!estimated_ || countMoved || ++stepsSinceEstimate_ >= BroadPhaseTimer::kTrialPeriod) {
            const BroadPhaseChoice choice = chooseBroadPhase(*searched, timer_.inUse(), pool);
            if (!estimated_ || countMoved || choice.decisive) estimate = choice.kind;
            estimateDecisive_ = choice.decisive;
            estimated_ = true;
            countAtEstimate_ = n;
            stepsSinceEstimate_ = 0;
        }
        kind = timer_.next(estimate, !estimateDecisive_);
    }
    const auto searchBegin = std::chrono::steady_clock::now();
    if (kind == BroadPhaseKind::Grid) {
        // The grid's kept layout follows rows; the awake rows are gathered anew each step.
        RowContinuity continuity = RowContinuity::None;
        const bool sameRows = !awakeOnly && !lastSearchWasAwakeOnly_ && lastKind_ == BroadPhaseKind::Grid;
        if (sameRows && storage.layoutChanges() == layoutAtLastCall_)
            continuity = RowContinuity::SameRows;
        else if (sameRows && storage.layoutChanges() == layoutInCellOrder_)
            continuity = RowContinuity::InCellOrder;
        grid_->findPairs(*searched, searchFilter, pool, out.moving, continuity);
        out.droppedMoving = grid_->droppedPairs();
    } else {
        sap_->findPairs(*searched, searchSlots, static_cast<std::uint32_t>(storage.slots().size()), searchFilter, pool,
                        out.moving);
        out.droppedMoving = sap_->droppedPairs();
    }
    if (requested == BroadPhaseKind::Auto)
        timer_.record(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - searchBegin).count());
    // A switch loses SAP's kept order; it is rebuilt from scratch the next time SAP runs.
    if (kind != lastKind_ && lastKind_ == BroadPhaseKind::SweepAndPrune) sap_->reset();
    lastKind_ = kind;
    lastSearchWasAwakeOnly_ = awakeOnly;
    layoutAtLastCall_ = storage.layoutChanges();
    if (awakeOnly) {
        // Awake rows are in dense order, so a < b still holds in dense indices.
        for (BodyPair& p : out.moving) p = {awake_[p.a], awake_[p.b]};
        findSleeperPairs(storage, filter, searchFilter, pool, out);
    }
    sortPairs(out.moving, pool);

    // A sleeper against a static is never a pair: with sleepers, the awake rows alone look (a kept hit belongs to the
    // box it was found for, not to a row, so rows that shift as bodies wake and sleep stay exact).
    if (!bvh_->empty() && searched->size() > 0) {
        StaticQueryFilter staticFilter;
        staticFilter.moving = searchFilter;
        staticFilter.staticCategory = staticCategory_.data();
        staticFilter.staticMask = staticMask_.data();
        bvh_->query(*searched, staticFilter, pool, out.statics, out.meshes, out.meshTriangles);
        out.droppedStatic = bvh_->droppedHits();
        // The BVH speaks in stable slots; the narrow phase wants dense rows of StaticBodies.
        const auto& slots = storage.slots();
        for (BodyPair& p : out.statics) p.b = slots[p.b].dense;
        for (MeshPair& p : out.meshes) p.staticBody = slots[p.staticBody].dense;
        if (awakeOnly) {
            for (BodyPair& p : out.statics) p.a = awake_[p.a];
            for (MeshPair& p : out.meshes) p.moving = awake_[p.moving];
        }
    }
}

}  // namespace rubble::detail
