// Viewer cameras: the spring against its closed-form solution, the follow dead zone, and the view matrices and
// picking rays against each other.
#include <gtest/gtest.h>

#include <cmath>

#include "camera.h"

using namespace rubble;
using namespace rubble::viewer;

namespace {

Vec3 transformPoint(const Mat4& m, Vec3 p, float& w) {
    const float x = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    const float y = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    const float z = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14];
    w = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15];
    return {x, y, z};
}

}  // namespace

TEST(CriticallyDampedSpring, SmallStepsFollowTheClosedFormAndNeverOvershoot) {
    // From rest at 1 towards 0: x(t) = (1 + omega t) exp(-omega t), monotone, never below 0. Steps are exact for
    // any dt, so 1000 small steps must land where one big step does (float rounding: 1e-5).
    const CriticallyDampedSpring spring{3.0f};
    Vec3 x{1, 0, 0}, v{};
    for (int i = 0; i < 1000; ++i) {
        const float before = x.x;
        spring.step(x, v, {}, 0.001f);
        EXPECT_LE(x.x, before + 1e-7f);
        EXPECT_GE(x.x, 0.0f);
    }
    const float expected = (1 + 3.0f) * std::exp(-3.0f);
    EXPECT_NEAR(x.x, expected, 1e-5f);
    Vec3 y{1, 0, 0}, w{};
    spring.step(y, w, {}, 1.0f);
    EXPECT_NEAR(y.x, expected, 1e-6f);
    EXPECT_NEAR(v.x, w.x, 1e-5f);
}

TEST(FollowTarget, IgnoresMotionInsideTheDeadZoneAndCatchesUpOutsideIt) {
    FollowTarget follow;
    follow.deadZone = 1.0f;
    follow.reset({0, 0, 0});
    for (int i = 0; i < 120; ++i) follow.update({0.8f * std::sin(0.3f * static_cast<float>(i)), 0, 0}, 1.0f / 60);
    EXPECT_EQ(follow.lookAt, (Vec3{0, 0, 0})) << "a body jiggling inside the dead zone moved the camera";
    // A body that moves 10 m away: the look-at point ends within the dead zone of it, not on it.
    for (int i = 0; i < 600; ++i) follow.update({10, 0, 0}, 1.0f / 60);
    EXPECT_NEAR(follow.lookAt.x, 9.0f, 0.01f);
}

TEST(OrbitCamera, TargetProjectsToTheCentreAndTheCentreRayHitsIt) {
    OrbitCamera camera;
    camera.target = {3, 1, -2};
    camera.yaw = 0.8f;
    camera.pitch = 0.3f;
    camera.distance = 12;
    const Mat4 viewProjection = multiply(camera.projection(16.0f / 9.0f), camera.view());
    float w = 0;
    const Vec3 clip = transformPoint(viewProjection, camera.target, w);
    EXPECT_NEAR(clip.x / w, 0, 1e-5f);
    EXPECT_NEAR(clip.y / w, 0, 1e-5f);
    EXPECT_NEAR(length(camera.eye() - camera.target), 12, 1e-4f);
    // A pixel's ray projects back to that pixel: take a point along it and project it.
    Vec3 origin, direction;
    camera.rayThroughPixel(100, 50, 1600, 900, origin, direction);
    const Vec3 p = transformPoint(viewProjection, origin + direction * 20.0f, w);
    EXPECT_NEAR((p.x / w + 1) * 0.5f * 1600 - 0.5f, 100, 0.05f);
    EXPECT_NEAR((1 - p.y / w) * 0.5f * 900 - 0.5f, 50, 0.05f);
}

TEST(OrbitCamera, PitchStopsShortOfThePoles) {
    OrbitCamera camera;
    camera.orbit(0, 10);
    EXPECT_LT(camera.pitch, 1.5708f);
    EXPECT_TRUE(isFinite(camera.right()));
    EXPECT_GT(length(camera.right()), 0.99f);
}
