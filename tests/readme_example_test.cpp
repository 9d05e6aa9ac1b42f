// The README's API example, compiled and checked: a pushed crate falls and drifts as the closed form says.
#include <gtest/gtest.h>

#include "rubble/world.h"

TEST(ReadmeExample, RunsAndFallsAsExpected) {
    rubble::WorldSettings settings;
    settings.threads = 2;
    rubble::World world(settings);

    const rubble::ShapeId crate = world.createShape(rubble::BoxDef{{0.5f, 0.5f, 0.5f}});
    rubble::BodyDef def;
    def.shape = crate;
    def.position = {0, 10, 0};
    def.material = {.friction = 0.6f, .restitution = 0.1f, .density = 500};
    const rubble::BodyId body = world.createBody(def);

    world.applyImpulseAtPoint(body, {50, 0, 0}, {0, 10.5f, 0});
    for (int i = 0; i < 60; ++i) world.step(settings.timeStep);

    // 500 kg crate, 50 N s impulse: 0.1 m/s sideways; semi-implicit Euler with substeps of h falls g t (t + h) / 2 in
    // t = 1 s.
    const rubble::Vec3 p = world.position(body);
    EXPECT_NEAR(p.x, 0.1f, 1e-4f);
    const float h = settings.timeStep / static_cast<float>(settings.substeps), fall = 9.81f * 1.0f * (1.0f + h) / 2;
    EXPECT_NEAR(p.y, 10.0f - fall, 1e-3f);
    // The push at the top edge spins the crate about -z.
    EXPECT_LT(world.angularVelocity(body).z, 0.0f);
}
