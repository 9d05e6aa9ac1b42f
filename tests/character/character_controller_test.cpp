// The character controller through the public API, in levels built of meshes and boxes: what it must do is stated
// by geometry (walls it may not enter, step and slope limits, the terrain under it) and checked every step.
//
// Tolerances: the controller keeps a skin of 1 cm from surfaces and shape casts stop within 0.1 mm of contact, so
// "never inside" allows 2 mm (the casts' and the float poses' rounding); heights it reaches are checked to 2 cm (the
// skin plus the ground snap's rounding).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/character.h"
#include "rubble/error.h"
#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kPi = 3.14159265f;

BodyId addBox(World& world, Vec3 center, Vec3 half, Quat rotation = {}, BodyType type = BodyType::Static) {
    BodyDef def;
    def.type = type;
    def.shape = world.createShape(BoxDef{half});
    def.position = center;
    def.orientation = rotation;
    return world.createBody(def);
}

/// A flat mesh floor at y = 0 over [x0, x1] x [z0, z1], in 1 m squares.
BodyId addMeshFloor(World& world, float x0, float x1, float z0, float z1) {
    TriangleMeshDef mesh;
    const int nx = static_cast<int>(x1 - x0), nz = static_cast<int>(z1 - z0);
    for (int i = 0; i <= nx; ++i)
        for (int k = 0; k <= nz; ++k)
            mesh.vertices.push_back({x0 + static_cast<float>(i), 0, z0 + static_cast<float>(k)});
    const auto at = [&](int i, int k) { return static_cast<std::uint32_t>(i * (nz + 1) + k); };
    for (int i = 0; i < nx; ++i)
        for (int k = 0; k < nz; ++k)
            mesh.indices.insert(mesh.indices.end(),
                                {at(i, k), at(i, k + 1), at(i + 1, k), at(i + 1, k), at(i, k + 1), at(i + 1, k + 1)});
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(mesh);
    return world.createBody(def);
}

Quat aboutZ(float angle) { return {0, 0, std::sin(angle / 2), std::cos(angle / 2)}; }

/// Walks toward (x, z) at `speed` until within 5 cm or `seconds` pass; returns whether it got there. `each` runs
/// after every step.
template <class Each>
bool walkTo(World& world, CharacterController& c, float x, float z, float speed, float seconds, Each&& each) {
    for (int i = 0; i * kDt < seconds; ++i) {
        Vec3 to{x - c.position().x, 0, z - c.position().z};
        const float d = length(to);
        if (d < 0.05f) return true;
        c.update(kDt, to * (std::min(speed, d / kDt) / d));
        world.step(kDt);
        each();
    }
    return false;
}

bool walkTo(World& world, CharacterController& c, float x, float z, float speed, float seconds) {
    return walkTo(world, c, x, z, speed, seconds, [] {});
}

void idle(World& world, CharacterController& c, int steps) {
    for (int i = 0; i < steps; ++i) {
        c.update(kDt, {});
        world.step(kDt);
    }
}

TEST(CharacterController, StandsOnMeshGroundAndReportsIt) {
    World world;
    const BodyId floor = addMeshFloor(world, -3, 3, -3, 3);
    CharacterController c(world, {0.2f, 0.5f, 0.3f});
    idle(world, c, 60);
    EXPECT_TRUE(c.grounded());
    EXPECT_EQ(c.ground(), floor);
    EXPECT_NEAR(c.groundNormal().y, 1.0f, 1e-4f);
    EXPECT_NEAR(c.position().y, c.settings().skin, 2e-3f);
    // Its body follows it, for sensors and queries.
    EXPECT_NEAR(world.position(c.body()).y, c.position().y + 0.5f * c.settings().height, 1e-3f);
    EXPECT_TRUE(c.jump(4));
    c.update(kDt, {});
    world.step(kDt);
    EXPECT_FALSE(c.grounded());
    EXPECT_GT(c.velocity().y, 3.5f);
    idle(world, c, 90);
    EXPECT_TRUE(c.grounded());
}

TEST(CharacterController, SlidesAlongAWallAndNeverEntersIt) {
    World world;
    addMeshFloor(world, -5, 5, -5, 5);
    addBox(world, {0, 1, 1.2f}, {5, 1, 0.2f});  // wall face at z = 1
    CharacterController c(world, {-3, 0.02f, 0});
    // Into the wall at 45 degrees: it ends against the wall, having kept the speed along it.
    for (int i = 0; i < 120; ++i) {
        c.update(kDt, {2, 0, 2});
        world.step(kDt);
        EXPECT_LE(c.position().z, 1 - c.settings().radius + 2e-3f) << "step " << i;
    }
    EXPECT_NEAR(c.position().z, 1 - c.settings().radius - c.settings().skin, 0.01f);
    EXPECT_NEAR(c.position().x, -3 + 2 * 120 * kDt, 0.1f);
    EXPECT_TRUE(c.grounded());
}

TEST(CharacterController, ClimbsStepsUpToItsStepHeightOnly) {
    for (const float step : {0.1f, 0.3f, 0.45f}) {
        World world;
        addMeshFloor(world, -3, 6, -2, 2);
        addBox(world, {3, 0.5f * step, 0}, {1.5f, 0.5f * step, 2});  // riser at x = 1.5
        CharacterController c(world, {0, 0.02f, 0});
        const bool arrived = walkTo(world, c, 3, 0, 2, 3);
        const bool climbable = step <= c.settings().stepHeight;
        EXPECT_EQ(arrived, climbable) << "step " << step;
        if (climbable) {
            EXPECT_NEAR(c.position().y, step, 0.02f) << "step " << step;
            EXPECT_TRUE(c.grounded());
        } else {
            EXPECT_LE(c.position().x, 1.5f - c.settings().radius + 2e-3f) << "step " << step;
            EXPECT_LT(c.position().y, 0.05f);
        }
    }
}

TEST(CharacterController, WalksUpWalkableSlopesAndSlidesDownSteepOnes) {
    // A 30 degree ramp it walks up, then a 60 degree one it cannot.
    for (const float degrees : {30.0f, 60.0f}) {
        World world;
        addMeshFloor(world, -4, 8, -2, 2);
        const float angle = degrees * kPi / 180;
        // A slab tilted about z, its upper face through (1, 0, 0) rising towards +x.
        const float half = 4, thick = 0.25f;
        const Vec3 along{std::cos(angle), std::sin(angle), 0}, normal{-std::sin(angle), std::cos(angle), 0};
        addBox(world, Vec3{1, 0, 0} + along * half - normal * thick, {half, thick, 2}, aboutZ(angle));
        CharacterController c(world, {-1, 0.02f, 0});
        walkTo(world, c, 3, 0, 2, 4);
        if (degrees < 45) {
            EXPECT_NEAR(c.position().x, 3, 0.06f);
            EXPECT_NEAR(c.position().y, 2 * std::tan(angle), 0.05f);
            EXPECT_TRUE(c.grounded());
        } else {
            // Held at the foot of the slope, not up it.
            EXPECT_LT(c.position().y, 0.2f);
            EXPECT_LT(c.position().x, 1.2f);
            // Put on the steep slope, it slides down it.
            c.teleport(Vec3{1, 0, 0} + along * 2.0f + normal * 0.05f);
            const float startHeight = c.position().y;
            idle(world, c, 120);
            EXPECT_LT(c.position().y, 0.2f * startHeight);
        }
    }
}

TEST(CharacterController, NeverPassesThroughAThinWallAtRunSpeed) {
    World world;
    addMeshFloor(world, -5, 40, -3, 3);
    addBox(world, {20, 1.5f, 0}, {0.01f, 1.5f, 3});  // 2 cm thick
    CharacterController c(world, {0, 0.02f, 0});
    for (int i = 0; i < 120; ++i) {
        c.update(kDt, {30, 0, 0});  // half a metre a step
        world.step(kDt);
        ASSERT_LE(c.position().x, 19.99f - c.settings().radius + 2e-3f) << "step " << i;
    }
    EXPECT_NEAR(c.position().x, 19.99f - c.settings().radius - c.settings().skin, 0.01f);
}

TEST(CharacterController, RunsOverBumpyMeshTerrainWithoutFallingThrough) {
    World world;
    HeightfieldDef field;
    field.rows = field.columns = 41;
    field.spacing = {1, 1, 1};
    for (std::uint32_t r = 0; r < field.rows; ++r)
        for (std::uint32_t k = 0; k < field.columns; ++k)
            field.heights.push_back(0.4f * std::sin(0.7f * static_cast<float>(k)) *
                                    std::cos(0.5f * static_cast<float>(r)));
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(field);
    world.createBody(ground);
    CharacterController c(world, {2, 1, 20});
    int groundedSteps = 0;
    for (int i = 0; i < 240; ++i) {
        c.update(kDt, {8, 0, 1});
        world.step(kDt);
        float terrain = 0;
        ASSERT_TRUE(world.terrainHeightAt(c.position().x, c.position().z, terrain));
        // The capsule's bottom can rest on a slope above the point under its axis, never below the surface there.
        ASSERT_GE(c.position().y, terrain - 2e-3f) << "step " << i;
        groundedSteps += c.grounded();
    }
    EXPECT_GT(c.position().x, 30.0f);
    EXPECT_GT(groundedSteps, 200);
}

TEST(CharacterController, PushesDynamicBodiesWithItsForceOnly) {
    for (const float force : {600.0f, 0.0f}) {
        World world;
        addMeshFloor(world, -3, 10, -3, 3);
        const BodyId crate = addBox(world, {2, 0.4f, 0}, {0.4f, 0.4f, 0.4f}, {}, BodyType::Dynamic);  // 512 kg
        CharacterSettings settings;
        settings.pushForce = force;
        CharacterController c(world, {0, 0.02f, 0}, settings);
        walkTo(world, c, 7, 0, 1.5f, 4);
        if (force > 0) {
            // Friction holds 512 kg with 0.6 g, 3,000 N: 600 N leaves the crate where it is.
            EXPECT_LT(world.position(crate).x, 2.01f);
        } else {
            EXPECT_NEAR(world.position(crate).x, 2.0f, 1e-3f);
        }
        EXPECT_LE(c.position().x, world.position(crate).x - 0.4f - c.settings().radius + 2e-3f);
    }
    // A light crate (64 kg, friction 380 N) gives way to 600 N.
    World world;
    addMeshFloor(world, -3, 10, -3, 3);
    const BodyId crate = addBox(world, {2, 0.2f, 0}, {0.2f, 0.2f, 0.2f}, {}, BodyType::Dynamic);
    CharacterController c(world, {0, 0.02f, 0});
    walkTo(world, c, 7, 0, 1.5f, 6);
    EXPECT_GT(world.position(crate).x, 5.0f);
    EXPECT_GT(c.position().x, 4.0f);
}

TEST(CharacterController, SensorsSeeTheCharacterAndPickupsAreCollectedOnce) {
    World world;
    addMeshFloor(world, -3, 10, -3, 3);
    BodyDef pickup;
    pickup.type = BodyType::Static;
    pickup.shape = world.createShape(SphereDef{0.3f});
    pickup.position = {4, 1, 0};
    pickup.sensor = true;
    const BodyId coin = world.createBody(pickup);
    CharacterController c(world, {0, 0.02f, 0});
    int collected = 0;
    walkTo(world, c, 8, 0, 3, 4, [&] {
        for (const SensorBeginEvent& e : world.sensorEvents().begins) {
            EXPECT_EQ(e.sensor, coin);
            EXPECT_EQ(e.visitor, c.body());
            ++collected;
        }
    });
    EXPECT_EQ(collected, 1);
    EXPECT_NEAR(c.position().x, 8, 0.06f);  // the coin did not stop it
}

/// The course: a corridor, stairs up, a landing, a ramp down, a lift up to a ledge, and the ledge's end.
TEST(CharacterController, WalksACourseOfCorridorStairsRampAndLiftToItsEnd) {
    World world;
    addMeshFloor(world, -4, 34, -4, 4);
    // Corridor x in [0, 8], 3 m wide, with a pillar in its middle to go round.
    addBox(world, {4, 1.25f, 1.6f}, {4, 1.25f, 0.1f});
    addBox(world, {4, 1.25f, -1.6f}, {4, 1.25f, 0.1f});
    addBox(world, {4, 1.25f, -0.65f}, {0.3f, 1.25f, 0.85f});
    // Six stairs of 0.2 m, treads 0.35 m deep, from x = 10, to a landing at 1.2 m up to x = 16.
    for (int s = 0; s < 6; ++s) {
        const float top = 0.2f * static_cast<float>(s + 1), front = 10 + 0.35f * static_cast<float>(s);
        addBox(world, {0.5f * (front + 16), 0.5f * top, 0}, {0.5f * (16 - front), 0.5f * top, 1.5f});
    }
    // A 20 degree ramp down from the landing's edge at x = 16 to the floor.
    const float ramp = 20 * kPi / 180, rampLength = 1.2f / std::sin(ramp);
    const Vec3 down{std::cos(ramp), -std::sin(ramp), 0}, rampNormal{std::sin(ramp), std::cos(ramp), 0};
    addBox(world, Vec3{16, 1.2f, 0} + down * (0.5f * rampLength) - rampNormal * 0.1f, {0.5f * rampLength, 0.1f, 1.5f},
           aboutZ(-ramp));
    // A lift at x in [22, 24], its top 5 cm above the floor, up to a ledge 2 m high from x = 24 to 32.
    const BodyId lift = addBox(world, {23, -0.05f, 0}, {1, 0.1f, 1.5f}, {}, BodyType::Kinematic);
    addBox(world, {28, 1, 0}, {4, 1, 1.5f});
    CharacterController c(world, {-2, 0.02f, 0});

    float lowest = 1e9f;
    const auto check = [&] {
        // Never in a corridor wall or the pillar (x in [3.7, 4.3], z in [-1.5, 0.2]), never under the floor.
        const Vec3 p = c.position();
        const float r = c.settings().radius;
        if (p.x > 0 - r && p.x < 8 + r) {
            ASSERT_LT(std::fabs(p.z), 1.5f - r + 2e-3f);
        }
        const float dx = std::max({3.7f - p.x, 0.0f, p.x - 4.3f}), dz = std::max({-1.5f - p.z, 0.0f, p.z - 0.2f});
        ASSERT_GT(std::sqrt(dx * dx + dz * dz), r - 2e-3f);
        lowest = std::min(lowest, p.y);
    };
    float liftHeight = 0;
    const auto moveLift = [&](float height) {
        liftHeight = height;
        world.moveKinematic(lift, {23, height - 0.1f, 0}, {}, kDt);
    };
    moveLift(0.05f);
    ASSERT_TRUE(walkTo(world, c, -0.5f, 0, 3, 3, check));
    ASSERT_TRUE(walkTo(world, c, 3, 0.85f, 3, 3, check));  // round the pillar on its +z side
    ASSERT_TRUE(walkTo(world, c, 5, 0.85f, 3, 3, check));
    ASSERT_TRUE(walkTo(world, c, 9, 0, 3, 3, check));
    ASSERT_TRUE(walkTo(world, c, 14, 0, 2, 5, check));  // up the stairs
    EXPECT_NEAR(c.position().y, 1.2f, 0.02f);
    ASSERT_TRUE(walkTo(world, c, 15.8f, 0, 2, 3, check));
    ASSERT_TRUE(walkTo(world, c, 21, 0, 2, 5, check));  // down the ramp
    EXPECT_NEAR(c.position().y, 0, 0.02f);
    ASSERT_TRUE(walkTo(world, c, 23, 0, 2, 3, check));  // onto the lift
    EXPECT_EQ(c.ground(), lift);
    // The lift rises to 2 m in 2 s, starting and stopping smoothly, carrying the character.
    for (int i = 1; i <= 120; ++i) {
        const float t = static_cast<float>(i) / 120;
        moveLift(0.05f + 1.95f * (t - std::sin(2 * kPi * t) / (2 * kPi)));
        c.update(kDt, {});
        world.step(kDt);
        check();
        ASSERT_NEAR(c.position().y, liftHeight + c.settings().skin, 0.03f) << "step " << i;
    }
    moveLift(2);
    EXPECT_EQ(c.ground(), lift);
    ASSERT_TRUE(walkTo(world, c, 31, 0, 3, 4, [&] {
        moveLift(2);
        check();
    }));
    EXPECT_NEAR(c.position().y, 2, 0.02f);
    EXPECT_TRUE(c.grounded());
    EXPECT_GT(lowest, -2e-3f);
}

TEST(CharacterController, RefusesBadSettings) {
    World world;
    CharacterSettings s;
    s.height = 0.5f;
    EXPECT_THROW(CharacterController(world, {}, s), Error);
    s = {};
    s.maxSlope = 2;
    EXPECT_THROW(CharacterController(world, {}, s), Error);
    s = {};
    s.stepHeight = 2;
    EXPECT_THROW(CharacterController(world, {}, s), Error);
    CharacterController c(world, {});
    EXPECT_THROW(c.update(0, {}), Error);
    EXPECT_THROW(c.update(kDt, {NAN, 0, 0}), Error);
    EXPECT_EQ(world.bodyCount(), 1u);
}

}  // namespace
}  // namespace rubble
