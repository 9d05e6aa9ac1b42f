// A world that sleeps costs the broad phase only its awake bodies: the sleepers go into a tree of their own
// (BroadPhaseStage::findPairs), SAP or the grid search the awake ones, and update bounds leaves batches of sleepers
// as they are (updateBounds with keepSleepers). Checked through the World, on piles that fall asleep and are woken
// by hits, impulses, moves, removals, a kinematic body and the effect turned off and on, and that fall asleep again:
// after every step, the step's moving pairs must be exactly the brute-force pairs over the step's own boxes under the
// filter it started with (awake against asleep kept, asleep against asleep left out), and the box of every body that
// slept through the search must be, to the bit, a box computed anew from its state.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "bounds/bounds.h"
#include "broadphase/static_bvh.h"
#include "rubble/world.h"
#include "support/broadphase_scenarios.h"
#include "world/world_access.h"

namespace rubble {
namespace {

using detail::WorldAccess;

constexpr float kDt = 1.0f / 60.0f;

struct SleepyPiles {
    World world;
    ShapeId cube, ball, wideBox;
    std::vector<BodyId> bodies;
    BodyId pusher;
    std::mt19937 rng{7};

    explicit SleepyPiles(BroadPhaseKind kind)
        : world([kind] {
              WorldSettings s;
              s.threads = 2;
              s.broadPhase = kind;
              s.effects = EffectSet::defaults().with(Effect::Sleeping);
              return s;
          }()) {
        cube = world.createShape(BoxDef{{0.4f, 0.4f, 0.4f}});
        ball = world.createShape(SphereDef{0.35f});
        wideBox = world.createShape(BoxDef{{0.5f, 0.5f, 2.5f}});
        BodyDef ground;
        ground.type = BodyType::Static;
        ground.shape = world.createShape(BoxDef{{30, 0.5f, 30}});
        ground.position = {0, -0.5f, 0};
        world.createBody(ground);
        // Nine stacks of six layers of four boxes, each box a little off (so that they settle at different times),
        // and a ball resting beside each stack.
        std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
        for (int pile = 0; pile < 9; ++pile) {
            const float x = float(pile % 3) * 6 - 6, z = float(pile / 3) * 6 - 6;
            for (int layer = 0; layer < 6; ++layer)
                for (int k = 0; k < 4; ++k) {
                    const Vec3 at{x + float(k % 2) * 0.82f - 0.41f + jitter(rng), 0.41f + float(layer) * 0.82f,
                                  z + float(k / 2) * 0.82f - 0.41f + jitter(rng)};
                    bodies.push_back(add(at, false));
                }
            bodies.push_back(add({x + 2, 0.35f, z}, true));
        }
        BodyDef kinematic;
        kinematic.type = BodyType::Kinematic;
        kinematic.shape = wideBox;
        kinematic.position = {-20, 0.5f, 0};
        pusher = world.createBody(kinematic);
    }

    BodyId add(Vec3 at, bool sphere) {
        BodyDef def;
        def.shape = sphere ? ball : cube;
        def.position = at;
        return world.createBody(def);
    }

    std::size_t asleep() const {
        std::size_t count = 0;
        for (const BodyId b : bodies)
            if (world.isValid(b) && !world.isAwake(b)) ++count;
        return count;
    }
};

/// One step, checked against brute force (see the top of the file). Returns the number of pairs of the step with a
/// sleeping side, so that the caller can see the case was met.
std::size_t checkedStep(World& world, const std::string& what) {
    const auto& w = WorldAccess::of(static_cast<const World&>(world));
    const detail::MovingBodies& m = w.bodies.moving;
    // The search reads the sleep flags the step starts with (a body the step's islands wake was searched asleep).
    // Nothing but the sleep stage moves rows or changes them in a step of a world this small.
    std::vector<std::uint8_t> flags = m.flags;
    // With the effect turned off, the step wakes every sleeper before it searches.
    if (!world.settings().effects.has(Effect::Sleeping))
        for (std::uint8_t& f : flags) f &= static_cast<std::uint8_t>(~detail::kFlagAsleep);
    detail::Bounds fresh;
    detail::updateBoundsScalar(m, w.shapeBounds, {kDt, w.settings.contactMargin}, fresh);
    world.step(kDt);
    detail::PairFilter filter;
    filter.category = m.filterCategory.data();
    filter.mask = m.filterMask.data();
    filter.flags = flags.data();
    filter.asleepBit = detail::kFlagAsleep;
    EXPECT_EQ(w.pairs.moving, test::bruteForcePairs(w.movingBounds, filter)) << what;
    // Against the statics (the ground), the awake rows alone: a sleeper against a static is never a pair.
    std::vector<detail::StaticPrimitive> primitives;
    const detail::StaticBodies& statics = w.bodies.statics;
    for (std::uint32_t j = 0; j < statics.size(); ++j) {
        const Transform pose{{statics.px[j], statics.py[j], statics.pz[j]},
                             {statics.qx[j], statics.qy[j], statics.qz[j], statics.qw[j]}};
        detail::appendStaticPrimitives(w.shapes[statics.shape[j]], pose, j, primitives);
    }
    std::vector<detail::BodyPair> staticPairs;
    const detail::Bounds& boxes = w.movingBounds;
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
        for (const detail::StaticPrimitive& q : primitives)
            if (!(flags[i] & detail::kFlagAsleep) && boxes.minX[i] <= q.box.max.x && q.box.min.x <= boxes.maxX[i] &&
                boxes.minY[i] <= q.box.max.y && q.box.min.y <= boxes.maxY[i] && boxes.minZ[i] <= q.box.max.z &&
                q.box.min.z <= boxes.maxZ[i])
                staticPairs.push_back({i, q.body});
    EXPECT_EQ(w.pairs.statics, staticPairs) << what;
    std::size_t withSleeper = 0;
    for (const detail::BodyPair& p : w.pairs.moving)
        withSleeper += ((flags[p.a] | flags[p.b]) & detail::kFlagAsleep) != 0;
    const detail::Bounds& kept = w.movingBounds;
    for (std::uint32_t i = 0; i < kept.size(); ++i) {
        if (!(flags[i] & detail::kFlagAsleep)) continue;
        const bool same = kept.minX[i] == fresh.minX[i] && kept.minY[i] == fresh.minY[i] &&
                          kept.minZ[i] == fresh.minZ[i] && kept.maxX[i] == fresh.maxX[i] &&
                          kept.maxY[i] == fresh.maxY[i] && kept.maxZ[i] == fresh.maxZ[i];
        EXPECT_TRUE(same) << what << ": sleeper row " << i << " kept a box that is not its own";
        if (!same) break;
    }
    return withSleeper;
}

class SleepersTest : public ::testing::TestWithParam<BroadPhaseKind> {};

TEST_P(SleepersTest, PairsWithSleepersAreExactlyBruteForceAsTheyWakeAndSleep) {
    SleepyPiles s(GetParam());
    World& world = s.world;
    std::size_t withSleeper = 0;
    int step = 0;
    const auto run = [&](int steps, const char* phase) {
        for (int k = 0; k < steps && !::testing::Test::HasFailure(); ++k, ++step)
            withSleeper += checkedStep(world, std::string(phase) + ", step " + std::to_string(step));
    };
    run(240, "falling asleep");
    ASSERT_GT(s.asleep(), s.bodies.size() / 2) << "the piles must be mostly asleep for the test to mean anything";

    // A ball dropped onto a sleeping pile wakes it through a pair with a sleeper.
    s.bodies.push_back(s.add({0, 12, 0}, true));
    run(90, "ball dropped on a pile");
    EXPECT_GT(withSleeper, 0u) << "no pair of an awake body with a sleeper was ever found";

    // Between steps: an impulse, a move, a removal, a wake-up, each on a sleeper.
    std::vector<BodyId> sleepers;
    for (const BodyId b : s.bodies)
        if (world.isValid(b) && !world.isAwake(b)) sleepers.push_back(b);
    ASSERT_GE(sleepers.size(), 8u);
    world.applyLinearImpulse(sleepers[0], {0, 3, 0});
    world.setTransform(sleepers[1], {0, 15, 10}, Quat{});
    world.destroyBody(sleepers[2]);
    world.wakeUp(sleepers[3]);
    // A removed body's slot taken by a new body at once.
    world.destroyBody(sleepers[4]);
    s.bodies.push_back(s.add({6, 14, 6}, false));
    run(60, "edits between steps");

    // A kinematic body sweeping through the piles' row keeps what it touches awake.
    for (int k = 0; k < 120 && !::testing::Test::HasFailure(); ++k, ++step) {
        world.moveKinematic(s.pusher, {-20 + 0.3f * float(k), 0.5f, 0}, Quat{}, kDt);
        withSleeper += checkedStep(world, "kinematic sweep, step " + std::to_string(step));
    }

    // The effect off wakes everything between steps; on again, the piles fall asleep anew.
    WorldSettings settings = world.settings();
    settings.effects = settings.effects.without(Effect::Sleeping);
    world.setSettings(settings);
    run(5, "sleeping off");
    EXPECT_EQ(s.asleep(), 0u);
    settings.effects = settings.effects.with(Effect::Sleeping);
    world.setSettings(settings);
    run(300, "asleep again");
    EXPECT_GT(s.asleep(), s.bodies.size() / 2);
}

INSTANTIATE_TEST_SUITE_P(BroadPhase, SleepersTest,
                         ::testing::Values(BroadPhaseKind::SweepAndPrune, BroadPhaseKind::Grid),
                         [](const ::testing::TestParamInfo<BroadPhaseKind>& param) {
                             return param.param == BroadPhaseKind::Grid ? "Grid" : "SweepAndPrune";
                         });

}  // namespace
}  // namespace rubble
