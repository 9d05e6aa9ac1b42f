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
    grid.setPairBudget(PairBudget::unlimited());  // every pair of the all-overlapping scenario, against brute force
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

/// The exact pairs by a sweep along x: an answer that shares nothing with the grid, fast enough for large sets.
std::vector<BodyPair> sweptPairs(const Bounds& b) {
    std::vector<std::uint32_t> order(b.size());
    for (std::uint32_t i = 0; i < b.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) { return b.minX[x] < b.minX[y]; });
    std::vector<BodyPair> out;
    for (std::size_t k = 0; k < order.size(); ++k)
        for (std::size_t l = k + 1; l < order.size() && b.minX[order[l]] <= b.maxX[order[k]]; ++l)
            if (overlaps(b, order[k], b, order[l]))
                out.push_back({std::min(order[k], order[l]), std::max(order[k], order[l])});
    std::sort(out.begin(), out.end());
    return out;
}

TEST(MultiResolutionGrid, IncrementalSortFindsWhatAFullSortFinds) {
    // A large sparse cloud stepped as a world steps it: most steps the rows are the same bodies (only the boxes that
    // changed cell are re-sorted and merged), once they are put in the grid's cell order, once a body is removed
    // (the rows no longer match: sort from scratch), once a box outgrows the layout and once one flies off its span
    // (the layout is built again). Every step must give the pairs of a grid that sorts everything from scratch.
    TaskPool pool(2);
    MultiResolutionGrid grid, fresh;
    constexpr std::uint32_t kBoxes = 70000;  // above the grid's incremental threshold
    std::mt19937 rng(21);
    const float half = 0.5f * std::cbrt(80.0f * kBoxes);  // S4's density of unit spheres
    std::uniform_real_distribution<float> at(-half, half), speed(-0.15f, 0.15f);
    Bounds b;
    std::vector<float> vx, vy, vz;
    for (std::uint32_t i = 0; i < kBoxes; ++i) {
        pushCube(b, at(rng), at(rng), at(rng), 0.55f);
        vx.push_back(speed(rng)), vy.push_back(speed(rng)), vz.push_back(speed(rng));
    }
    std::uint32_t incrementalSteps = 0;
    for (int step = 0; step < 14; ++step) {
        RowContinuity continuity = step == 0 ? RowContinuity::None : RowContinuity::SameRows;
        if (step == 3) {
            // The first two chunks of last step's slots all change cell (moved by more than a cell in x): chunks of
            // the merge with no box that stayed.
            const AlignedVector<std::uint32_t>& order = grid.boxesInCellOrder();
            for (std::uint32_t k = 0; k < 8192; ++k) b.minX[order[k]] += 1.3f, b.maxX[order[k]] += 1.3f;
        }
        if (step == 5) {
            // Rows into the last call's cell order, velocities with them.
            const AlignedVector<std::uint32_t> order = grid.boxesInCellOrder();
            Bounds sorted;
            sorted.resize(b.size());
            std::vector<float> ux(b.size()), uy(b.size()), uz(b.size());
            for (std::uint32_t k = 0; k < b.size(); ++k) {
                const std::uint32_t i = order[k];
                sorted.minX[k] = b.minX[i], sorted.minY[k] = b.minY[i], sorted.minZ[k] = b.minZ[i];
                sorted.maxX[k] = b.maxX[i], sorted.maxY[k] = b.maxY[i], sorted.maxZ[k] = b.maxZ[i];
                ux[k] = vx[i], uy[k] = vy[i], uz[k] = vz[i];
            }
            b = sorted, vx = ux, vy = uy, vz = uz;
            continuity = RowContinuity::InCellOrder;
        }
        if (step == 8) {
            // Swap-remove, as the world's storage does: the rows no longer name last step's bodies.
            const std::uint32_t last = b.size() - 1;
            for (auto* a : {&b.minX, &b.minY, &b.minZ, &b.maxX, &b.maxY, &b.maxZ}) (*a)[17] = (*a)[last];
            b.resize(last);
            vx[17] = vx[last], vy[17] = vy[last], vz[17] = vz[last];
            vx.pop_back(), vy.pop_back(), vz.pop_back();
            continuity = RowContinuity::None;
        }
        if (step == 10) b.maxX[3] += 0.2f;                                   // outgrows the top level: a new layout
        if (step == 12) b.minY[5] -= 3.0f * half, b.maxY[5] -= 3.0f * half;  // leaves the span: a new layout
        std::vector<BodyPair> got, want;
        grid.findPairs(b, {}, pool, got, continuity);
        fresh.findPairs(b, {}, pool, want);
        std::sort(got.begin(), got.end());
        std::sort(want.begin(), want.end());
        ASSERT_EQ(got, want) << "step " << step;
        if (grid.lastSortWasIncremental()) {
            ++incrementalSteps;
            EXPECT_LT(grid.changedCells(), (step == 3 ? 8192 : 0) + b.size() / 4) << "step " << step;
            EXPECT_TRUE(step != 3 || grid.changedCells() >= 8192u) << "the shifted boxes changed cell";
        }
        EXPECT_EQ(grid.lastSortWasIncremental(), step != 0 && step != 8 && step != 10 && step != 12) << "step " << step;
        if (step == 13) {
            EXPECT_EQ(got, sweptPairs(b));
        }
        for (std::uint32_t i = 0; i < b.size(); ++i) {
            b.minX[i] += vx[i], b.maxX[i] += vx[i];
            b.minY[i] += vy[i], b.maxY[i] += vy[i];
            b.minZ[i] += vz[i], b.maxZ[i] += vz[i];
        }
    }
    EXPECT_EQ(incrementalSteps, 10u);
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
