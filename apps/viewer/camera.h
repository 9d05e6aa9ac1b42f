#pragma once
// Cameras of the viewer: an orbit camera (yaw, pitch, distance about a look-at point) and a follow mode that moves
// the look-at point after a body with a dead zone and a critically damped spring, so small motions do not shake
// the view. No OpenGL here: the matrices are plain arrays the renderer uploads.
#include <array>

#include "rubble/math.h"

namespace rubble::viewer {

/// Column-major 4x4 matrix, as OpenGL takes it.
using Mat4 = std::array<float, 16>;

Mat4 multiply(const Mat4& a, const Mat4& b);
Mat4 perspective(float verticalFovRadians, float aspect, float nearPlane, float farPlane);
Mat4 lookAt(Vec3 eye, Vec3 target, Vec3 up);

/// One axis of a critically damped spring (no overshoot, fastest settling without it), stepped exactly:
/// x(t) = (c1 + c2 t) exp(-omega t) about the target.
struct CriticallyDampedSpring {
    float omega = 4.0f;  ///< stiffness as an angular frequency, 1/s; settles in about 4 / omega seconds

    /// Moves `value` (with its velocity) towards `target` over `dt` seconds.
    void step(Vec3& value, Vec3& velocity, Vec3 target, float dt) const;
};

/// Where a follow camera aims: it stays put while the followed point is within `deadZone` of it and, when the
/// point leaves, is pulled by the spring towards the nearest point that has it back inside.
struct FollowTarget {
    float deadZone = 1.0f;  ///< m
    CriticallyDampedSpring spring;
    Vec3 lookAt, velocity;

    void reset(Vec3 at) {
        lookAt = at;
        velocity = {};
    }
    void update(Vec3 followed, float dt);
};

/// Orbit camera around `target`. Angles in radians: yaw about +y, pitch above the horizon.
struct OrbitCamera {
    Vec3 target{0, 2, 0};
    float yaw = 0.6f;
    float pitch = 0.45f;
    float distance = 30.0f;
    float verticalFov = 0.9f;  ///< radians
    float nearPlane = 0.05f, farPlane = 2000.0f;

    Vec3 eye() const;
    /// Unit vectors of the view: forward (eye to target), right and up.
    Vec3 forward() const;
    Vec3 right() const;
    Vec3 up() const;

    void orbit(float dYaw, float dPitch);
    /// Wheel zoom: each notch scales the distance by 0.9 (in) or 1/0.9 (out).
    void zoom(float notches);
    /// Moves the target in the view plane by a fraction of the view's height (so panning feels the same at any
    /// distance).
    void pan(float dxFraction, float dyFraction);

    Mat4 view() const;
    Mat4 projection(float aspect) const;
    /// World-space ray through the pixel (x right, y down) of a viewport of `width` x `height` pixels.
    void rayThroughPixel(float x, float y, float width, float height, Vec3& origin, Vec3& direction) const;
};

}  // namespace rubble::viewer
