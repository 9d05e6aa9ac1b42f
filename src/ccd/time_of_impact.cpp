// Conservative advancement on the GJK distance; see time_of_impact.h.
#include "ccd/time_of_impact.h"

#include <cmath>

namespace rubble::detail {
namespace {

/// Advances before giving up (each is one GJK query). Head-on faces take one; a body grazing a curved target takes
/// the most, and stopping early leaves it short of the contact, never past it.
constexpr int kMaxAdvances = 32;

}  // namespace

BodySweep::BodySweep(Vec3 c0, Quat q0, Vec3 c1, Quat q1, Vec3 localCenter)
    : c0_(c0), c1_(c1), localCenter_(localCenter), q0_(q0) {
    // q1 q0^-1 as an axis and an angle, on the short side of the double cover.
    Quat d = q1 * conjugate(q0);
    if (d.w < 0) d = {-d.x, -d.y, -d.z, -d.w};
    const float s = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    angle_ = 2.0f * std::atan2(s, d.w);
    axis_ = s > 1e-12f ? Vec3{d.x / s, d.y / s, d.z / s} : Vec3{1, 0, 0};
}

Transform BodySweep::at(float t) const {
    const Quat q = angle_ > 0 ? Quat::fromAxisAngle(axis_, angle_ * t) * q0_ : q0_;
    const Vec3 c = c0_ + (c1_ - c0_) * t;
    return {c - rotate(q, localCenter_), q};
}

TimeOfImpact timeOfImpact(const GjkShape& part, const BodySweep& sweep, float reach, const GjkShape& target, float gap,
                          float tolerance) {
    TimeOfImpact out;
    const Vec3 move = sweep.translation();
    const float turn = sweep.angle() * reach;
    GjkShape moving = part;
    GjkSettings settings;
    float t = 0;
    for (int i = 0; i < kMaxAdvances; ++i) {
        const Transform body = sweep.at(t);
        moving.pose = {apply(body, part.pose.position), body.rotation * part.pose.rotation};
        const GjkResult g = gjkDistance(moving, target, settings);
        out.iterations = i + 1;
        // Cores overlapping: deeper than any rounding; the step's own contacts hold the body (t = 0), or the last
        // advance stepped onto the target, which the margin of `gap` keeps from happening but rounding might.
        const float distance = g.status == GjkStatus::CoresOverlap ? -INFINITY : g.distance;
        if (distance <= gap + tolerance) {
            out.state = t == 0 ? TimeOfImpact::State::Touching : TimeOfImpact::State::Hit;
            out.t = t;
            out.normal = g.status == GjkStatus::CoresOverlap ? out.normal : g.normal;
            return out;
        }
        out.normal = g.normal;
        settings.initialDirection = g.normal;
        const float closing = dot(move, g.normal) + turn;
        if (!(closing > 0)) break;  // moving away along the separating direction: it cannot close
        t += (distance - gap) / closing;
        if (!(t < 1)) break;
        if (i + 1 == kMaxAdvances) {
            // Out of advances short of the contact: stop there, which is safe.
            out.state = TimeOfImpact::State::Hit;
            out.t = t;
            return out;
        }
    }
    out.state = TimeOfImpact::State::Separated;
    out.t = 1;
    return out;
}

}  // namespace rubble::detail
