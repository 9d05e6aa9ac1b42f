// Stacks that must stand. Bounds are the where the engine meets them, and otherwise the measured figure
// with a margin, so that a regression fails; what is not met yet is said next to the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "rubble/scene.h"
#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

/// Sleeping off: these tests are about the solver's stability, not sleep's (a still tower sleeps within 1 s).
WorldSettings awake(WorldSettings s) {
    s.effects = s.effects.without(Effect::Sleeping);
    return s;
}

/// The soft step with four substeps of 2 + 1 iterations and 60 Hz contacts: the setting that holds towers.
WorldSettings softStepSubsteps() {
    WorldSettings s;
    s.threads = 1;
    s.substeps = 4;
    s.velocityIterations = 2;
    s.positionIterations = 1;
    s.solver.positionCorrection = PositionCorrection::SoftStep;
    s.solver.contactHertz = 60;
    return awake(s);
}

struct Stack {
    World world;
    std::vector<BodyId> cubes;
    std::vector<Vec3> starts;

    explicit Stack(const WorldSettings& s) : world(s) {
        BodyDef ground;
        ground.type = BodyType::Static;
        ground.shape = world.createShape(BoxDef{{100, 0.5f, 100}});
        ground.position = {0, -0.5f, 0};
        world.createBody(ground);
    }
    BodyId add(Vec3 position, float density = 1000, Quat orientation = {}) {
        static const BoxDef cube{{0.5f, 0.5f, 0.5f}};
        BodyDef def;
        def.material.density = density;
        def.orientation = orientation;
        if (cubeShape.isNull()) cubeShape = world.createShape(cube);
        def.shape = cubeShape;
        def.position = position;
        cubes.push_back(world.createBody(def));
        starts.push_back(position);
        return cubes.back();
    }
    float largestDisplacement() const {
        float largest = 0;
        for (std::size_t i = 0; i < cubes.size(); ++i)
            largest = std::max(largest, length(world.position(cubes[i]) - starts[i]));
        return largest;
    }
    ShapeId cubeShape;
};

// S1's construction with 10 layers (385 cubes) at the default settings (Baumgarte, 8 + 2 iterations, one
// substep) for 5 s. Every contact starts from the loads that hold the pyramid still (the resting-load guess), and the
// iterations keep them: measured 1e-9 m (0.74 cm without the guess). S1 itself (20 layers, 600 steps) moves < 0.1 mm.
TEST(Stacking, PyramidStandsAtDefaultSettings) {
    WorldSettings s;
    s.threads = 2;
    Stack stack(s);
    const int layers = 10;
    for (int k = 0; k < layers; ++k) {
        const int n = layers - k;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) stack.add({i - (n - 1) / 2.0f, 0.5f + k, j - (n - 1) / 2.0f});
    }
    for (int i = 0; i < 300; ++i) stack.world.step(kDt);
    EXPECT_LT(stack.largestDisplacement(), 0.001f);
}

// The tower: twenty cubes for 30 s. The soft step with four substeps of 2 + 1 iterations and 60 Hz contacts
// holds it: measured 1.6 mm sideways at the top. Its contacts are springs, so the tower settles under its own
// weight: load * g / omega^2 per contact, 2.7 cm over the twenty contacts (measured), hence the separate bound.
TEST(Stacking, TowerOfTwentyStandsThirtySecondsWithSoftStepSubsteps) {
    Stack stack(softStepSubsteps());
    for (int k = 0; k < 20; ++k) stack.add({0, 0.5f + k, 0});
    for (int i = 0; i < 1800; ++i) stack.world.step(kDt);
    const Vec3 top = stack.world.position(stack.cubes.back());
    EXPECT_LT(std::hypot(top.x, top.z), 0.01f);
    EXPECT_GT(top.y, 19.5f - 0.04f);
}

// Shock propagation against plain iterations, at the default Baumgarte settings (8 iterations, one substep): the
// issue's twenty-cube tower for 30 s. Plain iterations leave each step's stack unconverged; the residue rocks the
// tower until it falls (measured: the top lands 8.8 m away). With the shock pass each cube ends the iterations
// supported by the one below: measured 2.1 cm sideways at the top, short of the 1 cm, which the soft step
// with substeps meets (above).
TEST(Stacking, ShockPropagationHoldsATowerThatPlainIterationsTopple) {
    WorldSettings s;
    s.threads = 1;
    s.solver.shockPropagation = true;
    s.solver.seedRestingLoads = false;
    Stack stack(awake(s));
    for (int k = 0; k < 20; ++k) stack.add({0, 0.5f + k, 0});
    for (int i = 0; i < 1800; ++i) stack.world.step(kDt);
    const Vec3 top = stack.world.position(stack.cubes.back());
    EXPECT_LT(std::hypot(top.x, top.z), 0.03f);
    EXPECT_GT(top.y, 19.49f);
}

/// S5's wall (Box3D's large pyramid) with `rows` rows: cubes of density 100, each resting on two below.
void buildWall(Stack& stack, int rows) {
    const float h = 0.5f;
    for (int i = 0; i < rows; ++i)
        for (int j = i; j < rows; ++j) stack.add({(i + 1) * h + 2 * (j - i) * h - h * rows, (2 * i + 1) * h, 0}, 100);
}

// S5's wall at a fifth of its size (20 rows, 210 cubes) for 200 steps at the default settings, against plain
// iterations (no resting-load guess, no shock pass) and the shock pass alone. Every contact is new in the first step:
// plain iterations pass the loads down a layer or so per iteration and let the wall spread (measured 15 cm); the
// shock pass holds it (measured 0.58 cm), and so does the resting-load guess (1e-7 m).
TEST(Stacking, RestingLoadsAndShockPropagationHoldAWallThatPlainIterationsSpread) {
    const auto run = [](bool seed, bool shock) {
        WorldSettings s;
        s.threads = 2;
        s.solver.seedRestingLoads = seed;
        s.solver.shockPropagation = shock;
        Stack stack(awake(s));
        buildWall(stack, 20);
        for (int i = 0; i < 200; ++i) stack.world.step(kDt);
        return stack.largestDisplacement();
    };
    const float plain = run(false, false), shock = run(false, true), seeded = run(true, false);
    EXPECT_GT(plain, 0.05f);
    EXPECT_LT(shock, 0.02f);
    EXPECT_LT(seeded, 0.001f);
}

// S5 itself (scenes/s5_large_pyramid.json: 100 rows, 5,050 cubes) stands 200 steps at the default settings within
// the 5 cm. Measured 2.0 cm, the same at 1 and 2 threads; without the resting-load guess the upper rows fall
// into the lower ones and the wall collapses (10.8 m).
TEST(Stacking, LargePyramidStandsAtDefaultSettings) {
    const Scene scene = loadScene(std::string(RUBBLE_SOURCE_DIR) + "/scenes/s5_large_pyramid.json");
    WorldSettings s = scene.settings;
    ASSERT_EQ(s.velocityIterations, WorldSettings{}.velocityIterations);
    ASSERT_EQ(s.positionIterations, WorldSettings{}.positionIterations);
    ASSERT_EQ(s.substeps, WorldSettings{}.substeps);
    s.threads = 2;
    World world(s);
    const std::vector<BodyId> ids = instantiate(scene, world);
    std::vector<Vec3> starts;
    for (BodyId id : ids) starts.push_back(world.position(id));
    for (int i = 0; i < scene.steps; ++i) world.step(s.timeStep);
    float largest = 0;
    for (std::size_t i = 0; i < ids.size(); ++i)
        largest = std::max(largest, length(world.position(ids[i]) - starts[i]));
    EXPECT_LT(largest, 0.05f);
}

// Heavy on light at the default settings: the resting-load guess starts both contacts from the loads they carry
// (1,000 kg at the upper, 1,010 kg at the ground's), so the iterations only keep them: measured no motion at all.
// Not met: the same pair with the heavy cube dropped from 1 cm. Its contacts then start from the landing, and eight
// iterations cannot balance the 1:100 ratio: it topples.
TEST(Stacking, HeavyOnLightStandsAtDefaultSettings) {
    WorldSettings s;
    s.threads = 1;
    Stack stack(awake(s));
    stack.add({0, 0.5f, 0}, 10);
    const BodyId heavy = stack.add({0, 1.5f, 0}, 1000);
    for (int i = 0; i < 600; ++i) stack.world.step(kDt);
    EXPECT_LT(length(stack.world.position(heavy) - Vec3{0, 1.5f, 0}), 0.001f);
}

// Heavy on light: a cube 100 times heavier resting on a light one, for 10 s. The soft step (four substeps of 2 + 1
// iterations, 60 Hz contacts) holds it; its springs sag by load * g / omega^2: 100 g / (2 pi 60)^2 = 6.9 mm at the
// light-heavy contact plus 1.7 mm at the ground's (twice as stiff), measured 8.7 mm in all. It also holds the heavy
// cube dropped from 1 cm or 10 cm (measured 2.5 mm and 2.5 cm sideways), which the default settings do not (above).
TEST(Stacking, HeavyOnLightStandsWithSoftStepSubsteps) {
    Stack stack(softStepSubsteps());
    stack.add({0, 0.5f, 0}, 10);
    const BodyId heavy = stack.add({0, 1.5f, 0}, 1000);
    for (int i = 0; i < 600; ++i) stack.world.step(kDt);
    const Vec3 top = stack.world.position(heavy);
    EXPECT_LT(std::hypot(top.x, top.z), 0.005f);
    EXPECT_GT(top.y, 1.5f - 0.012f);
    EXPECT_LT(top.y, 1.5f + 0.001f);
}

// A settled pile gains no energy: 96 cubes dropped in a loose heap (random offsets and turns) settle for 5 s; over the
// next 5 s the pile's total energy (kinetic + potential) never rises above its value at 5 s by more than 0.1% of the
// energy it lost settling, and its kinetic energy stays below that of every cube moving at a stated speed:
// - soft step: 2 cm/s (0.5 M v^2 = 19 J); measured 0.2-0.7 J, the pile is at rest;
// - Baumgarte (the default): 10 cm/s (480 J); measured 6-260 J: the pile does not gain energy, but it never comes
//   quite to rest either (its contacts jitter inside the slop), the default's known weakness.
TEST(Stacking, SettledPileGainsNoEnergy) {
    for (const auto& [correction, speed] :
         {std::pair{PositionCorrection::SoftStep, 0.02}, std::pair{PositionCorrection::Baumgarte, 0.1}}) {
        WorldSettings s;
        s.threads = 2;
        s.solver.positionCorrection = correction;
        Stack stack(awake(s));
        World& world = stack.world;
        const std::vector<BodyId>& cubes = stack.cubes;
        std::mt19937 rng(42);
        std::uniform_real_distribution<float> jitter(-0.2f, 0.2f), angle(-0.5f, 0.5f);
        for (int l = 0; l < 6; ++l)
            for (int i = 0; i < 4; ++i)
                for (int k = 0; k < 4; ++k) {
                    const Vec3 at{i * 1.2f - 1.8f + jitter(rng), 0.7f + l * 1.3f, k * 1.2f - 1.8f + jitter(rng)};
                    const float a = angle(rng);
                    stack.add(at, 1000, {0, std::sin(a / 2), 0, std::cos(a / 2)});
                }
        const auto kinetic = [&] {
            double energy = 0;
            for (BodyId id : cubes) {
                const MassProperties mp = world.massProperties(id);
                const Vec3 v = world.linearVelocity(id), w = world.angularVelocity(id);
                // A cube's inertia is isotropic: m a^2 / 6 for edge a = 1.
                energy += 0.5 * mp.mass * dot(v, v) + 0.5 * (mp.mass / 6.0) * dot(w, w);
            }
            return energy;
        };
        const auto potential = [&] {
            double energy = 0;
            for (BodyId id : cubes) energy += world.massProperties(id).mass * 9.81 * world.centerOfMass(id).y;
            return energy;
        };
        const double dropped = potential();
        for (int i = 0; i < 300; ++i) world.step(kDt);
        const double settled = kinetic() + potential();
        const double kineticBound = 0.5 * 1000.0 * double(cubes.size()) * speed * speed;
        double largestKinetic = 0, largestGain = -INFINITY;
        for (int i = 0; i < 300; ++i) {
            world.step(kDt);
            const double k = kinetic();
            largestKinetic = std::max(largestKinetic, k);
            largestGain = std::max(largestGain, k + potential() - settled);
        }
        const char* name = positionCorrectionName(correction).data();
        EXPECT_LT(largestKinetic, kineticBound) << name;
        EXPECT_LT(largestGain, 1e-3 * (dropped - settled)) << name;
    }
}

}  // namespace
}  // namespace rubble
