#pragma once
// Wide 3-vectors, quaternions and 3x3 matrices in SoA form over a lane type F (float or simd::FloatW). The
// formulas are spelled out once here and used by both forms, so scalar and wide results agree bit for bit.
// Quaternions are (x, y, z) vector part and w scalar part, multiplied as in include/rubble/math.h.
// Caveat for float instantiations under GCC 12: its SLP vectoriser may fuse the alternating +/- lanes of the
// quaternion product into vfmsubadd even with -ffp-contract=off; a file that needs bit agreement with the wide form
// disables it (see src/integrate/integrate.cpp).
#include <cstddef>

#include "simd/simd.h"

namespace rubble::simd {

template <class F>
struct Vec3W {
    F x, y, z;

    Vec3W() = default;
    Vec3W(const F& x_, const F& y_, const F& z_) : x(x_), y(y_), z(z_) {}

    static Vec3W zero() { return {F(0.0f), F(0.0f), F(0.0f)}; }
    static Vec3W broadcast(float x_, float y_, float z_) { return {F(x_), F(y_), F(z_)}; }
    /// Loads lanes [i, i + lanesOf<F>) of three SoA arrays.
    static Vec3W load(const float* px, const float* py, const float* pz, std::size_t i) {
        return {simd::load<F>(px + i), simd::load<F>(py + i), simd::load<F>(pz + i)};
    }
    void store(float* px, float* py, float* pz, std::size_t i) const {
        simd::store(px + i, x);
        simd::store(py + i, y);
        simd::store(pz + i, z);
    }

    Vec3W operator+(const Vec3W& b) const { return {x + b.x, y + b.y, z + b.z}; }
    Vec3W operator-(const Vec3W& b) const { return {x - b.x, y - b.y, z - b.z}; }
    Vec3W operator-() const { return {-x, -y, -z}; }
    Vec3W operator*(const F& s) const { return {x * s, y * s, z * s}; }
    Vec3W operator/(const F& s) const { return {x / s, y / s, z / s}; }
    /// Component-wise product.
    Vec3W operator*(const Vec3W& b) const { return {x * b.x, y * b.y, z * b.z}; }
    Vec3W& operator+=(const Vec3W& b) { return *this = *this + b; }
    Vec3W& operator-=(const Vec3W& b) { return *this = *this - b; }
    Vec3W& operator*=(const F& s) { return *this = *this * s; }
    friend Vec3W operator*(const F& s, const Vec3W& v) { return v * s; }
};

template <class F>
F dot(const Vec3W<F>& a, const Vec3W<F>& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class F>
Vec3W<F> cross(const Vec3W<F>& a, const Vec3W<F>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class F>
F lengthSquared(const Vec3W<F>& v) {
    return dot(v, v);
}
template <class F>
F length(const Vec3W<F>& v) {
    return simd::sqrt(dot(v, v));
}
template <class F>
Vec3W<F> select(const MaskOf<F>& m, const Vec3W<F>& a, const Vec3W<F>& b) {
    return {simd::select(m, a.x, b.x), simd::select(m, a.y, b.y), simd::select(m, a.z, b.z)};
}
template <class F>
MaskOf<F> isFinite(const Vec3W<F>& v) {
    return andMask(andMask(isFinite(v.x), isFinite(v.y)), isFinite(v.z));
}
/// Lanes whose every component lies in [-limit, limit] (never a NaN lane).
template <class F>
MaskOf<F> isWithin(const Vec3W<F>& v, float limit) {
    const F l(limit);
    return andMask(andMask(abs(v.x) <= l, abs(v.y) <= l), abs(v.z) <= l);
}
template <class F>
Vec3W<F> min(const Vec3W<F>& a, const Vec3W<F>& b) {
    return {simd::min(a.x, b.x), simd::min(a.y, b.y), simd::min(a.z, b.z)};
}
template <class F>
Vec3W<F> max(const Vec3W<F>& a, const Vec3W<F>& b) {
    return {simd::max(a.x, b.x), simd::max(a.y, b.y), simd::max(a.z, b.z)};
}
template <class F>
Vec3W<F> abs(const Vec3W<F>& v) {
    return {simd::abs(v.x), simd::abs(v.y), simd::abs(v.z)};
}

// ---------------------------------------------------------------------------------------------------------------

template <class F>
struct QuatW {
    F x, y, z, w;

    QuatW() = default;
    QuatW(const F& x_, const F& y_, const F& z_, const F& w_) : x(x_), y(y_), z(z_), w(w_) {}
    /// Pure quaternion (v, 0).
    static QuatW pure(const Vec3W<F>& v) { return {v.x, v.y, v.z, F(0.0f)}; }
    static QuatW identity() { return {F(0.0f), F(0.0f), F(0.0f), F(1.0f)}; }
    static QuatW load(const float* px, const float* py, const float* pz, const float* pw, std::size_t i) {
        return {simd::load<F>(px + i), simd::load<F>(py + i), simd::load<F>(pz + i), simd::load<F>(pw + i)};
    }
    void store(float* px, float* py, float* pz, float* pw, std::size_t i) const {
        simd::store(px + i, x);
        simd::store(py + i, y);
        simd::store(pz + i, z);
        simd::store(pw + i, w);
    }

    Vec3W<F> vec() const { return {x, y, z}; }
    QuatW operator+(const QuatW& b) const { return {x + b.x, y + b.y, z + b.z, w + b.w}; }
    QuatW operator-(const QuatW& b) const { return {x - b.x, y - b.y, z - b.z, w - b.w}; }
    QuatW operator*(const F& s) const { return {x * s, y * s, z * s, w * s}; }
    friend QuatW operator*(const F& s, const QuatW& q) { return q * s; }
};

/// Hamilton product a b (apply b, then a).
template <class F>
QuatW<F> operator*(const QuatW<F>& a, const QuatW<F>& b) {
    return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
template <class F>
QuatW<F> conjugate(const QuatW<F>& q) {
    return {-q.x, -q.y, -q.z, q.w};
}
template <class F>
F dot(const QuatW<F>& a, const QuatW<F>& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
}
/// q / |q| with an exact square root and division (no reciprocal estimate), so both forms agree.
template <class F>
QuatW<F> normalize(const QuatW<F>& q) {
    const F len = simd::sqrt(dot(q, q));
    return {q.x / len, q.y / len, q.z / len, q.w / len};
}
/// Rotates v by the unit quaternion q (same formula as rubble::rotate).
template <class F>
Vec3W<F> rotate(const QuatW<F>& q, const Vec3W<F>& v) {
    const Vec3W<F> u = q.vec();
    const Vec3W<F> t = cross(u, v) * F(2.0f);
    return v + t * q.w + cross(u, t);
}
/// Rotates v by the inverse of the unit quaternion q.
template <class F>
Vec3W<F> rotateInverse(const QuatW<F>& q, const Vec3W<F>& v) {
    return rotate(conjugate(q), v);
}
template <class F>
QuatW<F> select(const MaskOf<F>& m, const QuatW<F>& a, const QuatW<F>& b) {
    return {simd::select(m, a.x, b.x), simd::select(m, a.y, b.y), simd::select(m, a.z, b.z), simd::select(m, a.w, b.w)};
}
template <class F>
MaskOf<F> isFinite(const QuatW<F>& q) {
    return andMask(andMask(isFinite(q.x), isFinite(q.y)), andMask(isFinite(q.z), isFinite(q.w)));
}

// ---------------------------------------------------------------------------------------------------------------

/// General 3x3 matrix, row major: m[r][c] is row r, column c.
template <class F>
struct Mat3W {
    F m[3][3];

    Vec3W<F> row(int r) const { return {m[r][0], m[r][1], m[r][2]}; }
    Vec3W<F> col(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
};

template <class F>
Vec3W<F> operator*(const Mat3W<F>& a, const Vec3W<F>& v) {
    return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z, a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
            a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
/// a^T v.
template <class F>
Vec3W<F> transposeMultiply(const Mat3W<F>& a, const Vec3W<F>& v) {
    return {a.m[0][0] * v.x + a.m[1][0] * v.y + a.m[2][0] * v.z, a.m[0][1] * v.x + a.m[1][1] * v.y + a.m[2][1] * v.z,
            a.m[0][2] * v.x + a.m[1][2] * v.y + a.m[2][2] * v.z};
}

/// Rotation matrix of the unit quaternion q (columns are the rotated basis vectors).
template <class F>
Mat3W<F> rotationMatrix(const QuatW<F>& q) {
    const F one(1.0f), two(2.0f);
    const F xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const F xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    const F wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    Mat3W<F> r;
    r.m[0][0] = one - two * (yy + zz);
    r.m[0][1] = two * (xy - wz);
    r.m[0][2] = two * (xz + wy);
    r.m[1][0] = two * (xy + wz);
    r.m[1][1] = one - two * (xx + zz);
    r.m[1][2] = two * (yz - wx);
    r.m[2][0] = two * (xz - wy);
    r.m[2][1] = two * (yz + wx);
    r.m[2][2] = one - two * (xx + yy);
    return r;
}

/// Solves a x = b by Cramer's rule; det receives det(a). Non-finite where a is singular.
template <class F>
Vec3W<F> solve(const Mat3W<F>& a, const Vec3W<F>& b, F& det) {
    const Vec3W<F> c0 = a.col(0), c1 = a.col(1), c2 = a.col(2);
    const Vec3W<F> c1x2 = cross(c1, c2);
    det = dot(c0, c1x2);
    // x_i = det(a with column i replaced by b) / det(a)
    const F dx = dot(b, c1x2);
    const F dy = dot(c0, cross(b, c2));
    const F dz = dot(c0, cross(c1, b));
    return {dx / det, dy / det, dz / det};
}

// ---------------------------------------------------------------------------------------------------------------

/// Symmetric 3x3 matrix (inertia tensors): six unique entries.
template <class F>
struct SymMat3W {
    F xx, yy, zz, xy, xz, yz;

    static SymMat3W load(const float* pxx, const float* pyy, const float* pzz, const float* pxy, const float* pxz,
                         const float* pyz, std::size_t i) {
        return {simd::load<F>(pxx + i), simd::load<F>(pyy + i), simd::load<F>(pzz + i),
                simd::load<F>(pxy + i), simd::load<F>(pxz + i), simd::load<F>(pyz + i)};
    }
    void store(float* pxx, float* pyy, float* pzz, float* pxy, float* pxz, float* pyz, std::size_t i) const {
        simd::store(pxx + i, xx);
        simd::store(pyy + i, yy);
        simd::store(pzz + i, zz);
        simd::store(pxy + i, xy);
        simd::store(pxz + i, xz);
        simd::store(pyz + i, yz);
    }
};

template <class F>
Vec3W<F> operator*(const SymMat3W<F>& s, const Vec3W<F>& v) {
    return {s.xx * v.x + s.xy * v.y + s.xz * v.z, s.xy * v.x + s.yy * v.y + s.yz * v.z,
            s.xz * v.x + s.yz * v.y + s.zz * v.z};
}

/// R diag(d) R^T: a principal-frame tensor expressed in the frame R maps to.
template <class F>
SymMat3W<F> rotateDiagonal(const Mat3W<F>& r, const Vec3W<F>& d) {
    const auto entry = [&](int i, int j) {
        return r.m[i][0] * d.x * r.m[j][0] + r.m[i][1] * d.y * r.m[j][1] + r.m[i][2] * d.z * r.m[j][2];
    };
    return {entry(0, 0), entry(1, 1), entry(2, 2), entry(0, 1), entry(0, 2), entry(1, 2)};
}

template <class F>
SymMat3W<F> select(const MaskOf<F>& m, const SymMat3W<F>& a, const SymMat3W<F>& b) {
    return {simd::select(m, a.xx, b.xx), simd::select(m, a.yy, b.yy), simd::select(m, a.zz, b.zz),
            simd::select(m, a.xy, b.xy), simd::select(m, a.xz, b.xz), simd::select(m, a.yz, b.yz)};
}
template <class F>
MaskOf<F> isFinite(const SymMat3W<F>& s) {
    return andMask(andMask(andMask(isFinite(s.xx), isFinite(s.yy)), andMask(isFinite(s.zz), isFinite(s.xy))),
                   andMask(isFinite(s.xz), isFinite(s.yz)));
}

}  // namespace rubble::simd
