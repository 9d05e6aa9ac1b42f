#pragma once
// Joints: constraints between two bodies (or a body and the world, through a static body). Every joint is created
// from a *Def with defaults; anchors are points in each body's local frame (relative to the body's origin, the point
// BodyDef::position places), axes are directions in each body's local frame. One side may be static; the same body
// twice, or two static bodies, is refused.
//
// Every joint can break: when the force it had to apply in a substep (accumulated impulse / substep) exceeds
// breakForce, or its torque exceeds breakTorque, it stops acting at once and is reported by World::takeBrokenJoints.
#include <limits>
#include <optional>

#include "rubble/id.h"
#include "rubble/math.h"

namespace rubble {

enum class JointType : unsigned char { Distance, Spring, Ball, Hinge };

/// What every joint has.
struct JointBase {
    BodyId bodyA;  ///< required
    BodyId bodyB;  ///< required, not bodyA
    Vec3 localAnchorA;
    Vec3 localAnchorB;
    /// The bodies' contacts with each other are solved only when true (a chain's overlapping links usually must not).
    bool collideConnected = false;
    /// Linear reaction force above which the joint breaks, N (> 0; infinity: never).
    float breakForce = std::numeric_limits<float>::infinity();
    /// Reaction torque above which the joint breaks, N m (> 0; infinity: never). Only hinges apply torques.
    float breakTorque = std::numeric_limits<float>::infinity();
};

/// A rigid rod between the two anchors.
struct DistanceJointDef : JointBase {
    /// Rod length, m (>= 1e-3; use a ball joint for coincident anchors). Empty: the anchors' distance at creation.
    std::optional<float> length;
};

/// A damped spring between the two anchors: force k (d - restLength) + c d'(d) along the line of the anchors.
/// Solved as a soft constraint (implicit in the substep), so it stays stable however stiff it is.
struct SpringJointDef : JointBase {
    float stiffness = 100.0f;  ///< k, N/m, >= 0
    float damping = 0.0f;      ///< c, N s/m, >= 0
    /// m, >= 0. Empty: the anchors' distance at creation.
    std::optional<float> restLength;
};

/// Ball and socket: the two anchors coincide; the bodies turn freely about it.
struct BallJointDef : JointBase {};

/// Hinge: a ball joint whose bodies may only turn relative to each other about the hinge axis (localAxisA in A,
/// localAxisB in B, kept aligned). The hinge angle is B's rotation about the axis relative to A, zero at creation.
struct HingeJointDef : JointBase {
    Vec3 localAxisA{0, 1, 0};  ///< non-zero; normalised
    Vec3 localAxisB{0, 1, 0};  ///< non-zero; normalised
    bool enableLimit = false;
    float lowerAngle = 0.0f;  ///< rad, in [-pi, upperAngle]
    float upperAngle = 0.0f;  ///< rad, in [lowerAngle, pi]
    /// A motor drives the relative angular speed about the axis towards motorSpeed with at most maxMotorTorque.
    bool enableMotor = false;
    float motorSpeed = 0.0f;      ///< rad/s
    float maxMotorTorque = 0.0f;  ///< N m, >= 0
};

}  // namespace rubble
