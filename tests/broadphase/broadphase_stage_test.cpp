// The broad-phase stage end to end: bounds of real shapes, SAP / grid / auto for moving pairs, the static BVH for
// static bodies and mesh triangles, filters, and bodies added and removed between steps (moving and static),
// all against brute force over the same boxes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>
#include <tuple>

#include "bounds/bounds.h"
#include "broadphase/broadphase_stage.h"
#include "broadphase/multi_resolution_grid.h"
#include "broadphase/sweep_and_prune.h"
#include "core/parallel.h"
#include "rubble/limits.h"
#include "rubble/world.h"
#include "storage/body_storage.h"
#include "support/broadphase_scenarios.h"

using namespace rubble;
using namespace rubble::detail;

namespace {

struct TestWorld {
    BodyStorage storage;
    std::vector<Shape> shapes;
    ShapeBoundsTable table;
    std::vector<BodyId> moving, statics;
    std::mt19937 rng{17};
    TaskPool editPool{1};  ///< for the static BVH's batch builds as bodies are added

    std::uint32_t addShape(const ShapeDef& def) {
        shapes.push_back(buildShape(def));
        const auto index = static_cast<std::uint32_t>(shapes.size() - 1);
        if (!shapes.back().staticOnly()) table.set(index, shapeBoundsInfo(shapes.back()));
        return index;
    }

    void addMoving(std::uint32_t shape, Vec3 p, Vec3 v, std::uint32_t category = 1, std::uint32_t mask = ~0u) {
        std::uint32_t i;
        moving.push_back(storage.allocate(BodySet::Moving, i));
        MovingBodies& m = storage.moving;
        m.px[i] = p.x, m.py[i] = p.y, m.pz[i] = p.z;
        std::normal_distribution<float> g;
        Quat q{g(rng), g(rng), g(rng), g(rng)};
        const float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
        m.qx[i] = q.x / n, m.qy[i] = q.y / n, m.qz[i] = q.z / n, m.qw[i] = q.w / n;
        m.vx[i] = v.x, m.vy[i] = v.y, m.vz[i] = v.z;
        m.shape[i] = shape;
        m.filterCategory[i] = category;
        m.filterMask[i] = mask;
    }

    BodyId addStatic(std::uint32_t shape, Vec3 p, Quat q, BroadPhaseStage& stage, std::uint32_t category = 1) {
        std::uint32_t i;
        const BodyId id = storage.allocate(BodySet::Static, i);
        StaticBodies& s = storage.statics;
        s.px[i] = p.x, s.py[i] = p.y, s.pz[i] = p.z;
        s.qx[i] = q.x, s.qy[i] = q.y, s.qz[i] = q.z, s.qw[i] = q.w;
        s.shape[i] = shape;
        s.filterCategory[i] = category;
        s.filterMask[i] = ~0u;
        statics.push_back(id);
        stage.staticAdded(id.index, storage, shapes, editPool);
        return id;
    }
};

bool overlapsBox(const Bounds& b, std::uint32_t i, const Aabb& box) {
    return b.minX[i] <= box.max.x && box.min.x <= b.maxX[i] && b.minY[i] <= box.max.y && box.min.y <= b.maxY[i] &&
           b.minZ[i] <= box.max.z && box.min.z <= b.maxZ[i];
}

Aabb triangleBox(Vec3 a, Vec3 b, Vec3 c) {
    return {{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
            {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})}};
}

/// Every moving-static pair and every (moving, mesh, triangle) by brute force, in the stage's order
/// (moving index, static slot, triangle), static bodies given by dense index as the stage reports them.
void bruteForceStatics(const TestWorld& w, const Bounds& bounds, std::vector<BodyPair>& pairs,
                       std::vector<std::array<std::uint32_t, 3>>& triangles) {
    const StaticBodies& s = w.storage.statics;
    std::vector<std::uint32_t> bySlot;  // static dense indices ordered by slot
    for (std::uint32_t i = 0; i < s.size(); ++i) bySlot.push_back(i);
    std::sort(bySlot.begin(), bySlot.end(), [&](std::uint32_t a, std::uint32_t b) { return s.slot[a] < s.slot[b]; });
    const MovingBodies& m = w.storage.moving;
    for (std::uint32_t i = 0; i < bounds.size(); ++i) {
        for (std::uint32_t j : bySlot) {
            if ((m.filterCategory[i] & s.filterMask[j]) == 0 || (s.filterCategory[j] & m.filterMask[i]) == 0) continue;
            const Shape& shape = w.shapes[s.shape[j]];
            const Transform pose{{s.px[j], s.py[j], s.pz[j]}, {s.qx[j], s.qy[j], s.qz[j], s.qw[j]}};
            if (shape.kind != ShapeKind::TriangleMesh) {
                if (overlapsBox(bounds, i, worldBounds(shape, pose))) pairs.push_back({i, j});
                continue;
            }
            const TriangleMesh& mesh = *shape.mesh;
            for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
                const Aabb box = triangleBox(apply(pose, mesh.vertices[mesh.indices[3 * t]]),
                                             apply(pose, mesh.vertices[mesh.indices[3 * t + 1]]),
                                             apply(pose, mesh.vertices[mesh.indices[3 * t + 2]]));
                if (overlapsBox(bounds, i, box)) triangles.push_back({i, j, t});
            }
        }
    }
}

TriangleMeshDef wavyTerrain(int cells, float size) {
    TriangleMeshDef mesh;
    for (int r = 0; r <= cells; ++r)
        for (int c = 0; c <= cells; ++c) {
            const float x = -size / 2 + size * c / cells, z = -size / 2 + size * r / cells;
            mesh.vertices.push_back({x, 2 * std::sin(x / 8) * std::cos(z / 8), z});
        }
    for (int r = 0; r < cells; ++r)
        for (int c = 0; c < cells; ++c) {
            const std::uint32_t a = r * (cells + 1) + c, b = a + 1, d = a + cells + 1, e = d + 1;
            mesh.indices.insert(mesh.indices.end(), {a, d, e, a, e, b});
        }
    return mesh;
}

void checkStep(TestWorld& w, BroadPhaseStage& stage, BroadPhaseKind kind, TaskPool& pool, const char* what) {
    Bounds bounds;
    updateBounds(w.storage.moving, w.table, BoundsParams{1.0f / 60, 0.02f}, pool, bounds);
    CandidatePairs pairs;
    stage.findPairs(bounds, w.storage, kind, {}, pool, pairs);

    PairFilter filter;
    filter.category = w.storage.moving.filterCategory.data();
    filter.mask = w.storage.moving.filterMask.data();
    EXPECT_EQ(pairs.moving, test::bruteForcePairs(bounds, filter)) << what;

    std::vector<BodyPair> staticPairs;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    bruteForceStatics(w, bounds, staticPairs, triangles);
    EXPECT_EQ(pairs.statics, staticPairs) << what;
    std::vector<std::array<std::uint32_t, 3>> found;
    for (const MeshPair& p : pairs.meshes)
        for (std::uint32_t k = 0; k < p.triangleCount; ++k)
            found.push_back({p.moving, p.staticBody, pairs.meshTriangles[p.firstTriangle + k]});
    EXPECT_EQ(found, triangles) << what;
    EXPECT_FALSE(pairs.moving.empty()) << what << ": the scene must produce pairs to prove anything";
    EXPECT_FALSE(triangles.empty()) << what;
}

}  // namespace

TEST(BroadPhaseStage, MatchesBruteForceWithChurnForEveryAlgorithm) {
    for (BroadPhaseKind kind : {BroadPhaseKind::SweepAndPrune, BroadPhaseKind::Grid, BroadPhaseKind::Auto}) {
        for (int threads : {1, 2}) {
            TaskPool pool(threads);
            TestWorld w;
            BroadPhaseStage stage;
            const std::uint32_t ball = w.addShape(SphereDef{0.5f}), box = w.addShape(BoxDef{{0.4f, 0.2f, 0.9f}}),
                                pill = w.addShape(CapsuleDef{0.3f, 0.5f}), big = w.addShape(BoxDef{{6, 1, 6}}),
                                terrain = w.addShape(wavyTerrain(30, 60));
            std::uniform_real_distribution<float> xz(-30, 30), y(-3, 8), v(-5, 5);
            const std::uint32_t kinds[] = {ball, box, pill};
            for (int i = 0; i < 1500; ++i)
                w.addMoving(kinds[i % 3], {xz(w.rng), y(w.rng), xz(w.rng)}, {v(w.rng), v(w.rng), v(w.rng)},
                            i % 7 == 0 ? 2u : 1u, i % 11 == 0 ? ~2u : ~0u);
            w.addStatic(terrain, {0, -1, 0}, {}, stage);
            w.addStatic(big, {10, 2, -5}, Quat::fromAxisAngle({0, 1, 0}, 0.4f), stage);
            w.addStatic(big, {-12, 3, 8}, {}, stage, 4);  // category 4: only bodies whose mask has bit 2 see it

            for (int step = 0; step < 6; ++step) {
                checkStep(w, stage, kind, pool, broadPhaseName(kind).data());
                // Churn between steps: move everything a little, remove some moving bodies (swap-remove reuses
                // their rows and later their slots), add new ones, and add, move and remove static bodies.
                MovingBodies& m = w.storage.moving;
                for (std::uint32_t i = 0; i < m.size(); ++i) m.px[i] += m.vx[i] / 60, m.py[i] += m.vy[i] / 60;
                for (int k = 0; k < 40; ++k) {
                    const std::size_t victim = w.rng() % w.moving.size();
                    w.storage.release(w.moving[victim]);
                    w.moving[victim] = w.moving.back();
                    w.moving.pop_back();
                }
                for (int k = 0; k < 50; ++k) w.addMoving(kinds[k % 3], {xz(w.rng), y(w.rng), xz(w.rng)}, {});
                if (step == 1) w.addStatic(big, {0, 5, 0}, {}, stage);
                if (step == 3) {
                    const BodyId gone = w.statics[1];
                    stage.staticRemoved(gone.index);
                    w.storage.release(gone);
                    w.statics.erase(w.statics.begin() + 1);
                }
                if (step == 4) {  // a moved static body: removed and added again
                    const BodyId moved = w.statics.back();
                    const std::uint32_t i = w.storage.find(moved)->dense;
                    w.storage.statics.px[i] += 3;
                    stage.staticRemoved(moved.index);
                    stage.staticAdded(moved.index, w.storage, w.shapes, w.editPool);
                }
            }
        }
    }
}

TEST(BroadPhaseTimer, TriesTheOtherAlgorithmNowAndThenAndKeepsTheFasterOne) {
    // Synthetic timings: the estimate's grid takes 1 ms a step, SAP 0.7 ms (0.5 ms more on its first two steps,
    // which rebuild its order). The trial comes after kTrialPeriod steps, runs SAP for kTrialSteps, and SAP stays.
    using Timer = BroadPhaseTimer;
    Timer timer;
    const auto cost = [](BroadPhaseKind k, std::uint32_t stepInRun, double sap) {
        return k == BroadPhaseKind::Grid ? 1.0 : sap + (stepInRun < Timer::kTrialWarmup ? 0.5 : 0.0);
    };
    auto run = [&](std::uint32_t steps, double sap, std::optional<BroadPhaseKind> estimate = std::nullopt) {
        std::vector<BroadPhaseKind> ran;
        std::uint32_t inRun = 0;
        for (std::uint32_t k = 0; k < steps; ++k) {
            const BroadPhaseKind kind = timer.next(k == 0 ? estimate : std::nullopt);
            inRun = !ran.empty() && ran.back() == kind ? inRun + 1 : 0;
            ran.push_back(kind);
            timer.record(cost(kind, inRun, sap));
        }
        return ran;
    };
    std::vector<BroadPhaseKind> ran = run(Timer::kTrialPeriod, 0.7, BroadPhaseKind::Grid);
    EXPECT_TRUE(std::all_of(ran.begin(), ran.end(), [](BroadPhaseKind k) { return k == BroadPhaseKind::Grid; }));
    ran = run(Timer::kTrialSteps, 0.7);
    EXPECT_TRUE(std::all_of(ran.begin(), ran.end(), [](BroadPhaseKind k) {
        return k == BroadPhaseKind::SweepAndPrune;
    })) << "the trial runs the other algorithm";
    EXPECT_EQ(timer.inUse(), BroadPhaseKind::SweepAndPrune) << "0.7 ms beats 1 ms by more than a tenth";

    // Now SAP slows to 1.3 ms (the scene changed): the grid's trial, a period later, wins it back.
    run(Timer::kTrialPeriod, 1.3);
    EXPECT_EQ(timer.inUse(), BroadPhaseKind::SweepAndPrune);
    run(Timer::kTrialSteps, 1.3);
    EXPECT_EQ(timer.inUse(), BroadPhaseKind::Grid);
    // Within a tenth of each other (SAP at 0.95 ms): no switch back, trial after trial.
    for (int period = 0; period < 3; ++period) run(Timer::kTrialPeriod + Timer::kTrialSteps, 0.95);
    EXPECT_EQ(timer.inUse(), BroadPhaseKind::Grid);
    // A new estimate (the body count moved) is followed at once.
    EXPECT_EQ(timer.next(BroadPhaseKind::SweepAndPrune), BroadPhaseKind::SweepAndPrune);
    EXPECT_EQ(timer.inUse(), BroadPhaseKind::SweepAndPrune);
}

TEST(BroadPhaseTimer, NoTrialAfterADecisiveEstimate) {
    // The grid is in use and SAP would be faster, but the estimate was decisive: three periods, never a SAP step.
    BroadPhaseTimer timer;
    for (std::uint32_t k = 0; k < 3 * (BroadPhaseTimer::kTrialPeriod + BroadPhaseTimer::kTrialSteps); ++k) {
        const BroadPhaseKind kind =
            timer.next(k == 0 ? std::optional(BroadPhaseKind::Grid) : std::nullopt, /*mayTry=*/false);
        ASSERT_EQ(kind, BroadPhaseKind::Grid) << "step " << k;
        timer.record(1.0);
    }
}

// A world that starts as a long row (SAP, decisively) and piles up without its count changing: the estimate renewed
// each trial period finds the pile and moves auto to the grid, though no trial runs after a decisive estimate.
TEST(BroadPhaseStage, AutoFollowsAWorldThatPilesUpAfterADecisiveEstimate) {
    TestWorld w;
    const std::uint32_t box = w.addShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    constexpr std::uint32_t kCount = 2000;
    for (std::uint32_t i = 0; i < kCount; ++i) w.addMoving(box, {2.0f * i, 0, 0}, {});
    TaskPool pool(1);
    BroadPhaseStage stage;
    CandidatePairs pairs;
    Bounds bounds;
    bounds.resize(kCount);
    const auto place = [&](float spacing) {
        for (std::uint32_t i = 0; i < kCount; ++i) {
            // A row along x, or a pile: a 4 m cube holding every box (about 500 boxes a sweep).
            const float x = spacing > 0 ? spacing * i : 0.25f * (i % 16);
            const float y = spacing > 0 ? 0.0f : 0.25f * ((i / 16) % 16), z = spacing > 0 ? 0.0f : 0.5f * (i / 256);
            bounds.minX[i] = x - 0.5f, bounds.minY[i] = y - 0.5f, bounds.minZ[i] = z - 0.5f;
            bounds.maxX[i] = x + 0.5f, bounds.maxY[i] = y + 0.5f, bounds.maxZ[i] = z + 0.5f;
        }
    };
    place(2.0f);
    ASSERT_TRUE(chooseBroadPhase(bounds, BroadPhaseKind::Auto, pool).decisive);
    for (int step = 0; step < 10; ++step) stage.findPairs(bounds, w.storage, BroadPhaseKind::Auto, {}, pool, pairs);
    EXPECT_EQ(stage.lastKind(), BroadPhaseKind::SweepAndPrune);
    place(0.0f);
    const BroadPhaseChoice pile = chooseBroadPhase(bounds, BroadPhaseKind::SweepAndPrune, pool);
    ASSERT_TRUE(pile.decisive && pile.kind == BroadPhaseKind::Grid) << pile.sweepCandidatesPerBody;
    for (std::uint32_t step = 0; step <= BroadPhaseTimer::kTrialPeriod; ++step)
        stage.findPairs(bounds, w.storage, BroadPhaseKind::Auto, {}, pool, pairs);
    EXPECT_EQ(stage.lastKind(), BroadPhaseKind::Grid);
}

TEST(BroadPhaseStage, AutoPicksTheGridForDenseSweepsAndSapForSparseOnes) {
    // S4-like: 100k boxes in a 200 m cube meet ~600 others per sweep: the grid.
    TaskPool one(1), two(2);
    const Bounds dense = test::makeScenario(test::Scenario::Uniform, 100000);
    EXPECT_EQ(chooseBroadPhase(dense, BroadPhaseKind::Auto, one).kind, BroadPhaseKind::Grid);
    EXPECT_EQ(chooseBroadPhase(dense, BroadPhaseKind::Auto, one).sweepCandidatesPerBody,
              chooseBroadPhase(dense, BroadPhaseKind::Auto, two).sweepCandidatesPerBody);
    EXPECT_TRUE(chooseBroadPhase(dense, BroadPhaseKind::Auto, one).decisive) << "no SAP trial for S4";
    // A long thin row of boxes meets about one other per sweep along its length: SAP.
    Bounds row;
    row.resize(1000);
    for (std::uint32_t i = 0; i < 1000; ++i) {
        row.minX[i] = 2.0f * i, row.maxX[i] = 2.0f * i + 1;
        row.minY[i] = row.minZ[i] = 0, row.maxY[i] = row.maxZ[i] = 1;
    }
    const BroadPhaseChoice choice = chooseBroadPhase(row, BroadPhaseKind::Auto, one);
    EXPECT_EQ(choice.kind, BroadPhaseKind::SweepAndPrune);
    // Centres spread uniformly over 2000 m: n * width / spread = 1000 * 1 / 2000.
    EXPECT_NEAR(choice.sweepCandidatesPerBody, 0.5f, 0.01f);
    EXPECT_TRUE(choice.decisive);
    // S1's pyramid (about 190 a sweep), where SAP beats the grid though the estimate says grid: measured, not decided.
    Bounds pyramid;
    pyramid.resize(2870);
    std::uint32_t at = 0;
    for (int layer = 0; layer < 20; ++layer)
        for (int i = 0; i < 20 - layer; ++i)
            for (int j = 0; j < 20 - layer; ++j, ++at) {
                const float x = i + 0.5f * layer, y = static_cast<float>(layer), z = j + 0.5f * layer;
                pyramid.minX[at] = x - 0.5f, pyramid.minY[at] = y - 0.5f, pyramid.minZ[at] = z - 0.5f;
                pyramid.maxX[at] = x + 0.5f, pyramid.maxY[at] = y + 0.5f, pyramid.maxZ[at] = z + 0.5f;
            }
    EXPECT_FALSE(chooseBroadPhase(pyramid, BroadPhaseKind::Auto, one).decisive)
        << chooseBroadPhase(pyramid, BroadPhaseKind::Auto, one).sweepCandidatesPerBody;
}

// The pair budget (docs/limits.md): 2,000 balls created at one point make 2 million candidate pairs; the step keeps a
// bounded number, counts the rest as dropped, completes, and keeps the same pairs on one and two threads. A dense
// but sane pile (8,000 boxes touching in a grid, 26 neighbours each) drops nothing under either algorithm.
TEST(PairBudget, BodiesPiledOnOnePointDegradeWithinTheBudgetAndSanePilesDropNothing) {
    const auto pileOnAPoint = [](int threads, BroadPhaseKind kind) {
        World world(WorldSettings{.threads = threads, .broadPhase = kind});
        const ShapeId ball = world.createShape(SphereDef{0.5f});
        BodyDef def;
        def.shape = ball;
        for (int i = 0; i < 2000; ++i) world.createBody(def);
        world.step(1.0f / 60);
        return std::tuple{world.lastProfile().movingPairs, world.lastProfile().droppedPairs, world.stateHash()};
    };
    for (const BroadPhaseKind kind : {BroadPhaseKind::SweepAndPrune, BroadPhaseKind::Grid}) {
        const auto [kept, dropped, hash] = pileOnAPoint(1, kind);
        EXPECT_EQ(std::uint64_t{kept} + dropped, 2000ull * 1999 / 2) << "every pair is kept or counted";
        EXPECT_GT(dropped, 0u);
        // At most kPairsPerBody a body per chunk, at least kMinChunkPairs a chunk: the chunks of 2,000 boxes are
        // at most 8 (SAP, 256 boxes each) and the grid's one cell is one chunk.
        EXPECT_LE(kept, 8 * limits::kMinChunkPairs);
        const auto [kept2, dropped2, hash2] = pileOnAPoint(2, kind);
        EXPECT_EQ(kept2, kept);
        EXPECT_EQ(dropped2, dropped);
        EXPECT_EQ(hash2, hash) << "the pairs kept do not depend on the threads";
    }

    for (const BroadPhaseKind kind : {BroadPhaseKind::SweepAndPrune, BroadPhaseKind::Grid}) {
        World world(WorldSettings{.threads = 2, .broadPhase = kind});
        const ShapeId box = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
        BodyDef def;
        def.shape = box;
        for (int i = 0; i < 8000; ++i) {
            def.position = {static_cast<float>(i % 20), static_cast<float>(i / 20 % 20), static_cast<float>(i / 400)};
            world.createBody(def);
        }
        world.step(1.0f / 60);
        EXPECT_EQ(world.lastProfile().droppedPairs, 0u) << broadPhaseName(kind);
        // 3 x 19 x 20^2 along the axes, 6 x 19^2 x 20 along face diagonals, 4 x 19^3 along body diagonals.
        EXPECT_EQ(world.lastProfile().movingPairs, 93556u) << broadPhaseName(kind);
    }
}

// The pair budget in time (issue 38): a pile at one point must not cost n^2 / 2 tests. Once a chunk's cap is full,
// each body's search stops after kSearchOverlapsPerBody overlaps and counts what it leaves untested, so every pair
// of the pile is still kept or counted, the same on one and two threads; and the chunk searches again with its cap
// shared among its bodies, so that the kept pairs spread over the pile (each body in at least kPairsPerBody of them,
// none in a tenth of the pile) rather than tying the first bodies to all the others. Small and 20x larger boxes share
// the point, so the grid's search of coarser levels carries what each body met and kept in its own level. And a sane
// scene in which one body overlaps far more boxes than kSearchOverlapsPerBody (a platform under 1,936 crates, which
// SAP's sweep finds from the platform's side) keeps every pair: the search is exact until the budget is spent.
TEST(PairBudget, APileAtOnePointCostsLinearTimeAndAPlatformKeepsEveryCrate) {
    const auto bothAlgorithms = [](const Bounds& boxes, int threads) {
        const std::uint32_t n = boxes.size();
        std::vector<std::uint32_t> slots(n);
        std::iota(slots.begin(), slots.end(), 0u);
        TaskPool pool(threads);
        SweepAndPrune sap;
        MultiResolutionGrid grid;
        std::vector<BodyPair> fromSap, fromGrid;
        sap.findPairs(boxes, slots.data(), n, {}, pool, fromSap);
        grid.findPairs(boxes, {}, pool, fromGrid);
        std::sort(fromSap.begin(), fromSap.end());
        std::sort(fromGrid.begin(), fromGrid.end());
        return std::tuple{fromSap, sap.droppedPairs(), fromGrid, grid.droppedPairs()};
    };

    constexpr std::uint32_t n = 6000;
    const Bounds pile = test::pileAtOnePoint(n / 2, n / 2);
    const auto one = bothAlgorithms(pile, 1);
    const auto& [sapPairs, sapDropped, gridPairs, gridDropped] = one;
    for (const auto& [name, pairs, dropped] :
         {std::tuple{"sap", &sapPairs, sapDropped}, std::tuple{"grid", &gridPairs, gridDropped}}) {
        EXPECT_EQ(pairs->size() + dropped, std::uint64_t{n} * (n - 1) / 2) << name << ": every pair kept or counted";
        std::vector<std::uint32_t> pairsOf(n, 0);
        for (const BodyPair& p : *pairs) ++pairsOf[p.a], ++pairsOf[p.b];
        const auto [fewest, most] = std::minmax_element(pairsOf.begin(), pairsOf.end());
        EXPECT_GE(*fewest, limits::kPairsPerBody) << name;
        EXPECT_LE(*most, n / 10) << name << ": no body holds a large part of the pile";
    }
    EXPECT_EQ(bothAlgorithms(pile, 2), one) << "what is kept and counted does not depend on the threads";

    Bounds platform;
    const auto push = [&](float x, float y, float z, float hx, float hy, float hz) {
        platform.minX.push_back(x - hx), platform.minY.push_back(y - hy), platform.minZ.push_back(z - hz);
        platform.maxX.push_back(x + hx), platform.maxY.push_back(y + hy), platform.maxZ.push_back(z + hz);
    };
    push(0, 0, 0, 10, 0.5f, 10);
    for (int i = 0; i < 44; ++i)
        for (int j = 0; j < 44; ++j) push(-9.7f + 0.45f * i, 0.69f, -9.7f + 0.45f * j, 0.2f, 0.2f, 0.2f);
    std::vector<BodyPair> expected;
    for (std::uint32_t j = 1; j < platform.size(); ++j) expected.push_back({0, j});
    const auto [onSap, droppedSap, onGrid, droppedGrid] = bothAlgorithms(platform, 2);
    EXPECT_EQ(onSap, expected);
    EXPECT_EQ(onGrid, expected);
    EXPECT_EQ(droppedSap + droppedGrid, 0u);
}

// The static budget (docs/limits.md): 70,000 static balls created at one point hand a ball dropped into them 70,000
// static candidates; it keeps kMinChunkStaticHits of them (one moving body is one chunk), counts the rest as dropped
// and completes, the same on one and two threads. A large box on a fine heightfield, which holds some 20,000
// triangles in its query box, is what the per-chunk floor is for: nothing is dropped.
TEST(PairBudget, StaticBodiesPiledOnOnePointDegradeWithinTheStaticBudget) {
    const auto dropInto = [](int threads) {
        World world(WorldSettings{.threads = threads});
        const ShapeId sphere = world.createShape(SphereDef{0.5f});
        BodyDef pile;
        pile.type = BodyType::Static;
        pile.shape = sphere;
        for (int i = 0; i < 70000; ++i) world.createBody(pile);
        BodyDef falling;
        falling.shape = sphere;
        falling.position = {0, 0.8f, 0};
        const BodyId ball = world.createBody(falling);
        std::vector<std::uint64_t> dropped;
        for (int step = 0; step < 3; ++step) {
            // Held in the pile, which pushes it out: every step sees the whole pile around it.
            world.setTransform(ball, falling.position, Quat{});
            world.setLinearVelocity(ball, {0, 0, 0});
            world.step(1.0f / 60);
            EXPECT_EQ(world.lastProfile().staticPairs, limits::kMinChunkStaticHits);
            dropped.push_back(world.lastProfile().droppedStaticHits);
        }
        return std::pair{dropped, world.stateHash()};
    };
    const auto [dropped, hash] = dropInto(1);
    EXPECT_EQ(dropped, std::vector<std::uint64_t>(3, 70000 - limits::kMinChunkStaticHits));
    const auto [dropped2, hash2] = dropInto(2);
    EXPECT_EQ(dropped2, dropped);
    EXPECT_EQ(hash2, hash) << "the candidates kept do not depend on the threads";

    World world;
    HeightfieldDef field;
    field.rows = field.columns = 201;
    field.heights.assign(201 * 201, 0.0f);
    field.spacing = {0.1f, 1, 0.1f};
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(field);
    ground.position = {-10, 0, -10};
    world.createBody(ground);
    BodyDef box;
    box.shape = world.createShape(BoxDef{{4, 0.5f, 4}});
    box.position = {0, 0.5f, 0};
    world.createBody(box);
    world.step(1.0f / 60);
    EXPECT_EQ(world.lastProfile().droppedStaticHits, 0u);
    EXPECT_GT(world.lastProfile().meshTriangles, 10000u) << "one body may hold far more than the average";
}
