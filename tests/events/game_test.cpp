// A game, in one test, through the public API only: a character walks a course (corridor, stairs, a lift to a
// ledge), picks up a coin on the way (a sensor, collected exactly once and then removed), and at the ledge's end
// fires a projectile at a crate; the projectile's hit event reports the impulse that stopped it, checked against the
// projectile's own change of momentum (it touches nothing else and flies without gravity).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/character.h"
#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

BodyId addBox(World& world, Vec3 center, Vec3 half, BodyType type = BodyType::Static) {
    BodyDef def;
    def.type = type;
    def.shape = world.createShape(BoxDef{half});
    def.position = center;
    return world.createBody(def);
}

TEST(Game, CharacterWalksCollectsACoinOnceAndItsShotReportsItsImpulse) {
    WorldSettings settings;
    settings.effects = EffectSet::defaults().with(Effect::ContinuousCollision);
    World world(settings);
    TriangleMeshDef floorMesh;
    floorMesh.vertices = {{-5, 0, -5}, {-5, 0, 5}, {30, 0, -5}, {30, 0, 5}};
    floorMesh.indices = {0, 1, 2, 2, 1, 3};
    BodyDef floorDef;
    floorDef.type = BodyType::Static;
    floorDef.shape = world.createShape(floorMesh);
    world.createBody(floorDef);
    addBox(world, {3, 1, 1.2f}, {3, 1, 0.1f});  // corridor
    addBox(world, {3, 1, -1.2f}, {3, 1, 0.1f});
    for (int s = 0; s < 3; ++s)  // stairs of 0.25 m up to a landing at 0.75 m, x in [8, 12]
        addBox(world, {0.5f * (8 + 0.4f * static_cast<float>(s) + 12), 0.125f * static_cast<float>(s + 1), 0},
               {0.5f * (12 - 8 - 0.4f * static_cast<float>(s)), 0.125f * static_cast<float>(s + 1), 1.5f});
    const BodyId lift = addBox(world, {14, 0.75f - 0.1f, 0}, {1, 0.1f, 1.5f}, BodyType::Kinematic);
    addBox(world, {20, 1.25f, 0}, {5, 1.25f, 1.5f});  // ledge, 2.5 m high, x in [15, 25]
    const BodyId crate = addBox(world, {24, 2.9f, 0}, {0.4f, 0.4f, 0.4f}, BodyType::Dynamic);
    BodyDef coinDef;
    coinDef.type = BodyType::Static;
    coinDef.shape = world.createShape(SphereDef{0.3f});
    coinDef.position = {4, 1, 0};
    coinDef.sensor = true;
    const BodyId coin = world.createBody(coinDef);

    CharacterController hero(world, {-2, 0.02f, 0});
    float liftTop = 0.75f;
    int coins = 0;
    const auto frame = [&](Vec3 walk) {
        // The lift rises at 1 m/s while the hero rides it, up to the ledge's top.
        if (hero.ground() == lift) liftTop = std::min(2.5f, liftTop + kDt);
        world.moveKinematic(lift, {14, liftTop - 0.1f, 0}, {}, kDt);
        hero.update(kDt, walk);
        world.step(kDt);
        for (const SensorBeginEvent& e : world.sensorEvents().begins)
            if (e.sensor == coin && e.visitor == hero.body()) {
                ++coins;
                world.destroyBody(coin);
            }
    };
    const auto walkTo = [&](float x, float seconds) {
        for (int i = 0; i * kDt < seconds; ++i) {
            const float d = x - hero.position().x;
            if (std::fabs(d) < 0.05f) return true;
            frame({std::copysign(std::min(3.0f, std::fabs(d) / kDt), d), 0, -hero.position().z});
        }
        return false;
    };
    ASSERT_TRUE(walkTo(7, 5));  // through the corridor and the coin
    EXPECT_EQ(coins, 1);
    ASSERT_TRUE(walkTo(11.5f, 3));  // up the stairs
    EXPECT_NEAR(hero.position().y, 0.75f, 0.02f);
    ASSERT_TRUE(walkTo(14, 3));  // onto the lift
    for (int i = 0; i < 150; ++i) frame({});
    EXPECT_NEAR(hero.position().y, 2.5f, 0.02f);
    ASSERT_TRUE(walkTo(21, 4));  // onto the ledge
    EXPECT_TRUE(hero.grounded());
    EXPECT_EQ(coins, 1);

    // Fire: a 5 cm steel ball at 60 m/s from knee height at the crate 3 m ahead.
    BodyDef shot;
    shot.shape = world.createShape(SphereDef{0.05f});
    shot.position = hero.position() + Vec3{0.5f, 0.5f, 0};
    shot.linearVelocity = {60, 0, 0};
    shot.gravityScale = 0;
    shot.material.density = 7800;
    shot.contactEvents = true;
    shot.bullet = true;
    const BodyId bullet = world.createBody(shot);
    const float mass = world.massProperties(bullet).mass;
    int hits = 0;
    for (int i = 0; i < 30 && hits == 0; ++i) {
        const float before = world.linearVelocity(bullet).x;
        frame({});
        for (const ContactHitEvent& hit : world.contactEvents().hits) {
            ASSERT_TRUE((hit.a == bullet && hit.b == crate) || (hit.a == crate && hit.b == bullet));
            ++hits;
            const float stopped = mass * (before - world.linearVelocity(bullet).x);
            EXPECT_GT(stopped, 0.5f * mass * 60);
            EXPECT_NEAR(hit.impulse, stopped, 0.02f * stopped);  // the bullet's only contact: momentum balance
            EXPECT_NEAR(hit.approachSpeed, 60, 1);
        }
    }
    EXPECT_EQ(hits, 1);
    EXPECT_GT(world.linearVelocity(crate).x, 0.0f);  // the crate took the blow
}

}  // namespace
}  // namespace rubble
