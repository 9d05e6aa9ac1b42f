// Sweeps of one shape pair (src/query/shape_cast.h) against the search on GJK distance of query_reference.h: every
// pair of sphere, box, capsule and hull, and spheres and boxes against triangles.
//
// Tolerances: conservative advancement stops when the gap is below kSweepTolerance (1e-4 m) and then extrapolates
// the rest of the gap at the current closing speed, which never passes the contact (the distance is convex in the
// travel). So the reported travel is never beyond the reference's by more than rounding (1e-5 m) and short of it by
// at most 1e-4 m / the closing speed (rays are aimed, so the closing speed is rarely small; 2e-3 m bounds it here).
// Sweeps whose closest approach lies within 1.5e-4 m of touching may go either way and are not compared.
#include "query/shape_cast.h"

#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "query/query_reference.h"
#include "query/ray_cast.h"
#include "shapes/shape.h"

namespace rubble::detail {
namespace {

using test::randomRotation;
using test::SweepReference;

constexpr double kBehind = 1e-5;  ///< how far past the true contact a sweep may report (rounding)
constexpr double kShort = 2e-3;   ///< how far short of it

std::vector<Shape> convexShapes() {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-0.8f, 0.8f);
    ConvexHullDef hull;
    for (int i = 0; i < 16; ++i) hull.points.push_back({u(rng), u(rng), u(rng)});
    return {buildShape(SphereDef{0.5f}), buildShape(BoxDef{{0.6f, 0.3f, 0.4f}}), buildShape(CapsuleDef{0.3f, 0.6f}),
            buildShape(hull)};
}

/// Compares sweeps of `moving` towards `target` from random starts with the reference; returns the hits compared.
int compareSweeps(const Shape& moving, const Shape& target, std::mt19937& rng, int count) {
    std::uniform_real_distribution<float> u(-5, 5), s(-1.5f, 1.5f);
    int hits = 0;
    for (int i = 0; i < count; ++i) {
        const Transform targetPose{{s(rng), s(rng), s(rng)}, randomRotation(rng)};
        const Vec3 start{u(rng), u(rng), u(rng)};
        const Vec3 aim = targetPose.position + Vec3{s(rng), s(rng), s(rng)};
        const Vec3 dir = normalized(aim - start);
        const float maxT = 12;
        const GjkShape a = gjkShapeOf(moving, {start, randomRotation(rng)});
        const GjkShape b = gjkShapeOf(target, targetPose);
        const SweepReference ref = test::sweepReference(a, dir, maxT, b, 1.5e-4);
        if (ref.kind == SweepReference::Kind::Ambiguous) continue;
        SweepHit hit;
        const SweepResult result = sweepConvex(a, dir, maxT, b, hit);
        if (ref.kind == SweepReference::Kind::StartsInside) {
            EXPECT_EQ(result, SweepResult::StartsInside) << "sweep " << i;
            continue;
        }
        EXPECT_EQ(result == SweepResult::Hit, ref.kind == SweepReference::Kind::Hit) << "sweep " << i;
        if (result != SweepResult::Hit || ref.kind != SweepReference::Kind::Hit) continue;
        ++hits;
        EXPECT_LE(hit.t, ref.t + kBehind) << "sweep " << i << " went past the contact";
        EXPECT_GE(hit.t, ref.t - kShort) << "sweep " << i;
        // The point lies on the target's surface, and the normal points from it towards the swept shape.
        GjkShape point;
        point.pose.position = hit.point;
        const GjkResult g = gjkDistance(point, b);
        EXPECT_TRUE(g.status != GjkStatus::Separated || g.distance < 2e-4f) << "point off the surface, sweep " << i;
        GjkShape moved = a;
        moved.pose.position = a.pose.position + dir * hit.t;
        const GjkResult atHit = gjkDistance(b, moved);
        if (atHit.status == GjkStatus::Separated && atHit.distance > 1e-5f) {
            EXPECT_GT(dot(hit.normal, atHit.normal), 0.99f) << "sweep " << i;
        }
        EXPECT_LT(dot(hit.normal, dir), 1e-6f) << "the normal opposes the motion, sweep " << i;
    }
    return hits;
}

TEST(QuerySweepShapes, EveryConvexPairMatchesGjkSearch) {
    const std::vector<Shape> shapes = convexShapes();
    std::mt19937 rng(12);
    for (std::size_t i = 0; i < shapes.size(); ++i)
        for (std::size_t j = 0; j < shapes.size(); ++j) {
            SCOPED_TRACE(testing::Message()
                         << "moving kind " << int(shapes[i].kind) << ", target kind " << int(shapes[j].kind));
            EXPECT_GT(compareSweeps(shapes[i], shapes[j], rng, 40), 10);
        }
}

TEST(QuerySweepShapes, FlatContactsLandOnTheContact) {
    // A box dropped flat onto a box: the gap closes at full speed, so the travel is exact to the tolerance's
    // extrapolation (that is, to rounding).
    const Shape box = buildShape(BoxDef{{1, 1, 1}});
    const GjkShape ground = gjkShapeOf(box, {{0, -1, 0}, {}});
    const GjkShape falling = gjkShapeOf(box, {{0.3f, 4, -0.2f}, {}});
    SweepHit hit;
    ASSERT_EQ(sweepConvex(falling, {0, -1, 0}, 10, ground, hit), SweepResult::Hit);
    EXPECT_NEAR(hit.t, 3, 1e-5);
    EXPECT_NEAR(hit.normal.y, 1, 1e-5);
    EXPECT_NEAR(hit.point.y, 0, 1e-4);
    // Out of range, moving away, and sliding along without closing in: no hit.
    EXPECT_EQ(sweepConvex(falling, {0, -1, 0}, 2.9f, ground, hit), SweepResult::Miss);
    EXPECT_EQ(sweepConvex(falling, {0, 1, 0}, 10, ground, hit), SweepResult::Miss);
    const GjkShape resting = gjkShapeOf(box, {{0, 1.00005f, 0}, {}});
    EXPECT_EQ(sweepConvex(resting, {1, 0, 0}, 10, ground, hit), SweepResult::Miss);
    EXPECT_EQ(sweepConvex(gjkShapeOf(box, {{0, 0.5f, 0}, {}}), {1, 0, 0}, 10, ground, hit), SweepResult::StartsInside);
}

TEST(QuerySweepShapes, SphereAgainstTriangleMatchesGjkSearch) {
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> u(-2, 2), radius(0.05f, 1.0f);
    int hits = 0, culled = 0, edgeOrVertex = 0;
    for (int i = 0; i < 1500; ++i) {
        const Vec3 tri[3] = {{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
        const float r = radius(rng);
        const Vec3 start = Vec3{u(rng), u(rng), u(rng)} * 3.0f;
        const Vec3 dir = normalized((tri[0] + tri[1] + tri[2]) / 3 + Vec3{u(rng), u(rng), u(rng)} * 0.5f - start);
        GjkShape sphere;
        sphere.radius = r;
        sphere.pose.position = start;
        const SweepReference ref = test::sweepReference(sphere, dir, 15, gjkTriangle(tri, {}), 2e-5);
        if (ref.kind == SweepReference::Kind::Ambiguous) continue;
        SweepHit hit;
        const SweepResult result = sweepSphereTriangle(start, r, dir, 15, tri[0], tri[1], tri[2], true, hit);
        if (ref.kind == SweepReference::Kind::StartsInside) {
            EXPECT_EQ(result, SweepResult::StartsInside) << "sweep " << i;
            continue;
        }
        ASSERT_EQ(result == SweepResult::Hit, ref.kind == SweepReference::Kind::Hit) << "sweep " << i;
        if (result != SweepResult::Hit) continue;
        ++hits;
        EXPECT_NEAR(hit.t, ref.t, 2e-5 * (1 + ref.t)) << "sweep " << i;
        // The contact is on the triangle, one radius from the centre at the time of impact, along the normal.
        const Vec3 center = start + dir * hit.t;
        const Vec3 onTriangle = closestPointOnTriangle(center, tri[0], tri[1], tri[2]);
        EXPECT_LT(length(onTriangle - hit.point), 1e-4f) << "sweep " << i;
        EXPECT_NEAR(length(center - hit.point), r, 1e-4f) << "sweep " << i;
        EXPECT_GT(dot(hit.normal, normalized(center - hit.point)), 1 - 1e-4f) << "sweep " << i;
        const Vec3 n = normalized(cross(tri[1] - tri[0], tri[2] - tri[0]));
        if (std::fabs(dot(hit.normal, n)) < 1 - 1e-4f) ++edgeOrVertex;
        // One-sided: a triangle seen from behind is not hit.
        if (dot(n, dir) >= 0) {
            EXPECT_EQ(sweepSphereTriangle(start, r, dir, 15, tri[0], tri[1], tri[2], false, hit), SweepResult::Miss);
            ++culled;
        }
    }
    EXPECT_GT(hits, 300);
    EXPECT_GT(culled, 50);
    EXPECT_GT(edgeOrVertex, 50);
}

TEST(QuerySweepShapes, BoxAgainstTriangleMatchesGjkSearch) {
    std::mt19937 rng(14);
    std::uniform_real_distribution<float> u(-2, 2);
    const Shape box = buildShape(BoxDef{{0.4f, 0.2f, 0.3f}});
    int hits = 0;
    for (int i = 0; i < 300; ++i) {
        const Vec3 tri[3] = {{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
        const Vec3 start = Vec3{u(rng), u(rng), u(rng)} * 3.0f;
        const Vec3 dir = normalized((tri[0] + tri[1] + tri[2]) / 3 + Vec3{u(rng), u(rng), u(rng)} * 0.5f - start);
        const GjkShape moving = gjkShapeOf(box, {start, randomRotation(rng)});
        const GjkShape target = gjkTriangle(tri, {});
        const SweepReference ref = test::sweepReference(moving, dir, 15, target, 1.5e-4);
        if (ref.kind != SweepReference::Kind::Hit && ref.kind != SweepReference::Kind::Miss) continue;
        SweepHit hit;
        const SweepResult result = sweepConvex(moving, dir, 15, target, hit);
        ASSERT_EQ(result == SweepResult::Hit, ref.kind == SweepReference::Kind::Hit) << "sweep " << i;
        if (result != SweepResult::Hit) continue;
        ++hits;
        EXPECT_LE(hit.t, ref.t + kBehind);
        EXPECT_GE(hit.t, ref.t - kShort);
    }
    EXPECT_GT(hits, 80);
}

TEST(QuerySweepShapes, ClosestPointOnTriangleMatchesDenseSampling) {
    std::mt19937 rng(15);
    std::uniform_real_distribution<float> u(-2, 2);
    for (int i = 0; i < 200; ++i) {
        const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
        const Vec3 p = Vec3{u(rng), u(rng), u(rng)} * 2.0f;
        float best = INFINITY;
        const int n = 200;
        for (int s = 0; s <= n; ++s)
            for (int t = 0; s + t <= n; ++t) {
                const Vec3 q = a + (b - a) * (float(s) / n) + (c - a) * (float(t) / n);
                best = std::fmin(best, length(p - q));
            }
        const float d = length(p - closestPointOnTriangle(p, a, b, c));
        EXPECT_LE(d, best + 1e-5f);
        EXPECT_GE(d, best - 0.03f);  // the sampling step bounds how far the sampled minimum may be off
    }
}

}  // namespace
}  // namespace rubble::detail
