// Continuous collision (Effect::ContinuousCollision) through the World API: fast and spinning bodies against thin
// static geometry, a bullet into a stack, and a fast slide over a tessellated floor, each with 0 tunnelled.
//
// "Tunnelled" is judged from where each body is after every step: on the far side of a wall it started in front of
// (by more than the contact slop), or more than half its size below a floor. Without the effect the fast balls,
// planks and bullets do tunnel (checked below), so each test can fail; spinning rods are held by their speculative
// contacts alone, and their tests check that with the effect and without.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rubble/world.h"
#include "support/sanitized.h"
#include "support/test_shapes.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

World makeWorld(bool continuous, bool gravity = true, int threads = 1) {
    WorldSettings s;
    s.threads = threads;
    s.effects = EffectSet{}.with(Effect::Rotation).with(Effect::Friction);
    if (gravity) s.effects = s.effects.with(Effect::Gravity);
    if (continuous) s.effects = s.effects.with(Effect::ContinuousCollision);
    return World(s);
}

BodyId addStatic(World& world, const ShapeDef& shape, Vec3 position, Quat rotation = {}) {
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(shape);
    def.position = position;
    def.orientation = rotation;
    return world.createBody(def);
}

BodyId addBody(World& world, const ShapeDef& shape, Vec3 position, Vec3 velocity, Vec3 spin = {}, Quat rotation = {}) {
    BodyDef def;
    def.shape = world.createShape(shape);
    def.position = position;
    def.orientation = rotation;
    def.linearVelocity = velocity;
    def.angularVelocity = spin;
    return world.createBody(def);
}

/// A 5 cm ball fired at a 5 cm wall: after every step its centre is still in front of the wall's far face.
/// Returns how many steps ended with the ball past the wall.
int ballThroughWall(bool continuous, float speed, bool meshWall) {
    World world = makeWorld(continuous, false);
    const float wallX = 1.0f;
    if (meshWall) {
        // One-sided: two triangles facing -x (towards the ball), 4 m square.
        TriangleMeshDef quad;
        quad.vertices = {{wallX, -2, -2}, {wallX, -2, 2}, {wallX, 2, 2}, {wallX, 2, -2}};
        quad.indices = {0, 1, 2, 0, 2, 3};
        addStatic(world, quad, {});
    } else {
        addStatic(world, BoxDef{{0.025f, 2, 2}}, {wallX + 0.025f, 0, 0});
    }
    const BodyId ball = addBody(world, SphereDef{0.05f}, {0, 0, 0.3f}, {speed, 0, 0});
    int through = 0;
    for (int step = 0; step < 30; ++step) {
        world.step(kDt);
        through += world.position(ball).x > wallX ? 1 : 0;
    }
    return through;
}

TEST(ContinuousCollision, FastBallsStayInFrontOfAThinWallAndAOneSidedMeshWall) {
    for (float speed : {100.0f, 300.0f})
        for (bool mesh : {false, true}) {
            EXPECT_EQ(ballThroughWall(true, speed, mesh), 0) << speed << " m/s, " << (mesh ? "mesh" : "box") << " wall";
        }
}

/// Returns the number of steps at whose end a tip of the rod was beyond the wall's near face by more than its
/// thickness: a rod 2 m long and 2 cm thick, spinning about its centre, `wallX` in front of a 2 cm wall; at 50 rad/s
/// its tips sweep 0.83 m of arc a step, through where the wall is.
int spinningRodThroughWall(bool continuous, float spin, float wallX) {
    World world = makeWorld(continuous, false);
    addStatic(world, BoxDef{{0.01f, 2, 2}}, {wallX + 0.01f, 0, 0});
    // Along y at the start, so that both tips are in front of the wall.
    const BodyId rod = addBody(world, BoxDef{{1.0f, 0.01f, 0.01f}}, {0, 0, 0}, {}, {0, 0, spin},
                               Quat::fromAxisAngle({0, 0, 1}, 1.5707964f));
    int through = 0;
    for (int step = 0; step < 60; ++step) {
        world.step(kDt);
        const Transform t = world.transform(rod);
        for (float end : {-1.0f, 1.0f}) through += apply(t, {end, 0, 0}).x > wallX + 0.02f ? 1 : 0;
    }
    return through;
}

// The tips' speculative contacts, made from the rod's pose at the step's start, hold the rod: they did not while the
// hits spun it up (below), when a tip turned through the wall at 40 rad/s, 0.3 m from it, unless swept. Held with
// continuous collision and without, up to 2,000 rad/s (measured).
TEST(ContinuousCollision, SpinningRodDoesNotTurnThroughAThinWall) {
    for (const bool continuous : {true, false})
        for (float spin : {40.0f, 60.0f, 80.0f, 100.0f, 400.0f})
            for (float wallX : {0.3f, 0.45f, 0.6f, 0.9f})
                EXPECT_EQ(spinningRodThroughWall(continuous, spin, wallX), 0)
                    << spin << " " << wallX << " " << continuous;
}

/// S3's terrain (SCENES.md): 100 x 100 cells over [-50, 50]^2, y = 2 sin(x / 8) cos(z / 8).
TriangleMeshDef s3Terrain() {
    return rubble::test::gridMesh(100, 100, -50, -50,
                                  [](float x, float z) { return 2.0f * std::sin(x / 8.0f) * std::cos(z / 8.0f); });
}

/// Bodies whose centre is more than `depth` under the terrain (bodies beside it, which rolled off its edge, are not
/// counted), or under the ground's top at y = 0 when the world has no terrain.
int tunnelled(const World& world, const std::vector<BodyId>& bodies, float depth, bool terrain) {
    int count = 0;
    for (const BodyId id : bodies) {
        const Vec3 c = world.centerOfMass(id);
        float ground = 0;
        if (terrain && !world.terrainHeightAt(c.x, c.z, ground)) continue;
        count += c.y < ground - depth ? 1 : 0;
    }
    return count;
}

/// Planks 1 m x 2 cm x 40 cm thrown down at 50 m/s, level and tilted, onto a ground box or S3's terrain.
int planksThroughTheGround(bool continuous, bool terrain) {
    World world = makeWorld(continuous);
    if (terrain)
        addStatic(world, s3Terrain(), {});
    else
        addStatic(world, BoxDef{{50, 0.5f, 50}}, {0, -0.5f, 0});
    std::vector<BodyId> planks;
    for (int k = 0; k < 12; ++k) {
        const float x = -20.0f + 3.7f * static_cast<float>(k), z = 1.3f * static_cast<float>(k % 5) - 3.0f;
        const Quat tilt = Quat::fromAxisAngle({0.3f, 0.2f, 1.0f}, 0.25f * static_cast<float>(k % 4));
        planks.push_back(addBody(world, BoxDef{{0.5f, 0.01f, 0.2f}}, {x, 6, z}, {0, -50, 0}, {}, tilt));
    }
    int through = 0;
    std::vector<bool> counted(planks.size(), false);
    for (int step = 0; step < 60; ++step) {
        world.step(kDt);
        for (std::size_t k = 0; k < planks.size(); ++k)
            if (!counted[k] && tunnelled(world, {planks[k]}, 0.05f, terrain) > 0) counted[k] = true, ++through;
    }
    return through;
}

TEST(ContinuousCollision, ThinPlanksThrownAtTheGroundAndTheTerrainStayOnThem) {
    EXPECT_EQ(planksThroughTheGround(true, false), 0);
    EXPECT_EQ(planksThroughTheGround(true, true), 0);
}

// 1,000 balls dropped from 500 m (99 m/s, 1.65 m a step, at the terrain) onto S3's terrain: none ends under it.
TEST(ContinuousCollision, ThousandBallsDroppedFromFiveHundredMetresStayOnTheTerrain) {
    World world = makeWorld(true);
    addStatic(world, s3Terrain(), {});
    std::vector<BodyId> balls;
    // Under a sanitizer a tenth of them: the same sweeps, for the code the sanitizer watches.
    const int count = rubble::test::kSanitized ? 100 : 1000;
    for (int k = 0; k < count; ++k) {
        const float x = -45.0f + 3.0f * static_cast<float>(k % 31), z = -45.0f + 3.0f * static_cast<float>(k / 31);
        balls.push_back(addBody(world, SphereDef{0.5f}, {x, 500, z}, {}));
    }
    int worst = 0;
    std::uint32_t arrivingFast = 0;
    for (int step = 0; step < 680; ++step) {
        world.step(kDt);
        if (step == 600) arrivingFast = world.lastProfile().ccdBodies;
        if (step > 560) worst = std::max(worst, tunnelled(world, balls, 0.5f, true));
    }
    EXPECT_EQ(worst, 0);
    EXPECT_GT(arrivingFast, static_cast<std::uint32_t>(count * 9 / 10))
        << "the balls must have been swept as they arrived";
}

/// A bullet (5 cm, 300 m/s, flagged) fired into a row of five boxes standing 1.5 m apart: the first box stops it.
/// Returns the steps at whose end the bullet was past the first box's far face.
int bulletPastFirstBox(bool bullet, bool& firstBoxHit) {
    World world = makeWorld(true);
    addStatic(world, BoxDef{{50, 0.5f, 50}}, {0, -0.5f, 0});
    std::vector<BodyId> boxes;
    for (int k = 0; k < 5; ++k)
        boxes.push_back(addBody(world, BoxDef{{0.5f, 0.5f, 0.5f}}, {5.0f + 1.5f * k, 0.5f, 0}, {}));
    BodyDef def;
    def.shape = world.createShape(SphereDef{0.05f});
    def.position = {0, 0.5f, 0};
    def.linearVelocity = {300, 0, 0};
    def.gravityScale = 0;
    def.bullet = bullet;
    const BodyId shot = world.createBody(def);
    int past = 0;
    firstBoxHit = false;
    for (int step = 0; step < 20; ++step) {
        world.step(kDt);
        const float farFace = world.position(boxes[0]).x + 0.5f;
        past += world.position(shot).x > farFace + 0.05f ? 1 : 0;
        firstBoxHit = firstBoxHit || world.linearVelocity(boxes[0]).x > 0.01f;
    }
    return past;
}

TEST(ContinuousCollision, BulletIntoARowOfBoxesHitsTheFirstBox) {
    bool hit = false;
    EXPECT_EQ(bulletPastFirstBox(true, hit), 0);
    EXPECT_TRUE(hit);
}

// A box sliding without friction at 50 m/s over a flat mesh floor of 1 m cells (a triangle edge every 1-2 cm of its
// travel per substep) is never stopped at an internal edge: it keeps its speed and covers 50 m a second.
TEST(ContinuousCollision, FastSlideOverATessellatedFloorIsNeverStoppedAtAnEdge) {
    World world = makeWorld(true);
    const TriangleMeshDef floor = rubble::test::gridMesh(200, 4, -100, -2, [](float, float) { return 0.0f; });
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(floor);
    ground.material.friction = 0;
    world.createBody(ground);
    BodyDef def;
    def.shape = world.createShape(BoxDef{{0.3f, 0.1f, 0.3f}});
    def.position = {-90, 0.1f, 0.2f};
    def.linearVelocity = {50, 0, 0};
    def.material.friction = 0;
    const BodyId box = world.createBody(def);
    float slowest = 50;
    for (int step = 0; step < 120; ++step) {
        world.step(kDt);
        slowest = std::min(slowest, world.linearVelocity(box).x);
    }
    EXPECT_GT(slowest, 49.5f);
    EXPECT_NEAR(world.position(box).x, -90.0f + 100.0f, 0.5f);
}

// The stage's result does not depend on the thread count: bodies sweep in parallel, bullets after the rest.
TEST(ContinuousCollision, StateIsTheSameForOneAndTwoThreads) {
    const auto run = [](int threads) {
        World world = makeWorld(true, true, threads);
        addStatic(world,
                  rubble::test::gridMesh(40, 40, -20, -20, [](float x, float z) { return 0.3f * std::sin(x + z); }),
                  {});
        addStatic(world, BoxDef{{0.01f, 2, 20}}, {3, 1, 0});
        for (int k = 0; k < 300; ++k) {
            const float x = -15.0f + 0.1f * static_cast<float>(k), z = -10.0f + 0.07f * static_cast<float>(k);
            const ShapeDef shape = k % 3 == 0   ? ShapeDef{SphereDef{0.1f}}
                                   : k % 3 == 1 ? ShapeDef{BoxDef{{0.3f, 0.02f, 0.1f}}}
                                                : ShapeDef{CapsuleDef{0.05f, 0.2f}};
            BodyDef def;
            def.shape = world.createShape(shape);
            def.position = {x, 3.0f + 0.01f * static_cast<float>(k), z};
            def.linearVelocity = {60.0f * std::sin(0.3f * static_cast<float>(k)), -40, 0};
            def.angularVelocity = {0, 0, 30};
            def.bullet = k % 10 == 0;
            world.createBody(def);
        }
        std::uint32_t hits = 0;
        for (int step = 0; step < 40; ++step) {
            world.step(kDt);
            hits += world.lastProfile().ccdHits;
        }
        return std::pair{world.stateHash(), hits};
    };
    const auto one = run(1), two = run(2);
    EXPECT_GT(one.second, 0u) << "some bodies were moved back";
    EXPECT_EQ(one.first, two.first);
    EXPECT_EQ(one.second, two.second);
}

}  // namespace
}  // namespace rubble
