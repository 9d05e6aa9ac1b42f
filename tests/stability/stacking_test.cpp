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
#include "support/sanitized.h"
#include "support/standard_solver.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

/// Sleeping off: these tests are about the solver's stability, not sleep's (a still tower sleeps within 1 s).
WorldSettings awake(WorldSettings s) {
    s.effects = s.effects.without(Effect::Sleeping);
    return s;
}

/// The defaults: the soft step with four substeps of 2 + 1 iterations and 60 Hz contacts, the setting that holds
/// towers.
WorldSettings softStepSubsteps() {
    WorldSettings s;
    s.threads = 1;
    return awake(s);
}

/// The standard scenes' solver (S1-S4): Baumgarte, 8 iterations, one substep.
WorldSettings baumgarte() { return test::withStandardScenesSolver(WorldSettings{}); }

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

// Under a sanitizer the whole-scene tests here run 10 steps (tests/support/sanitized.h).
//
// S1's construction with 10 layers (385 cubes) at the default settings (the soft step, four substeps of 2 + 1
// iterations) for 5 s. Its contacts are springs: the pyramid settles by load / stiffness, under 1 mm here (bound). The
// standard scenes' Baumgarte (one substep, 8 iterations) with the resting-load guess moves it 1e-9 m; S1 itself (20
// layers, 600 steps) moves < 0.1 mm so.
TEST(Stacking, PyramidStandsAtDefaultSettings) {
    WorldSettings s;
    s.threads = 2;
    Stack stack(awake(s));
    const int layers = 10;
    for (int k = 0; k < layers; ++k) {
        const int n = layers - k;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) stack.add({i - (n - 1) / 2.0f, 0.5f + k, j - (n - 1) / 2.0f});
    }
    for (int i = 0; i < test::scaledSteps(300); ++i) stack.world.step(kDt);
    EXPECT_LT(stack.largestDisplacement(), 0.001f);
}

// The tower: twenty cubes for 30 s. The defaults (the soft step, four substeps of 2 + 1 iterations, 60 Hz
// contacts) hold it: measured 1.6 mm sideways at the top. Its contacts are springs, so the tower settles under its own
// weight: load * g / omega^2 per contact, 2.7 cm over the twenty contacts (measured), hence the separate bound.
TEST(Stacking, TowerOfTwentyStandsThirtySecondsAtDefaultSettings) {
    Stack stack(softStepSubsteps());
    for (int k = 0; k < 20; ++k) stack.add({0, 0.5f + k, 0});
    for (int i = 0; i < 1800; ++i) stack.world.step(kDt);
    const Vec3 top = stack.world.position(stack.cubes.back());
    EXPECT_LT(std::hypot(top.x, top.z), 0.01f);
    EXPECT_GT(top.y, 19.5f - 0.04f);
}

// Shock propagation against plain iterations, with Baumgarte at 8 iterations and one substep (the standard scenes'
// solver): the twenty-cube tower for 30 s. Plain iterations leave each step's stack unconverged; the residue
// rocks the tower until it falls (measured: the top lands 8.8 m away). With the shock pass each cube ends the
// iterations supported by the one below: measured 2.1 cm sideways at the top, short of the 1 cm, which the
// defaults meet (above).
TEST(Stacking, ShockPropagationHoldsATowerThatPlainIterationsTopple) {
    WorldSettings s = baumgarte();
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

// S5's wall at a fifth of its size (20 rows, 210 cubes) for 200 steps with Baumgarte at 8 iterations and one substep,
// against plain iterations (no resting-load guess, no shock pass) and the shock pass alone. Every contact is new in the
// first step: plain iterations pass the loads down a layer or so per iteration and let the wall spread (measured
// 15 cm); the shock pass holds it (measured 0.58 cm), and so does the resting-load guess (1e-7 m).
TEST(Stacking, RestingLoadsAndShockPropagationHoldAWallThatPlainIterationsSpread) {
    const auto run = [](bool seed, bool shock) {
        WorldSettings s = baumgarte();
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

// S5 itself (scenes/s5_large_pyramid.json: 100 rows, 5,050 cubes, the engine's own defaults as SCENES.md asks) for
// 200 steps. The defaults' contacts are springs: the wall settles by load / stiffness, summed over a hundred rows,
// measured 25 cm (21 cm without the resting-load guess; Box3D's softer contacts 69 cm), so the bound is 30 cm. Not met:
// the 5 cm, which Baumgarte with the guess meets (measured 1.2 cm, bound 2 cm) but which collapses without the
// guess (10.8 m) or dropped (16 m). Past 200 steps every setting lets this wall, one cube deep, tip out of its plane
// (after about 5 s): the sag of its contacts under the load grows the tilt, like a tower on soft ground.
TEST(Stacking, LargePyramidStandsAtDefaultSettings) {
    const Scene scene = loadScene(std::string(RUBBLE_SOURCE_DIR) + "/scenes/s5_large_pyramid.json");
    const auto run = [&](WorldSettings s) {
        s.threads = 2;
        World world(s);
        const std::vector<BodyId> ids = instantiate(scene, world);
        std::vector<Vec3> starts;
        for (BodyId id : ids) starts.push_back(world.position(id));
        for (int i = 0; i < test::scaledSteps(scene.steps); ++i) world.step(s.timeStep);
        float largest = 0;
        for (std::size_t i = 0; i < ids.size(); ++i)
            largest = std::max(largest, length(world.position(ids[i]) - starts[i]));
        return largest;
    };
    const WorldSettings& defaults = scene.settings;
    ASSERT_EQ(defaults.velocityIterations, WorldSettings{}.velocityIterations);
    ASSERT_EQ(defaults.positionIterations, WorldSettings{}.positionIterations);
    ASSERT_EQ(defaults.substeps, WorldSettings{}.substeps);
    ASSERT_EQ(defaults.solver.positionCorrection, WorldSettings{}.solver.positionCorrection);
    EXPECT_LT(run(defaults), 0.30f);
    WorldSettings stiff = baumgarte();
    stiff.effects = scene.settings.effects;
    EXPECT_LT(run(stiff), 0.02f);
}

// Heavy on light with Baumgarte at 8 iterations and one substep: the resting-load guess starts both contacts from
// the loads they carry (1,000 kg at the upper, 1,010 kg at the ground's), so the iterations only keep it: measured no
// motion at all. Dropped from 1 cm, its contacts start from the landing instead, eight iterations cannot balance the
// 1:100 ratio and it topples (scenes/hard/heavy_on_light.json: 2.6 m), which the defaults hold (below).
TEST(Stacking, HeavyOnLightStandsWithBaumgarteAndTheGuess) {
    WorldSettings s = baumgarte();
    s.threads = 1;
    Stack stack(awake(s));
    stack.add({0, 0.5f, 0}, 10);
    const BodyId heavy = stack.add({0, 1.5f, 0}, 1000);
    for (int i = 0; i < 600; ++i) stack.world.step(kDt);
    EXPECT_LT(length(stack.world.position(heavy) - Vec3{0, 1.5f, 0}), 0.001f);
}

// Heavy on light: a cube 100 times heavier resting on a light one, for 10 s. The defaults (the soft step, four
// substeps of 2 + 1 iterations, 60 Hz contacts) hold it; its springs sag by load * g / omega^2: 100 g / (2 pi 60)^2
// = 6.9 mm at the light-heavy contact plus 1.7 mm at the ground's (twice as stiff), measured 8.7 mm in all. It also
// holds the heavy cube dropped from 1 cm or 10 cm (measured 2.5 mm and 2.5 cm sideways), which Baumgarte does not
// (above).
TEST(Stacking, HeavyOnLightStandsAtDefaultSettings) {
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
// - the defaults (soft step, four substeps of 2 + 1): 2 cm/s (0.5 M v^2 = 19 J); the pile is at rest;
// - Baumgarte at 8 iterations and one substep: 10 cm/s (480 J); measured 6-260 J: the pile does not gain energy, but
//   it never comes quite to rest either (its contacts jitter inside the slop), Baumgarte's known weakness.
TEST(Stacking, SettledPileGainsNoEnergy) {
    for (const auto& [correction, speed] :
         {std::pair{PositionCorrection::SoftStep, 0.02}, std::pair{PositionCorrection::Baumgarte, 0.1}}) {
        WorldSettings s = correction == PositionCorrection::SoftStep ? WorldSettings{} : baumgarte();
        s.threads = 2;
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
