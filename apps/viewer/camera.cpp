// Camera maths of the viewer (see camera.h).
#include "camera.h"

#include <algorithm>
#include <cmath>

namespace rubble::viewer {

namespace {

Vec3 normalized(Vec3 v) {
    const float len = length(v);
    return len > 0 ? v / len : Vec3{};
}

constexpr float kMaxPitch = 1.55f;  // just short of straight up or down, where yaw would be undefined

}  // namespace

Mat4 multiply(const Mat4& a, const Mat4& b) {
    Mat4 m{};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            float sum = 0;
            for (int k = 0; k < 4; ++k) sum += a[k * 4 + r] * b[c * 4 + k];
            m[c * 4 + r] = sum;
        }
    return m;
}

Mat4 perspective(float verticalFovRadians, float aspect, float nearPlane, float farPlane) {
    const float f = 1.0f / std::tan(0.5f * verticalFovRadians);
    Mat4 m{};
    m[0] = f / aspect;
    m[5] = f;
    m[10] = (farPlane + nearPlane) / (nearPlane - farPlane);
    m[11] = -1;
    m[14] = 2 * farPlane * nearPlane / (nearPlane - farPlane);
    return m;
}

Mat4 lookAt(Vec3 eye, Vec3 target, Vec3 up) {
    const Vec3 f = normalized(target - eye);
    const Vec3 s = normalized(cross(f, up));
    const Vec3 u = cross(s, f);
    Mat4 m{};
    m[0] = s.x, m[4] = s.y, m[8] = s.z;
    m[1] = u.x, m[5] = u.y, m[9] = u.z;
    m[2] = -f.x, m[6] = -f.y, m[10] = -f.z;
    m[12] = -dot(s, eye), m[13] = -dot(u, eye), m[14] = dot(f, eye);
    m[15] = 1;
    return m;
}

void CriticallyDampedSpring::step(Vec3& value, Vec3& velocity, Vec3 target, float dt) const {
    const Vec3 c1 = value - target;
    const Vec3 c2 = velocity + c1 * omega;
    const float decay = std::exp(-omega * dt);
    const Vec3 offset = (c1 + c2 * dt) * decay;
    velocity = (c2 - (c1 + c2 * dt) * omega) * decay;
    value = target + offset;
}

void FollowTarget::update(Vec3 followed, float dt) {
    const Vec3 away = lookAt - followed;
    const float distance = length(away);
    // Inside the dead zone the goal is where the camera already looks: the spring only bleeds off its velocity.
    const Vec3 goal = distance <= deadZone ? lookAt : followed + away * (deadZone / distance);
    spring.step(lookAt, velocity, goal, dt);
}

Vec3 OrbitCamera::forward() const {
    return {-std::cos(pitch) * std::sin(yaw), -std::sin(pitch), -std::cos(pitch) * std::cos(yaw)};
}
Vec3 OrbitCamera::eye() const { return target - forward() * distance; }
Vec3 OrbitCamera::right() const { return normalized(cross(forward(), {0, 1, 0})); }
Vec3 OrbitCamera::up() const { return cross(right(), forward()); }

void OrbitCamera::orbit(float dYaw, float dPitch) {
    yaw += dYaw;
    pitch = std::clamp(pitch + dPitch, -kMaxPitch, kMaxPitch);
}

void OrbitCamera::zoom(float notches) { distance = std::clamp(distance * std::pow(0.9f, notches), 0.5f, 1500.0f); }

void OrbitCamera::pan(float dxFraction, float dyFraction) {
    const float viewHeight = 2 * distance * std::tan(0.5f * verticalFov);
    target += right() * (-dxFraction * viewHeight) + up() * (dyFraction * viewHeight);
}

Mat4 OrbitCamera::view() const { return lookAt(eye(), target, {0, 1, 0}); }

Mat4 OrbitCamera::projection(float aspect) const { return perspective(verticalFov, aspect, nearPlane, farPlane); }

void OrbitCamera::rayThroughPixel(float x, float y, float width, float height, Vec3& origin, Vec3& direction) const {
    const float ndcX = 2 * (x + 0.5f) / width - 1;
    const float ndcY = 1 - 2 * (y + 0.5f) / height;
    const float t = std::tan(0.5f * verticalFov);
    origin = eye();
    direction = normalized(forward() + right() * (ndcX * t * width / height) + up() * (ndcY * t));
}

}  // namespace rubble::viewer
