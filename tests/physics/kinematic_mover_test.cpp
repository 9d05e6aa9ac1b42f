// Kinematic movers (World::moveKinematic): the body reaches the pose it is sent to in one step, and the velocity that
// takes it there pushes and carries dynamic bodies as a platform or a door does.
//
// Tolerances: a pose reached over one step is exact up to the substeps' float rounding and the orientation
// integrator's error (an angle of a few degrees per step loses less than 1e-4 rad of it); a box standing on a platform
// that starts and stops smoothly is carried by friction (0.6 on both), so it keeps within a centimetre of the platform
// once the start's jerk is over.
#include <gtest/gtest.h>

#include <cmath>

#include "rubble/error.h"
#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

Quat aboutY(float angle) { return {0, std::sin(angle / 2), 0, std::cos(angle / 2)}; }

float angleBetween(Quat a, Quat b) {
    const float d = std::fabs(a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w);
    return 2 * std::acos(std::min(1.0f, d));
}

void addGround(World& world) {
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(BoxDef{{50, 0.5f, 50}});
    ground.position = {0, -0.5f, 0};
    world.createBody(ground);
}

BodyId addPlatform(World& world, Vec3 position) {
    BodyDef def;
    def.type = BodyType::Kinematic;
    def.shape = world.createShape(BoxDef{{1.5f, 0.1f, 1.5f}});
    def.position = position;
    return world.createBody(def);
}

TEST(KinematicMover, ReachesTheTargetPoseInOneStep) {
    World world;
    BodyDef def;
    def.type = BodyType::Kinematic;
    // A hull whose centre of mass is off its origin: the move is of the origin, the velocity of the centre of mass.
    def.shape = world.createShape(ConvexHullDef{{{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 1, 1}}});
    const BodyId body = world.createBody(def);
    Vec3 target{0, 0, 0};
    for (int i = 1; i <= 120; ++i) {
        target = {std::sin(0.05f * static_cast<float>(i)), 0.02f * static_cast<float>(i), 0};
        const Quat turn = aboutY(0.04f * static_cast<float>(i));
        world.moveKinematic(body, target, turn, kDt);
        world.step(kDt);
        EXPECT_LT(length(world.position(body) - target), 1e-4f) << "step " << i;
        EXPECT_LT(angleBetween(world.orientation(body), turn), 1e-3f) << "step " << i;
    }
}

TEST(KinematicMover, PlatformCarriesWhatStandsOnIt) {
    World world;
    addGround(world);
    const BodyId platform = addPlatform(world, {0, 1.0f, 0});
    BodyDef box;
    box.shape = world.createShape(BoxDef{{0.3f, 0.3f, 0.3f}});
    box.position = {0, 1.4f, 0};
    const BodyId cargo = world.createBody(box);
    for (int i = 0; i < 30; ++i) world.step(kDt);  // settles on the still platform
    const float offset = world.position(cargo).x - world.position(platform).x;
    // 2 m along x in 2 s, then up 0.5 m in 1 s, a lift, each leg starting and stopping smoothly (accelerations up to
    // pi m/s^2: friction holds the box up to 0.6 g).
    const float pi = 3.14159265f;
    for (int i = 1; i <= 180; ++i) {
        const float t = static_cast<float>(i) * kDt;
        const float up = t - 2;
        const Vec3 target = t <= 2 ? Vec3{t - std::sin(pi * t) / pi, 1.0f, 0}
                                   : Vec3{2, 1.0f + 0.5f * (up - std::sin(2 * pi * up) / (2 * pi)), 0};
        world.moveKinematic(platform, target, Quat{}, kDt);
        world.step(kDt);
    }
    EXPECT_NEAR(world.position(platform).x, 2.0f, 1e-3f);
    EXPECT_NEAR(world.position(platform).y, 1.5f, 1e-3f);
    EXPECT_NEAR(world.position(cargo).x - world.position(platform).x, offset, 0.01f);
    EXPECT_NEAR(world.position(cargo).y - world.position(platform).y, 0.4f, 0.01f);
}

TEST(KinematicMover, DoorPushesADynamicBoxAside) {
    World world;
    addGround(world);
    BodyDef door;
    door.type = BodyType::Kinematic;
    door.shape = world.createShape(BoxDef{{0.1f, 1, 1}});
    door.position = {-1, 1.0f, 0};
    const BodyId pusher = world.createBody(door);
    BodyDef box;
    box.shape = world.createShape(BoxDef{{0.25f, 0.25f, 0.25f}});
    box.position = {0, 0.25f, 0};
    const BodyId pushed = world.createBody(box);
    for (int i = 1; i <= 120; ++i) {
        world.moveKinematic(pusher, {-1 + 1.5f * static_cast<float>(i) * kDt, 1.0f, 0}, Quat{}, kDt);
        world.step(kDt);
        // Never inside the door (1 cm: the soft contact's give under the push).
        EXPECT_GT(world.position(pushed).x - 0.25f, world.position(pusher).x + 0.1f - 0.01f) << "step " << i;
    }
    EXPECT_GT(world.position(pushed).x, 1.2f);
}

TEST(KinematicMover, RefusesStaticAndDynamicBodiesAndBadInput) {
    World world;
    BodyDef def;
    def.shape = world.createShape(SphereDef{0.5f});
    const BodyId dynamic = world.createBody(def);
    def.type = BodyType::Static;
    const BodyId fixed = world.createBody(def);
    def.type = BodyType::Kinematic;
    const BodyId kinematic = world.createBody(def);
    const auto message = [&](BodyId id, Vec3 p, Quat q, float dt) {
        try {
            world.moveKinematic(id, p, q, dt);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message(dynamic, {}, {}, kDt).find("is dynamic"), std::string::npos);
    EXPECT_NE(message(fixed, {}, {}, kDt).find("is static"), std::string::npos);
    EXPECT_NE(message(kinematic, {NAN, 0, 0}, {}, kDt).find("position"), std::string::npos);
    EXPECT_NE(message(kinematic, {}, {0, 0, 0, 2}, kDt).find("orientation"), std::string::npos);
    EXPECT_NE(message(kinematic, {}, {}, 0).find("dt"), std::string::npos);
    EXPECT_EQ(message(kinematic, {1, 2, 3}, {}, kDt), "");
    EXPECT_NEAR(world.linearVelocity(kinematic).y, 2 / kDt, 1e-2f);
}

}  // namespace
}  // namespace rubble
