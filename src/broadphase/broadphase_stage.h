#pragma once
// The broad-phase stage: runs the moving-moving algorithm the settings ask for (or the one `auto` picks from the
// scene), the static BVH for moving-static pairs, and brings all pairs into the canonical order.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "broadphase/broadphase.h"
#include "rubble/settings.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;
class SweepAndPrune;
class MultiResolutionGrid;
class StaticBvh;
struct StaticPrimitive;

/// What `auto` looks at: the expected number of boxes a sweep meets per body along the best axis. SAP wins while
/// that stays small; the grid's cost per body does not depend on it.
struct BroadPhaseChoice {
    BroadPhaseKind kind = BroadPhaseKind::SweepAndPrune;
    float sweepCandidatesPerBody = 0;
    /// The estimate lies so far from the threshold that timing the other algorithm cannot pay: S4 (540 boxes a sweep)
    /// or a million sparse bodies (2,600), where one trial step of SAP took 0.56 s against the grid's 68 ms.
    bool decisive = false;
};

/// Picks SAP or the grid for these boxes. `current` adds hysteresis so the choice does not flip every step.
/// The statistics are summed in fixed chunks merged in order, so the choice is the same on any thread count.
BroadPhaseChoice chooseBroadPhase(const Bounds& bounds, BroadPhaseKind current, TaskPool& pool);

/// `auto` by measurement. The estimate (chooseBroadPhase) picks at first and whenever the body count moves by an
/// eighth, and is renewed every kTrialPeriod steps (followed then only when decisive); unless the last estimate was
/// decisive, every kTrialPeriod steps the other algorithm runs for kTrialSteps steps, and it stays if its
/// time (the median of the steps after its first two, which rebuild SAP's kept order) beats the running average of
/// the one in use by a tenth. The estimate gets the common cases right, but not all of them: on the standard scenes
/// SAP is faster on S1, S2 and S3 and the grid on S5 and S6, with estimates that do not separate them (S1 189, S3
/// 73-101, S5 66-78, S6 69). Which algorithm ran never changes the pairs (their order is canonical), so the timing
/// cannot change the result.
class BroadPhaseTimer {
public:
    static constexpr std::uint32_t kTrialPeriod = 120;
    static constexpr std::uint32_t kTrialSteps = 6;
    static constexpr std::uint32_t kTrialWarmup = 2;

    /// The algorithm to run this step, given the estimate's pick when it was asked again (else nullopt). No trial
    /// starts while `mayTry` is false (the last estimate was decisive).
    BroadPhaseKind next(std::optional<BroadPhaseKind> estimate, bool mayTry = true);
    /// How long the moving-pair search of this step took, ms.
    void record(double ms);
    BroadPhaseKind inUse() const { return inUse_; }

private:
    static BroadPhaseKind other(BroadPhaseKind k) {
        return k == BroadPhaseKind::Grid ? BroadPhaseKind::SweepAndPrune : BroadPhaseKind::Grid;
    }
    BroadPhaseKind inUse_ = BroadPhaseKind::SweepAndPrune;
    double averageMs_ = 0;  ///< of the algorithm in use, outside trials
    std::uint32_t samples_ = 0;
    std::uint32_t stepsSinceTrial_ = 0;
    std::uint32_t trialStep_ = 0;  ///< 0: no trial; else the trial's step count so far
    double trialMs_[kTrialSteps] = {};
};

class BroadPhaseStage {
public:
    BroadPhaseStage();
    ~BroadPhaseStage();
    BroadPhaseStage(const BroadPhaseStage&) = delete;
    BroadPhaseStage& operator=(const BroadPhaseStage&) = delete;

    /// Static bodies changed between steps: the static BVH takes them in at once (a full batch of primitives is
    /// built when it fills, so a large world pays for its tree while it is created, not in a step); a moved static
    /// body is a removal plus an addition. The body's row in `storage` must be current.
    void staticAdded(std::uint32_t slot, const BodyStorage& storage, const std::vector<Shape>& shapes, TaskPool& pool);
    void staticRemoved(std::uint32_t slot);
    /// A static body's collision filter changed.
    void staticFilterChanged(std::uint32_t slot, std::uint32_t category, std::uint32_t mask);

    /// Candidate pairs for this step: moving-moving pairs from SAP or the grid over the awake bodies, and from a
    /// tree of the sleeping bodies' boxes for awake against asleep; moving-static pairs from the static BVH.
    /// `sleepChanges` (since the last call) keeps the tree of sleepers current. A world that sleeps costs the search
    /// only its awake bodies: sleepers are in the tree, built as they fall asleep (a static BVH of their own: the same
    /// incremental forest), and a pair of two sleepers is never a candidate anyway.
    void findPairs(const Bounds& moving, const BodyStorage& storage, BroadPhaseKind requested,
                   SleepChanges sleepChanges, TaskPool& pool, CandidatePairs& out);
    /// Sleeping bodies in the broad phase's tree of sleepers.
    std::uint32_t sleeperCount() const { return sleeperCount_; }

    /// The algorithm the last call used for moving-moving pairs.
    BroadPhaseKind lastKind() const { return lastKind_; }
    /// The moving bodies in the grid's cell order, when the last call ran the grid and no body was added or removed
    /// since (else null): an order of the storage that keeps bodies near in space near in memory. When the grid saw
    /// only the awake bodies, they come first in its order and the sleepers after them.
    const std::uint32_t* movingInCellOrder(const BodyStorage& storage);
    /// The storage was just put in movingInCellOrder()'s order: the grid's next search may re-sort only the bodies
    /// that change cell.
    void movingPutInCellOrder(const BodyStorage& storage) { layoutInCellOrder_ = storage.layoutChanges(); }
    /// The grid as the last step that ran it left it (read-only, for debug drawing; lastKind() says whether that
    /// was the last step).
    const MultiResolutionGrid& grid() const { return *grid_; }
    std::uint32_t staticPrimitiveCount() const;
    /// The static BVH with the static edits made since the last step committed, for the scene queries (src/query/)
    /// and continuous collision, which then only read it. Not thread-safe: the queries call it under their own lock.
    const StaticBvh& staticBvh(TaskPool& pool);
    /// Holds the static tree's background merges back for as long as it lives, the step's own time, when the step
    /// takes every core (`takesEveryCore`; see StaticBvh::StepGate). A step that leaves a core free leaves it to them.
    class StepInProgress {
    public:
        StepInProgress(BroadPhaseStage& stage, bool takesEveryCore);
        ~StepInProgress();
        StepInProgress(const StepInProgress&) = delete;
        StepInProgress& operator=(const StepInProgress&) = delete;

    private:
        StaticBvh* bvh_;       ///< null when the merges may run
        StaticBvh* sleepers_;  ///< likewise
    };

private:
    /// Puts the bodies that fell asleep into the tree of sleepers and takes out those that woke or are gone.
    void syncSleepers(const Bounds& moving, const BodyStorage& storage, SleepChanges changes, TaskPool& pool);
    /// The awake bodies' rows (boxes, filters, slots) in dense order, for a search without the sleepers.
    void gatherAwake(const Bounds& moving, const MovingBodies& bodies, TaskPool& pool);
    /// Appends the pairs of awake bodies with sleepers (dense indices, a < b) to `out`. `filter` is over the dense
    /// rows, `awakeFilter` over the awake rows.
    void findSleeperPairs(const BodyStorage& storage, const PairFilter& filter, const PairFilter& awakeFilter,
                          TaskPool& pool, CandidatePairs& out);

    std::unique_ptr<SweepAndPrune> sap_;
    std::unique_ptr<MultiResolutionGrid> grid_;
    std::unique_ptr<StaticBvh> bvh_;
    BroadPhaseKind lastKind_ = BroadPhaseKind::SweepAndPrune;
    std::uint64_t layoutAtLastCall_ = 0;                   ///< BodyStorage::layoutChanges() when findPairs last ran
    std::uint64_t layoutInCellOrder_ = ~std::uint64_t{0};  ///< ... right after the storage took the grid's order
    BroadPhaseTimer timer_;
    bool estimated_ = false;
    bool estimateDecisive_ = false;
    std::uint32_t countAtEstimate_ = 0;
    std::uint32_t stepsSinceEstimate_ = 0;
    std::vector<std::uint32_t> staticCategory_, staticMask_;  ///< by static slot
    std::vector<StaticPrimitive> addedPrimitives_;            ///< scratch of staticAdded
    // The sleepers: their tree (body id = slot), which slots it holds, and the awake rows the search runs over.
    std::unique_ptr<StaticBvh> sleepers_;
    std::vector<std::uint8_t> sleeperSlot_;
    std::uint32_t sleeperCount_ = 0;
    bool lastSearchWasAwakeOnly_ = false;
    std::vector<std::uint32_t> changedSlots_;
    std::vector<StaticPrimitive> fellAsleep_;
    std::vector<std::uint32_t> chunkAwake_;
    std::vector<std::uint32_t> awake_;      ///< dense index of each awake row
    std::vector<std::uint32_t> cellOrder_;  ///< movingInCellOrder() of a search over the awake rows
    Bounds awakeBounds_;
    std::vector<std::uint32_t> awakeCategory_, awakeMask_, awakeSlot_;
    std::vector<BodyPair> sleeperPairs_;
    std::vector<MeshPair> sleeperMeshes_;  ///< always empty: a sleeper is one box
    std::vector<std::uint32_t> sleeperTriangles_;
};

}  // namespace rubble::detail
