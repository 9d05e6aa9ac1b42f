#pragma once
// The contact solver: sequential impulses over this step's manifolds, with friction in the Coulomb cone,
// restitution above a speed threshold, warm starting from the contact cache, and position correction by soft step,
// Baumgarte or split impulses (rubble::PositionCorrection).
//
// Parallel and SIMD through graph colouring: manifolds are coloured so that no dynamic body appears twice in a
// colour; each colour is cut into batches of simd::kLanes manifolds solved together in SIMD lanes, and the batches
// of one colour are independent, so they run on any thread in any order with the same result. Colours run in a
// fixed order, so the state after the solve does not depend on the thread count.
//
// Island-parallel: given the step's islands, small islands are packed, in island order, into blocks of a few
// hundred manifolds that share no body with any other block. Each block is coloured on its own and solved whole by
// one task, every iteration of it while its rows are still in the core's cache. Islands too large for one task (S1's
// pyramid) are solved colour by colour across the threads; when their colours are small (few batches each, so that
// waits between colours cost more than the second thread saves: S3's pile) they are first cut in two slabs across
// their longest axis: in each pass each slab is solved whole by one task, and the manifolds that cross the cut are
// coloured together and solved colour by colour across the threads, before or after the slabs in turn. The packing
// and the cut depend only on the islands, the bodies' positions and the last step's colouring, never on the thread
// count.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "contacts/contact_cache.h"
#include "contacts/contacts.h"
#include "core/parallel.h"
#include "rubble/settings.h"
#include "solver/contact_batch.h"
#include "storage/aligned_vector.h"
#include "storage/body_storage.h"

namespace rubble::detail {

struct Islands;

/// Whether the solver moves this body (not kinematic, frozen, asleep or of infinite mass).
inline bool isDynamicBody(const MovingBodies& m, std::uint32_t dense) {
    return (m.flags[dense] & (kFlagKinematic | kFlagFrozen | kFlagAsleep)) == 0 && m.invMass[dense] > 0;
}
/// Bits of ContactSolver's per-manifold traits: the point count; which sides are dynamic bodies, and which are
/// moving bodies the solver holds still (kinematic, frozen, asleep or of infinite mass); whether the manifold is
/// left out of the solve (no dynamic body, or a pair of jointed bodies that do not collide).
inline constexpr std::uint8_t kTraitPoints = 0x7, kTraitDynamicA = 0x8, kTraitDynamicB = 0x10, kTraitHeldA = 0x20,
                              kTraitHeldB = 0x40, kTraitLeftOut = 0x80;
/// Colours beyond this go to one overflow set solved lane by lane on one thread (bodies with more than 63
/// neighbours of their own colour are rare: a heap of debris around one big body).
inline constexpr std::uint32_t kMaxColors = 63;
inline constexpr std::uint32_t kOverflowColor = kMaxColors;
inline constexpr std::uint8_t kNoColor = 0xFF;
/// Before colouring, segmentOfIsland_ names segments; this one is the large islands'.
inline constexpr std::uint32_t kLargeSegment = ~0u;

/// The joints' share of one pass over the contacts, for one segment: a block's joints (segment = block index) or the
/// large islands' joints (segment = number of blocks). Pass 0 is the warm start when the call asks for one.
using JointPass = FunctionRef<void(std::uint32_t segment, int pass)>;

/// The solver's view of the bodies in contact: velocities and the motion since prepare(), by solver index.
/// Rows [0, count) are the moving bodies the constraints touch, row `count` is the still body that stands for
/// every static body (always zero), and the rows after it are per-worker scratch rows that absorb the writes aimed
/// at bodies that cannot move (static and kinematic), so that no two threads ever write the same row.
/// Each kind of row is one array of 32-byte BodyRows (AoS), so that a SIMD lane's body is one load, not six.
struct SolverBodies {
    AlignedVector<BodyRow> velocity;  ///< linear and angular velocity
    /// Displacement of the centre of mass since prepare() (linear), and the rotation since as a small-angle vector.
    AlignedVector<BodyRow> motion;
    AlignedVector<BodyRow> pseudo;  ///< split impulses' pseudo-velocities
    /// Inverse masses and world inverse inertias: zero for the bodies that cannot move, the still row and the
    /// scratch rows (and the inertias without Effect::Rotation). Fixed from prepare() on.
    AlignedVector<MassRow> mass;
    std::vector<std::uint32_t> moving;  ///< solver index -> dense index of the moving body
    std::uint32_t count = 0;
};

inline constexpr std::uint32_t kNoCoupledBody = ~0u;

/// What the joints add to a contact solve (src/solver/joint_solver.h): their moving bodies, which get body rows
/// even when no manifold touches them, so that joints and contacts share the rows and the iterations; and the pairs
/// of jointed bodies whose contacts are not solved (collideConnected false), as sorted keys of the two body slots,
/// lower slot in the high half (jointedPairKey).
struct JointCoupling {
    std::vector<std::uint32_t> bodies;  ///< dense indices; kNoCoupledBody for a static side or a broken joint
    std::vector<std::uint64_t> noContactPairs;
    std::uint64_t pairsVersion = 0;  ///< JointStore::pairsVersion() noContactPairs were listed at

    /// The joint graph for the island builder: one (dense index, dense index) pair per unbroken joint whose two
    /// bodies both move, in store order. Joints to static bodies tie nothing together.
    void appendEdges(std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) const {
        for (std::size_t i = 0; i + 1 < bodies.size(); i += 2)
            if (bodies[i] != kNoCoupledBody && bodies[i + 1] != kNoCoupledBody)
                edges.emplace_back(bodies[i], bodies[i + 1]);
    }
};

inline std::uint64_t jointedPairKey(std::uint32_t slotA, std::uint32_t slotB) {
    return slotA < slotB ? (std::uint64_t{slotA} << 32 | slotB) : (std::uint64_t{slotB} << 32 | slotA);
}

/// A contact's softness for one substep: the bias rate, and how much of the rigid response and of the accumulated
/// impulse each iteration uses (rigid: {baumgarte / h, 1, 0}).
struct ContactSoftness {
    float biasRate = 0, massScale = 1, impulseScale = 0;
};

struct ContactSolverStats {
    std::uint32_t constraints = 0;  ///< manifolds with at least one dynamic body
    std::uint32_t colors = 0;       ///< the most colours any block or the large islands needed
    std::uint32_t batches = 0;
    std::uint32_t blocks = 0;                  ///< blocks of small islands, each solved whole by one task
    std::uint32_t largeIslandConstraints = 0;  ///< constraints solved colour by colour across the threads
    /// Lanes filled over lanes used, in [0, 1]: how well colouring packs the SIMD batches.
    float laneOccupancy = 0;
};

class ContactSolver {
public:
    /// Builds the constraints for this step's manifolds, starting from `warm` (kMaxManifoldPoints per manifold, as
    /// ContactCache::warmStart gives them). `h` is the substep the solve runs at.
    /// With `joints`, the joints' bodies get rows too and the manifolds of their no-contact pairs are left out.
    /// With `islands` (built over the same contacts), small islands are solved in blocks (see above); without, every
    /// manifold is coloured together.
    void prepare(const Contacts& contacts, const std::vector<PointImpulse>& warm, const BodyStorage& storage,
                 const WorldSettings& settings, EffectSet effects, float h, TaskPool& pool,
                 const JointCoupling* joints = nullptr, const Islands* islands = nullptr);
    bool empty() const { return stats_.constraints == 0; }

    /// The body rows, shared with the joint solver (valid from loadBodies() to storeVelocities()).
    SolverBodies& bodies() { return bodies_; }
    const SolverBodies& bodies() const { return bodies_; }
    /// Row of a moving body (by dense index) since the last prepare(), or -1 when it has none.
    std::int32_t solverIndexOf(std::uint32_t dense) const {
        return dense < solverIndex_.size() ? solverIndex_[dense] : -1;
    }

    /// Copies the touched bodies' velocities in and measures their motion since prepare(). Call at the start of a
    /// substep and after integrate positions (before relaxing).
    void loadBodies(const MovingBodies& bodies, TaskPool& pool);
    /// Copies the solved velocities back (dynamic bodies only).
    void storeVelocities(MovingBodies& bodies, TaskPool& pool) const;

    /// Applies the accumulated impulses (every substep; soft step and split impulses carry them through).
    void warmStart(TaskPool& pool);
    /// `iterations` velocity iterations (a block runs all of them in one task). With bias, overlap is corrected by
    /// the chosen position correction; without, only speculative gaps are respected (the relax iterations of the
    /// soft step, and split impulses' velocity pass). The soft step's friction runs only without bias (in its relax
    /// iterations), unless it has none. With `warmStartFirst`, warmStart() runs first in the same tasks. With `joints`,
    /// each pass of a segment starts with its joints' pass (a block's joints in the block's task, the large islands'
    /// joints on the calling thread before their colours).
    void solveVelocities(bool useBias, TaskPool& pool, int iterations = 1, bool warmStartFirst = false,
                         const JointPass* joints = nullptr);
    /// The segment an island's constraints are solved in since the last prepare(): its block, or blocks().size().
    std::uint32_t segmentOfIsland(std::uint32_t island) const {
        return island < segmentOfIsland_.size() ? segmentOfIsland_[island] : static_cast<std::uint32_t>(blocks_.size());
    }
    /// Shock propagation (SolverSettings::shockPropagation): one pass over the contacts from the ground up, each
    /// contact's lower body held still. Serial, in a fixed order.
    void propagateShock();
    /// Split impulses: `iterations` iterations on the pseudo-velocities.
    void solvePositions(TaskPool& pool, int iterations = 1);
    /// Split impulses: moves the bodies by their pseudo-velocities over the substep and clears them.
    void applyPseudoVelocities(MovingBodies& bodies, TaskPool& pool);
    /// Bounces: approach speeds above the threshold are reversed by the restitution coefficient.
    void applyRestitution(TaskPool& pool);
    /// The final accumulated impulses, in manifold order, for the contact cache: gathered batch by batch into lane
    /// order, then copied out manifold by manifold, so that each thread writes a range of its own.
    void storeImpulses(std::vector<PointImpulse>& impulses, TaskPool& pool);

    /// For the contact events (src/events/): the manifold (index into the contacts of the last prepare()) in each
    /// lane (batch * kBatchLanes + lane), or ~0u for an empty lane.
    std::span<const std::uint32_t> manifoldOfLane() const { return manifoldOfLane_; }
    /// Normal impulse point `point` of the manifold in `lane` has accumulated in the current substep (its whole push
    /// in the substep, the warm start included), once the substep's passes ran.
    float normalImpulse(std::uint32_t lane, int point) const {
        return batches_[lane / kBatchLanes].points[point].normalImpulse[lane % kBatchLanes];
    }

    const ContactSolverStats& stats() const { return stats_; }
    struct ColorRange {
        std::uint32_t firstBatch = 0;
        std::uint32_t batchCount = 0;
        /// Manifolds that found no free colour, solved one lane at a time; an overflow range is its block's last.
        bool overflow = false;
    };
    /// Colour ranges [firstColor, firstColor + colorCount) solved in order by one task, or by all threads.
    struct ColorSpan {
        std::uint32_t firstColor = 0;
        std::uint32_t colorCount = 0;
    };
    /// Prepared batches and the colour ranges, for tests: the blocks' colours, then the large islands' colours.
    const std::vector<ContactBatch>& batches() {
        buildPendingBlocks();
        return batches_;
    }
    const std::vector<ColorRange>& colorRanges() const { return colors_; }
    const std::vector<ColorSpan>& blocks() const { return blocks_; }
    const std::vector<ColorSpan>& slabs() const { return slabs_; }
    ColorSpan largeIslands() const { return large_; }
    bool hasOverflow() const {
        return std::any_of(colors_.begin(), colors_.end(), [](const ColorRange& r) { return r.overflow; });
    }

private:
    /// Runs kernel(batch, lane, rows, pass) over every colour `passes` times (pass 0, 1, ...): a block runs all its
    /// passes in one task; in each pass the large islands' slabs run one task each, and the manifolds that cross
    /// them colour by colour across the threads, after the slabs, or before them in every other pass from
    /// `firstIteration` on (the iterations; a warm start or a bounce keeps one order).
    template <class Kernel>
    void forEachColor(TaskPool& pool, Kernel&& kernel, int passes = 1, const JointPass* joints = nullptr,
                      int firstIteration = std::numeric_limits<int>::max());
    /// forEachColor's work in one parallel region (more than one thread, no joints): each worker runs its share of
    /// the blocks, then pass by pass its share of each of the large islands' colours and of the slabs, helping with
    /// the others' shares when done, with a barrier after each colour instead of a fork and join. A solve of fewer
    /// than kBatchesForTwoWorkers batches runs on the calling thread alone.
    template <class Kernel>
    void forEachColorInOneRegion(TaskPool& pool, Kernel& kernel, int passes, int firstIteration);
    template <class Kernel>
    void solveRange(const ColorRange& range, const BodyRows& rows, Kernel& kernel, int pass);
    /// Every colour of a block or slab in order, one pass.
    template <class Kernel>
    void solveSpan(const ColorSpan& span, const BodyRows& rows, Kernel& kernel, int pass) {
        for (std::uint32_t c = 0; c < span.colorCount; ++c)
            solveRange(colors_[span.firstColor + c], rows, kernel, pass);
    }
    /// Batches [begin, end) of a colour that is not an overflow, one pass.
    template <class Kernel>
    void solveBatches(const ColorRange& range, std::size_t begin, std::size_t end, const BodyRows& rows, Kernel& kernel,
                      int pass) {
        for (std::size_t i = begin; i < end; ++i)
            kernel.template operator()<simd::FloatW>(batches_[range.firstBatch + i], 0, rows, pass);
    }
    /// Whether the manifolds that cross the slabs run before them in this pass (see forEachColor).
    bool crossingFirst(int pass, int firstIteration) const {
        return !slabs_.empty() && pass >= firstIteration && (pass - firstIteration) % 2 == 0;
    }
    /// Lists the manifolds by block (blocks_ spans, then the slabs, then large_), into segmentManifolds_ /
    /// segmentStart_.
    void partition(const Contacts& contacts, const Islands* islands, const MovingBodies& m);
    /// Appends largePart_ as slabs (when large enough) and the manifolds that cross them (see the .cpp).
    void splitIntoSlabs(const Contacts& contacts, const MovingBodies& m);
    /// Gives a body row (solver index) to every body the constraints touch, segment by segment (see the .cpp).
    void assignRows(const Contacts& contacts, const Islands* islands, const MovingBodies& m, bool anyHeld);
    /// The body's row, given one if it has none yet.
    std::uint32_t touchRow(std::uint32_t dense) {
        if (solverIndex_[dense] < 0) {
            solverIndex_[dense] = static_cast<std::int32_t>(bodies_.moving.size());
            bodies_.moving.push_back(dense);
        }
        return static_cast<std::uint32_t>(solverIndex_[dense]);
    }
    /// Greedy colouring of every segment in its manifold order, into segmentColor_ and segmentColours_.
    void colourSegments(const Contacts& contacts, const MovingBodies& m, TaskPool& pool);
    /// False if a dynamic body of the segment has no row in the segment's range.
    bool colourSegment(const Contacts& contacts, std::size_t segment);
    /// The colours' batch ranges (colors_), the blocks', slabs' and large islands' spans and the stats, from the
    /// segments' colour counts; returns the number of batches.
    std::uint32_t layOutColours();
    /// Each segment's manifolds into their colours' lanes (manifoldOfLane_, batchPoints_), the segments in parallel.
    void fillLanes(TaskPool& pool);
    BodyRows rowsFor(int worker);
    /// Builds the constraint rows of batches [begin, end) from the inputs prepare() kept.
    void buildBatches(std::uint32_t begin, std::uint32_t end);
    void buildBlock(std::size_t block);
    /// Builds the blocks' rows now if no solve has built them yet (in parallel).
    void buildPendingBlocks();
    void orderForShock();

    /// A contact of the shock pass: where its manifold sits, and which side is held still (0 = A, 1 = B).
    struct ShockContact {
        std::uint32_t level = 0;  ///< the upper body's distance in contacts from a body that cannot move
        std::uint32_t lane = 0;   ///< batch * kBatchLanes + lane
        std::uint32_t heldSide = 0;
        /// Normal and tangent effective masses of each point with the lower side held: the upper body's alone.
        float heldMasses[kMaxManifoldPoints][3] = {};
    };
    void computeHeldMasses(ShockContact& s) const;
    void solveHeld(const ShockContact& s, const BodyRows& rows, const SolveParams& params);

    /// What building the rows reads, kept from prepare() to the first solve, which builds the blocks' rows.
    struct BuildInputs {
        const Contacts* contacts = nullptr;
        const std::vector<PointImpulse>* warm = nullptr;
        const BodyStorage* storage = nullptr;
        ContactSoftness dynamicSoft, staticSoft, stiff;
        bool softStep = false;
        float slop = 0;
        bool warmStarting = true;
        bool bounce = false;
        Vec3 gravity;  ///< zero without the gravity effect
    };
    BuildInputs build_;
    /// What each phase of forEachColorInOneRegion is: the blocks (phase 0), then per pass a colour of the large
    /// islands (its colour index) or the slabs (kSlabsPhase).
    struct PhaseWork {
        std::uint32_t color = 0;
        int pass = 0;
    };
    static constexpr std::uint32_t kSlabsPhase = ~0u;
    std::vector<PhaseWork> phaseWork_;
    std::vector<std::uint32_t>
        blockShareStart_;  ///< each worker's share of the blocks (about equal work), then the end
    WorkPhases phases_;
    TaskPool* pool_ = nullptr;
    bool blocksPending_ = false;  ///< the blocks' rows are still to be built
    SolverSettings settings_;
    float h_ = 0;
    bool friction_ = true;
    bool frictionInRelaxOnly_ = true;  ///< the soft step with relax iterations: friction is solved in those only
    bool rotation_ = true;
    int scratchRows_ = 1;
    bool moved_ = false;  ///< some body moved since prepare(): separations must follow the motion rows
    ContactSolverStats stats_;
    SolverBodies bodies_;
    std::vector<ContactBatch> batches_;
    /// Beside batches_ when the step has restitution or split impulses, empty otherwise.
    std::vector<ContactBatchExtras> extras_;
    ContactBatchExtras* extrasOf(const ContactBatch& b) {
        return extras_.empty() ? nullptr : &extras_[static_cast<std::size_t>(&b - batches_.data())];
    }
    std::vector<ColorRange> colors_;
    std::vector<ColorSpan> blocks_;
    /// Slabs of the large islands, each solved whole by one task in every pass, before large_, which then holds
    /// only the manifolds that cross from one slab to another.
    std::vector<ColorSpan> slabs_;
    ColorSpan large_;
    std::vector<std::uint32_t> manifoldOfLane_;  ///< batch * kLanes + lane -> manifold, ~0u for an empty lane
    std::vector<std::uint32_t> laneOfManifold_;  ///< the inverse: manifold -> lane, ~0u for a manifold in none
    std::vector<PointImpulse> impulsesByLane_;   ///< storeImpulses: lane * kMaxManifoldPoints + point
    std::vector<std::uint8_t> batchPoints_;      ///< per batch: the most points of its lanes' manifolds
    std::vector<ShockContact> shockOrder_;       ///< by level, then by lane
    std::vector<std::uint32_t> levelOf_;         ///< shock pass: level per solver index
    std::vector<std::uint32_t> adjacencyStart_, adjacency_, adjacencyFill_;  ///< shock pass: contact graph (CSR)
    std::vector<std::uint32_t> shockQueue_;                                  ///< shock pass: breadth-first order
    // Prepare scratch.
    std::vector<std::uint32_t> segmentManifolds_;  ///< manifold indices by segment: each block, then the large part
    std::vector<std::uint32_t> segmentStart_;      ///< segment k is segmentManifolds_[segmentStart_[k], ...[k + 1])
    std::vector<std::uint8_t> placed_;             ///< per manifold: listed in a block
    std::vector<std::uint32_t> segmentOfIsland_;   ///< per island: its block, or blocks_.size()
    std::vector<std::uint32_t> largePart_;         ///< manifolds in no block
    std::vector<Vec3> slabPlaces_;                 ///< where every 8th manifold of largePart_ lies
    std::vector<float> slabKeys_;                  ///< those places along the cut's axis
    std::vector<std::uint32_t> slabParts_[3];      ///< largePart_ split: two slabs, then the crossing manifolds
    std::size_t slabSegments_ = 0;                 ///< segments before the last that are slabs
    float largeBatchesPerColor_ = INFINITY;        ///< last step's, for the choice of slabs
    std::vector<std::uint32_t> blockOfSegment_;    ///< prepare scratch: a segment's block, if it kept constraints
    std::vector<std::int32_t> solverIndex_;        ///< dense index of a moving body -> solver index, -1 if untouched
    std::vector<std::uint64_t> bodyColors_;        ///< per solver index: colours that already hold the body
    /// What colouring found in one segment: per colour, its manifolds and how many of them have each point count;
    /// where the colour's batches start (layOutColours).
    struct SegmentColours {
        std::uint32_t manifolds[kMaxColors + 1];
        std::uint32_t byPoints[kMaxColors + 1][kMaxManifoldPoints + 1];
        std::uint32_t firstBatch[kMaxColors + 1];
        std::uint32_t constraints;
    };
    std::vector<SegmentColours> segmentColours_;
    /// Per segment: the rows its dynamic bodies must lie in (assignRows), checked as it is coloured.
    struct RowRange {
        std::uint32_t begin = 0, end = 0;
    };
    std::vector<RowRange> segmentRows_;
    std::vector<std::uint8_t> segmentColor_;  ///< per entry of segmentManifolds_: its colour, or kNoColor
    std::vector<std::uint8_t> chunkHeld_;     ///< prepare scratch: a chunk of manifolds touches a held body
    bool segmentsFromIslands_ = false;        ///< partition() placed the manifolds by their islands
    int slabAxis_ = 0;                        ///< the slabs' cut: along this axis...
    float slabCut_ = 0;                       ///< ...a body below this lies in slab 0, else in slab 1
    /// Per manifold, what partitioning and colouring read of it (see ManifoldTraits in the .cpp), gathered in
    /// parallel so that the serial passes read one byte, not a manifold's cache line and two bodies' flags.
    std::vector<std::uint8_t> traits_;
    std::vector<std::uint8_t> movedInChunk_;  ///< loadBodies: whether a chunk of bodies moved since prepare()
    AlignedVector<float> p0x_, p0y_, p0z_, q0x_, q0y_, q0z_, q0w_;  ///< pose at prepare(), by solver index
};

}  // namespace rubble::detail
