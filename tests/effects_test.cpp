// Effects: the engine drops declared effects that the world's content cannot show.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "rubble/world.h"
#include "world/effects.h"
#include "world/world_access.h"

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

// A static body's material counts as a moving one's, and keeps counting through its coming, its changes and its
// going (the world keeps counts of static materials rather than scanning its static bodies).
TEST(Effects, StaticBodiesMaterialsCountAsTheyComeChangeAndGo) {
    World world(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId ball = world.createShape(SphereDef{0.5f});
    BodyDef moving;
    moving.shape = ball;
    moving.material = {0.0f, 0.0f, 1000.0f};
    world.createBody(moving);
    EXPECT_FALSE(world.activeEffects().has(Effect::Friction));
    EXPECT_FALSE(world.activeEffects().has(Effect::Restitution));

    BodyDef wall;
    wall.type = BodyType::Static;
    wall.shape = ball;
    wall.position = {5, 0, 0};
    wall.material = {0.5f, 0.0f, 1000.0f};
    const BodyId rough = world.createBody(wall);
    wall.material = {0.0f, 0.0f, 1000.0f};
    const BodyId smooth = world.createBody(wall);
    EXPECT_TRUE(world.activeEffects().has(Effect::Friction));
    EXPECT_FALSE(world.activeEffects().has(Effect::Restitution));

    world.setMaterial(smooth, {0.0f, 0.8f, 1000.0f});
    EXPECT_TRUE(world.activeEffects().has(Effect::Restitution));
    world.destroyBody(rough);
    EXPECT_FALSE(world.activeEffects().has(Effect::Friction));
    world.setMaterial(smooth, {0.0f, 0.0f, 1000.0f});
    EXPECT_FALSE(world.activeEffects().has(Effect::Restitution));
    world.setMaterial(smooth, {0.3f, 0.0f, 1000.0f});
    EXPECT_TRUE(world.activeEffects().has(Effect::Friction));
    world.destroyBody(smooth);
    EXPECT_FALSE(world.activeEffects().has(Effect::Friction));
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

TEST(Effects, MovingBodiesMaterialsCountAsTheyComeChangeAndGo) {
    // The counts that decide the effects are kept body by body (a world of a million does not scan them all when one
    // comes or goes): after every creation, removal and change of material they must equal a count from scratch.
    World world;
    const ShapeId ball = world.createShape(SphereDef{0.5f});
    const ShapeId box = world.createShape(BoxDef{});
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> pick(0, 7);
    std::vector<BodyId> bodies;
    const auto check = [&](int op) {
        const auto& w = detail::WorldAccess::of(static_cast<const World&>(world));
        ASSERT_TRUE(w.movingMaterials == detail::countMovingMaterials(w.bodies.moving, w.shapes)) << "after op " << op;
    };
    for (int op = 0; op < 400; ++op) {
        const int what = pick(rng);
        if (what < 4 || bodies.empty()) {
            BodyDef def;
            def.shape = what % 2 ? ball : box;
            def.type = what == 3 ? BodyType::Kinematic : BodyType::Dynamic;
            def.material = {float(pick(rng) % 2) * 0.5f, float(pick(rng) % 2) * 0.5f, 1000.0f};
            def.linearDamping = pick(rng) == 0 ? 0.1f : 0.0f;
            def.gravityScale = pick(rng) == 0 ? 0.0f : 1.0f;
            def.position = {float(op), 0, 0};
            bodies.push_back(world.createBody(def));
        } else if (what < 6) {
            const std::size_t k = std::size_t(pick(rng)) % bodies.size();
            world.destroyBody(bodies[k]);
            bodies.erase(bodies.begin() + std::ptrdiff_t(k));
        } else {
            world.setMaterial(bodies[std::size_t(pick(rng)) % bodies.size()],
                              {float(pick(rng) % 2) * 0.3f, float(pick(rng) % 2) * 0.3f, 500.0f});
        }
        check(op);
        if (::testing::Test::HasFatalFailure()) return;
        if (op % 50 == 0) world.step(1.0f / 60);
    }
}
