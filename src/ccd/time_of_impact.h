#pragma once
// Time of impact of a body moving over one step against a shape that stays still: conservative advancement on the
// GJK distance (Mirtich 1996). The body's centre of mass moves on a line and its orientation turns at a constant
// rate about a fixed axis, so no point of it moves faster than |dc| + angle * reach per unit of step time; advancing
// by distance / (that bound projected on the separating normal) can never pass the first contact. It lands on it in
// one advance for a face met head-on and converges from the safe side elsewhere; when it runs out of iterations the
// time it reached is still before the contact.
#include "narrowphase/gjk.h"
#include "rubble/math.h"

namespace rubble::detail {

/// A body's motion over a step, t from 0 to 1: the centre of mass from c0 to c1 in a line, the orientation from q0 to
/// q1 about one axis at a constant rate (the shorter way).
class BodySweep {
public:
    BodySweep(Vec3 c0, Quat q0, Vec3 c1, Quat q1, Vec3 localCenter);
    /// The body frame (its origin, not its centre of mass) at t.
    Transform at(float t) const;
    Vec3 translation() const { return c1_ - c0_; }
    float angle() const { return angle_; }  ///< radians turned over the whole step

private:
    Vec3 c0_, c1_, axis_, localCenter_;
    Quat q0_;
    float angle_ = 0;
};

struct TimeOfImpact {
    enum class State : unsigned char {
        Separated,  ///< no contact within the step
        Hit,        ///< first within `gap` of the target at t
        Touching,   ///< already within `gap` at t = 0 (the step's contacts have it)
    };
    State state = State::Separated;
    float t = 1;
    Vec3 normal;  ///< from the body towards the target, at t
    int iterations = 0;
};

/// First t in [0, 1] at which `part` (posed in the body frame by part.pose), carried by `sweep`, comes within `gap`
/// (> 0) of `target` (posed in the world), to `tolerance`. `reach` bounds the distance of the part's core from the
/// body's centre of mass (radians of turn move it at most that far per radian).
TimeOfImpact timeOfImpact(const GjkShape& part, const BodySweep& sweep, float reach, const GjkShape& target, float gap,
                          float tolerance);

}  // namespace rubble::detail
