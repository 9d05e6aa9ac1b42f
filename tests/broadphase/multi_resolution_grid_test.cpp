// Multi-resolution grid: exact against the brute-force answer (same pairs, none twice) on every shared scenario and
// on the cases a grid gets wrong first (cell edges, touching boxes, far and negative coordinates, huge size ranges,
// level ratios, moving and changing sets), and independent of the thread count.
#include "broadphase/multi_resolution_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/parallel.h"
#include "support/broadphase_scenarios.h"

namespace rubble::detail {
namespace {

using test::bruteForcePairs;
using test::makeScenario;
using test::Scenario;

std::vector<BodyPair> sortedPairs(MultiResolutionGrid& grid, const Bounds& b, TaskPool& pool,
                                  const PairFilter& filter = {}) {
    std::vector<BodyPair> out;
    grid.findPairs(b, filter, pool, out);
    for (const BodyPair& p : out) EXPECT_LT(p.a, p.b);
    std::sort(out.begin(), out.end());
    return out;
}

void pushBox(Bounds& b, float x0, float y0, float z0, float x1, float y1, float z1) {
    const std::size_t i = b.size();
    b.resize(i + 1);
    b.minX[i] = x0, b.minY[i] = y0, b.minZ[i] = z0;
    b.maxX[i] = x1, b.maxY[i] = y1, b.maxZ[i] = z1;
}

void pushCube(Bounds& b, float cx, float cy, float cz, float half) {
    pushBox(b, cx - half, cy - half, cz - half, cx + half, cy + half, cz + half);
}

void translate(Bounds& b, float dx, float dy, float dz) {
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        b.minX[i] += dx, b.maxX[i] += dx;
        b.minY[i] += dy, b.maxY[i] += dy;
        b.minZ[i] += dz, b.maxZ[i] += dz;
    }
}

class MultiResolutionGridScenario : public ::testing::TestWithParam<Scenario> {};

TEST_P(MultiResolutionGridScenario, MatchesBruteForce) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    for (std::uint32_t n : {2000u, 5000u}) {
        const Bounds b = makeScenario(GetParam(), n, 7 + n);
        const auto expected = bruteForcePairs(b);
        EXPECT_EQ(sortedPairs(grid, b, pool), expected) << test::scenarioName(GetParam()) << " n=" << n;
    }
}

INSTANTIATE_TEST_SUITE_P(AllScenarios, MultiResolutionGridScenario,
                         ::testing::Values(Scenario::Uniform, Scenario::Clustered, Scenario::Flat, Scenario::MixedSizes,
                                           Scenario::AllOverlapping),
                         [](const ::testing::TestParamInfo<Scenario>& p) {
                             return std::string(test::scenarioName(p.param));
                         });

TEST(MultiResolutionGrid, EmptyAndSingle) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    Bounds b;
    std::vector<BodyPair> out{{1, 2}};
    grid.findPairs(b, {}, pool, out);
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(grid.levelCount(), 0);
    pushCube(b, 3, -4, 5, 0.5f);
    grid.findPairs(b, {}, pool, out);
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(grid.levelCount(), 1);
    EXPECT_EQ(grid.cellCount(), 1u);
}

TEST(MultiResolutionGrid, UniformSizesUseOneLevelMixedSizesSeveral) {
    TaskPool pool(1);
    MultiResolutionGrid grid;
    std::vector<BodyPair> out;
    grid.findPairs(makeScenario(Scenario::Uniform, 3000), {}, pool, out);
    EXPECT_EQ(grid.levelCount(), 1);
    EXPECT_LE(grid.maxBodiesPerCell(), 8u);
    grid.findPairs(makeScenario(Scenario::MixedSizes, 3000), {}, pool, out);
    EXPECT_GE(grid.levelCount(), 4);
    for (int l = 1; l < grid.levelCount(); ++l) EXPECT_GT(grid.levelCellSize(l), grid.levelCellSize(l - 1));
}

TEST(MultiResolutionGrid, MixedSizesOneToThousandWithFewGiants) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-60.0f, 60.0f), t(0.0f, 1.0f);
    Bounds b;
    for (int i = 0; i < 3000; ++i) pushCube(b, u(rng), u(rng), u(rng), 0.05f * std::pow(1000.0f, t(rng) * t(rng)));
    for (int i = 0; i < 5; ++i) pushCube(b, u(rng), u(rng), u(rng), 50.0f);  // touch thousands of small ones
    EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b));
}

TEST(MultiResolutionGrid, LevelRatiosTwoAndEight) {
    TaskPool pool(2);
    for (float ratio : {2.0f, 8.0f}) {
        MultiResolutionGrid grid(ratio);
        for (Scenario s : {Scenario::MixedSizes, Scenario::Uniform, Scenario::Clustered}) {
            const Bounds b = makeScenario(s, 3000, 11);
            EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b))
                << "ratio " << ratio << " " << test::scenarioName(s);
        }
    }
}

TEST(MultiResolutionGrid, TouchingBoxesOnCellEdgesAndNegativeCoordinates) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    // A lattice of unit boxes [i, i+1]^3 around the origin: every box touches its 26 neighbours exactly on a face,
    // edge or corner, and every box edge lies on a cell edge (the cell size equals the box size).
    Bounds b;
    for (int z = -4; z < 4; ++z)
        for (int y = -4; y < 4; ++y)
            for (int x = -4; x < 4; ++x)
                pushBox(b, float(x), float(y), float(z), float(x + 1), float(y + 1), float(z + 1));
    auto expected = bruteForcePairs(b);
    // Pairs at offset d number prod(8 - |d_a|); summed over the 26 offsets and halved: ((8 + 2 * 7)^3 - 8^3) / 2.
    EXPECT_EQ(expected.size(), 5068u);
    EXPECT_EQ(sortedPairs(grid, b, pool), expected);
    // Half-size boxes in the lattice's corners and on its faces: other levels, same exact contacts.
    for (int k = -4; k <= 4; ++k) pushBox(b, float(k), float(k), -4.5f, float(k) + 0.25f, float(k) + 0.25f, -4.0f);
    // A giant whose faces touch the lattice from outside.
    pushBox(b, 4.0f, -40.0f, -40.0f, 84.0f, 40.0f, 40.0f);
    EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b));
    // Same lattice far in the negative octant.
    translate(b, -1000.0f, -2000.0f, -3000.0f);
    EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b));
}

TEST(MultiResolutionGrid, TouchingPairsAcrossEveryNeighbourDirection) {
    TaskPool pool(1);
    MultiResolutionGrid grid;
    // Two unit boxes touching along each of the 26 directions, at offsets that put cell edges on and off the
    // contact plane: the pair must be found exactly once.
    for (float shift : {0.0f, 0.5f, 0.25f, -0.75f})
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if (dx == 0 && dy == 0 && dz == 0) continue;
                    Bounds b;
                    pushCube(b, shift, shift, shift, 0.5f);
                    pushCube(b, shift + float(dx), shift + float(dy), shift + float(dz), 0.5f);
                    pushCube(b, shift + 5.0f, shift, shift, 0.5f);  // gives the grid a span
                    const auto got = sortedPairs(grid, b, pool);
                    ASSERT_EQ(got, bruteForcePairs(b)) << dx << " " << dy << " " << dz << " shift " << shift;
                    ASSERT_EQ(got.size(), 1u);
                }
}

TEST(MultiResolutionGrid, LongRowsUseExactXWindows) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    // Rows far longer than a SIMD batch (a 300 x 3 x 3 lattice of touching unit boxes, plus jittered copies): the
    // same-level search goes row by row through x windows, which must neither lose nor repeat a pair.
    Bounds b;
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
    for (int z = 0; z < 3; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 300; ++x) {
                pushBox(b, float(x), float(y), float(z), float(x + 1), float(y + 1), float(z + 1));
                pushCube(b, float(x) + jitter(rng), float(y) + jitter(rng), float(z) + jitter(rng), 0.5f);
            }
    EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b));
}

TEST(MultiResolutionGrid, FarAwayCoordinates) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    for (float offset : {1e5f, -3e5f, 1e6f}) {
        for (Scenario s : {Scenario::Uniform, Scenario::MixedSizes}) {
            Bounds b = makeScenario(s, 3000, 5);
            translate(b, offset, -offset, 0.5f * offset);
            EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b)) << offset << " " << test::scenarioName(s);
        }
    }
}

TEST(MultiResolutionGrid, WorldWiderThanTheCellRangeStaysExact) {
    // Small boxes spread over 2000 km: more cells per axis than the key holds, so the far edge is clamped together.
    TaskPool pool(2);
    MultiResolutionGrid grid;
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1e6f, 1e6f), jitter(-0.6f, 0.6f);
    Bounds b;
    for (int i = 0; i < 800; ++i) {
        const float x = u(rng), y = u(rng), z = u(rng);
        pushCube(b, x, y, z, 0.5f);
        pushCube(b, x + jitter(rng), y + jitter(rng), z + jitter(rng), 0.5f);  // a close partner
    }
    pushCube(b, 1e6f, 1e6f, 1e6f, 0.5f);
    pushCube(b, 1e6f + 1.0f, 1e6f, 1e6f, 0.5f);  // touches exactly at the extreme corner
    pushCube(b, -1e6f, -1e6f, -1e6f, 0.5f);
    pushCube(b, -1e6f, -1e6f - 1.0f, -1e6f, 0.5f);
    const auto expected = bruteForcePairs(b);
    EXPECT_GE(expected.size(), 2u);
    EXPECT_EQ(sortedPairs(grid, b, pool), expected);
}

TEST(MultiResolutionGrid, DegenerateBoxes) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    Bounds b = makeScenario(Scenario::Uniform, 1000, 1);
    pushBox(b, 1, 1, 1, 1, 1, 1);  // points, one of them inside a unit box
    pushBox(b, 1, 1, 1, 1, 1, 1);
    pushBox(b, b.minX[0] + 0.5f, b.minY[0] + 0.5f, b.minZ[0] + 0.5f, b.minX[0] + 0.5f, b.minY[0] + 0.5f,
            b.minZ[0] + 0.5f);
    pushBox(b, 3, 3, 3, 2, 2, 2);  // inverted
    pushBox(b, 1.5f, 1.5f, 1.5f, 3.5f, 3.5f, 3.5f);
    EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b));
    Bounds points;
    for (int i = 0; i < 50; ++i) pushBox(points, float(i % 5), 0, 0, float(i % 5), 0, 0);
    EXPECT_EQ(sortedPairs(grid, points, pool), bruteForcePairs(points));
}

TEST(MultiResolutionGrid, NonFiniteBoxesNeitherCrashNorHidePairs) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    Bounds b = makeScenario(Scenario::Uniform, 1000, 2);
    constexpr float inf = std::numeric_limits<float>::infinity();
    pushBox(b, -inf, -inf, -inf, inf, inf, inf);  // overlaps everything
    pushBox(b, 0, 0, 0, std::nanf(""), 1, 1);     // overlaps nothing
    pushBox(b, 0, -inf, 0, 1, inf, 1);            // an infinite column
    EXPECT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b));
}

TEST(MultiResolutionGrid, FilterBitsAndSleeping) {
    TaskPool pool(2);
    MultiResolutionGrid grid;
    const Bounds b = makeScenario(Scenario::Clustered, 4000, 21);
    std::mt19937 rng(4);
    std::vector<std::uint32_t> category(b.size()), mask(b.size());
    std::vector<std::uint8_t> flags(b.size());
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        category[i] = 1u << (rng() % 4);
        mask[i] = rng() % 16;
        flags[i] = (rng() % 2 == 0) ? 0x4 : 0x1;
    }
    PairFilter filter;
    filter.category = category.data();
    filter.mask = mask.data();
    filter.flags = flags.data();
    filter.asleepBit = 0x4;
    const auto expected = bruteForcePairs(b, filter);
    EXPECT_LT(expected.size(), bruteForcePairs(b).size());
    EXPECT_EQ(sortedPairs(grid, b, pool, filter), expected);

    PairFilter sleepOnly;
    sleepOnly.flags = flags.data();
    sleepOnly.asleepBit = 0x4;
    const auto got = sortedPairs(grid, b, pool, sleepOnly);
    EXPECT_EQ(got, bruteForcePairs(b, sleepOnly));
    for (const BodyPair& p : got) EXPECT_FALSE(sleepOnly.asleep(p.a) && sleepOnly.asleep(p.b));
}

TEST(MultiResolutionGrid, MovingSceneWithInsertionsAndRemovals) {
    TaskPool pool(2);
    MultiResolutionGrid grid;  // one grid for every step: buffers are reused
    Bounds b = makeScenario(Scenario::MixedSizes, 3000, 8);
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> pos(-60.0f, 60.0f), half(0.05f, 3.0f);
    for (int step = 0; step < 10; ++step) {
        test::jiggle(b, 0.4f, 100 + step);
        // Swap-remove a few bodies, as the world's dense arrays do, and spawn a few.
        for (int r = 0; r < 40 && b.size() > 0; ++r) {
            const std::uint32_t i = rng() % b.size(), last = b.size() - 1;
            for (auto* a : {&b.minX, &b.minY, &b.minZ, &b.maxX, &b.maxY, &b.maxZ}) (*a)[i] = (*a)[last];
            b.resize(last);
        }
        for (int k = 0; k < 25 + 10 * step; ++k) pushCube(b, pos(rng), pos(rng), pos(rng), half(rng));
        ASSERT_EQ(sortedPairs(grid, b, pool), bruteForcePairs(b)) << "step " << step;
    }
}

TEST(MultiResolutionGrid, OutputIndependentOfThreadCount) {
    TaskPool one(1), two(2);
    MultiResolutionGrid gridOne, gridTwo;
    // Big enough for several sort chunks and many query chunks.
    for (Scenario s : {Scenario::Uniform, Scenario::Clustered, Scenario::MixedSizes}) {
        const Bounds b = makeScenario(s, 60000, 31);
        std::vector<BodyPair> a, c;
        gridOne.findPairs(b, {}, one, a);
        gridTwo.findPairs(b, {}, two, c);
        EXPECT_EQ(a, c) << test::scenarioName(s);  // the same order, not just the same set
        gridTwo.findPairs(b, {}, two, c);          // and again on warm buffers
        EXPECT_EQ(a, c) << test::scenarioName(s);
        std::sort(a.begin(), a.end());
        EXPECT_TRUE(std::adjacent_find(a.begin(), a.end()) == a.end()) << "duplicate pair";
    }
}

}  // namespace
}  // namespace rubble::detail
