// Per-shape ray tests (src/query/ray_cast.h) against independent answers: closed forms in double for spheres and
// boxes, Moller-Trumbore in double for triangles, and a search on GJK distance for capsules and hulls
// (query_reference.h).
//
// Tolerances: shapes of 0.1 .. 2 m, rays of up to ~20 m. Float arithmetic over such lengths resolves ~2e-6 m; the
// closed forms agree to 2e-5 m. The GJK search stops at 1e-9 of the range but GJK itself is exact to ~1e-6 relative,
// so 5e-5 m there. Rays whose closest approach lies within 2e-5 m of the surface (or, for triangles, that cross
// within 1e-5 of an edge) may go either way and are not compared.
#include "query/ray_cast.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "narrowphase/gjk.h"
#include "query/query_reference.h"
#include "shapes/shape.h"

namespace rubble::detail {
namespace {

using test::randomRotation;
using test::randomUnit;
using test::SweepReference;

/// A ray from a random point in a 16 m cube towards a random point near `target`, so that about half of them hit.
Ray aimedRay(std::mt19937& rng, Vec3 target, float spread, float maxT = 40) {
    std::uniform_real_distribution<float> u(-8, 8), s(-spread, spread);
    const Vec3 origin{u(rng), u(rng), u(rng)};
    const Vec3 aim = target + Vec3{s(rng), s(rng), s(rng)};
    return {origin, normalized(aim - origin), maxT};
}

/// The normal n at surface point p is an outward normal there: the plane through p with normal n supports the shape.
void expectOutwardNormal(const GjkShape& shape, Vec3 p, Vec3 n) {
    EXPECT_NEAR(length(n), 1.0f, 1e-5f);
    const Vec3 support = gjkSupport(shape, n) + n * shape.radius;
    EXPECT_NEAR(dot(support - p, n), 0, 1e-4) << "not a supporting plane's normal";
}

TEST(QueryRayShapes, SphereMatchesClosedForm) {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> radius(0.1f, 2.0f), pos(-3, 3);
    int hits = 0, compared = 0;
    for (int i = 0; i < 2000; ++i) {
        const float r = radius(rng);
        const Vec3 c{pos(rng), pos(rng), pos(rng)};
        const Ray ray = aimedRay(rng, c, 1.5f * r);
        const Vec3 m = ray.origin - c;
        const Vec3 perpendicular = m - ray.dir * dot(m, ray.dir);
        if (std::fabs(length(perpendicular) - r) < 2e-5f || length(m) < r) continue;  // grazing or inside
        SurfaceHit hit;
        const RayResult result = raySphere(c, r, ray, hit);
        const auto expected = test::raySphereRef(ray.origin, ray.dir, c, r);
        ++compared;
        ASSERT_EQ(result == RayResult::Hit, expected.has_value()) << "ray " << i;
        if (!expected) continue;
        ++hits;
        EXPECT_NEAR(hit.t, *expected, 2e-5);
        const Vec3 exact = normalized(ray.origin + ray.dir * float(*expected) - c);
        EXPECT_GT(dot(hit.normal, exact), 1 - 1e-5f);
    }
    EXPECT_GT(hits, 300);
    EXPECT_GT(compared, 1900);
}

TEST(QueryRayShapes, BoxMatchesSlabsInDouble) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> size(0.1f, 2.0f);
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
        const Vec3 half{size(rng), size(rng), size(rng)};
        const Ray ray = aimedRay(rng, {}, 2.5f);
        SurfaceHit hit;
        const RayResult result = rayBox(half, ray, hit);
        const auto expected = test::rayBoxRef(ray.origin, ray.dir, half);
        if (!expected) {
            EXPECT_NE(result, RayResult::Hit) << "ray " << i;
            continue;
        }
        ASSERT_EQ(result, RayResult::Hit) << "ray " << i;
        ++hits;
        EXPECT_NEAR(hit.t, *expected, 2e-5);
        // The normal is the axis of the face the ray enters: the point lies on that face.
        const Vec3 p = ray.origin + ray.dir * hit.t;
        const float onFace = dot(p, hit.normal) - std::fabs(dot(half, hit.normal));
        EXPECT_NEAR(onFace, 0, 2e-5);
        EXPECT_LT(dot(hit.normal, ray.dir), 0);
    }
    EXPECT_GT(hits, 300);
}

/// Capsules and hulls against the GJK search, which sees a ray as a point swept along it.
void compareWithGjkSearch(const Shape& shape, std::uint32_t seed, int rays) {
    std::mt19937 rng(seed);
    int hits = 0, misses = 0;
    for (int i = 0; i < rays; ++i) {
        const Transform pose{{}, randomRotation(rng)};
        const GjkShape target = gjkShapeOf(shape, pose);
        const Ray world = aimedRay(rng, {}, 1.0f, 20);
        GjkShape point;
        point.pose.position = world.origin;
        const SweepReference ref = test::sweepReference(point, world.dir, world.maxT, target);
        if (ref.kind == SweepReference::Kind::Ambiguous || ref.kind == SweepReference::Kind::StartsInside) continue;
        SurfaceHit hit;
        const RayResult result = rayConvex(shape, toLocal(pose, world), hit);
        ASSERT_EQ(result == RayResult::Hit, ref.kind == SweepReference::Kind::Hit) << "ray " << i;
        if (result != RayResult::Hit) {
            ++misses;
            continue;
        }
        ++hits;
        EXPECT_NEAR(hit.t, ref.t, 5e-5) << "ray " << i;
        expectOutwardNormal(target, world.origin + world.dir * hit.t, rotate(pose.rotation, hit.normal));
    }
    EXPECT_GT(hits, rays / 5);
    EXPECT_GT(misses, rays / 10);
}

TEST(QueryRayShapes, CapsuleMatchesGjkSearch) {
    compareWithGjkSearch(buildShape(CapsuleDef{0.4f, 0.9f}), 3, 300);
    compareWithGjkSearch(buildShape(CapsuleDef{1.0f, 0.05f}), 4, 200);
}

TEST(QueryRayShapes, HullMatchesGjkSearch) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    for (int h = 0; h < 4; ++h) {
        ConvexHullDef def;
        for (int i = 0; i < 20; ++i) def.points.push_back({u(rng), 0.5f * u(rng), 1.5f * u(rng)});
        compareWithGjkSearch(buildShape(def), 10 + h, 150);
    }
}

TEST(QueryRayShapes, StartsInsideOnTheSurfaceAndOut) {
    const Shape shapes[] = {
        buildShape(SphereDef{1}), buildShape(BoxDef{{1, 1, 1}}), buildShape(CapsuleDef{1, 0.5f}),
        buildShape(ConvexHullDef{
            {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 1}}})};
    for (const Shape& s : shapes) {
        SCOPED_TRACE(int(s.kind));
        SurfaceHit hit;
        // Strictly inside: t = 0, normal against the ray.
        ASSERT_EQ(rayConvex(s, {{0.2f, 0.1f, 0}, {1, 0, 0}, 10}, hit), RayResult::StartsInside);
        EXPECT_EQ(hit.t, 0);
        EXPECT_EQ(hit.normal, (Vec3{-1, 0, 0}));
        // On the surface (x = 1 for every shape here) heading out: nothing to enter.
        EXPECT_EQ(rayConvex(s, {{1, 0, 0}, {1, 0, 0}, 10}, hit), RayResult::Miss);
        // On the surface heading in: enters at once, with the surface normal.
        ASSERT_EQ(rayConvex(s, {{1, 0, 0}, {-1, 0, 0}, 10}, hit), RayResult::Hit);
        EXPECT_EQ(hit.t, 0);
        EXPECT_NEAR(hit.normal.x, 1, 1e-6);
        // Outside, out of reach, and exactly in reach (the range is closed).
        EXPECT_EQ(rayConvex(s, {{3, 0, 0}, {-1, 0, 0}, 1.5f}, hit), RayResult::Miss);
        ASSERT_EQ(rayConvex(s, {{3, 0, 0}, {-1, 0, 0}, 2}, hit), RayResult::Hit);
        EXPECT_NEAR(hit.t, 2, 1e-6);
    }
}

TEST(QueryRayShapes, TriangleMatchesMollerTrumboreInDouble) {
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> u(-2, 2);
    int front = 0, back = 0;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
        const Ray ray = aimedRay(rng, (a + b + c) / 3, 1.5f);
        // Skip rays that cross within 1e-5 of an edge (relative to the triangle's size): either answer is right.
        const Vec3 n = cross(b - a, c - a);
        const float nd = dot(n, ray.dir);
        if (std::fabs(nd) < 1e-3f * length(n)) continue;
        const float tPlane = dot(n, a - ray.origin) / nd;
        const Vec3 p = ray.origin + ray.dir * tPlane;
        const float w0 = dot(cross(b - a, p - a), n), w1 = dot(cross(c - b, p - b), n),
                    w2 = dot(cross(a - c, p - c), n);
        const float scale = dot(n, n);
        if (std::fabs(w0) < 1e-5f * scale || std::fabs(w1) < 1e-5f * scale || std::fabs(w2) < 1e-5f * scale) continue;

        const auto expected = test::rayTriangleRef(ray.origin, ray.dir, a, b, c);
        SurfaceHit hit;
        const bool twoSided = rayTriangle(ray, a, b, c, true, hit);
        ASSERT_EQ(twoSided, expected.has_value()) << "ray " << i;
        if (!expected) continue;
        EXPECT_NEAR(hit.t, *expected, 2e-5 * (1 + *expected));
        EXPECT_LT(dot(hit.normal, ray.dir), 0) << "the normal faces the ray";
        EXPECT_GT(std::fabs(dot(hit.normal, normalized(n))), 1 - 1e-5f);
        const bool isFront = nd < 0;
        (isFront ? front : back) += 1;
        EXPECT_EQ(rayTriangle(ray, a, b, c, false, hit), isFront) << "one-sided test hits front faces only";
    }
    EXPECT_GT(front, 200);
    EXPECT_GT(back, 200);
}

TEST(QueryRayShapes, TriangleGridIsWatertightAtEdgesAndVertices) {
    // A 4 x 4 grid of cells split along one diagonal, bumpy; rays aimed exactly at every inner vertex and at the
    // midpoints of the edges around it, from many directions: each must hit at least one triangle.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> bump(-0.1f, 0.1f);
    const int n = 5;
    std::vector<Vec3> v;
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) v.push_back({float(c), bump(rng), float(r)});
    std::vector<std::array<Vec3, 3>> tris;
    for (int r = 0; r + 1 < n; ++r)
        for (int c = 0; c + 1 < n; ++c) {
            const Vec3 p00 = v[r * n + c], p10 = v[r * n + c + 1], p01 = v[(r + 1) * n + c],
                       p11 = v[(r + 1) * n + c + 1];
            tris.push_back({p00, p01, p11});
            tris.push_back({p00, p11, p10});
        }
    std::vector<Vec3> targets;
    for (int r = 1; r + 1 < n; ++r)
        for (int c = 1; c + 1 < n; ++c) {
            const Vec3 p = v[r * n + c];
            targets.push_back(p);
            targets.push_back((p + v[r * n + c + 1]) * 0.5f);
            targets.push_back((p + v[(r + 1) * n + c]) * 0.5f);
            targets.push_back((p + v[(r + 1) * n + c + 1]) * 0.5f);
        }
    int rays = 0;
    for (const Vec3 target : targets) {
        for (int k = 0; k < 40; ++k) {
            // Steeper than any slope of the surface (at most 0.2 m of bump per metre), so every ray crosses it.
            Vec3 dir = randomUnit(rng);
            dir.y = 0;
            dir =
                normalized(normalized(dir) * 0.4f + Vec3{0, -1, 0} * std::uniform_real_distribution<float>(1, 3)(rng));
            const Ray ray{target - dir * 5.0f, dir, 10};
            bool any = false;
            for (const auto& t : tris) {
                SurfaceHit hit;
                any = any || rayTriangle(ray, t[0], t[1], t[2], false, hit);
            }
            EXPECT_TRUE(any) << "ray at (" << target.x << ", " << target.y << ", " << target.z << ") slipped through";
            ++rays;
        }
    }
    EXPECT_GT(rays, 1000);
}

TEST(QueryRayShapes, DegenerateTrianglesAreNeverHit) {
    const Ray ray{{0.3f, 1, 0.2f}, {0, -1, 0}, 10};
    SurfaceHit hit;
    const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 0, 1};
    ASSERT_TRUE(rayTriangle(ray, a, c, b, false, hit));          // the same ray hits a proper triangle
    EXPECT_FALSE(rayTriangle(ray, a, a, b, true, hit));          // repeated vertex
    EXPECT_FALSE(rayTriangle(ray, a, b, {2, 0, 0}, true, hit));  // collinear
    EXPECT_FALSE(rayTriangle(ray, a, a, a, true, hit));          // a point
    EXPECT_TRUE(degenerateTriangle({0, 0, 0}, {1, 0, 0}, {3, 1e-9f, 0}));
    EXPECT_FALSE(degenerateTriangle({0, 0, 0}, {1, 0, 0}, {3, 1e-3f, 0}));
}

}  // namespace
}  // namespace rubble::detail
