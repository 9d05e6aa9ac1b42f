// Large worlds keep their moving bodies in the broad-phase grid's cell order (World::step, "spatial order"): the
// storage's permutation must keep every handle on its own body, the order must put touching bodies near each other
// in memory, and a world stepped with it must move like the same world stepped without it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "core/parallel.h"
#include "rubble/world.h"
#include "storage/body_storage.h"
#include "world/world_access.h"

using namespace rubble;

namespace {

/// A value of every element type per row, derived from the body's slot, so a row that lands on another body shows.
struct RowProbe {
    float px;
    float iwYZ;
    float sleepTimer;
    std::uint32_t sleepGroup;
    std::uint64_t userData;
    std::uint8_t flags;
};

RowProbe probeOf(std::uint32_t slot) {
    return {static_cast<float>(slot) * 0.5f, static_cast<float>(slot) + 0.25f,
            static_cast<float>(slot) * 2.0f, slot * 3u + 1u,
            std::uint64_t{slot} << 33 | 7u,  static_cast<std::uint8_t>(slot * 5u)};
}

void writeProbe(detail::MovingBodies& m, std::uint32_t row, const RowProbe& p) {
    m.px[row] = p.px, m.iwYZ[row] = p.iwYZ, m.sleepTimer[row] = p.sleepTimer;
    m.sleepGroup[row] = p.sleepGroup, m.userData[row] = p.userData, m.flags[row] = p.flags;
}

/// S4's gas at a small scale: spheres of radius 0.5 at S4's density (one per 80 m^3), random velocities, no
/// gravity on them; and apart from the gas, boxes dropped one by one on a static floor, which must come to rest and
/// sleep in both worlds.
struct Gas {
    World world;
    std::vector<BodyId> spheres;
    std::vector<BodyId> boxes;

    // The grid on both sides: the order is the grid's (auto may time the sweep for a few steps).
    explicit Gas(int count)
        : world([] {
              WorldSettings s{.threads = 2, .broadPhase = BroadPhaseKind::Grid};
              s.manifoldReuseDistance = 0;
              return s;
          }()) {
        const ShapeId ball = world.createShape(SphereDef{0.5f});
        const ShapeId box = world.createShape(BoxDef{{0.4f, 0.4f, 0.4f}});
        const ShapeId floor = world.createShape(BoxDef{{40.0f, 0.5f, 40.0f}});
        const float half = 0.5f * std::cbrt(80.0f * static_cast<float>(count));
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> at(-half, half), speed(-5.0f, 5.0f);
        std::vector<Vec3> placed;
        while (placed.size() < static_cast<std::size_t>(count)) {
            // No sphere starts inside another: pairs form while the spheres move, as in a game, and lone pairs stay
            // the rule (a deep overlap at the start makes clusters whose Gauss-Seidel order shows).
            const Vec3 c{at(rng), at(rng) + half + 10.0f, at(rng)};
            if (std::any_of(placed.begin(), placed.end(), [&](Vec3 q) { return length(q - c) < 1.05f; })) continue;
            placed.push_back(c);
            BodyDef def;
            def.shape = ball;
            def.position = c;
            def.linearVelocity = {speed(rng), speed(rng), speed(rng)};
            def.gravityScale = 0.0f;
            def.allowSleep = false;
            spheres.push_back(world.createBody(def));
        }
        BodyDef ground;
        ground.type = BodyType::Static;
        ground.shape = floor;
        ground.position = {0, -0.5f, 0};
        world.createBody(ground);
        for (int i = 0; i < 16; ++i) {
            BodyDef def;
            def.shape = box;
            def.position = {-30.0f + 4.0f * static_cast<float>(i), 0.6f + 0.1f * static_cast<float>(i % 3), 20.0f};
            boxes.push_back(world.createBody(def));
        }
    }
};

}  // namespace

TEST(SpatialOrder, ReorderKeepsEveryHandleOnItsBody) {
    detail::BodyStorage storage;
    detail::TaskPool pool(2);
    std::vector<BodyId> moving;
    std::mt19937 rng(17);
    // Churn first, so that slots and rows no longer agree before the reorder.
    for (int i = 0; i < 40000; ++i) {
        std::uint32_t row;
        if (moving.empty() || rng() % 4 != 0) {
            const bool isStatic = rng() % 5 == 0;
            const BodyId id = storage.allocate(isStatic ? detail::BodySet::Static : detail::BodySet::Moving, row);
            if (!isStatic) moving.push_back(id);
        } else {
            const std::size_t k = rng() % moving.size();
            storage.release(moving[k]);
            moving[k] = moving.back();
            moving.pop_back();
        }
    }
    for (BodyId id : moving) writeProbe(storage.moving, storage.find(id)->dense, probeOf(id.index));
    std::vector<std::uint32_t> order(storage.moving.size());
    std::iota(order.begin(), order.end(), 0u);
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<std::uint32_t> slotBefore(order.size());
    for (std::uint32_t k = 0; k < order.size(); ++k) slotBefore[k] = storage.moving.slot[order[k]];
    const std::uint64_t layout = storage.layoutChanges();

    storage.reorderMoving(order.data(), pool);

    EXPECT_EQ(storage.checkInvariants(), "");
    EXPECT_EQ(storage.layoutChanges(), layout + 1);
    std::size_t wrong = 0;
    for (std::uint32_t k = 0; k < order.size(); ++k) wrong += storage.moving.slot[k] != slotBefore[k];
    EXPECT_EQ(wrong, 0u) << "row k must hold the body that was at row order[k]";
    for (BodyId id : moving) {
        const std::uint32_t row = storage.find(id)->dense;
        const RowProbe want = probeOf(id.index);
        const detail::MovingBodies& m = storage.moving;
        ASSERT_EQ(m.px[row], want.px);
        ASSERT_EQ(m.iwYZ[row], want.iwYZ);
        ASSERT_EQ(m.sleepTimer[row], want.sleepTimer);
        ASSERT_EQ(m.sleepGroup[row], want.sleepGroup);
        ASSERT_EQ(m.userData[row], want.userData);
        ASSERT_EQ(m.flags[row], want.flags);
    }
}

TEST(SpatialOrder, TouchingBodiesSitNearEachOtherInMemory) {
    // The order is a performance promise, so check it where it acts: the rows of the bodies in a pair. In creation
    // (random) order a pair's rows are ~0.3 n apart (the median gap of two uniform draws); in cell order one layer
    // of cells (one z) holds ~n^(2/3) bodies, and the two bodies of a pair lie in the same layer or the next.
    auto medianRowGap = [](Gas& gas, bool ordered) {
        World::Impl& w = detail::WorldAccess::of(gas.world);
        w.spatialOrderFrom = ordered ? 0 : ~0u;
        w.spatialOrderPeriod = 4;
        for (int s = 0; s < 6; ++s) gas.world.step(1.0f / 60);
        std::vector<std::uint32_t> gaps;
        for (const detail::BodyPair& p : w.pairs.moving) gaps.push_back(p.b - p.a);
        EXPECT_GT(gaps.size(), 50u);
        std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
        return gaps.empty() ? 0u : gaps[gaps.size() / 2];
    };
    constexpr int kSpheres = 8000;
    Gas unordered(kSpheres), ordered(kSpheres);
    const std::uint32_t randomGap = medianRowGap(unordered, false);
    const std::uint32_t cellGap = medianRowGap(ordered, true);
    EXPECT_GT(randomGap, kSpheres / 5u);
    EXPECT_LT(cellGap, kSpheres / 20u);
}

TEST(SpatialOrder, OrderedWorldMovesLikeTheUnorderedOne) {
    // The order decides only the order of pairs; a pair's own solve does not depend on it, except for which body is
    // `a` (the normal's sign) and which of several contacts of one island comes first: rounding-level changes. The
    // gas is free flight and lone pairs, so nearly every sphere must end exactly where it ends without the order.
    // Not every one: a rounding difference can tip a borderline decision (a speculative contact kept or not, a
    // bounce or none) and then grows with the sphere's flight; measured over 90 steps, 15 of 6,000 spheres moved
    // more than 1e-5 m (the bound is 1%), 11 more than 1 mm. The gas's momentum, which collisions only pass between
    // spheres, must agree to 1e-3 of its size; the boxes on the floor must come to rest and sleep in both worlds.
    constexpr int kSpheres = 6000;
    Gas plain(kSpheres), ordered(kSpheres);
    World::Impl& p = detail::WorldAccess::of(plain.world);
    World::Impl& o = detail::WorldAccess::of(ordered.world);
    p.spatialOrderFrom = ~0u;
    o.spatialOrderFrom = 0;
    o.spatialOrderPeriod = 4;
    const std::uint64_t layoutBefore = o.bodies.layoutChanges();
    for (int s = 0; s < 90; ++s) {
        plain.world.step(1.0f / 60);
        ordered.world.step(1.0f / 60);
    }
    EXPECT_GE(o.bodies.layoutChanges() - layoutBefore, 20u) << "the world was ordered every 4 steps";
    EXPECT_EQ(p.bodies.layoutChanges(), layoutBefore);
    EXPECT_EQ(o.bodies.checkInvariants(), "");
    std::size_t apart = 0;
    Vec3 momentum[2] = {{0, 0, 0}, {0, 0, 0}};
    for (std::size_t i = 0; i < plain.spheres.size(); ++i) {
        apart += length(plain.world.position(plain.spheres[i]) - ordered.world.position(ordered.spheres[i])) > 1e-5f;
        momentum[0] = momentum[0] + plain.world.linearVelocity(plain.spheres[i]);
        momentum[1] = momentum[1] + ordered.world.linearVelocity(ordered.spheres[i]);
    }
    EXPECT_LT(apart, plain.spheres.size() / 100);
    EXPECT_LT(length(momentum[0] - momentum[1]), 1e-3f * length(momentum[0]));
    for (std::size_t i = 0; i < plain.boxes.size(); ++i) {
        EXPECT_FALSE(plain.world.isAwake(plain.boxes[i]));
        EXPECT_FALSE(ordered.world.isAwake(ordered.boxes[i]));
        EXPECT_LT(length(plain.world.position(plain.boxes[i]) - ordered.world.position(ordered.boxes[i])), 1e-4f);
    }
}
