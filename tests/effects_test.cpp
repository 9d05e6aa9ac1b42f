// Effects: the engine drops declared effects that the world's content cannot show.
#include <gtest/gtest.h>

#include "rubble/world.h"

using namespace rubble;

TEST(Effects, FrictionlessSpheresInZeroGravityNeedOnlyMotion) {
    World world(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId ball = world.createShape(SphereDef{0.5f});
    BodyDef def;
    def.shape = ball;
    def.material = {0.0f, 1.0f, 1000.0f};
    world.createBody(def);
    const EffectSet active = world.activeEffects();
    EXPECT_FALSE(active.has(Effect::Gravity));
    EXPECT_FALSE(active.has(Effect::Rotation));
    EXPECT_FALSE(active.has(Effect::Friction));
    EXPECT_TRUE(active.has(Effect::Restitution));
    EXPECT_FALSE(active.has(Effect::Joints));
}

TEST(Effects, BoxesWithFrictionTurnAndDeclaredOffStaysOff) {
    World world;
    const ShapeId box = world.createShape(BoxDef{});
    BodyDef def;
    def.shape = box;
    world.createBody(def);
    EXPECT_TRUE(world.activeEffects().has(Effect::Rotation));
    EXPECT_TRUE(world.activeEffects().has(Effect::Gravity));
    EXPECT_TRUE(world.activeEffects().has(Effect::Friction));

    WorldSettings s = world.settings();
    s.effects = s.effects.without(Effect::Rotation);
    world.setSettings(s);
    EXPECT_FALSE(world.activeEffects().has(Effect::Rotation));
}

TEST(Effects, SpinningASphereTurnsRotationOn) {
    World world(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId ball = world.createShape(SphereDef{0.5f});
    BodyDef def;
    def.shape = ball;
    def.material.friction = 0;
    const BodyId id = world.createBody(def);
    EXPECT_FALSE(world.activeEffects().has(Effect::Rotation));
    world.setAngularVelocity(id, {0, 1, 0});
    EXPECT_TRUE(world.activeEffects().has(Effect::Rotation));
    world.step(0.1f);
    // The sphere really turned: its orientation moved away from the identity about y.
    EXPECT_GT(std::abs(world.orientation(id).y), 0.04f);
}

TEST(Effects, NamesRoundTrip) {
    for (int b = 0; b < kEffectCount; ++b) {
        const auto e = static_cast<Effect>(1u << b);
        EXPECT_EQ(effectFromName(effectName(e)), e);
    }
    EXPECT_FALSE(effectFromName("telekinesis").has_value());
    EXPECT_EQ(integratorFromName("rk4"), Integrator::RungeKutta4);
    EXPECT_EQ(broadPhaseFromName("sap"), BroadPhaseKind::SweepAndPrune);
}
