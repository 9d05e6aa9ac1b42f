// Sweep-and-prune against the brute-force answer: every shared scenario, a moving world with insertions and
// removals through a slot map like the world's, filters and sleep, forced axis changes, the closed-interval edge
// cases (touching and identical boxes), the scalar reference kernel, and identical output on 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "broadphase/sweep_and_prune.h"
#include "core/parallel.h"
#include "support/broadphase_scenarios.h"

namespace {

using namespace rubble::detail;
using rubble::test::bruteForcePairs;
using rubble::test::jiggle;
using rubble::test::makeScenario;
using rubble::test::Scenario;

std::vector<std::uint32_t> identitySlots(std::uint32_t n) {
    std::vector<std::uint32_t> s(n);
    std::iota(s.begin(), s.end(), 0u);
    return s;
}

std::vector<BodyPair> sorted(std::vector<BodyPair> pairs) {
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

// One call on a fresh instance with identity slots; the raw (unsorted) output.
std::vector<BodyPair> findOnce(const Bounds& b, TaskPool& pool, const PairFilter& filter = {}) {
    SweepAndPrune sap;
    sap.setPairBudget(PairBudget::unlimited());  // every pair of the all-overlapping scenario, against brute force
    const std::vector<std::uint32_t> slots = identitySlots(b.size());
    std::vector<BodyPair> out;
    sap.findPairs(b, slots.data(), b.size(), filter, pool, out);
    return out;
}

// A body set that changes like the world's: removal swaps the last body into the hole, slots are reused.
struct MovingWorld {
    Bounds bounds;
    std::vector<std::uint32_t> slotOfDense;
    std::vector<std::uint32_t> freeSlots;
    std::uint32_t slotCount = 0;

    explicit MovingWorld(Bounds b) : bounds(std::move(b)), slotOfDense(identitySlots(bounds.size())) {
        slotCount = bounds.size();
    }
    void remove(std::uint32_t dense) {
        const std::uint32_t last = bounds.size() - 1;
        freeSlots.push_back(slotOfDense[dense]);
        for (auto* a : {&bounds.minX, &bounds.minY, &bounds.minZ, &bounds.maxX, &bounds.maxY, &bounds.maxZ}) {
            (*a)[dense] = (*a)[last];
            a->pop_back();
        }
        slotOfDense[dense] = slotOfDense[last];
        slotOfDense.pop_back();
    }
    void add(float x, float y, float z, float h) {
        bounds.minX.push_back(x - h), bounds.maxX.push_back(x + h);
        bounds.minY.push_back(y - h), bounds.maxY.push_back(y + h);
        bounds.minZ.push_back(z - h), bounds.maxZ.push_back(z + h);
        if (freeSlots.empty()) {
            slotOfDense.push_back(slotCount++);
        } else {
            slotOfDense.push_back(freeSlots.back());
            freeSlots.pop_back();
        }
    }
    void find(SweepAndPrune& sap, TaskPool& pool, std::vector<BodyPair>& out, const PairFilter& filter = {}) {
        sap.findPairs(bounds, slotOfDense.data(), slotCount, filter, pool, out);
    }
};

TEST(SweepAndPrune, EveryScenarioMatchesBruteForce) {
    TaskPool one(1), two(2);
    for (Scenario s :
         {Scenario::Uniform, Scenario::Clustered, Scenario::Flat, Scenario::MixedSizes, Scenario::AllOverlapping}) {
        SCOPED_TRACE(std::string(rubble::test::scenarioName(s)));
        const std::uint32_t n = s == Scenario::AllOverlapping ? 1500 : 4000;
        const Bounds b = makeScenario(s, n);
        const std::vector<BodyPair> expected = bruteForcePairs(b);
        const std::vector<BodyPair> out1 = findOnce(b, one), out2 = findOnce(b, two);
        EXPECT_EQ(sorted(out1), expected);  // equal as sorted lists: no pair missed, none twice
        EXPECT_EQ(out1, out2);              // and the raw sequence does not depend on the thread count
        for (const BodyPair& p : out1) ASSERT_LT(p.a, p.b);
    }
}

TEST(SweepAndPrune, ScalarKernelAgreesWithSimd) {
    TaskPool pool(2);
    for (Scenario s : {Scenario::Clustered, Scenario::MixedSizes}) {
        const Bounds b = makeScenario(s, 3000, 5);
        const std::vector<std::uint32_t> slots = identitySlots(b.size());
        SweepAndPrune wide, scalar;
        scalar.useScalarKernel(true);
        std::vector<BodyPair> w, r;
        wide.findPairs(b, slots.data(), b.size(), {}, pool, w);
        scalar.findPairs(b, slots.data(), b.size(), {}, pool, r);
        EXPECT_EQ(w, r);
    }
}

// Ten steps of a world whose bodies move, leave and arrive; every step must match brute force and a sort from
// scratch, on 1 and 2 threads alike. Returns how many steps re-sorted the kept order by insertion.
int runMovingScene(Scenario scenario, float jiggleStep) {
    TaskPool one(1), two(2);
    MovingWorld world(makeScenario(scenario, 3000, 17));
    SweepAndPrune sap1, sap2;
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    int insertionSteps = 0;
    for (int step = 0; step < 10; ++step) {
        SCOPED_TRACE(::testing::Message() << "step " << step);
        std::vector<BodyPair> out1, out2;
        world.find(sap1, one, out1);
        world.find(sap2, two, out2);
        EXPECT_EQ(sorted(out1), bruteForcePairs(world.bounds));
        EXPECT_EQ(out1, out2);
        EXPECT_EQ(sap1.lastAxis(), sap2.lastAxis());
        EXPECT_EQ(sap1.lastUsedInsertionSort(), sap2.lastUsedInsertionSort());
        insertionSteps += sap1.lastUsedInsertionSort();

        // The kept order reaches the same sequence as a sort from scratch: (minimum, dense index) is a total order.
        SweepAndPrune cold;
        std::vector<BodyPair> fresh;
        world.find(cold, two, fresh);
        if (cold.lastAxis() == sap1.lastAxis()) {
            EXPECT_EQ(fresh, out1);
        }

        jiggle(world.bounds, jiggleStep, 1000 + step);
        if (step % 3 == 2) continue;  // some steps change nothing but positions
        const int removals = 5 + step * 3, additions = 12;
        for (int k = 0; k < removals; ++k) world.remove(static_cast<std::uint32_t>(rng() % world.bounds.size()));
        for (int k = 0; k < additions; ++k)
            world.add((unit(rng) - 0.5f) * 60.0f, (unit(rng) - 0.5f) * 60.0f, (unit(rng) - 0.5f) * 60.0f,
                      0.3f + unit(rng));
        if (step == 5) {  // remove a run of bodies at the end, where swap-remove moves nothing
            for (int k = 0; k < 10; ++k) world.remove(world.bounds.size() - 1);
        }
    }
    return insertionSteps;
}

TEST(SweepAndPrune, MovingSceneWithInsertionsAndRemovals) {
    // At a step's typical motion the kept order is re-sorted by insertion on every step after the first.
    EXPECT_EQ(runMovingScene(Scenario::Uniform, 0.002f), 9);
    // Larger motion in dense clusters: whichever sort runs, the answer is exact.
    runMovingScene(Scenario::Clustered, 0.2f);
}

TEST(SweepAndPrune, LargeDisorderFallsBackToRadixSort) {
    TaskPool pool(2);
    MovingWorld world(makeScenario(Scenario::Uniform, 5000, 3));
    SweepAndPrune sap;
    sap.setPairBudget(PairBudget::unlimited());  // 3,000 boxes 1 cm apart: 100 pairs a box, past the budget
    std::vector<BodyPair> out;
    world.find(sap, pool, out);
    EXPECT_FALSE(sap.lastUsedInsertionSort());
    jiggle(world.bounds, 0.002f, 1);
    world.find(sap, pool, out);
    EXPECT_TRUE(sap.lastUsedInsertionSort());
    EXPECT_EQ(sorted(out), bruteForcePairs(world.bounds));
    jiggle(world.bounds, 30.0f, 2);  // a large fraction of the bodies jump far
    world.find(sap, pool, out);
    EXPECT_FALSE(sap.lastUsedInsertionSort());
    EXPECT_EQ(sorted(out), bruteForcePairs(world.bounds));
    // Replacing most bodies at once is also a rebuild, not a long merge.
    for (int k = 0; k < 3000; ++k) world.remove(0);
    for (int k = 0; k < 3000; ++k) world.add(k * 0.01f, 0.0f, 0.0f, 0.5f);
    world.find(sap, pool, out);
    EXPECT_FALSE(sap.lastUsedInsertionSort());
    EXPECT_EQ(sorted(out), bruteForcePairs(world.bounds));
}

TEST(SweepAndPrune, ManyNewBodiesMergeIntoTheKeptOrder) {
    // Thousands of arrivals (sorted apart by radix, then merged) while a tenth of the old bodies leave: still the
    // insertion path, and the same sequence a sort from scratch gives.
    TaskPool pool(2);
    MovingWorld world(makeScenario(Scenario::Uniform, 40'000, 8));
    SweepAndPrune sap;
    std::vector<BodyPair> out, fresh;
    world.find(sap, pool, out);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(-0.5f, 0.5f);
    for (int k = 0; k < 4000; ++k) world.remove(static_cast<std::uint32_t>(rng() % world.bounds.size()));
    for (int k = 0; k < 6000; ++k) world.add(unit(rng) * 120.0f, unit(rng) * 120.0f, unit(rng) * 120.0f, 0.5f);
    world.find(sap, pool, out);
    EXPECT_TRUE(sap.lastUsedInsertionSort());
    SweepAndPrune cold;
    world.find(cold, pool, fresh);
    EXPECT_EQ(sorted(out), sorted(fresh));
    if (cold.lastAxis() == sap.lastAxis()) {
        EXPECT_EQ(out, fresh);
    }
    EXPECT_FALSE(out.empty());
}

// A few moving bodies among many slots (the statics of a large world hold slots too): the kept order is followed
// through a table sorted by slot rather than an array over every slot. Bodies come, go and take freed slots; every
// answer is the brute force's, and the same sequence a sort from scratch gives.
TEST(SweepAndPrune, FewBodiesAmongManySlotsComeAndGo) {
    TaskPool pool(2);
    MovingWorld world(makeScenario(Scenario::Clustered, 400, 11));
    std::mt19937 rng(12);
    // The bodies' slots scattered over 200,000, the rest free in random order.
    std::vector<std::uint32_t> slots(200'000);
    std::iota(slots.begin(), slots.end(), 0u);
    std::shuffle(slots.begin(), slots.end(), rng);
    world.slotCount = static_cast<std::uint32_t>(slots.size());
    std::copy(slots.begin(), slots.begin() + world.bounds.size(), world.slotOfDense.begin());
    world.freeSlots.assign(slots.begin() + world.bounds.size(), slots.end());
    SweepAndPrune sap;
    std::vector<BodyPair> out, fresh;
    world.find(sap, pool, out);
    std::uniform_real_distribution<float> unit(-0.5f, 0.5f);
    int insertionSteps = 0;
    for (int step = 0; step < 12; ++step) {
        jiggle(world.bounds, 0.002f, static_cast<std::uint32_t>(step));
        for (int k = 0; k < 3; ++k) world.remove(static_cast<std::uint32_t>(rng() % world.bounds.size()));
        for (int k = 0; k < 4; ++k) world.add(unit(rng) * 20.0f, unit(rng) * 20.0f, unit(rng) * 20.0f, 0.5f);
        world.find(sap, pool, out);
        insertionSteps += sap.lastUsedInsertionSort() ? 1 : 0;
        ASSERT_EQ(sorted(out), bruteForcePairs(world.bounds)) << "step " << step;
        SweepAndPrune cold;
        world.find(cold, pool, fresh);
        if (cold.lastAxis() == sap.lastAxis()) {
            EXPECT_EQ(out, fresh) << "step " << step;
        }
    }
    EXPECT_GT(insertionSteps, 6);  // the kept order was followed through the slots: the test means something
}

TEST(SweepAndPrune, FilterCategoriesAndMasks) {
    TaskPool pool(2);
    const Bounds b = makeScenario(Scenario::Clustered, 4000, 8);
    std::mt19937 rng(4);
    std::vector<std::uint32_t> category(b.size()), mask(b.size());
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        category[i] = 1u << (rng() % 4);
        mask[i] = 0xFu & ~(i % 3 == 0 ? 0x2u : 0u);  // a third of the bodies ignore category 2
    }
    PairFilter filter;
    filter.category = category.data();
    filter.mask = mask.data();
    const std::vector<BodyPair> expected = bruteForcePairs(b, filter);
    EXPECT_LT(expected.size(), bruteForcePairs(b).size());
    EXPECT_EQ(sorted(findOnce(b, pool, filter)), expected);
}

TEST(SweepAndPrune, PairsOfSleepingBodiesAreSkipped) {
    TaskPool pool(2);
    const Bounds b = makeScenario(Scenario::Clustered, 4000, 12);
    constexpr std::uint8_t kAsleep = 0x4;
    std::vector<std::uint8_t> flags(b.size());
    for (std::uint32_t i = 0; i < b.size(); ++i) flags[i] = (i % 3 != 0 ? kAsleep : 0) | 0x1;
    PairFilter filter;
    filter.flags = flags.data();
    filter.asleepBit = kAsleep;
    const std::vector<BodyPair> out = sorted(findOnce(b, pool, filter));
    EXPECT_EQ(out, bruteForcePairs(b, filter));
    for (const BodyPair& p : out) ASSERT_FALSE(filter.asleep(p.a) && filter.asleep(p.b));
    EXPECT_FALSE(out.empty());
}

TEST(SweepAndPrune, AxisFollowsTheSpreadAndChangesCleanly) {
    TaskPool pool(2);
    // Long along x, then the same bodies rearranged to lie along y, then along z.
    const std::uint32_t n = 3000;
    MovingWorld world(makeScenario(Scenario::Uniform, n, 6));
    const auto stretch = [&](int axis) {
        std::array<AlignedVector<float>*, 3> mins = {&world.bounds.minX, &world.bounds.minY, &world.bounds.minZ};
        std::array<AlignedVector<float>*, 3> maxs = {&world.bounds.maxX, &world.bounds.maxY, &world.bounds.maxZ};
        for (int a = 0; a < 3; ++a)
            for (std::uint32_t i = 0; i < n; ++i) {
                const float h = ((*maxs[a])[i] - (*mins[a])[i]) * 0.5f;
                const float c = ((*maxs[a])[i] + (*mins[a])[i]) * 0.5f;
                const float scaled = a == axis ? c * 4.0f : c * 0.25f;
                (*mins[a])[i] = scaled - h, (*maxs[a])[i] = scaled + h;
            }
    };
    SweepAndPrune sap;
    std::vector<BodyPair> out;
    for (int axis : {0, 1, 2, 0}) {
        world = MovingWorld(makeScenario(Scenario::Uniform, n, 6));
        stretch(axis);
        world.find(sap, pool, out);
        EXPECT_EQ(sap.lastAxis(), axis);
        EXPECT_FALSE(sap.lastUsedInsertionSort());  // a new axis needs a new order
        EXPECT_EQ(sorted(out), bruteForcePairs(world.bounds));
        jiggle(world.bounds, 0.001f, axis);
        world.find(sap, pool, out);
        EXPECT_EQ(sap.lastAxis(), axis);
        EXPECT_TRUE(sap.lastUsedInsertionSort());
        EXPECT_EQ(sorted(out), bruteForcePairs(world.bounds));
    }
}

TEST(SweepAndPrune, TouchingBoxesOverlap) {
    // A k^3 lattice of unit boxes that share faces, edges and corners exactly: closed intervals make every pair of
    // lattice neighbours (26 directions) a pair, and nothing else.
    TaskPool pool(2);
    const int k = 12;
    Bounds b;
    b.resize(k * k * k);
    std::uint32_t i = 0;
    for (int x = 0; x < k; ++x)
        for (int y = 0; y < k; ++y)
            for (int z = 0; z < k; ++z, ++i) {
                b.minX[i] = static_cast<float>(x), b.maxX[i] = static_cast<float>(x + 1);
                b.minY[i] = static_cast<float>(y), b.maxY[i] = static_cast<float>(y + 1);
                b.minZ[i] = static_cast<float>(z), b.maxZ[i] = static_cast<float>(z + 1);
            }
    // Neighbouring cells per axis: k - 1 adjacent pairs plus k same-cell "pairs" -> (3k - 2)^3 ordered-with-self.
    const std::size_t m = 3 * k - 2, cells = static_cast<std::size_t>(k) * k * k;
    const std::size_t expectedCount = (m * m * m - cells) / 2;
    const std::vector<BodyPair> out = sorted(findOnce(b, pool));
    EXPECT_EQ(out.size(), expectedCount);
    EXPECT_EQ(out, bruteForcePairs(b));
}

TEST(SweepAndPrune, DuplicateBoxesPairUpOnce) {
    TaskPool pool(2);
    Bounds b = makeScenario(Scenario::Uniform, 1000, 2);
    for (std::uint32_t i = 0; i < 200; ++i) {  // 200 identical boxes mixed in at every 5th place
        const std::uint32_t d = i * 5;
        b.minX[d] = 1.0f, b.maxX[d] = 2.0f, b.minY[d] = -3.0f, b.maxY[d] = -2.0f, b.minZ[d] = 0.5f, b.maxZ[d] = 0.75f;
    }
    const std::vector<BodyPair> out = sorted(findOnce(b, pool));
    EXPECT_EQ(out, bruteForcePairs(b));
    EXPECT_EQ(std::adjacent_find(out.begin(), out.end()), out.end());
    EXPECT_GE(out.size(), 200u * 199u / 2u);
}

TEST(SweepAndPrune, SameOutputOnOneAndTwoThreadsAcrossSteps) {
    TaskPool one(1), two(2);
    for (Scenario s : {Scenario::Uniform, Scenario::Clustered, Scenario::MixedSizes}) {
        Bounds b = makeScenario(s, 20'000, 31);
        const std::vector<std::uint32_t> slots = identitySlots(b.size());
        SweepAndPrune sap1, sap2;
        for (int step = 0; step < 3; ++step) {
            std::vector<BodyPair> out1, out2;
            sap1.findPairs(b, slots.data(), b.size(), {}, one, out1);
            sap2.findPairs(b, slots.data(), b.size(), {}, two, out2);
            ASSERT_EQ(out1, out2);
            jiggle(b, 0.1f, step);
        }
    }
}

TEST(SweepAndPrune, EmptyAndSingleBody) {
    TaskPool pool(2);
    SweepAndPrune sap;
    std::vector<BodyPair> out{{1, 2}};
    Bounds empty;
    sap.findPairs(empty, nullptr, 0, {}, pool, out);
    EXPECT_TRUE(out.empty());
    Bounds one;
    one.resize(1);
    one.maxX[0] = one.maxY[0] = one.maxZ[0] = 1.0f;
    const std::uint32_t slot = 7;
    sap.findPairs(one, &slot, 8, {}, pool, out);
    EXPECT_TRUE(out.empty());
    sap.findPairs(one, &slot, 8, {}, pool, out);
    EXPECT_TRUE(out.empty());
    EXPECT_TRUE(sap.lastUsedInsertionSort());
    sap.findPairs(empty, nullptr, 0, {}, pool, out);  // everything removed, then a body again
    EXPECT_TRUE(out.empty());
    sap.findPairs(one, &slot, 8, {}, pool, out);
    EXPECT_TRUE(out.empty());
}

}  // namespace
