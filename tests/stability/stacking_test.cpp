// Stacks that must stand. Bounds are the where the engine meets them, and otherwise the measured figure
// with a margin, so that a regression fails; what is not met yet is said next to the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

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
    void add(Vec3 position) {
        static const BoxDef cube{{0.5f, 0.5f, 0.5f}};
        BodyDef def;
        if (cubeShape.isNull()) cubeShape = world.createShape(cube);
        def.shape = cubeShape;
        def.position = position;
        cubes.push_back(world.createBody(def));
        starts.push_back(position);
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
// substep) for 5 s. Measured: 0.74 cm; S1 itself (20 layers, 600 steps) moves 4.6 cm, within the 5 cm.
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
    EXPECT_LT(stack.largestDisplacement(), 0.02f);
}

// A tower of ten cubes for 10 s. The soft step with four substeps holds it upright: the top moves sideways less
// than 1 cm. Its soft contacts sag under the load (measured 5.6 cm over the ten contacts), hence the separate
// bound on height. Not met yet: the 20-box tower with < 1 cm drift, and towers at the default Baumgarte
// settings, whose eight iterations let a ten-box tower topple.
TEST(Stacking, TowerOfTenStandsWithSoftStepSubsteps) {
    WorldSettings s;
    s.threads = 1;
    s.substeps = 4;
    s.velocityIterations = 2;
    s.positionIterations = 1;
    s.solver.positionCorrection = PositionCorrection::SoftStep;
    s.solver.contactHertz = 60;
    Stack stack(s);
    for (int k = 0; k < 10; ++k) stack.add({0, 0.5f + k, 0});
    for (int i = 0; i < 600; ++i) stack.world.step(kDt);
    const Vec3 top = stack.world.position(stack.cubes.back());
    EXPECT_LT(std::hypot(top.x, top.z), 0.01f);
    EXPECT_GT(top.y, 9.5f - 0.07f);
}

}  // namespace
}  // namespace rubble
