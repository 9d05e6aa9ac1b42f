// Sleeping per island through the World API: what falls asleep, what stays put, what wakes it.
//
// Tolerances: a box dropped 0.5 m lands in 0.32 s and the Baumgarte contact settles it within a few tenths of a
// second, so with timeToSleep = 0.5 s it must be asleep within 2 s. A sleeping body is not integrated, so "stays put"
// is exact (bit for bit). "Moves" after a wake means more than 1 cm, far above the solver's resting drift.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/error.h"
#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

WorldSettings sleepySettings(int threads = 1) {
    WorldSettings s;
    s.threads = threads;
    s.effects = EffectSet::defaults().with(Effect::Sleeping);
    return s;
}

BodyId addGround(World& world) {
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(BoxDef{{50, 0.5f, 50}});
    def.position = {0, -0.5f, 0};
    return world.createBody(def);
}

BodyId addBox(World& world, Vec3 position, BodyType type = BodyType::Dynamic) {
    BodyDef def;
    def.type = type;
    def.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    def.position = position;
    return world.createBody(def);
}

void steps(World& world, int n) {
    for (int i = 0; i < n; ++i) world.step(kDt);
}

/// Steps until `body` sleeps; returns the time it took, or a negative number if it did not within `limit` s.
float timeToFallAsleep(World& world, BodyId body, float limit) {
    for (int i = 1; i * kDt <= limit; ++i) {
        world.step(kDt);
        if (!world.isAwake(body)) return static_cast<float>(i) * kDt;
    }
    return -1;
}

float distance(Vec3 a, Vec3 b) { return length(a - b); }

TEST(Sleeping, DroppedBoxFallsAsleepAndStaysPut) {
    World world(sleepySettings());
    addGround(world);
    const BodyId box = addBox(world, {0, 1.0f, 0});
    const float t = timeToFallAsleep(world, box, 2.0f);
    ASSERT_GT(t, world.settings().sleep.timeToSleep);
    EXPECT_EQ(world.lastProfile().sleepingBodies, 1u);
    const Transform rest = world.transform(box);
    EXPECT_NEAR(rest.position.y, 0.5f, 0.02f);
    steps(world, 120);
    EXPECT_FALSE(world.isAwake(box));
    EXPECT_EQ(world.transform(box).position, rest.position);
    EXPECT_EQ(world.linearVelocity(box), Vec3{});
    EXPECT_EQ(world.angularVelocity(box), Vec3{});
    // Its contact with the ground is neither found nor solved while it sleeps.
    EXPECT_EQ(world.lastProfile().manifolds, 0u);
    EXPECT_EQ(world.lastProfile().constraints, 0u);
}

TEST(Sleeping, WithoutTheEffectNothingSleeps) {
    WorldSettings s = sleepySettings();
    s.effects = s.effects.without(Effect::Sleeping);
    World world(s);
    addGround(world);
    const BodyId box = addBox(world, {0, 1.0f, 0});
    for (int i = 0; i < 300; ++i) {
        world.step(kDt);
        ASSERT_TRUE(world.isAwake(box));
        ASSERT_EQ(world.lastProfile().sleepingBodies, 0u);
    }
}

TEST(Sleeping, TurningTheEffectOffWakesEverything) {
    World world(sleepySettings());
    addGround(world);
    const BodyId box = addBox(world, {0, 1.0f, 0});
    ASSERT_GT(timeToFallAsleep(world, box, 2.0f), 0);
    WorldSettings s = world.settings();
    s.effects = s.effects.without(Effect::Sleeping);
    world.setSettings(s);
    world.step(kDt);
    EXPECT_TRUE(world.isAwake(box));
}

struct Woken {
    World world{sleepySettings()};
    BodyId box;
    Vec3 rest;
    Woken() {
        addGround(world);
        box = addBox(world, {0, 1.0f, 0});
        EXPECT_GT(timeToFallAsleep(world, box, 2.0f), 0);
        rest = world.position(box);
    }
};

TEST(Sleeping, ABallHittingASleepingBoxWakesAndMovesIt) {
    Woken w;
    BodyDef ball;
    ball.shape = w.world.createShape(SphereDef{0.25f});
    ball.position = {-3, 0.5f, 0};
    ball.linearVelocity = {6, 0, 0};
    ball.gravityScale = 0;
    ball.material.density = 4000;
    w.world.createBody(ball);
    bool woke = false;
    for (int i = 0; i < 60 && !woke; ++i) {
        w.world.step(kDt);
        woke = w.world.isAwake(w.box);
    }
    ASSERT_TRUE(woke);
    steps(w.world, 10);
    EXPECT_GT(w.world.position(w.box).x - w.rest.x, 0.01f);
}

TEST(Sleeping, ImpulseWakesAndMoves) {
    Woken w;
    w.world.applyLinearImpulse(w.box, {0, 2000, 0});
    EXPECT_TRUE(w.world.isAwake(w.box));
    steps(w.world, 5);
    EXPECT_GT(w.world.position(w.box).y - w.rest.y, 0.01f);
}

TEST(Sleeping, ForceWakesAndMoves) {
    Woken w;
    w.world.addForce(w.box, {0, 3 * 1000 * 9.81f, 0});
    EXPECT_TRUE(w.world.isAwake(w.box));
    steps(w.world, 1);
    EXPECT_GT(w.world.linearVelocity(w.box).y, 0.1f);
}

TEST(Sleeping, SetLinearVelocityWakesAndMoves) {
    Woken w;
    w.world.setLinearVelocity(w.box, {2, 0, 0});
    EXPECT_TRUE(w.world.isAwake(w.box));
    steps(w.world, 5);
    EXPECT_GT(w.world.position(w.box).x - w.rest.x, 0.01f);
}

TEST(Sleeping, WakeUpWakesTheBodyAndItFallsAsleepAgain) {
    Woken w;
    w.world.wakeUp(w.box);
    EXPECT_TRUE(w.world.isAwake(w.box));
    // Nothing pushes it, so it rests again after timeToSleep, without having moved more than the resting drift.
    EXPECT_GT(timeToFallAsleep(w.world, w.box, 1.0f), 0);
    EXPECT_LT(distance(w.world.position(w.box), w.rest), 1e-3f);
}

std::vector<BodyId> addStack(World& world, int height, float x = 0) {
    std::vector<BodyId> boxes;
    for (int k = 0; k < height; ++k) boxes.push_back(addBox(world, {x, 0.5f + static_cast<float>(k), 0}));
    return boxes;
}

TEST(Sleeping, RemovingTheBottomBoxWakesTheStackAndItFalls) {
    World world(sleepySettings());
    addGround(world);
    const std::vector<BodyId> stack = addStack(world, 4);
    ASSERT_GT(timeToFallAsleep(world, stack.back(), 3.0f), 0);
    for (BodyId b : stack) ASSERT_FALSE(world.isAwake(b));
    const float topBefore = world.position(stack.back()).y;
    world.destroyBody(stack.front());
    for (std::size_t k = 1; k < stack.size(); ++k) EXPECT_TRUE(world.isAwake(stack[k]));
    steps(world, 40);
    // It falls by one box height (1 m) onto the ground; 0.9 m allows for the landing.
    EXPECT_LT(world.position(stack.back()).y, topBefore - 0.9f);
}

TEST(Sleeping, RemovingSeveralBodiesBetweenStepsWakesExactlyTheStacksTheyHeld) {
    // The first removal after a step indexes who touches a sleeping body; the later ones look up the same index
    // after the first has woken a stack, and a body created in between may take a removed body's slot.
    World world(sleepySettings());
    addGround(world);
    std::vector<std::vector<BodyId>> stacks;
    for (int k = 0; k < 4; ++k) stacks.push_back(addStack(world, 3, -6.0f + 4.0f * static_cast<float>(k)));
    for (const auto& stack : stacks) ASSERT_GT(timeToFallAsleep(world, stack.back(), 3.0f), 0);
    for (const auto& stack : stacks)
        for (BodyId b : stack) ASSERT_FALSE(world.isAwake(b));
    world.destroyBody(stacks[0].front());
    const BodyId newcomer = addBox(world, {0, 10, 20});
    world.destroyBody(stacks[1].front());
    world.destroyBody(newcomer);
    world.destroyBody(stacks[2].front());
    for (int k = 0; k < 3; ++k)
        for (std::size_t b = 1; b < stacks[k].size(); ++b) EXPECT_TRUE(world.isAwake(stacks[k][b])) << "stack " << k;
    for (BodyId b : stacks[3]) EXPECT_FALSE(world.isAwake(b)) << "the untouched stack sleeps on";
}

TEST(Sleeping, RemovingTheGroundWakesWhatRestsOnIt) {
    World world(sleepySettings());
    const BodyId ground = addGround(world);
    const BodyId box = addBox(world, {0, 1.0f, 0});
    ASSERT_GT(timeToFallAsleep(world, box, 2.0f), 0);
    world.destroyBody(ground);
    EXPECT_TRUE(world.isAwake(box));
    steps(world, 30);
    EXPECT_LT(world.position(box).y, 0.0f);
}

TEST(Sleeping, APileSleepsAsAUnit) {
    World world(sleepySettings());
    addGround(world);
    // A slab on the ground with a ball rolling on it: the slab rests, but shares an island with the moving ball.
    BodyDef slab;
    slab.shape = world.createShape(BoxDef{{4, 0.25f, 4}});
    slab.position = {0, 0.25f, 0};
    const BodyId slabId = world.createBody(slab);
    BodyDef ball;
    ball.shape = world.createShape(SphereDef{0.25f});
    ball.position = {-3, 0.75f, 0};
    ball.linearVelocity = {1.5f, 0, 0};
    ball.angularVelocity = {0, 0, -6};  // rolling without slipping: w = v / r
    const BodyId ballId = world.createBody(ball);
    // A box far away sleeps on its own: islands sleep independently.
    const BodyId loner = addBox(world, {20, 0.5f, 0});
    bool lonerSlept = false;
    for (int i = 0; i < 150; ++i) {
        world.step(kDt);
        lonerSlept = lonerSlept || !world.isAwake(loner);
        if (length(world.linearVelocity(ballId)) > world.settings().sleep.linearThreshold) {
            ASSERT_TRUE(world.isAwake(slabId)) << "step " << i;
            ASSERT_TRUE(world.isAwake(ballId)) << "step " << i;
        }
        ASSERT_EQ(world.isAwake(slabId), world.isAwake(ballId)) << "step " << i;
    }
    EXPECT_TRUE(lonerSlept);
    EXPECT_TRUE(world.isAwake(slabId));
}

// Bodies that touch nothing are in no island of the step; they still rest, fall asleep each on its own, and wake when
// something hits them.
TEST(Sleeping, ABodyTouchingNothingSleepsAloneAndWakesWhenHit) {
    WorldSettings settings = sleepySettings();
    settings.effects = settings.effects.without(Effect::Gravity);
    World world(settings);
    const BodyId floating = addBox(world, {0, 5, 0});
    const BodyId other = addBox(world, {10, 5, 0});
    // At rest from the start, it sleeps once its timer reaches timeToSleep (to float rounding of the summed steps).
    const float t = timeToFallAsleep(world, floating, 2.0f);
    ASSERT_NEAR(t, world.settings().sleep.timeToSleep, 1.5f * kDt);
    EXPECT_FALSE(world.isAwake(other));
    EXPECT_EQ(world.lastProfile().sleepingBodies, 2u);
    EXPECT_EQ(world.lastProfile().islands, 0u);  // nothing touches anything
    // A ball thrown at the sleeping box wakes it (and only it) and moves it.
    BodyDef ball;
    ball.shape = world.createShape(SphereDef{0.25f});
    ball.position = {-3, 5, 0};
    ball.linearVelocity = {6, 0, 0};
    world.createBody(ball);
    steps(world, 60);
    EXPECT_GT(distance(world.transform(floating).position, {0, 5, 0}), 0.01f);
    EXPECT_FALSE(world.isAwake(other));
    EXPECT_EQ(world.transform(other).position, (Vec3{10, 5, 0}));
}

TEST(Sleeping, AMovingKinematicBodyKeepsWhatItCarriesAwake) {
    World world(sleepySettings());
    const BodyId platform = addBox(world, {0, 0.5f, 0}, BodyType::Kinematic);
    world.setLinearVelocity(platform, {0.5f, 0, 0});
    const BodyId box = addBox(world, {0, 1.5f, 0});
    for (int i = 0; i < 120; ++i) {
        world.step(kDt);
        ASSERT_TRUE(world.isAwake(box)) << "step " << i;
    }
    // Friction carries it along with the platform.
    EXPECT_GT(world.position(box).x, 0.5f);
    world.setLinearVelocity(platform, {});
    EXPECT_GT(timeToFallAsleep(world, box, 2.0f), 0);
}

TEST(Sleeping, AllowSleepFalseKeepsItsIslandAwake) {
    World world(sleepySettings());
    addGround(world);
    BodyDef def;
    def.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    def.position = {0, 0.5f, 0};
    def.allowSleep = false;
    const BodyId bottom = world.createBody(def);
    const BodyId top = addBox(world, {0, 1.5f, 0});
    steps(world, 120);
    EXPECT_TRUE(world.isAwake(bottom));
    EXPECT_TRUE(world.isAwake(top));
}

/// Pyramids that settle and fall asleep, then balls thrown at some of them: sleeping, waking by touch and
/// warm-started restored contacts all happen; the state must be bit-identical for 1 and 2 threads.
std::uint64_t sleepingSceneHash(int threads, std::uint32_t& maxAsleep, std::uint32_t& minAsleepAfterHits) {
    World world(sleepySettings(threads));
    addGround(world);
    const ShapeId cube = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    for (int p = 0; p < 4; ++p)
        for (int k = 0; k < 4; ++k)
            for (int i = 0; i < 4 - k; ++i) {
                BodyDef def;
                def.shape = cube;
                def.position = {static_cast<float>(p) * 8.0f + static_cast<float>(i) - (3 - k) * 0.5f,
                                0.5f + static_cast<float>(k), 0};
                world.createBody(def);
            }
    maxAsleep = 0;
    for (int i = 0; i < 120; ++i) {
        world.step(kDt);
        maxAsleep = std::max(maxAsleep, world.lastProfile().sleepingBodies);
    }
    const ShapeId ballShape = world.createShape(SphereDef{0.3f});
    for (int p = 0; p < 4; p += 2) {
        BodyDef ball;
        ball.shape = ballShape;
        ball.position = {static_cast<float>(p) * 8.0f, 1.0f, -4};
        ball.linearVelocity = {0, 0, 10};
        ball.gravityScale = 0;
        world.createBody(ball);
    }
    minAsleepAfterHits = ~0u;
    for (int i = 0; i < 60; ++i) {
        world.step(kDt);
        minAsleepAfterHits = std::min(minAsleepAfterHits, world.lastProfile().sleepingBodies);
    }
    return world.stateHash();
}

TEST(Sleeping, StateHashDoesNotDependOnTheThreadCount) {
    std::uint32_t asleep1, woken1, asleep2, woken2;
    const std::uint64_t h1 = sleepingSceneHash(1, asleep1, woken1);
    const std::uint64_t h2 = sleepingSceneHash(2, asleep2, woken2);
    EXPECT_EQ(h1, h2);
    // Every pyramid slept (40 cubes), and the balls woke two of them.
    EXPECT_EQ(asleep1, 40u);
    EXPECT_LE(woken1, 20u);
    EXPECT_EQ(asleep1, asleep2);
    EXPECT_EQ(woken1, woken2);
}

TEST(Sleeping, SettingsAreValidated) {
    World world(sleepySettings());
    WorldSettings s = world.settings();
    s.sleep.timeToSleep = -1;
    EXPECT_THROW(world.setSettings(s), Error);
    s = world.settings();
    s.sleep.linearThreshold = std::nanf("");
    EXPECT_THROW(world.setSettings(s), Error);
}

}  // namespace
}  // namespace rubble
