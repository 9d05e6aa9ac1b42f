#pragma once
// Small scalar value types of the public API. Hot loops use the wide types of simd/ instead.
#include <cmath>

namespace rubble {

struct Vec3 {
    float x = 0, y = 0, z = 0;

    constexpr Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}

    /// Component by axis (0: x, 1: y, 2: z). Reaching y or z through a pointer to x would be undefined behaviour,
    /// and clang builds do not keep what such code meant.
    constexpr float operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
    constexpr float& operator[](int axis) { return axis == 0 ? x : (axis == 1 ? y : z); }

    constexpr Vec3 operator+(Vec3 b) const { return {x + b.x, y + b.y, z + b.z}; }
    constexpr Vec3 operator-(Vec3 b) const { return {x - b.x, y - b.y, z - b.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3& operator+=(Vec3 b) {
        x += b.x;
        y += b.y;
        z += b.z;
        return *this;
    }
    constexpr Vec3& operator-=(Vec3 b) {
        x -= b.x;
        y -= b.y;
        z -= b.z;
        return *this;
    }
    constexpr Vec3& operator*=(float s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    friend constexpr Vec3 operator*(float s, Vec3 v) { return v * s; }
    friend constexpr bool operator==(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
};

constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(Vec3 v) { return std::sqrt(dot(v, v)); }
inline bool isFinite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// Unit quaternion (x, y, z vector part, w scalar part). Identity by default.
struct Quat {
    float x = 0, y = 0, z = 0, w = 1;

    constexpr Quat() = default;
    constexpr Quat(float x_, float y_, float z_, float w_) : x(x_), y(y_), z(z_), w(w_) {}

    /// Rotation of `radians` about `axis` (normalised here; a zero axis gives the identity).
    static Quat fromAxisAngle(Vec3 axis, float radians) {
        const float len = length(axis);
        if (len == 0) return {};
        const float s = std::sin(0.5f * radians) / len;
        return {axis.x * s, axis.y * s, axis.z * s, std::cos(0.5f * radians)};
    }
    friend constexpr bool operator==(Quat a, Quat b) { return a.x == b.x && a.y == b.y && a.z == b.z && a.w == b.w; }
};

constexpr Quat operator*(Quat a, Quat b) {
    return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
constexpr Quat conjugate(Quat q) { return {-q.x, -q.y, -q.z, q.w}; }
inline bool isFinite(Quat q) {
    return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}

/// Rotates v by the unit quaternion q.
constexpr Vec3 rotate(Quat q, Vec3 v) {
    const Vec3 u{q.x, q.y, q.z};
    const Vec3 t = cross(u, v) * 2.0f;
    return v + t * q.w + cross(u, t);
}

/// Row-major 3x3 matrix; rows[i] is row i.
struct Mat3 {
    Vec3 rows[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

    constexpr float operator()(int r, int c) const { return rows[r][c]; }
    constexpr float& operator()(int r, int c) { return rows[r][c]; }
    static constexpr Mat3 zero() {
        Mat3 m;
        m.rows[0] = m.rows[1] = m.rows[2] = {};
        return m;
    }
    static constexpr Mat3 diagonal(Vec3 d) {
        Mat3 m = zero();
        m.rows[0].x = d.x;
        m.rows[1].y = d.y;
        m.rows[2].z = d.z;
        return m;
    }
};

constexpr Vec3 operator*(const Mat3& m, Vec3 v) { return {dot(m.rows[0], v), dot(m.rows[1], v), dot(m.rows[2], v)}; }

/// Rigid transform: rotate, then translate.
struct Transform {
    Vec3 position;
    Quat rotation;
};

constexpr Vec3 apply(const Transform& t, Vec3 p) { return rotate(t.rotation, p) + t.position; }
/// The inverse of apply: a world point in the transform's local frame.
constexpr Vec3 applyInverse(const Transform& t, Vec3 p) { return rotate(conjugate(t.rotation), p - t.position); }

}  // namespace rubble
