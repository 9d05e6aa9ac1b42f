// The contact solver against closed forms, through the World API.
//
// Tolerances: the (2% for accelerations, 3% for the stopping distance). Where the discretisation itself
// leaves a known error it is well inside them: accelerations are measured between two times after contact has
// settled, so the first step's landing does not enter; a box that stops within a step of the closed-form time is off
// by at most v * dt / 2 = 4 cm on 2.5 m (1.6%).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kG = 9.81f;
constexpr float kPi = 3.14159265358979f;

WorldSettings settingsFor(PositionCorrection correction) {
    WorldSettings s;
    s.threads = 1;
    s.solver.positionCorrection = correction;
    return s;
}

BodyId addStatic(World& world, const ShapeDef& shape, Vec3 position, Quat orientation, float friction) {
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(shape);
    def.position = position;
    def.orientation = orientation;
    def.material.friction = friction;
    return world.createBody(def);
}

BodyId addDynamic(World& world, const ShapeDef& shape, Vec3 position, Quat orientation, Material material) {
    BodyDef def;
    def.shape = world.createShape(shape);
    def.position = position;
    def.orientation = orientation;
    def.material = material;
    return world.createBody(def);
}

class ContactPhysics : public ::testing::TestWithParam<PositionCorrection> {};

// Equal masses, head-on, perfectly elastic: the velocities swap. Restitution is applied against the approach speed
// measured before the solve, so the swap is exact up to rounding; 1% covers the push-out of the overlap that the
// step's discrete contact leaves (the speculative margin catches the spheres within one step of touching).
TEST_P(ContactPhysics, ElasticHeadOnCollisionSwapsVelocities) {
    WorldSettings s = settingsFor(GetParam());
    s.gravity = {0, 0, 0};
    World world(s);
    const Material bouncy{.friction = 0.0f, .restitution = 1.0f, .density = 1000};
    const BodyId a = addDynamic(world, SphereDef{0.5f}, {-2, 0, 0}, {}, bouncy);
    const BodyId b = addDynamic(world, SphereDef{0.5f}, {2, 0, 0}, {}, bouncy);
    world.setLinearVelocity(a, {5, 0, 0});
    for (int i = 0; i < 60; ++i) world.step(kDt);
    EXPECT_NEAR(world.linearVelocity(a).x, 0.0f, 0.05f);
    EXPECT_NEAR(world.linearVelocity(b).x, 5.0f, 0.05f);
    EXPECT_GT(world.position(b).x, 2.5f);
}

// A ball of restitution 1 dropped from 2 m onto a ground of restitution 1 comes back to the height it fell from on
// each of its first five bounces, at every time step and substep count. The bounce reverses the approach speed that
// the ball has where the step leaves it: a ball still apart from the ground when the step's contacts are prepared
// meets it partway through the step, faster. Tolerance: at least 99% of the drop (the issue asks 98%; measured 99.6%
// at 1/30 s and one substep, 99.9% and more at 1/60 s and four) and at most 100.5% (no gain: the apex is sampled once a
// step, which can only miss height).
TEST_P(ContactPhysics, ElasticBallKeepsItsHeightOnEachOfItsFirstFiveBounces) {
    constexpr float kDrop = 2.0f, kRadius = 0.25f;
    for (const float dt : {1.0f / 30.0f, 1.0f / 60.0f, 1.0f / 120.0f}) {
        for (const int substeps : {1, 2, 4, 8}) {
            WorldSettings s = settingsFor(GetParam());
            s.substeps = substeps;
            World world(s);
            const Material bouncy{.friction = 0.0f, .restitution = 1.0f, .density = 1000};
            BodyDef ground;
            ground.type = BodyType::Static;
            ground.shape = world.createShape(BoxDef{{20, 0.5f, 20}});
            ground.position = {0, -0.5f, 0};
            ground.material = bouncy;
            world.createBody(ground);
            const BodyId ball = addDynamic(world, SphereDef{kRadius}, {0, kDrop + kRadius, 0}, {}, bouncy);
            std::vector<float> apexes;
            float previous = kDrop, highest = 0;
            bool rising = false;
            for (int step = 0; step < static_cast<int>(12.0f / dt) && apexes.size() < 5; ++step) {
                world.step(dt);
                const float height = world.position(ball).y - kRadius;
                if (rising && height < previous) apexes.push_back(highest);
                rising = height > previous;
                highest = rising ? height : 0;
                previous = height;
            }
            ASSERT_EQ(apexes.size(), 5u) << "dt " << dt << ", " << substeps << " substeps";
            for (std::size_t i = 0; i < apexes.size(); ++i) {
                EXPECT_GE(apexes[i], 0.99f * kDrop)
                    << "bounce " << i + 1 << ", dt " << dt << ", " << substeps << " substeps";
                EXPECT_LE(apexes[i], 1.005f * kDrop)
                    << "bounce " << i + 1 << ", dt " << dt << ", " << substeps << " substeps";
            }
        }
    }
}

struct Slope {
    World world;
    BodyId block;
    Vec3 down;  ///< unit vector down the slope
};

/// A 1 m cube resting on a 30 degree slope (a large static box turned about z), both with friction mu.
void buildSlope(Slope& s, float mu) {
    const float angle = 30.0f * kPi / 180.0f;
    const Quat tilt = Quat::fromAxisAngle({0, 0, 1}, angle);
    const Vec3 up = rotate(tilt, {0, 1, 0});
    s.down = rotate(tilt, {-1, 0, 0});
    addStatic(s.world, BoxDef{{50, 0.5f, 50}}, up * -0.5f, tilt, mu);
    s.block = addDynamic(s.world, BoxDef{{0.5f, 0.5f, 0.5f}}, up * 0.5f, tilt,
                         Material{.friction = mu, .restitution = 0, .density = 1000});
}

TEST_P(ContactPhysics, BlockOnThirtyDegreeSlopeHoldsWithHighFriction) {
    Slope s{World(settingsFor(GetParam())), {}, {}};
    buildSlope(s, 0.7f);  // tan 30 = 0.577 < 0.7: static friction holds
    const Vec3 start = s.world.position(s.block);
    for (int i = 0; i < 120; ++i) s.world.step(kDt);
    // Holding means creeping less than a centimetre in 2 s (the slop and the soft contact settle, nothing slides).
    EXPECT_LT(length(s.world.position(s.block) - start), 0.01f);
}

TEST_P(ContactPhysics, BlockOnThirtyDegreeSlopeSlidesWithLowFriction) {
    Slope s{World(settingsFor(GetParam())), {}, {}};
    const float mu = 0.3f;
    buildSlope(s, mu);
    const float angle = 30.0f * kPi / 180.0f;
    const float expected = kG * (std::sin(angle) - mu * std::cos(angle));
    for (int i = 0; i < 30; ++i) s.world.step(kDt);
    const float v0 = dot(s.world.linearVelocity(s.block), s.down);
    for (int i = 0; i < 60; ++i) s.world.step(kDt);
    const float v1 = dot(s.world.linearVelocity(s.block), s.down);
    const float measured = (v1 - v0) / (60 * kDt);
    EXPECT_NEAR(measured, expected, 0.02f * expected) << "a = g (sin t - mu cos t) = " << expected;
}

// A solid sphere rolling without slipping: a = 5/7 g sin t (mu = 0.6 exceeds the 2/7 tan t = 0.165 rolling needs).
TEST_P(ContactPhysics, SphereRollsDownInclineAtFiveSeventhsGSinTheta) {
    World world(settingsFor(GetParam()));
    const float angle = 30.0f * kPi / 180.0f;
    const Quat tilt = Quat::fromAxisAngle({0, 0, 1}, angle);
    const Vec3 up = rotate(tilt, {0, 1, 0}), down = rotate(tilt, {-1, 0, 0});
    addStatic(world, BoxDef{{80, 0.5f, 80}}, up * -0.5f, tilt, 0.6f);
    const BodyId ball = addDynamic(world, SphereDef{0.5f}, up * 0.5f, {},
                                   Material{.friction = 0.6f, .restitution = 0, .density = 1000});
    for (int i = 0; i < 30; ++i) world.step(kDt);
    const float v0 = dot(world.linearVelocity(ball), down);
    for (int i = 0; i < 60; ++i) world.step(kDt);
    const float v1 = dot(world.linearVelocity(ball), down);
    const float expected = 5.0f / 7.0f * kG * std::sin(angle);
    EXPECT_NEAR((v1 - v0) / (60 * kDt), expected, 0.02f * expected) << "a = 5/7 g sin t = " << expected;
    // Rolling, not sliding: the contact point is at rest, so v = w r.
    EXPECT_NEAR(length(world.angularVelocity(ball)) * 0.5f, v1, 0.02f * v1);
}

// A block sliding on the ground stops after v^2 / (2 mu g).
TEST_P(ContactPhysics, SlidingBlockStopsAfterClosedFormDistance) {
    World world(settingsFor(GetParam()));
    const float mu = 0.5f, v = 5.0f;
    addStatic(world, BoxDef{{50, 0.5f, 50}}, {0, -0.5f, 0}, {}, mu);
    const BodyId block = addDynamic(world, BoxDef{{0.5f, 0.5f, 0.5f}}, {0, 0.5f, 0}, {},
                                    Material{.friction = mu, .restitution = 0, .density = 1000});
    world.step(kDt);  // settle onto the ground first, so the slide starts from a resting contact
    const float x0 = world.position(block).x;
    world.setLinearVelocity(block, {v, 0, 0});
    for (int i = 0; i < 180; ++i) world.step(kDt);
    const float expected = v * v / (2 * mu * kG);
    EXPECT_NEAR(world.position(block).x - x0, expected, 0.03f * expected) << "d = v^2 / (2 mu g) = " << expected;
    EXPECT_NEAR(world.linearVelocity(block).x, 0.0f, 1e-3f);
}

// A cube spinning on the ground about the vertical slows under its corners' friction, mu m g / 4 at each, at the
// lever arm h sqrt(2): alpha = mu m g h sqrt(2) / (2/3 m h^2), so it stops after turning w^2 / (2 alpha) = 2.403 rad
// (measured 2.413-2.415 in the three position corrections). The contact is made again every step (the cube turns 10
// degrees a step at first), its friction warm-started from the last. 3%, as the sliding block's distance: it stops
// within a step of the closed-form time. Friction that turned the cube's corners about anything but its centre, or
// a twist left out of friction acting at a manifold's centre, would miss it.
TEST_P(ContactPhysics, SpinningCubeStopsAfterClosedFormTurn) {
    World world(settingsFor(GetParam()));
    const float mu = 0.5f, h = 0.5f, w0 = 10.0f;
    addStatic(world, BoxDef{{50, 0.5f, 50}}, {0, -0.5f, 0}, {}, mu);
    const BodyId cube = addDynamic(world, BoxDef{{h, h, h}}, {0, h, 0}, {},
                                   Material{.friction = mu, .restitution = 0, .density = 1000});
    world.step(kDt);  // settle onto the ground first, so the spin starts from a resting contact
    world.setAngularVelocity(cube, {0, w0, 0});
    const auto yaw = [&] {
        const Quat q = world.orientation(cube);
        return 2.0f * std::atan2(q.y, q.w);
    };
    float turned = 0, last = yaw();
    for (int i = 0; i < 60; ++i) {
        world.step(kDt);
        float step = yaw() - last;
        step -= 2.0f * kPi * std::round(step / (2.0f * kPi));
        turned += step;
        last = yaw();
    }
    const float alpha = mu * kG * h * std::sqrt(2.0f) / (2.0f / 3.0f * h * h);
    const float expected = w0 * w0 / (2 * alpha);
    EXPECT_NEAR(turned, expected, 0.03f * expected) << "turn = w^2 / (2 alpha) = " << expected;
    EXPECT_NEAR(world.angularVelocity(cube).y, 0.0f, 1e-3f);
    EXPECT_NEAR(world.position(cube).x, 0.0f, 1e-3f);
    EXPECT_NEAR(world.position(cube).z, 0.0f, 1e-3f);
}

// A rod 2 m long (mass m, I = m / 3 about a short axis) spinning at 75 rad/s about its centre swings a tip into a
// frictionless wall 0.4 m away: an inelastic impact at the tip, lever arm a, gives the centre v = u / (1 + 3 a^2) and
// leaves w = 75 - 3 a v, with u the tip's approach speed. The tip touches at a = 0.917 m (v 19.5 m/s, w 21.3 rad/s);
// the step's contacts are made where the step began, with the tip at a = 1 m (v 18.75 m/s, w 18.75 rad/s), so either
// is right to the discretisation. Bound: 5% outside that range where the impact ends within its first step (the soft
// step's relax iterations see the tip at the wall; Baumgarte and split impulses at one substep let the tip close only
// the gap the step began with, and finish the impact a step later from another pose), and everywhere the rod keeps
// turning in its plane (under 1 rad/s about the other axes) and leaves with less energy than it came with. It turns
// more than a radian in the step: with the inertia of its starting pose in the solve, the hit spun it at 190 rad/s
// about its long axis and tumbled it out of the plane with 70% more energy.
TEST_P(ContactPhysics, SpinningRodHitsAFrictionlessWallAsAnInelasticImpact) {
    for (const int substeps : {1, 2, 4, 8}) {
        WorldSettings settings = settingsFor(GetParam());
        settings.effects = EffectSet{}.with(Effect::Rotation).with(Effect::Friction);
        settings.substeps = substeps;
        World world(settings);
        addStatic(world, BoxDef{{0.01f, 2, 0.5f}}, {0.41f, 0, 0}, {}, 0.0f);
        const BodyId rod = addDynamic(world, BoxDef{{1.0f, 0.01f, 0.01f}}, {}, Quat::fromAxisAngle({0, 0, 1}, kPi / 2),
                                      Material{.friction = 0, .restitution = 0, .density = 1000});
        world.setAngularVelocity(rod, {0, 0, 75});
        for (int step = 0; step < 3; ++step) world.step(kDt);
        const Vec3 v = world.linearVelocity(rod), w = world.angularVelocity(rod);
        // Per unit mass: (v^2 + w_z^2 / 3) / 2; the rod's spin about its own axis weighs nothing here.
        EXPECT_LT(0.5f * (dot(v, v) + w.z * w.z / 3.0f), 0.5f * 75.0f * 75.0f / 3.0f) << substeps << " substeps";
        EXPECT_LT(std::hypot(w.x, w.y), 1.0f) << substeps << " substeps";
        if (substeps == 1 && GetParam() != PositionCorrection::SoftStep) continue;
        EXPECT_GT(-v.x, 18.75f * 0.95f) << substeps << " substeps";
        EXPECT_LT(-v.x, 19.5f * 1.05f) << substeps << " substeps";
        EXPECT_GT(w.z, 18.75f * 0.95f) << substeps << " substeps";
        EXPECT_LT(w.z, 21.3f * 1.05f) << substeps << " substeps";
    }
}

INSTANTIATE_TEST_SUITE_P(, ContactPhysics,
                         ::testing::Values(PositionCorrection::SoftStep, PositionCorrection::Baumgarte,
                                           PositionCorrection::SplitImpulse),
                         [](const auto& p) { return std::string(positionCorrectionName(p.param)); });

}  // namespace
}  // namespace rubble
