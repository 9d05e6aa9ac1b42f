#pragma once
// The joint solver: distance joints, springs, ball joints and hinges (with limits and a motor) as sequential
// impulses in the contact solver's iterations. Each velocity iteration solves every joint, then the contact colours;
// both read and write the same body rows (ContactSolver::bodies()), which prepare() gives to every body a joint
// touches.
//
// Rows are built once per step, like the contacts' (Catto, "Solver2D", 2024): anchors, axes and effective masses at
// the step's start. Each substep measures the joints' anchors and errors again from the bodies' motion since then
// (the body rows' `motion`, exact rotations) and the point rows' effective mass at those anchors (a light body on a
// long lever turns its anchor far within a step: a cloth of small spheres went non-finite on the step's first
// masses), so a substep costs the joints one light pass before their iterations, not a rebuild from the body store.
//
// Joints run within their island's segment of the contact solve (ContactSolver::segmentOfIsland): a block of small
// islands solves its joints serially in its own task. The large islands' joints run before their contact colours,
// serially in the joint store's order when they are few (a chain solved from one end carries its load down in one
// pass), else in colours of their own (greedy, in store order: no two joints of a colour share a moving body) whose
// joints run across the threads, the ball joints kBatchLanes at a time in SIMD lanes (solver/ball_joint_batch.h).
// When the joints split cleanly into two slabs across the middle of the island (a sheet, a lattice, a bridge), each
// slab's colours run whole in one task per pass and only the joints across the cut colour by colour after them, so a
// pass waits for the threads once rather than once per colour. The rows, colours and slabs depend only on the
// joints, the islands, the body rows and the bodies' places, never on the thread count, and the layout is kept from
// step to step while each joint's body rows and segment stay the same.
//
// Position error is fed back in the velocity rows. With Baumgarte (and with split impulses, whose pseudo-velocities
// only serve contacts) a fraction SolverSettings::baumgarte of the error is removed per substep; with the soft step
// the rows are soft constraints at SolverSettings::jointHertz and the relax iterations take the push-out velocity
// away again. Springs are always soft constraints built from their stiffness k and damping c (Catto, "Soft
// Constraints", GDC 2011): with the substep h, gamma = 1 / (h (c + h k)) and beta = h k / (c + h k), which is the
// damped spring integrated implicitly over the substep, stable for any k. Accumulated impulses carry from substep to
// substep, and through the joint store to the next step's first (warm starting); the store's reaction forces and the
// break checks use the step's last substep.
#include <cstdint>
#include <vector>

#include "rubble/settings.h"
#include "solver/ball_joint_batch.h"
#include "solver/contact_solver.h"
#include "storage/body_storage.h"
#include "storage/joint_storage.h"

namespace rubble::detail {

class TaskPool;
struct Islands;

/// Symmetric 3x3 matrix (world inverse inertias, effective masses).
struct JointSym3 {
    float xx = 0, yy = 0, zz = 0, xy = 0, xz = 0, yz = 0;
    Vec3 operator*(Vec3 v) const {
        return {xx * v.x + xy * v.y + xz * v.z, xy * v.x + yy * v.y + yz * v.z, xz * v.x + yz * v.y + zz * v.z};
    }
};

/// One joint prepared for the step: its bodies and effective masses, and the current substep's anchors and errors.
struct JointRow {
    std::uint32_t joint = 0;  ///< dense index in the store
    JointType type = JointType::Ball;
    bool active = false;  ///< unbroken, with a dynamic body, and (distance, spring) anchors apart
    bool dynamicA = false, dynamicB = false;
    bool limit = false, motor = false;
    std::int32_t rowA = -1, rowB = -1;  ///< body rows; -1 for a static body
    float invMassA = 0, invMassB = 0;
    JointSym3 inertiaA, inertiaB;  ///< world inverse inertia
    Vec3 rA, rB;                   ///< anchors from the centres of mass, world, this substep

    // Softness of the position rows: impulse = -massScale * mass * (J v + biasRate * C) - impulseScale * accumulated.
    float biasRate = 0, massScale = 1, impulseScale = 0;

    JointSym3 pointMass;  ///< ball, hinge: inverse of the point rows' 3x3 effective mass matrix
    Vec3 pointError;      ///< anchor B - anchor A
    Vec3 axis;            ///< distance, spring: unit line from anchor A to anchor B
    float axialMass = 0, axialError = 0;

    Vec3 hingeAxis, t1, t2;                ///< hinge: A's axis and two directions perpendicular to it
    float angularMass[3] = {};             ///< inverse of the 2x2 effective mass of the t1, t2 rows (11, 22, 12)
    float angularError[2] = {};            ///< axis misalignment along t1, t2
    float axisMass = 0;                    ///< effective mass about the axis (limits, motor)
    float lowerError = 0, upperError = 0;  ///< angle - lower, upper - angle
    float motorSpeed = 0, maxMotorImpulse = 0;

    Vec3 linearImpulse;  ///< ball, hinge
    float axialImpulse = 0;
    float angularImpulse1 = 0, angularImpulse2 = 0;
    float lowerImpulse = 0, upperImpulse = 0, motorImpulse = 0;
};

/// What a substep measures a joint's errors from: its geometry at the step's start (world frame).
struct JointFrame {
    Vec3 rA, rB;                ///< anchors from the centres of mass
    Vec3 centres;               ///< centre of mass of B - centre of mass of A
    Vec3 axisA, axisB, t1, t2;  ///< hinge: the bodies' axes, and two directions perpendicular to A's
    Quat orientationA;          ///< hinge limits: A's orientation, and B's times the inverse reference rotation
    Quat orientationBReference;
    Vec3 localAxisA;
    float lowerAngle = 0, upperAngle = 0;
    float length = 0;  ///< distance, spring: rest length
};

/// Current hinge angle of a joint (B relative to A about A's axis, zero at creation), rad in (-pi, pi].
float hingeAngle(const Joint& joint, const BodyStorage& storage);

class JointSolver {
public:
    /// The moving bodies of the unbroken joints (rows for the contact solver, edges for the island builder) and the
    /// jointed pairs whose contacts are not solved. Call before the islands are built.
    void couple(const JointStore& store, const BodyStorage& bodies, JointCoupling& out, TaskPool& pool) const;
    /// Builds the step's rows from the bodies' poses and the impulses kept in the store (zero without warm starting),
    /// and lists them by the contact solver's segment of their island (with `islands`, built over the same contacts
    /// as the contact solver's prepare(); without, every joint is in one segment). `h` is the substep. Call once per
    /// step, after ContactSolver::prepare.
    void prepare(const JointStore& store, const BodyStorage& bodies, const ContactSolver& contacts,
                 const JointCoupling& coupling, const WorldSettings& settings, float h, TaskPool& pool,
                 const Islands* islands = nullptr);
    /// Starts a substep for one segment's joints: measures their errors from the body rows' motion
    /// (call after ContactSolver::loadBodies), then applies the accumulated impulses (with `warm`) or clears them.
    /// `pool` runs a coloured segment's colours across the threads (pass none from inside a task).
    void beginSubstep(SolverBodies& rows, bool warm, std::uint32_t segment, TaskPool* pool = nullptr);
    /// One iteration over one segment's joints. Without bias (the soft step's relax iterations) rigid rows only
    /// remove relative velocity and springs are left alone: their softness is the physics, not a correction.
    void solve(SolverBodies& rows, bool useBias, std::uint32_t segment, TaskPool* pool = nullptr);
    /// Keeps the impulses for the next step, records the reaction force and torque, and breaks the joints whose
    /// force or torque exceeded their threshold (they are skipped from then on). Call after the step's last
    /// substep.
    void finish(JointStore& store, TaskPool& pool);

    /// The step's rows, by joint, of the joints not solved in SIMD batches (see batchedJoints()).
    const std::vector<JointRow>& rows() const { return rows_; }
    /// Colours of the large islands' joints (0 when they run serially in store order), and how many of their joints
    /// run in SIMD batches.
    std::uint32_t colourCount() const { return static_cast<std::uint32_t>(colours_.size()); }
    std::uint32_t batchedJoints() const { return batchedJoints_; }
    /// Whether the large islands' joints run as two slabs and the joints between them.
    bool slabs() const { return groups_.size() == 3; }

private:
    static constexpr std::uint32_t kInactive = ~0u;
    /// What partitioning and colouring read of a joint: its body rows (-1 for static bodies), which sides the solver
    /// moves, its segment (kInactive when broken or with no dynamic side), and whether it runs in a SIMD batch.
    struct JointLink {
        std::int32_t rowA = -1, rowB = -1;
        std::uint32_t segment = kInactive;
        bool dynamicA = false, dynamicB = false, ball = false, batched = false;
        /// The same bodies and segment (batched is the layout's, not the joint's).
        bool sameBodies(const JointLink& o) const {
            return rowA == o.rowA && rowB == o.rowB && segment == o.segment && dynamicA == o.dynamicA &&
                   dynamicB == o.dynamicB && ball == o.ball;
        }
    };
    struct BuildInputs {
        const JointStore& store;
        const BodyStorage& storage;
        const ContactSolver& contacts;
        const JointCoupling& coupling;
        BallJointSoftness rigid;
        float h;
        bool warm;
    };
    void buildRow(std::uint32_t joint, const BuildInputs& in);
    void buildBatch(BallJointBatch& b, std::uint32_t first, std::uint32_t count, std::int32_t stillRow,
                    const BuildInputs& in) const;
    void beginRow(JointRow& r, const JointFrame& f, SolverBodies& rows, bool warm) const;
    void solveRow(JointRow& r, SolverBodies& rows, bool useBias, float invH);
    void partition(const ContactSolver& contacts, const MovingBodies& m, std::uint32_t segments);
    void colourLarge(const ContactSolver& contacts, const MovingBodies& m);
    /// Colours segmentRows_[begin, begin + count) as one group (see groups_).
    void colourGroup(const ContactSolver& contacts, std::uint32_t begin, std::uint32_t count,
                     std::uint32_t& batchCount);
    /// Runs one segment: row(index into rows_) over its joints in store order, or colour by colour, batch(batch,
    /// body rows) over the colour's ball-joint batches and row() over its other joints, across the pool's threads.
    template <class Batch, class Row>
    void forEachJoint(std::uint32_t segment, SolverBodies& rows, TaskPool* pool, Batch&& batch, Row&& row);

    /// One colour of the large islands' joints: its ball joints segmentRows_[firstBall, first) in batches
    /// [firstBatch, + batchCount), then its other joints segmentRows_[first, last) one by one (all of them,
    /// serially, in the overflow colour).
    struct Colour {
        std::uint32_t firstBatch = 0, batchCount = 0;
        std::uint32_t firstBall = 0, first = 0, last = 0;
        bool overflow = false;
    };

    std::vector<JointRow> rows_;
    std::vector<JointFrame> frames_;    ///< by row
    std::vector<JointLink> links_;      ///< by joint
    std::vector<JointLink> lastLinks_;  ///< the links segmentStart_ .. batches_ were laid out for
    std::uint32_t linkedSegments_ = 0;
    std::vector<std::uint32_t> segmentFill_;
    std::vector<std::uint8_t> breaking_;       ///< by joint, in finish()
    std::vector<std::uint32_t> segmentStart_;  ///< segment k's joints are segmentRows_[segmentStart_[k], ...[k + 1])
    std::vector<std::uint32_t> segmentRows_;   ///< indices into rows_, in store order within a segment (or by colour)
    std::vector<Colour> colours_;              ///< empty when the large islands' joints run serially
    /// Colours [firstColour, + colourCount) coloured together: all the large islands' joints, or two slabs and the
    /// joints that cross them (colourLarge()).
    struct Group {
        std::uint32_t firstColour = 0, colourCount = 0;
    };
    std::vector<Group> groups_;
    std::vector<float> slabKeys_;
    AlignedVector<BallJointBatch> batches_;
    /// Batch k's lanes are joints segmentRows_[first, first + count).
    struct BatchJoints {
        std::uint32_t first = 0, count = 0;
    };
    std::vector<BatchJoints> batchJoints_;
    std::uint32_t batchedJoints_ = 0;
    BallJointSoftness rigid_;                  ///< the step's softness of rigid rows
    std::vector<std::uint64_t> bodyColours_;   ///< colouring scratch, by body row
    std::vector<std::uint8_t> colourOf_;       ///< colouring scratch, by joint of the large segment
    std::vector<std::uint32_t> orderScratch_;  ///< a range of segmentRows_ being reordered
    float h_ = 0;
};

}  // namespace rubble::detail
