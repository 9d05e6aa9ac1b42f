// Time of impact (ccd/time_of_impact.h) against closed forms: spheres, boxes and capsules moving at a wall, and a
// spinning rod whose tip reaches a wall (solved independently by bisection on the rod's corners in double). The
// issue's bound is 1e-4 s; a step of 1/60 s is the sweep's unit, so that is 6e-3 of it. The kernel is asked for
// touching (gap 1e-5 m, tolerance 1e-5 m), so it stops within 2e-5 m of the contact: at these speeds well inside.
#include <gtest/gtest.h>

#include <cmath>

#include "ccd/time_of_impact.h"
#include "narrowphase/gjk.h"

namespace rubble::detail {
namespace {

constexpr double kDt = 1.0 / 60.0;
constexpr double kBound = 1e-4;  // s
constexpr float kGap = 1e-5f;

/// A static wall: a box whose face at x = wallX faces -x.
GjkShape wallAt(float wallX) {
    GjkShape wall;
    wall.core = GjkShape::Core::Box;
    wall.halfExtents = {0.5f, 10, 10};
    wall.pose = {{wallX + 0.5f, 0, 0}, {}};
    return wall;
}

double hitSeconds(const GjkShape& part, const BodySweep& sweep, float reach, const GjkShape& target) {
    const TimeOfImpact toi = timeOfImpact(part, sweep, reach, target, kGap, kGap);
    EXPECT_EQ(toi.state, TimeOfImpact::State::Hit);
    return toi.t * kDt;
}

TEST(TimeOfImpact, SphereAtAWallMatchesTheClosedForm) {
    GjkShape ball;
    ball.core = GjkShape::Core::Point;
    ball.radius = 0.05f;
    for (float speed : {10.0f, 100.0f, 300.0f}) {
        const float move = speed * static_cast<float>(kDt), wallX = 0.3f * move + 0.05f;
        const BodySweep sweep({}, {}, {move, 0, 0}, {}, {});
        // The centre reaches wallX - radius at t = (wallX - r) / move.
        EXPECT_NEAR(hitSeconds(ball, sweep, 0, wallAt(wallX)), (wallX - 0.05) / speed, kBound) << speed;
    }
}

TEST(TimeOfImpact, TurnedBoxAtAWallMatchesTheClosedForm) {
    GjkShape box;
    box.core = GjkShape::Core::Box;
    box.halfExtents = {0.3f, 0.2f, 0.1f};
    for (float yaw : {0.0f, 0.4f, 1.1f}) {
        const Quat q = Quat::fromAxisAngle({0, 1, 0}, yaw);
        // Leading extent along x: |R| h.
        const double lead = 0.3 * std::fabs(std::cos(yaw)) + 0.1 * std::fabs(std::sin(yaw));
        const float speed = 120, move = speed * static_cast<float>(kDt), wallX = 1.2f;
        const BodySweep sweep({}, q, {move, 0, 0}, q, {});
        EXPECT_NEAR(hitSeconds(box, sweep, 0.4f, wallAt(wallX)), (wallX - lead) / speed, kBound) << yaw;
    }
}

TEST(TimeOfImpact, CapsuleSideOnAndEndOnMatchesTheClosedForm) {
    GjkShape capsule;
    capsule.core = GjkShape::Core::Segment;
    capsule.radius = 0.1f;
    capsule.halfHeight = 0.4f;
    const float speed = 200, move = speed * static_cast<float>(kDt), wallX = 2.0f;
    const Quat sideOn{}, endOn = Quat::fromAxisAngle({0, 0, 1}, 1.5707964f);  // axis along y, then along x
    EXPECT_NEAR(hitSeconds(capsule, BodySweep({}, sideOn, {move, 0, 0}, sideOn, {}), 0.4f, wallAt(wallX)),
                (wallX - 0.1) / speed, kBound);
    EXPECT_NEAR(hitSeconds(capsule, BodySweep({}, endOn, {move, 0, 0}, endOn, {}), 0.4f, wallAt(wallX)),
                (wallX - 0.5) / speed, kBound);
}

TEST(TimeOfImpact, SpinningRodTipMatchesBisection) {
    // A rod of half extents (1, 0.01, 0.01), along y at the start, turning about z at `spin` towards a wall at 0.6.
    GjkShape rod;
    rod.core = GjkShape::Core::Box;
    rod.halfExtents = {1, 0.01f, 0.01f};
    const double start = 1.5707963267948966, wallX = 0.6;
    for (double spin : {-50.0, -100.0}) {
        const double turn = spin * kDt;
        const Quat q0 = Quat::fromAxisAngle({0, 0, 1}, static_cast<float>(start));
        const Quat q1 = Quat::fromAxisAngle({0, 0, 1}, static_cast<float>(start + turn));
        const BodySweep sweep({}, q0, {}, q1, {});
        // Largest x over the corners at angle a, and the first a at which it reaches the wall.
        const auto lead = [&](double a) {
            double x = -1e9;
            for (double sx : {-1.0, 1.0})
                for (double sy : {-0.01, 0.01}) x = std::max(x, sx * std::cos(a) - sy * std::sin(a));
            return x;
        };
        double lo = 0, hi = 1;
        for (int i = 0; i < 60; ++i) {
            const double mid = 0.5 * (lo + hi);
            (lead(start + turn * mid) < wallX ? lo : hi) = mid;
        }
        EXPECT_NEAR(hitSeconds(rod, sweep, 1.0001f, wallAt(static_cast<float>(wallX))), lo * kDt, kBound) << spin;
    }
}

TEST(TimeOfImpact, MovingAwayOrStartingInContactIsNoHit) {
    GjkShape ball;
    ball.core = GjkShape::Core::Point;
    ball.radius = 0.5f;
    EXPECT_EQ(timeOfImpact(ball, BodySweep({}, {}, {-2, 0, 0}, {}, {}), 0, wallAt(1), kGap, kGap).state,
              TimeOfImpact::State::Separated);
    EXPECT_EQ(timeOfImpact(ball, BodySweep({}, {}, {0.2f, 0, 0}, {}, {}), 0, wallAt(1), kGap, kGap).state,
              TimeOfImpact::State::Separated);
    EXPECT_EQ(timeOfImpact(ball, BodySweep({0.5f, 0, 0}, {}, {3, 0, 0}, {}, {}), 0, wallAt(1), kGap, kGap).state,
              TimeOfImpact::State::Touching);
}

}  // namespace
}  // namespace rubble::detail
