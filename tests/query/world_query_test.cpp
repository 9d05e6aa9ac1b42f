// World queries on hand-made scenes with answers worked out independently: every shape kind at a known point,
// 10 km from the origin, grazing rays, rays that start inside, one-sided and zero-area triangles, ties, casts and
// overlaps of each kind, and the refusal of bad input.
//
// Tolerances: near the origin the closed forms are computed in double from the same float poses, and the queries
// agree to 1e-5 m (float rounding over ~10 m). At 10 km a float resolves 1 mm, so points (origin + t * dir) agree
// to 2e-3 m, while distances, computed relative to the hit body, keep 1e-4 m.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "query/query_reference.h"
#include "rubble/error.h"
#include "rubble/world.h"
#include "support/error_of.h"

namespace rubble {
namespace {

using test::errorOf;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

BodyId addBody(World& w, ShapeId shape, Vec3 position, Quat orientation = {}, BodyType type = BodyType::Dynamic) {
    BodyDef def;
    def.type = type;
    def.shape = shape;
    def.position = position;
    def.orientation = orientation;
    return w.createBody(def);
}

void expectNear(Vec3 a, Vec3 b, float tolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

/// A world with one body of every kind, laid out along x (each 10 m from the last), at `offset`.
struct EveryKind {
    World world;
    Vec3 offset;
    BodyId sphere, box, capsule, hull, compound, mesh, field;
    Quat boxRotation = Quat::fromAxisAngle({0, 1, 0}, 0.5f);
    HeightfieldDef fieldDef{3, 4, {0, 0.5f, 1, 0.2f, 0.3f, 1.2f, 0.4f, -0.5f, 0.1f, 0.8f, 0.6f, 0}, {1.5f, 1, 2}};

    explicit EveryKind(Vec3 at = {}) : offset(at) {
        sphere = addBody(world, world.createShape(SphereDef{1}), at + Vec3{0, 0, 0});
        box = addBody(world, world.createShape(BoxDef{{1, 2, 0.5f}}), at + Vec3{10, 0, 0}, boxRotation);
        capsule = addBody(world, world.createShape(CapsuleDef{0.5f, 1}), at + Vec3{20, 0, 0},
                          Quat::fromAxisAngle({0, 0, 1}, 1.5707963f));
        hull = addBody(
            world,
            world.createShape(ConvexHullDef{
                {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 1}}}),
            at + Vec3{30, 0, 0}, boxRotation, BodyType::Kinematic);
        CompoundDef pair;
        pair.children.push_back({SphereDef{0.5f}, {{0, 1, 0}, {}}});
        pair.children.push_back({BoxDef{{0.5f, 0.5f, 0.5f}}, {{0, -1, 0}, {}}});
        compound = addBody(world, world.createShape(pair), at + Vec3{40, 0, 0});
        TriangleMeshDef square{{{0, 0, 0}, {2, 0, 0}, {2, 0, 2}, {0, 0, 2}}, {0, 3, 2, 0, 2, 1}};
        mesh = addBody(world, world.createShape(square), at + Vec3{50, 0, 0}, {}, BodyType::Static);
        field = addBody(world, world.createShape(fieldDef), at + Vec3{60, 0, 0}, {}, BodyType::Static);
    }
};

void checkEveryKind(EveryKind& s, float pointTolerance, float distanceTolerance) {
    World& w = s.world;
    const Vec3 o = s.offset;
    // Far from the origin o + p is rounded to the float grid (1 mm at 10 km): the answers are worked out for the ray
    // that is actually cast, relative to the body (that subtraction of nearby floats is exact).
    auto at = [&](Vec3 p) { return o + p; };
    auto relative = [&](Vec3 p, Vec3 body) { return at(p) - at(body); };

    // Sphere: a ray about 0.5 off the centre line.
    {
        const Vec3 origin = relative({-5, 0.5f, 0}, {}), dir{1, 0, 0};
        const auto t = test::raySphereRef(origin, dir, {}, 1);
        ASSERT_TRUE(t);
        const auto hit = w.castRay(at({-5, 0.5f, 0}), dir, 100);
        ASSERT_TRUE(hit);
        EXPECT_EQ(hit->body, s.sphere);
        EXPECT_NEAR(hit->distance, *t, distanceTolerance);
        expectNear(hit->point, at({-5, 0.5f, 0}) + dir * float(*t), pointTolerance);
        expectNear(hit->normal, origin + dir * float(*t), 1e-4f);
        EXPECT_EQ(hit->triangle, kNoIndex);
        EXPECT_EQ(hit->child, kNoIndex);
    }
    // Box, turned 0.5 rad about y, and the hull (the cube [-1, 1]^3) turned the same way: slabs in their frames.
    for (const bool hull : {false, true}) {
        const Vec3 centre{hull ? 30.0f : 10.0f, 0, 0}, start{centre.x + 0.3f, hull ? -0.6f : 0.4f, -6}, dir{0, 0, 1};
        const Quat toLocal = conjugate(s.boxRotation);
        const auto t = test::rayBoxRef(rotate(toLocal, relative(start, centre)), rotate(toLocal, dir),
                                       hull ? Vec3{1, 1, 1} : Vec3{1, 2, 0.5f});
        ASSERT_TRUE(t);
        const auto hit = w.castRay(at(start), dir, 100);
        ASSERT_TRUE(hit);
        EXPECT_EQ(hit->body, hull ? s.hull : s.box);
        EXPECT_NEAR(hit->distance, *t, distanceTolerance);
        EXPECT_LT(dot(hit->normal, dir), 0);
    }
    // Capsule along x from 19 to 21: a ray down at x = 21.2 meets the cap around (21, 0, 0).
    {
        const float dx = relative({21.2f, 5, 0}, {20, 0, 0}).x - 1;
        const float dy = std::sqrt(0.25f - dx * dx);
        const auto hit = w.castRay(at({21.2f, 5, 0}), {0, -1, 0}, 100);
        ASSERT_TRUE(hit);
        EXPECT_EQ(hit->body, s.capsule);
        EXPECT_NEAR(hit->distance, 5 - dy, distanceTolerance);
        expectNear(hit->normal, Vec3{dx, dy, 0} / 0.5f, 1e-4f);
    }
    // Compound: straight down through the sphere child (top at y = 1.5) and the box child (top at y = -0.5).
    std::vector<RayHit> all;
    EXPECT_EQ(w.castRayAll(at({40, 5, 0}), {0, -1, 0}, 100, all), 2u);
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[0].body, s.compound);
    EXPECT_EQ(all[0].child, 0u);
    EXPECT_NEAR(all[0].distance, 3.5f, distanceTolerance);
    EXPECT_EQ(all[1].child, 1u);
    EXPECT_NEAR(all[1].distance, 5.5f, distanceTolerance);
    expectNear(all[1].normal, {0, 1, 0}, 1e-5f);
    // Mesh: the square [0, 2]^2 split along (0, 0)-(2, 2); (1.5, 0.5) lies in triangle 1 (0, 2, 1).
    auto hit = w.castRay(at({51.5f, 3, 0.5f}), {0, -1, 0}, 100);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, s.mesh);
    EXPECT_EQ(hit->triangle, 1u);
    EXPECT_NEAR(hit->distance, 3, distanceTolerance);
    expectNear(hit->normal, {0, 1, 0}, 1e-5f);
    hit = w.castRay(at({50.5f, 3, 1.5f}), {0, -1, 0}, 100);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->triangle, 0u);
    // Heightfield: every triangle by the documented numbering, each against Moller-Trumbore in double.
    const HeightfieldDef& f = s.fieldDef;
    for (std::uint32_t r = 0; r + 1 < f.rows; ++r)
        for (std::uint32_t c = 0; c + 1 < f.columns; ++c)
            for (std::uint32_t k = 0; k < 2; ++k) {
                auto vertex = [&](std::uint32_t row, std::uint32_t col) {  // in the heightfield's frame
                    return Vec3{float(col) * f.spacing.x, f.heights[row * f.columns + col] * f.spacing.y,
                                float(row) * f.spacing.z};
                };
                const Vec3 a = vertex(r, c), b = k == 0 ? vertex(r + 1, c) : vertex(r + 1, c + 1),
                           d = k == 0 ? vertex(r + 1, c + 1) : vertex(r, c + 1);
                const Vec3 inside = (a + b + d) / 3;
                const Vec3 start{60 + inside.x, 10, inside.z};
                const auto t = test::rayTriangleRef(relative(start, {60, 0, 0}), {0, -1, 0}, a, b, d);
                ASSERT_TRUE(t);
                hit = w.castRay(at(start), {0, -1, 0}, 100);
                ASSERT_TRUE(hit);
                EXPECT_EQ(hit->body, s.field);
                EXPECT_EQ(hit->triangle, 2 * (r * (f.columns - 1) + c) + k);
                EXPECT_NEAR(hit->distance, *t, distanceTolerance);
            }
    // Misses: past every body, and short of the sphere.
    EXPECT_FALSE(w.castRay(at({-5, 3, 0}), {1, 0, 0}, kInf));
    EXPECT_FALSE(w.castRay(at({-5, 0, 0}), {1, 0, 0}, 3.9f));
}

TEST(QueryWorld, RayHitsEveryShapeKindWhereClosedFormsSay) {
    EveryKind s;
    checkEveryKind(s, 1e-5f, 1e-5f);
    s.world.step(1.0f / 60);  // bodies fall a little under gravity: the answers follow them
    const Vec3 drop = s.world.position(s.sphere);
    const auto hit = s.world.castRay(drop + Vec3{-5, 0.5f, 0}, {1, 0, 0}, 100);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, s.sphere);
    EXPECT_NEAR(hit->distance, 5 - std::sqrt(0.75f), 1e-5f);
}

TEST(QueryWorld, TenKilometresFromTheOriginKeepsMillimetres) {
    EveryKind s({10000, 50, -10000});
    checkEveryKind(s, 2e-3f, 1e-4f);
    std::vector<BodyId> found;
    EXPECT_EQ(s.world.overlapSphere(s.offset + Vec3{0, 1.5f, 0}, 0.501f, found), 1u);
    const auto cast = s.world.castSphere(s.offset + Vec3{-5, 0, 0}, 0.5f, {1, 0, 0}, 100);
    ASSERT_TRUE(cast);
    EXPECT_NEAR(cast->distance, 3.5f, 1e-4f);
}

// Queries from the far end of the float range find nothing and read nothing they should not: the world fuzzer's
// sphere cast from y = -1.7e38 m padded the tree's boxes by infinity, which walked into unused lanes (a wild read).
TEST(QueryWorld, QueriesFromTheEdgeOfTheFloatRangeFindNothing) {
    EveryKind s({0, 0, 0});
    const float far = 1.7e38f;
    for (const Vec3 origin : {Vec3{-29.9f, -far, 30}, Vec3{far, far, far}, Vec3{-far, 0, 0}}) {
        EXPECT_FALSE(s.world.castRay(origin, {1, 1, 1}, 50));
        EXPECT_FALSE(s.world.castSphere(origin, 0.2f, {1, 1, 1}, 50));
        std::vector<BodyId> found;
        EXPECT_EQ(s.world.overlapSphere(origin, 1, found), 0u);
        EXPECT_EQ(s.world.overlapAabb(origin - Vec3{1, 1, 1}, origin + Vec3{1, 1, 1}, found), 0u);
    }
}

TEST(QueryWorld, GrazingRaysFollowClosedSets) {
    World w;
    const BodyId ball = addBody(w, w.createShape(SphereDef{1}), {});
    const BodyId crate = addBody(w, w.createShape(BoxDef{{1, 1, 1}}), {10, 0, 0});
    // Silhouette of the sphere: just inside hits, just outside misses.
    EXPECT_TRUE(w.castRay({-5, 1 - 1e-4f, 0}, {1, 0, 0}, 10));
    EXPECT_FALSE(w.castRay({-5, 1 + 1e-4f, 0}, {1, 0, 0}, 10));
    // In the plane of the box's top face: the box is closed, so the ray meets its edge at x = 9.
    auto hit = w.castRay({5, 1, 0}, {1, 0, 0}, 10);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, crate);
    EXPECT_NEAR(hit->distance, 4, 1e-6f);
    EXPECT_FALSE(w.castRay({5, 1 + 1e-4f, 0}, {1, 0, 0}, 10));
    EXPECT_TRUE(w.castRay({5, 1 - 1e-4f, 0}, {1, 0, 0}, 10));
    // Along the box's edge line, and along a diagonal through its corner.
    EXPECT_TRUE(w.castRay({5, 1, 1}, {1, 0, 0}, 10));
    hit = w.castRay({8, 2, 2}, {1, -1, -1}, 10);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance, std::sqrt(3.0f), 1e-5f);
    EXPECT_NE(ball, crate);
}

TEST(QueryWorld, RaysThroughTerrainVerticesAndEdgesNeverSlipThrough) {
    World w;
    TriangleMeshDef grid;
    const int n = 9;
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) grid.vertices.push_back({float(c), 0.25f * float((r * 7 + c * 3) % 5), float(r)});
    for (int r = 0; r + 1 < n; ++r)
        for (int c = 0; c + 1 < n; ++c) {
            const std::uint32_t v = std::uint32_t(r * n + c);
            grid.indices.insert(grid.indices.end(), {v, v + n, v + n + 1, v, v + n + 1, v + 1});
        }
    addBody(w, w.createShape(grid), {}, {}, BodyType::Static);
    int rays = 0;
    for (int r = 1; r + 1 < n; ++r)
        for (int c = 1; c + 1 < n; ++c)
            for (const float dx : {0.0f, 0.5f})
                for (const float dz : {0.0f, 0.5f}) {
                    const Vec3 target{float(c) + dx, 0, float(r) + dz};
                    const auto hit = w.castRay({target.x, 5, target.z}, {0, -1, 0}, 10);
                    EXPECT_TRUE(hit) << "straight down at (" << target.x << ", " << target.z << ")";
                    ++rays;
                }
    EXPECT_EQ(rays, 7 * 7 * 4);
}

TEST(QueryWorld, RaysStartingInsideHitAtZeroUnlessAskedNotTo) {
    World w;
    const BodyId outer = addBody(w, w.createShape(BoxDef{{2, 2, 2}}), {});
    const BodyId behind = addBody(w, w.createShape(SphereDef{1}), {6, 0, 0});
    auto hit = w.castRay({0.5f, 0.2f, 0}, {1, 0, 0}, 20);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, outer);
    EXPECT_EQ(hit->distance, 0);
    EXPECT_EQ(hit->normal, (Vec3{-1, 0, 0}));
    EXPECT_EQ(hit->point, (Vec3{0.5f, 0.2f, 0}));
    QueryFilter passThrough;
    passThrough.hitFromInside = false;
    hit = w.castRay({0.5f, 0.2f, 0}, {1, 0, 0}, 20, passThrough);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, behind);
    EXPECT_NEAR(hit->distance, 5.5f - std::sqrt(1 - 0.04f), 1e-5f);
    // A cast that starts overlapping: distance 0, normal against the motion, point at the start.
    const auto cast = w.castSphere({1.5f, 0, 0}, 1, {1, 0, 0}, 20);
    ASSERT_TRUE(cast);
    EXPECT_EQ(cast->body, outer);
    EXPECT_EQ(cast->distance, 0);
    EXPECT_EQ(cast->normal, (Vec3{-1, 0, 0}));
    const auto past = w.castSphere({1.5f, 0, 0}, 1, {1, 0, 0}, 20, passThrough);
    ASSERT_TRUE(past);
    EXPECT_EQ(past->body, behind);
    EXPECT_NEAR(past->distance, 2.5f, 1e-5f);
}

TEST(QueryWorld, TrianglesAreOneSidedUnlessBackFacesAreAsked) {
    World w;
    const BodyId ground =
        addBody(w, w.createShape(TriangleMeshDef{{{-5, 0, -5}, {5, 0, -5}, {5, 0, 5}, {-5, 0, 5}}, {0, 3, 2, 0, 2, 1}}),
                {}, {}, BodyType::Static);
    EXPECT_TRUE(w.castRay({0, 2, 0}, {0, -1, 0}, 10));
    EXPECT_FALSE(w.castRay({0, -2, 0}, {0, 1, 0}, 10));
    EXPECT_FALSE(w.castSphere({0, -2, 0}, 0.5f, {0, 1, 0}, 10));
    QueryFilter both;
    both.hitBackFaces = true;
    const auto hit = w.castRay({0, -2, 0}, {0, 1, 0}, 10, both);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, ground);
    EXPECT_EQ(hit->normal, (Vec3{0, -1, 0}));  // facing the ray
    const auto cast = w.castSphere({0, -2, 0}, 0.5f, {0, 1, 0}, 10, both);
    ASSERT_TRUE(cast);
    EXPECT_NEAR(cast->distance, 1.5f, 1e-5f);
    expectNear(cast->normal, {0, -1, 0}, 1e-5f);
}

TEST(QueryWorld, ZeroAreaTrianglesAreInvisible) {
    World w;
    // Two proper triangles far apart, and between them a repeated-vertex, a collinear and a point triangle.
    TriangleMeshDef def{
        {{-10, 0, 0}, {-9, 0, 0}, {-9, 0, 1}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {9, 0, 0}, {10, 0, 0}, {10, 0, 1}},
        {0, 2, 1, 3, 3, 4, 3, 4, 5, 4, 4, 4, 6, 8, 7}};
    const BodyId mesh = addBody(w, w.createShape(def), {}, {}, BodyType::Static);
    QueryFilter both;
    both.hitBackFaces = true;
    for (const float x : {0.0f, 0.5f, 1.0f, 1.5f}) {
        EXPECT_FALSE(w.castRay({x, 2, 0}, {0, -1, 0}, 10, both)) << x;
        EXPECT_FALSE(w.castSphere({x, 2, 0}, 0.3f, {0, -1, 0}, 10, both)) << x;
        std::vector<BodyId> found;
        EXPECT_EQ(w.overlapSphere({x, 0, 0}, 0.3f, found), 0u) << x;
    }
    const auto hit = w.castRay({9.5f, 2, 0.25f}, {0, -1, 0}, 10);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, mesh);
    EXPECT_EQ(hit->triangle, 4u);
}

TEST(QueryWorld, EqualDistancesGoToTheLowerSlot) {
    World w;
    const ShapeId ball = w.createShape(SphereDef{1});
    const BodyId first = addBody(w, ball, {0, 0, 0});
    const BodyId second = addBody(w, ball, {0, 0, 0}, {}, BodyType::Static);
    const BodyId third = addBody(w, ball, {0, 0, 0}, {}, BodyType::Kinematic);
    auto hit = w.castRay({-5, 0, 0}, {1, 0, 0}, 10);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, first);
    std::vector<RayHit> all;
    w.castRayAll({-5, 0, 0}, {1, 0, 0}, 10, all);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[0].body, first);
    EXPECT_EQ(all[1].body, second);
    EXPECT_EQ(all[2].body, third);
    QueryFilter notFirst;
    notFirst.ignore = first;
    hit = w.castRay({-5, 0, 0}, {1, 0, 0}, 10, notFirst);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, second);
    const auto cast = w.castSphere({-5, 0, 0}, 0.5f, {1, 0, 0}, 10);
    ASSERT_TRUE(cast);
    EXPECT_EQ(cast->body, first);
}

TEST(QueryWorld, CastsOfEveryShapeKindHitWhereExpected) {
    World w;
    const BodyId floor =
        addBody(w, w.createShape(BoxDef{{20, 0.5f, 20}}), {0, -0.5f, 0}, {}, BodyType::Static);  // top at y = 0
    const ShapeId ball = w.createShape(SphereDef{0.5f});
    const ShapeId crate = w.createShape(BoxDef{{0.5f, 0.25f, 0.5f}});
    const ShapeId pill = w.createShape(CapsuleDef{0.25f, 0.5f});
    const ShapeId rock = w.createShape(ConvexHullDef{{{0, -0.4f, 0}, {1, 0.5f, 0}, {-1, 0.5f, 0.5f}, {0, 0.6f, -1}}});
    CompoundDef dumbbellDef;
    dumbbellDef.children.push_back({SphereDef{0.3f}, {{-1, 0, 0}, {}}});
    dumbbellDef.children.push_back({SphereDef{0.5f}, {{1, 0, 0}, {}}});
    const ShapeId dumbbell = w.createShape(dumbbellDef);
    struct Case {
        ShapeId shape;
        float lowest;  ///< how far below the start position the shape reaches
        std::uint32_t castChild;
    };
    for (const Case& c : {Case{ball, 0.5f, kNoIndex}, Case{crate, 0.25f, kNoIndex}, Case{pill, 0.75f, kNoIndex},
                          Case{rock, 0.4f, kNoIndex}, Case{dumbbell, 0.5f, 1u}}) {
        const auto hit = w.castShape(c.shape, {{0.3f, 5, -0.2f}, {}}, {0, -1, 0}, 10);
        ASSERT_TRUE(hit);
        EXPECT_EQ(hit->body, floor);
        EXPECT_NEAR(hit->distance, 5 - c.lowest, 1e-4f);
        EXPECT_LE(hit->distance, 5 - c.lowest + 1e-6f);
        expectNear(hit->normal, {0, 1, 0}, 1e-3f);
        EXPECT_NEAR(hit->point.y, 0, 1e-4f);
        EXPECT_EQ(hit->castChild, c.castChild);
        EXPECT_FALSE(w.castShape(c.shape, {{0.3f, 5, -0.2f}, {}}, {0, -1, 0}, 4.2f - c.lowest));
    }
    // A sphere cast onto a capsule and a sphere: closed forms.
    const BodyId post = addBody(w, pill, {5, 3, 0});
    auto hit = w.castSphere({5, 10, 0}, 0.5f, {0, -1, 0}, 20);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, post);
    EXPECT_NEAR(hit->distance, 10 - 3 - 0.75f - 0.5f, 1e-5f);
    expectNear(hit->point, {5, 3.75f, 0}, 1e-5f);
    const BodyId target = addBody(w, ball, {-5, 3, 0});
    hit = w.castSphere({-5, 3, 7}, 0.25f, {0, 0, -1}, 20);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->body, target);
    EXPECT_NEAR(hit->distance, 6.25f, 1e-5f);
    expectNear(hit->normal, {0, 0, 1}, 1e-5f);
}

TEST(QueryWorld, OverlapsTestShapesNotBoxes) {
    World w;
    const BodyId ball = addBody(w, w.createShape(SphereDef{1}), {});
    const BodyId tilted =
        addBody(w, w.createShape(BoxDef{{1, 1, 1}}), {5, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, 0.785398f));
    std::vector<BodyId> found;
    // The corner region of the sphere's bounding box is empty: the box (0.75..1)^3 touches the box but not the ball.
    EXPECT_EQ(w.overlapAabb({0.75f, 0.75f, 0.75f}, {1, 1, 1}, found), 0u);
    EXPECT_EQ(w.overlapAabb({0.5f, 0.5f, 0.5f}, {1, 1, 1}, found), 1u);
    EXPECT_EQ(found.back(), ball);
    // The tilted box reaches sqrt(2) along x and y from its centre, but not its bounding box's corner.
    found.clear();
    EXPECT_EQ(w.overlapSphere({5 + 1.3f, 1.3f, 0}, 0.2f, found), 0u);
    EXPECT_EQ(w.overlapSphere({5 + 1.3f, 0, 0}, 0.2f, found), 1u);
    EXPECT_EQ(found.back(), tilted);
    // Every body, in slot order, appended after what the vector held.
    found = {BodyId{}};
    EXPECT_EQ(w.overlapSphere({2.5f, 0, 0}, 10, found), 2u);
    ASSERT_EQ(found.size(), 3u);
    EXPECT_EQ(found[1], ball);
    EXPECT_EQ(found[2], tilted);
    // Touching counts.
    found.clear();
    EXPECT_EQ(w.overlapSphere({0, 2, 0}, 1, found), 1u);
    const ShapeId slab = w.createShape(BoxDef{{1, 0.1f, 1}});
    EXPECT_EQ(w.overlapShape(slab, {{0, 1.05f, 0}, {}}, found), 1u);
    EXPECT_EQ(w.overlapShape(slab, {{0, 1.2f, 0}, {}}, found), 0u);
}

TEST(QueryWorld, EmptyWorldsAndWorldsThatNeverStepped) {
    World empty;
    std::vector<BodyId> found;
    std::vector<RayHit> hits;
    EXPECT_FALSE(empty.castRay({}, {1, 0, 0}, kInf));
    EXPECT_EQ(empty.castRayAll({}, {1, 0, 0}, kInf, hits), 0u);
    EXPECT_FALSE(empty.castSphere({}, 1, {1, 0, 0}, kInf));
    EXPECT_EQ(empty.overlapSphere({}, 100, found), 0u);
    World statics;
    const BodyId wall = addBody(statics, statics.createShape(BoxDef{}), {3, 0, 0}, {}, BodyType::Static);
    EXPECT_EQ(statics.castRay({}, {1, 0, 0}, kInf)->body, wall);
    statics.destroyBody(wall);
    EXPECT_FALSE(statics.castRay({}, {1, 0, 0}, kInf));
    const BodyId moved = addBody(statics, statics.createShape(SphereDef{}), {0, 3, 0}, {}, BodyType::Static);
    statics.setTransform(moved, {3, 0, 0}, {});
    EXPECT_EQ(statics.castRay({}, {1, 0, 0}, kInf)->body, moved);
    EXPECT_FALSE(statics.castRay({}, {0, 1, 0}, kInf));
}

TEST(QueryWorld, BadInputIsRefusedWithClearMessages) {
    World w;
    const ShapeId ball = w.createShape(SphereDef{1});
    const ShapeId ground = w.createShape(HeightfieldDef{2, 2, {0, 0, 0, 0}});
    std::vector<RayHit> hits;
    std::vector<BodyId> found;
    EXPECT_EQ(errorOf([&] {
                  w.castRay({kNaN, 0, 0}, {1, 0, 0}, 1);
              }),
              "World::castRay: origin is not finite (nan, 0, 0)");
    EXPECT_EQ(errorOf([&] { w.castRay({}, {0, 0, 0}, 1); }), "World::castRay: direction must not be zero (0, 0, 0)");
    EXPECT_EQ(errorOf([&] { w.castRay({}, {kInf, 0, 0}, 1); }), "World::castRay: direction is not finite (inf, 0, 0)");
    EXPECT_EQ(errorOf([&] { w.castRay({}, {1, 0, 0}, -1); }), "World::castRay: maxDistance must be >= 0 (got -1)");
    EXPECT_EQ(errorOf([&] { w.castRay({}, {1, 0, 0}, kNaN); }), "World::castRay: maxDistance is not a number (nan)");
    EXPECT_EQ(errorOf([&] {
                  w.castRayAll({}, {0, 0, 0}, 1, hits);
              }),
              "World::castRayAll: direction must not be zero (0, 0, 0)");
    EXPECT_EQ(errorOf([&] {
                  w.castSphere({}, -1, {1, 0, 0}, 1);
              }),
              "World::castSphere: radius must be >= 0 (got " + std::to_string(-1.0f) + ")");
    EXPECT_EQ(errorOf([&] {
                  w.castSphere({}, 1, {1, 0, 0}, -2);
              }),
              "World::castSphere: maxDistance must be >= 0 (got -2)");
    EXPECT_EQ(errorOf([&] { w.castShape(ShapeId{}, {}, {1, 0, 0}, 1); }), "World::castShape: the shape handle is null");
    EXPECT_EQ(errorOf([&] {
                  w.castShape(ShapeId{ball.index, ball.generation + 1}, {}, {1, 0, 0}, 1);
              }),
              "World::castShape: shape handle (index 0, generation 2) is stale or not from this world");
    EXPECT_EQ(errorOf([&] {
                  w.castShape(ground, {}, {1, 0, 0}, 1);
              }),
              "World::castShape: shape 1 is a triangle mesh or heightfield; only spheres, boxes, capsules, hulls and "
              "compounds can be cast or tested for overlap");
    EXPECT_EQ(errorOf([&] {
                  w.castShape(ball, {{}, {0, 0, 0, 2}}, {1, 0, 0}, 1);
              }),
              "World::castShape: start.rotation is not a unit quaternion (0, 0, 0, 2), length 2.000000");
    EXPECT_EQ(errorOf([&] {
                  w.castShape(ball, {{0, kInf, 0}, {}}, {1, 0, 0}, 1);
              }),
              "World::castShape: start.position is not finite (0, inf, 0)");
    EXPECT_EQ(errorOf([&] {
                  w.overlapAabb({1, 0, 0}, {0, 1, 1}, found);
              }),
              "World::overlapAabb: min (1, 0, 0) exceeds max (0, 1, 1) on some axis");
    EXPECT_EQ(errorOf([&] {
                  w.overlapAabb({0, 0, 0}, {kNaN, 1, 1}, found);
              }),
              "World::overlapAabb: max is not finite (nan, 1, 1)");
    EXPECT_EQ(errorOf([&] { w.overlapSphere({}, kNaN, found); }), "World::overlapSphere: radius is not finite (nan)");
    EXPECT_EQ(errorOf([&] { w.overlapShape(ground, {}, found); }).rfind("World::overlapShape: shape 1 is a", 0), 0u);
    // Refused calls change nothing; a tiny but non-zero direction is fine.
    EXPECT_TRUE(hits.empty());
    EXPECT_TRUE(found.empty());
    addBody(w, ball, {5, 0, 0});
    const auto hit = w.castRay({}, {1e-30f, 0, 0}, kInf);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance, 4, 1e-6f);
}

}  // namespace
}  // namespace rubble
