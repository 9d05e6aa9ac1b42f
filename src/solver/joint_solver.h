#pragma once
// The joint solver: distance joints, springs, ball joints and hinges (with limits and a motor) as sequential
// impulses in the contact solver's iterations. Each velocity iteration solves every joint, then the contact colours;
// both read and write the same body rows (ContactSolver::bodies()), which prepare() gives to every body a joint
// touches.
//
// Joints are solved serially within their island's segment of the contact solve (ContactSolver::segmentOfIsland):
// a block of small islands solves its joints in its own task, the large islands' joints run on the calling thread,
// each in the joint store's dense order, so the result does not depend on the thread count. A joint costs a few
// tens of nanoseconds per iteration (perf/joint_solver_perf.cpp measures it). Their rows are built in parallel.
//
// Position error is fed back in the velocity rows. With Baumgarte (and with split impulses, whose pseudo-velocities
// only serve contacts) a fraction SolverSettings::baumgarte of the error is removed per substep; with the soft step
// the rows are soft constraints at SolverSettings::jointHertz and the relax iterations take the push-out velocity
// away again. Springs are always soft constraints built from their stiffness k and damping c (Catto, "Soft
// Constraints", GDC 2011): with the substep h, gamma = 1 / (h (c + h k)) and beta = h k / (c + h k), which is the
// damped spring integrated implicitly over the substep, stable for any k. Error and impulses are measured at the
// start of each substep from the bodies' current poses; accumulated impulses persist in the joint store and warm
// start the next substep and step.
#include <cstdint>
#include <vector>

#include "rubble/settings.h"
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

/// One joint prepared for a substep.
struct JointRow {
    std::uint32_t joint = 0;  ///< dense index in the store
    JointType type = JointType::Ball;
    bool active = false;  ///< unbroken, with a dynamic body, and (distance, spring) anchors apart
    bool dynamicA = false, dynamicB = false;
    bool limit = false, motor = false;
    std::int32_t rowA = -1, rowB = -1;  ///< body rows; -1 for a static body
    float invMassA = 0, invMassB = 0;
    JointSym3 inertiaA, inertiaB;  ///< world inverse inertia
    Vec3 rA, rB;                   ///< anchors from the centres of mass, world

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

/// Current hinge angle of a joint (B relative to A about A's axis, zero at creation), rad in (-pi, pi].
float hingeAngle(const Joint& joint, const BodyStorage& storage);

class JointSolver {
public:
    /// The moving bodies of the unbroken joints (rows for the contact solver) and the jointed pairs whose contacts
    /// are not solved. Call before ContactSolver::prepare.
    void couple(const JointStore& store, const BodyStorage& bodies, JointCoupling& out) const;
    /// Builds this substep's rows from the bodies' current poses and the impulses kept in the store (zero without
    /// warm starting). Call after ContactSolver::loadBodies.
    void prepare(const JointStore& store, const BodyStorage& bodies, const ContactSolver& contacts,
                 const WorldSettings& settings, float h, TaskPool& pool);
    /// Lists the active joints by the contact solver's segment of their island (call after prepare(), and after
    /// the contact solver's prepare() with the same islands).
    void partition(const ContactSolver& contacts, const Islands& islands);
    /// Applies the accumulated impulses to the body rows: every joint's, or one segment's (after partition()).
    void warmStart(SolverBodies& rows) const;
    void warmStart(SolverBodies& rows, std::uint32_t segment) const;
    /// One iteration over every joint, or over one segment's. Without bias (the soft step's relax iterations) rigid
    /// rows only remove relative velocity and springs are left alone: their softness is the physics, not a
    /// correction.
    void solve(SolverBodies& rows, bool useBias);
    void solve(SolverBodies& rows, bool useBias, std::uint32_t segment);
    /// Keeps the impulses for the next substep, records the reaction force and torque, and breaks the joints whose
    /// force or torque exceeded their threshold (they are skipped from then on).
    void finish(JointStore& store);

    const std::vector<JointRow>& rows() const { return rows_; }

private:
    void warmStartRow(const JointRow& r, SolverBodies& rows) const;
    void solveRow(JointRow& r, SolverBodies& rows, bool useBias, float invH);

    std::vector<JointRow> rows_;
    std::vector<std::uint32_t> segmentStart_;  ///< segment k's joints are segmentRows_[segmentStart_[k], ...[k + 1])
    std::vector<std::uint32_t> segmentRows_;   ///< indices into rows_, in store order within a segment
    float h_ = 0;
};

}  // namespace rubble::detail
