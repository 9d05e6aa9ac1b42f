// Sensors through the public API: overlaps checked against exact sphere-box geometry, a pickup collected exactly
// once, sensors that push nothing (the same world without the sensor runs bit for bit the same), and what sensors
// do not see (filtered bodies, other sensors) or are not seen by (queries, continuous collision).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

BodyId addFloor(World& world) {
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(BoxDef{{50, 0.5f, 50}});
    def.position = {0, -0.5f, 0};
    return world.createBody(def);
}

BodyId addSensorBox(World& world, BodyType type, Vec3 position, Vec3 halfExtents, CollisionFilter filter = {}) {
    BodyDef def;
    def.type = type;
    def.shape = world.createShape(BoxDef{halfExtents});
    def.position = position;
    def.sensor = true;
    def.filter = filter;
    return world.createBody(def);
}

BodyId addBall(World& world, Vec3 position, Vec3 velocity, float radius = 0.2f) {
    BodyDef def;
    def.shape = world.createShape(SphereDef{radius});
    def.position = position;
    def.linearVelocity = velocity;
    return world.createBody(def);
}

/// Distance from p to the axis-aligned box [lo, hi] (0 inside).
float distanceToBox(Vec3 p, Vec3 lo, Vec3 hi) {
    const Vec3 d{std::max({lo.x - p.x, 0.0f, p.x - hi.x}), std::max({lo.y - p.y, 0.0f, p.y - hi.y}),
                 std::max({lo.z - p.z, 0.0f, p.z - hi.z})};
    return length(d);
}

TEST(Sensors, StaticSensorOverlapsMatchSphereBoxGeometryEveryStep) {
    World world;
    addFloor(world);
    const Vec3 center{0, 1.0f, 0}, half{1.0f, 0.5f, 1.0f};
    const BodyId sensor = addSensorBox(world, BodyType::Static, center, half);
    std::vector<BodyId> balls;
    const float r = 0.2f;
    // Thrown across and dropped through the sensor from several sides.
    for (int k = 0; k < 12; ++k) {
        const float a = 0.52f * static_cast<float>(k);
        balls.push_back(addBall(world, {3 * std::cos(a), 2.5f + 0.1f * static_cast<float>(k), 3 * std::sin(a)},
                                {-4 * std::cos(a), 1.0f, -4 * std::sin(a)}, r));
    }
    std::set<unsigned> inside;
    int compared = 0, insideSeen = 0, entries = 0;
    for (int i = 0; i < 120; ++i) {
        std::vector<Vec3> start;
        for (const BodyId b : balls) start.push_back(world.position(b));
        world.step(kDt);
        for (const SensorBeginEvent& e : world.sensorEvents().begins) {
            EXPECT_EQ(e.sensor, sensor);
            EXPECT_TRUE(inside.insert(e.visitor.index).second);
            ++entries;
        }
        for (const SensorEndEvent& e : world.sensorEvents().ends) EXPECT_EQ(inside.erase(e.visitor.index), 1u);
        // Overlaps are found from where the bodies start the step: a ball whose centre is within r of the box (1 mm
        // either side left out: the kernel's float depth may fall either way).
        for (std::size_t p = 0; p < balls.size(); ++p) {
            const float d = distanceToBox(start[p], center - half, center + half);
            if (std::fabs(d - r) < 1e-3f) continue;
            EXPECT_EQ(inside.count(balls[p].index) == 1, d < r) << "step " << i << " ball " << p << " at " << d;
            insideSeen += d < r;
            ++compared;
        }
    }
    EXPECT_GE(entries, 12);
    EXPECT_GT(insideSeen, 100);
    EXPECT_GT(compared, 1000);
}

TEST(Sensors, PickupIsCollectedExactlyOnceAndPushesNothing) {
    // The same rolling ball with and without a pickup in its path: the pickup must not change a bit of its motion.
    const auto run = [](bool withPickup, int& collected, int& left) {
        World world;
        addFloor(world);
        const BodyId ball = addBall(world, {-3, 0.2f, 0}, {3, 0, 0});
        BodyId pickup;
        if (withPickup) pickup = addSensorBox(world, BodyType::Kinematic, {0, 0.5f, 0}, {0.25f, 0.25f, 0.25f});
        for (int i = 0; i < 150; ++i) {
            world.step(kDt);
            for (const SensorBeginEvent& e : world.sensorEvents().begins) {
                EXPECT_EQ(e.sensor, pickup);
                EXPECT_EQ(e.visitor, ball);
                ++collected;
            }
            left += static_cast<int>(world.sensorEvents().ends.size());
        }
        return world.transform(ball);
    };
    int collected = 0, left = 0, none = 0, noneLeft = 0;
    const Transform with = run(true, collected, left);
    const Transform without = run(false, none, noneLeft);
    EXPECT_EQ(collected, 1);
    EXPECT_EQ(left, 1);
    EXPECT_GT(with.position.x, 1.0f);  // past the pickup
    EXPECT_EQ(with.position, without.position);
    EXPECT_EQ(with.rotation, without.rotation);
}

TEST(Sensors, FilteredBodiesAndOtherSensorsAreNotSeen) {
    World world;
    addFloor(world);
    const BodyId sensor = addSensorBox(world, BodyType::Static, {0, 1, 0}, {2, 1, 2}, {1, 0xFFFFFFFFu & ~4u});
    addSensorBox(world, BodyType::Kinematic, {0.5f, 1, 0}, {0.3f, 0.3f, 0.3f});
    BodyDef ghost;
    ghost.shape = world.createShape(SphereDef{0.2f});
    ghost.position = {-0.5f, 1, 0};
    ghost.filter = {4, 0xFFFFFFFFu};
    world.createBody(ghost);
    const BodyId seen = addBall(world, {0, 1, 1}, {});
    world.step(kDt);
    ASSERT_EQ(world.sensorEvents().begins.size(), 1u);
    EXPECT_EQ(world.sensorEvents().begins[0].sensor, sensor);
    EXPECT_EQ(world.sensorEvents().begins[0].visitor, seen);
    EXPECT_TRUE(world.isSensor(sensor));
    EXPECT_FALSE(world.isSensor(seen));
}

TEST(Sensors, MovingSensorSeesStaticBodiesAndBodiesWithoutResponse) {
    World world;
    const BodyId floor = addFloor(world);
    const BodyId sensor = addSensorBox(world, BodyType::Kinematic, {0, 0.2f, 0}, {0.5f, 0.5f, 0.5f});
    BodyDef ghost;
    ghost.type = BodyType::Kinematic;
    ghost.shape = world.createShape(SphereDef{0.2f});
    ghost.position = {3, 1, 0};
    ghost.contactResponse = false;
    const BodyId visitor = world.createBody(ghost);
    world.step(kDt);
    ASSERT_EQ(world.sensorEvents().begins.size(), 1u);
    EXPECT_EQ(world.sensorEvents().begins[0].visitor, floor);
    world.moveKinematic(visitor, {0, 0.5f, 0}, {}, kDt);
    world.step(kDt);
    world.setLinearVelocity(visitor, {});
    world.step(kDt);
    ASSERT_EQ(world.sensorEvents().begins.size(), 1u);
    EXPECT_EQ(world.sensorEvents().begins[0].sensor, sensor);
    EXPECT_EQ(world.sensorEvents().begins[0].visitor, visitor);
}

TEST(Sensors, DynamicSensorFallsThroughWhatItReportsAndPushesNothing) {
    // A falling dynamic sensor passes through a stack of boxes (pushing none: they keep their places bit for bit
    // against the same stack without it) and reports each box as it passes, then the floor, which it falls through.
    const auto run = [](bool withSensor, std::vector<BodyId>& seen) {
        World world;
        addFloor(world);
        std::vector<BodyId> boxes;
        for (int k = 0; k < 3; ++k) {
            BodyDef box;
            box.shape = world.createShape(BoxDef{{0.5f, 0.25f, 0.5f}});
            box.position = {0, 0.25f + 0.5f * static_cast<float>(k), 0};
            boxes.push_back(world.createBody(box));
        }
        if (withSensor) {
            BodyDef probe;
            probe.shape = world.createShape(SphereDef{0.2f});
            probe.position = {0, 3, 0};
            probe.sensor = true;
            const BodyId sensor = world.createBody(probe);
            for (int i = 0; i < 90; ++i) {
                world.step(kDt);
                for (const SensorBeginEvent& e : world.sensorEvents().begins) {
                    EXPECT_EQ(e.sensor, sensor);
                    seen.push_back(e.visitor);
                }
            }
            EXPECT_LT(world.position(sensor).y, -1.0f);  // through the floor
        } else {
            for (int i = 0; i < 90; ++i) world.step(kDt);
        }
        std::vector<Vec3> places;
        for (const BodyId b : boxes) places.push_back(world.position(b));
        return places;
    };
    std::vector<BodyId> seen, none;
    const std::vector<Vec3> with = run(true, seen), without = run(false, none);
    EXPECT_EQ(with, without);
    // The top box, the middle one, the bottom one, the floor: slots 3, 2, 1, 0.
    ASSERT_EQ(seen.size(), 4u);
    EXPECT_EQ(seen[0].index, 3u);
    EXPECT_EQ(seen[1].index, 2u);
    EXPECT_EQ(seen[2].index, 1u);
    EXPECT_EQ(seen[3].index, 0u);
}

TEST(Sensors, QueriesAndContinuousCollisionPassThroughSensors) {
    WorldSettings settings;
    settings.effects = EffectSet::defaults().with(Effect::ContinuousCollision);
    World world(settings);
    addFloor(world);
    const BodyId sensor = addSensorBox(world, BodyType::Static, {0, 1, 0}, {0.05f, 1, 1});
    const std::optional<RayHit> miss = world.castRay({-2, 1, 0}, {1, 0, 0}, 10);
    EXPECT_FALSE(miss.has_value());
    QueryFilter withSensors;
    withSensors.includeSensors = true;
    const std::optional<RayHit> hit = world.castRay({-2, 1, 0}, {1, 0, 0}, 10, withSensors);
    ASSERT_TRUE(hit.has_value());
    EXPECT_EQ(hit->body, sensor);
    // A fast ball crosses the thin sensor in one step: continuous collision must not stop it there.
    const BodyId ball = addBall(world, {-1, 1, 0}, {120, 0, 0}, 0.1f);
    world.step(kDt);
    EXPECT_GT(world.position(ball).x, 0.5f);
}

TEST(Sensors, SleepingVisitorStaysInside) {
    WorldSettings settings;
    settings.effects = EffectSet::defaults().with(Effect::Sleeping);
    World world(settings);
    addFloor(world);
    addSensorBox(world, BodyType::Static, {0, 0.5f, 0}, {1, 0.5f, 1});
    const BodyId ball = addBall(world, {0, 0.3f, 0}, {});
    int begins = 0, ends = 0;
    for (int i = 0; i < 120; ++i) {
        world.step(kDt);
        begins += static_cast<int>(world.sensorEvents().begins.size());
        ends += static_cast<int>(world.sensorEvents().ends.size());
    }
    EXPECT_FALSE(world.isAwake(ball));
    EXPECT_EQ(begins, 1);
    EXPECT_EQ(ends, 0);
    world.destroyBody(ball);
    world.step(kDt);
    EXPECT_EQ(world.sensorEvents().ends.size(), 1u);
}

}  // namespace
}  // namespace rubble
