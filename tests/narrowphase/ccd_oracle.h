#pragma once
// libccd as an independent oracle for the narrow-phase tests: shapes described here in double precision with their
// own support functions (written for the tests, sharing no code with src/narrowphase), queried through libccd's
// GJK intersection test and GJK+EPA penetration.
#include <ccd/ccd.h>

#include <cmath>
#include <vector>

#include "rubble/math.h"

namespace rubble::test {

struct OracleShape {
    enum class Kind { Sphere, Capsule, Box, Hull };
    Kind kind = Kind::Sphere;
    double radius = 0;      // sphere, capsule
    double halfHeight = 0;  // capsule, along local y
    double half[3] = {0, 0, 0};
    std::vector<Vec3> points;  // hull vertices, local
    double inflate = 0;        // extra radius (a tolerance band around the shape)
    double pos[3] = {0, 0, 0};
    double q[4] = {0, 0, 0, 1};  // x y z w

    static void rot(const double q[4], const double v[3], double out[3]) {
        const double u[3] = {q[0], q[1], q[2]};
        const double t[3] = {2 * (u[1] * v[2] - u[2] * v[1]), 2 * (u[2] * v[0] - u[0] * v[2]),
                             2 * (u[0] * v[1] - u[1] * v[0])};
        out[0] = v[0] + q[3] * t[0] + (u[1] * t[2] - u[2] * t[1]);
        out[1] = v[1] + q[3] * t[1] + (u[2] * t[0] - u[0] * t[2]);
        out[2] = v[2] + q[3] * t[2] + (u[0] * t[1] - u[1] * t[0]);
    }

    void support(const double dir[3], double out[3]) const {
        const double qi[4] = {-q[0], -q[1], -q[2], q[3]};
        double d[3];
        rot(qi, dir, d);
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double n[3] = {len > 0 ? d[0] / len : 0, len > 0 ? d[1] / len : 1, len > 0 ? d[2] / len : 0};
        double p[3] = {0, 0, 0};
        double round = inflate;
        switch (kind) {
            case Kind::Sphere:
                round += radius;
                break;
            case Kind::Capsule:
                p[1] = d[1] < 0 ? -halfHeight : halfHeight;
                round += radius;
                break;
            case Kind::Box:
                for (int i = 0; i < 3; ++i) p[i] = d[i] < 0 ? -half[i] : half[i];
                break;
            case Kind::Hull: {
                double best = -INFINITY;
                for (const Vec3& v : points) {
                    const double s = v.x * d[0] + v.y * d[1] + v.z * d[2];
                    if (s > best) best = s, p[0] = v.x, p[1] = v.y, p[2] = v.z;
                }
                break;
            }
        }
        for (int i = 0; i < 3; ++i) p[i] += round * n[i];
        rot(q, p, out);
        for (int i = 0; i < 3; ++i) out[i] += pos[i];
    }
};

/// Double-precision vectors for brute-force oracles (SAT over every axis, exact projections).
struct D3 {
    double x, y, z;
};
inline D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }
inline D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dotd(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline D3 crossd(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double lend(D3 a) { return std::sqrt(dotd(a, a)); }
/// A vector rotated by a transform's rotation, normalised in double first.
inline D3 rotd(const Transform& t, Vec3 v) {
    const double q[4] = {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w};
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const double qn[4] = {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
    const double in[3] = {v.x, v.y, v.z};
    double o[3];
    OracleShape::rot(qn, in, o);
    return {o[0], o[1], o[2]};
}

inline void oracleSupport(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* vec) {
    static_cast<const OracleShape*>(obj)->support(dir->v, vec->v);
}
inline void oracleCenter(const void* obj, ccd_vec3_t* center) {
    const auto* s = static_cast<const OracleShape*>(obj);
    for (int i = 0; i < 3; ++i) center->v[i] = s->pos[i];
}

inline ccd_t oracleSettings() {
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd.support2 = oracleSupport;
    ccd.center1 = ccd.center2 = oracleCenter;
    ccd.max_iterations = 500;
    ccd.epa_tolerance = 1e-7;
    ccd.mpr_tolerance = 1e-7;
    ccd.dist_tolerance = 1e-9;
    return ccd;
}

inline bool oracleIntersect(const OracleShape& a, const OracleShape& b) {
    const ccd_t ccd = oracleSettings();
    return ccdGJKIntersect(&a, &b, &ccd) != 0;
}

/// MPR's boolean test: libccd's GJK boolean test misses overlaps of ~1e-4 between round shapes in about one pose
/// in ten (it stops on its distance tolerance), MPR does not.
inline bool oracleMprIntersect(const OracleShape& a, const OracleShape& b) {
    const ccd_t ccd = oracleSettings();
    return ccdMPRIntersect(&a, &b, &ccd) != 0;
}

struct OraclePenetration {
    bool hit = false;
    double depth = 0;
    double dir[3] = {0, 0, 0};  // unit: moving B by depth along dir separates the shapes (A -> B)
};

inline OraclePenetration oraclePenetration(const OracleShape& a, const OracleShape& b) {
    const ccd_t ccd = oracleSettings();
    OraclePenetration r;
    ccd_vec3_t dir, pos;
    ccd_real_t depth = 0;
    r.hit = ccdGJKPenetration(&a, &b, &ccd, &depth, &dir, &pos) == 0;
    r.depth = depth;
    for (int i = 0; i < 3; ++i) r.dir[i] = dir.v[i];
    return r;
}

inline OraclePenetration oracleMprPenetration(const OracleShape& a, const OracleShape& b) {
    const ccd_t ccd = oracleSettings();
    OraclePenetration r;
    ccd_vec3_t dir, pos;
    ccd_real_t depth = 0;
    r.hit = ccdMPRPenetration(&a, &b, &ccd, &depth, &dir, &pos) == 0;
    r.depth = depth;
    for (int i = 0; i < 3; ++i) r.dir[i] = dir.v[i];
    return r;
}

inline void setPose(OracleShape& s, const Transform& t) {
    s.pos[0] = t.position.x, s.pos[1] = t.position.y, s.pos[2] = t.position.z;
    s.q[0] = t.rotation.x, s.q[1] = t.rotation.y, s.q[2] = t.rotation.z, s.q[3] = t.rotation.w;
}

}  // namespace rubble::test
