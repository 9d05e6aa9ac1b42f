#pragma once
// Independent answers for the query tests, written for the tests and sharing no code with src/query/:
//  - closed forms in double for spheres and boxes, and Moller-Trumbore in double for triangles;
//  - for any convex pair, the first contact along a sweep by search on the GJK distance (narrowphase/gjk.h): the
//    distance is a convex function of the travel, so a ternary search finds its minimum (or a point of overlap) and
//    a bisection then finds the first touch. A different algorithm from conservative advancement or ray clipping.
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "narrowphase/gjk.h"
#include "rubble/math.h"

namespace rubble::test {

struct D3 {
    double x = 0, y = 0, z = 0;
};
inline D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }
inline D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dotD(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline D3 crossD(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

inline Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> n(0.0f, 1.0f);
    Quat q{n(rng), n(rng), n(rng), n(rng)};
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    return {q.x / len, q.y / len, q.z / len, q.w / len};
}

inline Vec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<float> n(0.0f, 1.0f);
    const Vec3 v{n(rng), n(rng), n(rng)};
    return v / length(v);
}

/// Entry parameter of the ray into the sphere, double; empty when it misses or starts inside.
inline std::optional<double> raySphereRef(Vec3 o, Vec3 d, Vec3 c, double r) {
    const D3 m = d3(o) - d3(c), dir = d3(d);
    const double a = dotD(dir, dir), b = dotD(m, dir), cc = dotD(m, m) - r * r;
    const double disc = b * b - a * cc;
    if (cc < 0 || disc < 0) return std::nullopt;
    const double t = (-b - std::sqrt(disc)) / a;
    if (t < 0) return std::nullopt;
    return t;
}

/// Entry parameter of the ray into the box [-h, h] (local frame), double slabs; empty on a miss or a start inside.
inline std::optional<double> rayBoxRef(Vec3 o, Vec3 d, Vec3 h) {
    double t0 = 0, t1 = 1e300;
    bool inside = true;
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z}, hh[3] = {h.x, h.y, h.z};
    for (int a = 0; a < 3; ++a) {
        inside = inside && std::fabs(oo[a]) < hh[a];
        if (dd[a] == 0) {
            if (std::fabs(oo[a]) > hh[a]) return std::nullopt;
            continue;
        }
        double lo = (-hh[a] - oo[a]) / dd[a], hi = (hh[a] - oo[a]) / dd[a];
        if (lo > hi) std::swap(lo, hi);
        t0 = std::max(t0, lo), t1 = std::min(t1, hi);
    }
    if (inside || t0 > t1) return std::nullopt;
    return t0;
}

/// Moller-Trumbore in double, both faces; empty on a miss.
inline std::optional<double> rayTriangleRef(Vec3 o, Vec3 d, Vec3 a, Vec3 b, Vec3 c) {
    const D3 e1 = d3(b) - d3(a), e2 = d3(c) - d3(a), dir = d3(d);
    const D3 p = crossD(dir, e2);
    const double det = dotD(e1, p);
    if (std::fabs(det) < 1e-300) return std::nullopt;
    const D3 s = d3(o) - d3(a);
    const double u = dotD(s, p) / det;
    if (u < 0 || u > 1) return std::nullopt;
    const D3 q = crossD(s, e1);
    const double v = dotD(dir, q) / det;
    if (v < 0 || u + v > 1) return std::nullopt;
    const double t = dotD(e2, q) / det;
    if (t < 0) return std::nullopt;
    return t;
}

/// What the search found for a convex pair swept along a direction.
struct SweepReference {
    enum class Kind { Miss, Hit, StartsInside, Ambiguous } kind = Kind::Miss;
    double t = 0;
};

/// First travel t in [0, maxT] at which `moving`, translated by dir * t, touches `target`. Ambiguous when the closest
/// approach is within `band` of touching (a grazing sweep, where either answer is right).
inline SweepReference sweepReference(const detail::GjkShape& moving, Vec3 dir, double maxT,
                                     const detail::GjkShape& target, double band = 2e-5) {
    // GJK's default tolerance calls cores within 1e-6 m touching, which for a grazing sweep (closing at a few percent
    // of its speed) would put the contact 1e-4 m early; the reference wants the contact itself.
    detail::GjkSettings settings;
    settings.absoluteTolerance = 1e-9f;
    auto at = [&](double t) {
        detail::GjkShape a = moving;
        a.pose.position =
            Vec3{float(double(moving.pose.position.x) + dir.x * t), float(double(moving.pose.position.y) + dir.y * t),
                 float(double(moving.pose.position.z) + dir.z * t)};
        const detail::GjkResult g = detail::gjkDistance(a, target, settings);
        return g.status == detail::GjkStatus::Separated ? double(g.distance) : -1.0;
    };
    SweepReference r;
    if (at(0) < 0) return {SweepReference::Kind::StartsInside, 0};
    double lo = 0, hi = maxT, inside = -1;
    for (int i = 0; i < 200 && hi - lo > 1e-9 * (1 + maxT); ++i) {
        const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
        const double f1 = at(m1), f2 = at(m2);
        if (f1 < 0) {
            inside = m1;
            break;
        }
        if (f2 < 0) {
            inside = m2;
            break;
        }
        if (f1 < f2)
            hi = m2;
        else
            lo = m1;
    }
    if (inside < 0) {
        if (at(maxT) < 0) {
            inside = maxT;
        } else {
            const double closest = std::min(at(lo), at(hi));
            if (closest > band) return r;
            return {SweepReference::Kind::Ambiguous, lo};
        }
    }
    double out = 0;  // separated at `out`, overlapping at `inside`: the first touch is between
    for (int i = 0; i < 100 && inside - out > 1e-10 * (1 + maxT); ++i) {
        const double mid = 0.5 * (out + inside);
        (at(mid) < 0 ? inside : out) = mid;
    }
    return {SweepReference::Kind::Hit, out};
}

}  // namespace rubble::test
