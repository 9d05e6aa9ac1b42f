#pragma once
// Joints as the world stores them: one record per joint in a dense array, a slot map that turns a JointId into the
// dense index (removal swaps the last joint into the hole), and, per body slot, the joints attached to the body so
// that destroying a body finds its joints without a scan.
//
// Joints name their bodies by BodyId, not by dense index: a moving body's dense index changes when another body is
// removed (swap-remove), so the solver resolves the handles to rows when it prepares a step.
#include <cstdint>
#include <vector>

#include "rubble/id.h"
#include "rubble/joint.h"
#include "rubble/math.h"
#include "storage/body_storage.h"
#include "storage/slot_map.h"

namespace rubble::detail {

struct Joint {
    JointType type = JointType::Ball;
    BodyId bodyA, bodyB;
    Vec3 localAnchorA, localAnchorB;  ///< relative to each body's origin, body frame
    Vec3 localAxisA, localAxisB;      ///< hinge, unit, body frame
    /// Hinge: conj(qA) qB at creation, so that the hinge angle is measured from the pose the joint was made in.
    Quat referenceRotation;
    float length = 0;  ///< distance: rod length; spring: rest length
    float stiffness = 0, damping = 0;
    float lowerAngle = 0, upperAngle = 0;
    float motorSpeed = 0, maxMotorTorque = 0;
    float breakForce = 0, breakTorque = 0;
    bool collideConnected = false;
    bool enableLimit = false;
    bool enableMotor = false;
    bool broken = false;

    // Accumulated impulses of the last substep, kept for warm starting the next one (and the next step). Vectors are
    // world-frame impulses on B, so that they keep their meaning when the joint's rows turn with the bodies.
    Vec3 linearImpulse;   ///< ball, hinge: the point rows; distance, spring: along the anchors' line
    Vec3 angularImpulse;  ///< hinge: the two rows that keep the axes aligned
    float lowerImpulse = 0, upperImpulse = 0, motorImpulse = 0;  ///< hinge, about the axis
    Vec3 reactionForce, reactionTorque;                          ///< of the last substep the joint acted in

    std::uint32_t slot = 0;  ///< back-reference: dense index -> slot
};

class JointStore {
public:
    /// Adds a joint (already validated) and links it to its bodies' slots.
    JointId add(const Joint& joint);
    /// Unlinks and removes the joint; the last joint moves into its dense index.
    void remove(JointId id);
    /// Null when the handle is null, out of range or stale.
    Joint* find(JointId id);
    const Joint* find(JointId id) const;
    /// Removes every joint attached to the body; returns how many.
    std::uint32_t removeAttachedTo(BodyId body);

    std::vector<Joint>& joints() { return joints_; }
    const std::vector<Joint>& joints() const { return joints_; }
    std::uint32_t size() const { return static_cast<std::uint32_t>(joints_.size()); }
    /// Joints that have not broken.
    std::uint32_t activeCount() const { return size() - brokenCount_; }
    /// Changes whenever a joint is added, removed or broken (unique across stores): which bodies the unbroken joints
    /// join is the same as long as it does.
    std::uint64_t pairsVersion() const { return pairsVersion_; }
    JointId idOf(std::uint32_t dense) const { return ids_.idAt(joints_[dense].slot); }

    /// Marks a joint broken and queues its report.
    void markBroken(std::uint32_t dense);
    std::vector<JointId>& brokenReports() { return brokenReports_; }

private:
    void unlink(std::uint32_t bodySlot, std::uint32_t jointSlot);

    std::vector<Joint> joints_;
    SlotMap<JointId> ids_;
    std::vector<std::uint32_t> denseOfSlot_;                ///< joint slot -> index in joints_
    std::vector<std::vector<std::uint32_t>> jointsOfBody_;  ///< body slot -> joint slots
    std::vector<JointId> brokenReports_;
    std::uint32_t brokenCount_ = 0;
    std::uint64_t pairsVersion_ = nextPairsVersion();
    static std::uint64_t nextPairsVersion();
};

}  // namespace rubble::detail
