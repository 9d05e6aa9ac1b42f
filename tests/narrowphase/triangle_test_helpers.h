#pragma once
// Helpers shared by the triangle kernels' tests (triangle_pairs_test.cpp, hull_triangle_test.cpp): grid meshes,
// random triangles and poses, an independent point-triangle distance, and the comparison with the libccd oracle.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>

#include "narrowphase/ccd_oracle.h"
#include "narrowphase/manifold.h"
#include "narrowphase/triangle_pairs.h"
#include "shapes/shape.h"

namespace rubble::test {

using detail::Manifold;
using detail::TriangleMesh;
using detail::TriangleVertices;

/// n x n cells of size `cell` over [0, n cell]^2 in xz, heights from `height`, two triangles per cell numbered and
/// split like a heightfield (broadphase/static_bvh.h): counter-clockwise seen from +y.
template <class H>
inline TriangleMesh gridMesh(int n, float cell, H height) {
    TriangleMesh mesh;
    for (int r = 0; r <= n; ++r)
        for (int c = 0; c <= n; ++c) mesh.vertices.push_back({float(c) * cell, height(c, r), float(r) * cell});
    auto at = [&](int c, int r) { return std::uint32_t(r * (n + 1) + c); };
    for (int r = 0; r < n; ++r) {
        for (int c = 0; c < n; ++c) {
            const std::uint32_t p00 = at(c, r), p10 = at(c + 1, r), p01 = at(c, r + 1), p11 = at(c + 1, r + 1);
            mesh.indices.insert(mesh.indices.end(), {p00, p01, p11, p00, p11, p10});
        }
    }
    return mesh;
}

inline TriangleVertices triangleOf(const TriangleMesh& mesh, std::uint32_t t) {
    return {mesh.vertices[mesh.indices[3 * t]], mesh.vertices[mesh.indices[3 * t + 1]],
            mesh.vertices[mesh.indices[3 * t + 2]]};
}

inline Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
    const float n = std::sqrt(x * x + y * y + z * z + w * w);
    return {x / n, y / n, z / n, w / n};
}

inline bool finiteManifold(const Manifold& m, int count) {
    if (count == 0) return true;
    bool ok = isFinite(m.normal);
    for (int i = 0; i < count; ++i) ok = ok && isFinite(m.points[i].position) && std::isfinite(m.points[i].depth);
    return ok;
}

inline void expectVecNear(Vec3 a, Vec3 b, float tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

/// Distance of p from triangle tri (double precision, independent of the kernel's closest-point code: the minimum
/// over the plane projection when inside, else over the three edges).
inline double distanceToTriangle(Vec3 p, const TriangleVertices& t) {
    auto sub = [](Vec3 a, Vec3 b) {
        return std::array<double, 3>{double(a.x) - b.x, double(a.y) - b.y, double(a.z) - b.z};
    };
    auto dotd = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    };
    auto crossd = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    const auto n = crossd(sub(t[1], t[0]), sub(t[2], t[0]));
    bool inside = true;
    for (int e = 0; e < 3; ++e) inside = inside && dotd(crossd(sub(t[(e + 1) % 3], t[e]), sub(p, t[e])), n) >= 0;
    if (inside) return std::fabs(dotd(sub(p, t[0]), n)) / std::sqrt(dotd(n, n));
    double best = INFINITY;
    for (int e = 0; e < 3; ++e) {
        const auto d = sub(t[(e + 1) % 3], t[e]), ap = sub(p, t[e]);
        const double s = std::clamp(dotd(ap, d) / dotd(d, d), 0.0, 1.0);
        const std::array<double, 3> r{ap[0] - d[0] * s, ap[1] - d[1] * s, ap[2] - d[2] * s};
        best = std::min(best, std::sqrt(dotd(r, r)));
    }
    return best;
}

inline double separationAlong(const OracleShape& a, const OracleShape& b, const double n[3]) {
    double sa[3], sb[3];
    const double neg[3] = {-n[0], -n[1], -n[2]};
    a.support(n, sa);
    b.support(neg, sb);
    return (sa[0] - sb[0]) * n[0] + (sa[1] - sb[1]) * n[1] + (sa[2] - sb[2]) * n[2];
}

inline OracleShape moved(OracleShape s, const double dir[3], double distance) {
    for (int i = 0; i < 3; ++i) s.pos[i] += dir[i] * distance;
    return s;
}

struct OracleCheck {
    double bandAbsolute;  // allowed excess of our depth over libccd's
    double bandRelative;
    bool deepestIsSeparation;  // the deepest point must carry the full separation (round shapes)
    bool checkNormal;
};

/// Returns true when the pose was compared (clearly penetrating).
inline bool compareWithOracle(const Manifold& m, int count, const OracleShape& body, const TriangleVertices& tri,
                              const OracleCheck& check, int i) {
    if (count == 0) return false;
    float deepest = -INFINITY;
    for (int k = 0; k < count; ++k) deepest = std::max(deepest, m.points[k].depth);
    if (deepest < 0.02f) return false;
    OracleShape triangle;
    triangle.kind = OracleShape::Kind::Hull;
    // Points about the centroid, posed at it: MPR starts from the shape's centre, which must be inside.
    const Vec3 centroid = (tri[0] + tri[1] + tri[2]) / 3.0f;
    triangle.points = {tri[0] - centroid, tri[1] - centroid, tri[2] - centroid};
    triangle.pos[0] = centroid.x, triangle.pos[1] = centroid.y, triangle.pos[2] = centroid.z;
    const double n[3] = {m.normal.x, m.normal.y, m.normal.z};
    constexpr double kBand = 1e-4;
    const double along = separationAlong(body, triangle, n);
    EXPECT_FALSE(rubble::test::oracleMprIntersect(body, moved(triangle, n, along + kBand))) << i;
    // Exact only when our normal is the minimum direction (not for the box's hysteresis).
    if (check.deepestIsSeparation) {
        EXPECT_TRUE(rubble::test::oracleMprIntersect(body, moved(triangle, n, along - kBand)))
            << i << " along " << along << " deepest " << deepest << " n " << n[0] << " " << n[1] << " " << n[2] << " f "
            << m.points[0].feature << " count " << count;
    }
    if (check.deepestIsSeparation) {
        EXPECT_NEAR(deepest, along, 1e-4) << i;
    }
    EXPECT_LT(deepest, along + 1e-4) << i;
    double best = INFINITY;
    const double* bestDir = nullptr;
    const auto epa = rubble::test::oraclePenetration(body, triangle);
    const auto mpr = rubble::test::oracleMprPenetration(body, triangle);
    for (const auto* pen : {&epa, &mpr})
        if (pen->hit && pen->depth < best &&
            std::fabs(pen->dir[0] * pen->dir[0] + pen->dir[1] * pen->dir[1] + pen->dir[2] * pen->dir[2] - 1) < 1e-6 &&
            !rubble::test::oracleMprIntersect(body, moved(triangle, pen->dir, pen->depth + kBand)))
            best = pen->depth, bestDir = pen->dir;
    EXPECT_NE(bestDir, nullptr) << i;
    if (!bestDir) return true;
    EXPECT_LT(along, best * (1 + check.bandRelative) + check.bandAbsolute) << i;
    if (check.checkNormal && std::fabs(along - best) < 2e-4) {
        EXPECT_GT(m.normal.x * bestDir[0] + m.normal.y * bestDir[1] + m.normal.z * bestDir[2], 0.98) << i;
    }
    for (int k = 0; k < count; ++k) EXPECT_LT(distanceToTriangle(m.points[k].position, tri), 1e-4) << i;
    return true;
}

inline TriangleVertices randomTriangle(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1);
    for (;;) {
        const TriangleVertices t{Vec3{u(rng), u(rng), u(rng)}, Vec3{u(rng), u(rng), u(rng)},
                                 Vec3{u(rng), u(rng), u(rng)}};
        if (length(cross(t[1] - t[0], t[2] - t[0])) > 0.3f) return t;
    }
}

inline Vec3 randomPointOn(const TriangleVertices& t, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0, 1);
    float a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    return t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b;
}

inline Vec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const Vec3 v{g(rng), g(rng), g(rng)};
        if (length(v) > 1e-3f) return v / length(v);
    }
}

}  // namespace rubble::test
