// The contact solver's parallel structure: colouring keeps every dynamic body to one lane per colour, the wide
// kernels agree bit for bit with the one-lane (scalar) kernels, and the state after a step does not depend on the
// thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <random>
#include <set>

#include "core/parallel.h"
#include "islands/islands.h"
#include "rubble/build_info.h"
#include "rubble/world.h"
#include "solver/contact_batch.h"
#include "solver/contact_solver.h"
#include "solver/joint_solver.h"
#include "support/contact_batches.h"
#include "world/world_access.h"

namespace rubble {
namespace {

using detail::BodyRow;
using detail::BodyRows;

/// The linear and angular parts bit for bit (the pad of a row holds no meaning).
bool sameRow(const BodyRow& a, const BodyRow& b) { return std::memcmp(&a, &b, offsetof(BodyRow, pad)) == 0; }
using detail::ContactBatch;
using detail::kBatchLanes;

// Tests that read the batches the core prepared see them with this file's lane count; scripts/test.sh also runs the
// suite on a core level of another width (the loader's choice hidden), whose batches this file cannot lay out.
#define SKIP_UNLESS_CORE_BATCHES_THIS_WIDE()                                                               \
    if (buildInfo().floatLanes != static_cast<int>(kBatchLanes))                                           \
    GTEST_SKIP() << "the core batches " << buildInfo().floatLanes << " lanes, this test was compiled for " \
                 << kBatchLanes

/// A pyramid of `layers` layers of 1 m cubes on a ground box, as in SCENES.md S1.
void buildPyramid(World& world, int layers) {
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(BoxDef{{100, 0.5f, 100}});
    ground.position = {0, -0.5f, 0};
    world.createBody(ground);
    BodyDef cube;
    cube.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    for (int k = 0; k < layers; ++k) {
        const int n = layers - k;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                cube.position = {(i - (n - 1) / 2.0f), 0.5f + k, (j - (n - 1) / 2.0f)};
                world.createBody(cube);
            }
    }
}

std::uint64_t pyramidHash(int threads, PositionCorrection correction, bool shock = false, int layers = 8,
                          int steps = 40) {
    WorldSettings s;
    s.threads = threads;
    s.solver.positionCorrection = correction;
    s.solver.shockPropagation = shock;
    World world(s);
    buildPyramid(world, layers);
    // Knock it so that the solve is not symmetric and colours really interleave.
    world.applyLinearImpulse(world.bodies().back(), {800, 0, 300});
    for (int i = 0; i < steps; ++i) world.step(1.0f / 60.0f);
    return world.stateHash();
}

TEST(ContactSolver, StateDoesNotDependOnThreadCount) {
    for (const PositionCorrection c :
         {PositionCorrection::SoftStep, PositionCorrection::Baumgarte, PositionCorrection::SplitImpulse}) {
        const std::uint64_t one = pyramidHash(1, c);
        EXPECT_EQ(one, pyramidHash(2, c)) << positionCorrectionName(c);
        EXPECT_EQ(one, pyramidHash(3, c)) << positionCorrectionName(c);
    }
    // Twelve layers: 4,324 manifolds, so the pyramid is solved in slabs.
    EXPECT_EQ(pyramidHash(1, PositionCorrection::Baumgarte, false, 12, 10),
              pyramidHash(2, PositionCorrection::Baumgarte, false, 12, 10));
    const std::uint64_t shocked = pyramidHash(1, PositionCorrection::Baumgarte, true);
    EXPECT_EQ(shocked, pyramidHash(2, PositionCorrection::Baumgarte, true));
    EXPECT_NE(shocked, pyramidHash(1, PositionCorrection::Baumgarte)) << "the shock pass changed nothing";
}

TEST(ContactSolver, PyramidColoursFillTheLanes) {
    WorldSettings s;
    s.threads = 1;
    World world(s);
    buildPyramid(world, 8);
    world.step(1.0f / 60.0f);
    const Profile& profile = world.lastProfile();
    EXPECT_GT(profile.constraints, 500u);
    EXPECT_GE(profile.colors, 4u);  // a box touches up to 8 others plus the ground: at least that many colours
    EXPECT_LE(profile.colors, 63u);
    EXPECT_GT(profile.laneOccupancy, 0.5f);
}

// Random contact graphs, dense enough to need the overflow set: within a colour no dynamic body appears twice
// (checked by brute force over the prepared batches), every manifold with a dynamic body is in exactly one lane, and
// every one of its points (one to four) is within its batch's point count.
TEST(ContactSolver, ColoursNeverHoldADynamicBodyTwice) {
    SKIP_UNLESS_CORE_BATCHES_THIS_WIDE();
    std::mt19937 rng(7);
    for (const int bodies : {40, 400}) {
        detail::BodyStorage storage;
        for (int i = 0; i < bodies; ++i) {
            std::uint32_t dense = 0;
            storage.allocate(detail::BodySet::Moving, dense);
            storage.moving.invMass[dense] = 1.0f;
            storage.moving.qw[dense] = 1.0f;
            storage.moving.friction[dense] = 0.5f;
            // Every fifth body is kinematic: it may appear in any number of lanes of a colour.
            if (i % 5 == 4) storage.moving.flags[dense] = detail::kFlagKinematic, storage.moving.invMass[dense] = 0;
        }
        std::uint32_t ground = 0;
        storage.allocate(detail::BodySet::Static, ground);
        detail::Contacts contacts;
        std::uniform_int_distribution<int> pick(0, bodies - 1);
        const int manifolds = bodies * 40;
        for (int k = 0; k < manifolds; ++k) {
            detail::ContactPair pair;
            pair.a = static_cast<std::uint32_t>(pick(rng));
            if (k % 7 == 0) {
                pair.b = ground, pair.bStatic = true;
            } else {
                pair.b = static_cast<std::uint32_t>(pick(rng));
                if (pair.b == pair.a) continue;
            }
            detail::Manifold m;
            m.normal = {0, 1, 0};
            m.pointCount = 1 + k % detail::kMaxManifoldPoints;
            for (int i = 0; i < m.pointCount; ++i) m.points[i].depth = 0.01f;
            contacts.pairs.push_back(pair);
            contacts.manifolds.push_back(m);
        }
        const std::vector<detail::PointImpulse> warm(contacts.manifolds.size() * detail::kMaxManifoldPoints);
        detail::TaskPool pool(2);
        detail::ContactSolver solver;
        solver.prepare(contacts, warm, storage, WorldSettings{}, EffectSet::defaults(), 1.0f / 60.0f, pool);
        const auto& ranges = solver.colorRanges();
        std::size_t lanes = 0, points = 0;
        for (std::size_t c = 0; c < ranges.size(); ++c) {
            const bool overflow = solver.hasOverflow() && c + 1 == ranges.size();
            std::set<std::int32_t> seen;
            for (std::uint32_t bi = ranges[c].firstBatch; bi < ranges[c].firstBatch + ranges[c].batchCount; ++bi) {
                const ContactBatch& b = solver.batches()[bi];
                for (std::size_t lane = 0; lane < kBatchLanes; ++lane) {
                    const float invMassA = solver.bodies().mass[static_cast<std::size_t>(b.bodyA[lane])].inverseMass;
                    const float invMassB = solver.bodies().mass[static_cast<std::size_t>(b.bodyB[lane])].inverseMass;
                    if (invMassA == 0 && invMassB == 0) continue;
                    ++lanes;
                    for (int i = 0; i < b.pointCount; ++i) points += b.points[i].normalMass[lane] > 0 ? 1 : 0;
                    if (overflow) continue;  // solved one lane at a time, so sharing is allowed
                    if (invMassA > 0) {
                        EXPECT_TRUE(seen.insert(b.bodyA[lane]).second) << "colour " << c;
                    }
                    if (invMassB > 0) {
                        EXPECT_TRUE(seen.insert(b.bodyB[lane]).second) << "colour " << c;
                    }
                }
            }
        }
        std::size_t expected = 0, expectedPoints = 0;
        for (std::size_t k = 0; k < contacts.pairs.size(); ++k) {
            const detail::ContactPair& p = contacts.pairs[k];
            if (storage.moving.invMass[p.a] > 0 || (!p.bStatic && storage.moving.invMass[p.b] > 0))
                ++expected, expectedPoints += static_cast<std::size_t>(contacts.manifolds[k].pointCount);
        }
        EXPECT_EQ(lanes, expected);
        EXPECT_EQ(points, expectedPoints);
        EXPECT_EQ(solver.stats().constraints, expected);
        if (bodies == 40) {
            EXPECT_TRUE(solver.hasOverflow()) << "40 bodies with ~70 neighbours each need > 63 colours";
        }
    }
}

/// Expects every moving body's solved velocity to be bit for bit the same in both solvers (their rows are numbered
/// differently); returns how many bodies had rows.
std::size_t compareVelocities(const detail::ContactSolver& x, const detail::ContactSolver& y, std::size_t bodies) {
    std::size_t compared = 0;
    for (std::uint32_t dense = 0; dense < bodies; ++dense) {
        const std::int32_t a = x.solverIndexOf(dense), b = y.solverIndexOf(dense);
        EXPECT_EQ(a < 0, b < 0) << "body " << dense;
        if (a < 0 || b < 0) continue;
        EXPECT_TRUE(
            sameRow(x.bodies().velocity[static_cast<std::size_t>(a)], y.bodies().velocity[static_cast<std::size_t>(b)]))
            << "body " << dense;
        ++compared;
    }
    return compared;
}

/// Expects two solves of the same contacts to have stored the same impulses, bit for bit, and to have left every
/// moving body's velocity the same; returns how many bodies had rows.
std::size_t compareSolves(detail::ContactSolver& x, detail::ContactSolver& y, World::Impl& w) {
    std::vector<detail::PointImpulse> xImpulses(w.impulses.size()), yImpulses(w.impulses.size());
    x.storeImpulses(xImpulses, *w.pool);
    y.storeImpulses(yImpulses, *w.pool);
    EXPECT_EQ(std::memcmp(xImpulses.data(), yImpulses.data(), xImpulses.size() * sizeof(detail::PointImpulse)), 0);
    return compareVelocities(x, y, w.bodies.moving.size());
}

/// Two threads and no sleeping, as the solver tests that compare one solve with another run.
WorldSettings twoThreadsAwake() {
    WorldSettings s;
    s.threads = 2;
    s.effects = s.effects.without(Effect::Sleeping);
    return s;
}

// Islands share no body, and greedy colouring in manifold order gives each manifold the same colour whether its
// island is coloured alone or with every other: so blocks of small islands, each running all its iterations in one
// task (its warm start included), must end bit for bit where one colouring of everything, iteration by iteration,
// ends.
TEST(ContactSolver, IslandBlocksEndWhereOneColouringEnds) {
    SKIP_UNLESS_CORE_BATCHES_THIS_WIDE();
    World world(twoThreadsAwake());
    // One island too large for a block (1,785 manifolds), too small to be cut in slabs (their order of solving is
    // their own: LargeIslandsAreCutIntoSlabsThatShareNoBody).
    buildPyramid(world, 9);
    BodyDef box;
    box.shape = world.createShape(BoxDef{{0.4f, 0.4f, 0.4f}});
    for (int stack = 0; stack < 300; ++stack)  // small islands: stacks of three boxes beside the pyramid
        for (int level = 0; level < 3; ++level) {
            box.position = {20.0f + 2.0f * static_cast<float>(stack % 15), 0.4f + 0.8f * static_cast<float>(level),
                            -10.0f + 2.0f * static_cast<float>(stack / 15)};
            world.createBody(box);
        }
    // A small island whose plate touches more boxes than there are colours: its block ends in an overflow range.
    BodyDef plate;
    plate.shape = world.createShape(BoxDef{{5, 0.1f, 5}});
    plate.position = {-30, 0.1f, 0};
    world.createBody(plate);
    BodyDef pebble;
    pebble.shape = world.createShape(BoxDef{{0.2f, 0.2f, 0.2f}});
    for (int i = 0; i < 81; ++i) {
        pebble.position = {-34.0f + static_cast<float>(i % 9), 0.4f, -4.0f + static_cast<float>(i / 9)};
        world.createBody(pebble);
    }
    world.applyLinearImpulse(world.bodies().back(), {30, 0, 10});
    for (int i = 0; i < 5; ++i) world.step(1.0f / 60.0f);

    World::Impl& w = detail::WorldAccess::of(world);
    const float h = 1.0f / 60.0f;
    detail::ContactSolver blocked, together;
    blocked.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool, nullptr, &w.islands);
    together.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool);
    ASSERT_GE(blocked.blocks().size(), 2u);
    ASSERT_GT(blocked.largeIslands().colorCount, 0u);
    ASSERT_TRUE(blocked.slabs().empty());
    EXPECT_EQ(together.blocks().size(), 0u);
    EXPECT_EQ(blocked.stats().constraints, together.stats().constraints);

    // No dynamic body appears in two blocks, or in a block and the large islands.
    std::vector<int> ownerOfRow(blocked.bodies().count, -1);
    const auto massOf = [&](std::int32_t row) {
        return blocked.bodies().mass[static_cast<std::size_t>(row)].inverseMass;
    };
    const auto claim = [&](detail::ContactSolver::ColorSpan span, int owner) {
        for (std::uint32_t c = span.firstColor; c < span.firstColor + span.colorCount; ++c) {
            const auto range = blocked.colorRanges()[c];
            for (std::uint32_t bi = range.firstBatch; bi < range.firstBatch + range.batchCount; ++bi) {
                const ContactBatch& b = blocked.batches()[bi];
                for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
                    for (const auto& [row, invMass] : {std::pair{b.bodyA[lane], massOf(b.bodyA[lane])},
                                                       std::pair{b.bodyB[lane], massOf(b.bodyB[lane])}}) {
                        if (invMass == 0) continue;
                        int& owner_ = ownerOfRow[static_cast<std::size_t>(row)];
                        EXPECT_TRUE(owner_ == -1 || owner_ == owner) << "row " << row << " in two blocks";
                        owner_ = owner;
                    }
            }
        }
    };
    const auto overflowIn = [&](detail::ContactSolver::ColorSpan span) {
        return span.colorCount > 0 && blocked.colorRanges()[span.firstColor + span.colorCount - 1].overflow;
    };
    EXPECT_TRUE(std::any_of(blocked.blocks().begin(), blocked.blocks().end(), overflowIn))
        << "the plate's block should need the overflow range";

    blocked.loadBodies(w.bodies.moving, *w.pool);
    together.loadBodies(w.bodies.moving, *w.pool);
    together.warmStart(*w.pool);
    blocked.solveVelocities(true, *w.pool, 8, /*warmStartFirst=*/true);
    for (int i = 0; i < 8; ++i) together.solveVelocities(true, *w.pool);
    EXPECT_GT(compareSolves(blocked, together, w), 600u);
    // Only now look at the blocks' rows: the solve above built them in the blocks' own tasks.
    for (std::size_t k = 0; k < blocked.blocks().size(); ++k) claim(blocked.blocks()[k], static_cast<int>(k));
    claim(blocked.largeIslands(), -2);

    // Rows never solved are built when they are first read: the impulses stored straight after prepare() are the
    // carried ones.
    detail::ContactSolver unsolved;
    unsolved.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool, nullptr, &w.islands);
    std::vector<detail::PointImpulse> carried(w.impulses.size());
    unsolved.storeImpulses(carried, *w.pool);
    ASSERT_EQ(std::memcmp(carried.data(), w.impulses.data(), carried.size() * sizeof(detail::PointImpulse)), 0);
}

// Islands built over fewer manifolds than the solve gets: the last box's contact with the ground is left out. Alone,
// the box is then in no island and has no row; under another box, it shares an island with it and has a row in
// that island's block, while its contact with the ground lands in the large part, so two tasks would solve the box
// at once. Either way the solver must notice, colour everything as one segment, and end bit for bit where a solve
// without islands ends.
TEST(ContactSolver, IslandsThatMissAManifoldFallBackToOneColouring) {
    for (const bool stacked : {false, true}) {
        SCOPED_TRACE(stacked ? "a box on the last one" : "the last box alone");
        World world(twoThreadsAwake());
        buildPyramid(world, 5);
        BodyDef box;
        box.shape = world.createShape(BoxDef{{0.4f, 0.4f, 0.4f}});
        for (int k = 0; k < 40; ++k) {  // lone boxes on the ground, one island each
            box.position = {20.0f + 2.0f * static_cast<float>(k % 8), 0.4f, -8.0f + 2.0f * static_cast<float>(k / 8)};
            world.createBody(box);
        }
        if (stacked) {  // made before the last box, so that the last manifold is still the last box's on the ground
            box.position = {40, 1.2f, 0};
            world.createBody(box);
        }
        box.position = {40, 0.4f, 0};
        world.createBody(box);
        for (int i = 0; i < 3; ++i) world.step(1.0f / 60.0f);

        World::Impl& w = detail::WorldAccess::of(world);
        const std::uint32_t lastBox = w.bodies.moving.size() - 1;
        const detail::ContactPair& lastPair = w.contacts.pairs.back();
        ASSERT_TRUE(lastPair.a == lastBox && lastPair.bStatic)
            << "the last manifold must be the last box's on the ground";
        detail::Contacts fewer = w.contacts;
        fewer.pairs.pop_back();
        fewer.manifolds.pop_back();
        detail::IslandBuilder builder;
        detail::Islands missing;
        builder.build(fewer, {}, w.bodies.moving, *w.pool, missing);
        EXPECT_EQ(
            missing.islandOf[lastBox] != detail::kNoIsland &&
                missing.manifoldStart[missing.islandOf[lastBox] + 1] > missing.manifoldStart[missing.islandOf[lastBox]],
            stacked)
            << "stacked, the last box keeps an island with a manifold";

        const float h = 1.0f / 60.0f;
        detail::ContactSolver fallback, together, blocked;
        fallback.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool, nullptr, &missing);
        together.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool);
        blocked.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool, nullptr, &w.islands);
        EXPECT_GT(blocked.blocks().size(), 0u) << "with islands that cover every manifold the lone boxes go in blocks";
        EXPECT_EQ(fallback.blocks().size(), 0u);
        EXPECT_EQ(fallback.stats().constraints, together.stats().constraints);
        EXPECT_GE(fallback.solverIndexOf(lastBox), 0);

        fallback.loadBodies(w.bodies.moving, *w.pool);
        together.loadBodies(w.bodies.moving, *w.pool);
        for (int i = 0; i < 8; ++i) {
            fallback.solveVelocities(true, *w.pool);
            together.solveVelocities(true, *w.pool);
        }
        EXPECT_GT(compareSolves(fallback, together, w), 90u);
    }
}

// Jointed islands in blocks: each block solves its own joints in its task before its colours, and the large
// islands' joints (a hanging chain with no contact) run before theirs. Per island that is the order of one serial
// joint pass over the store followed by one colouring of everything, so the two must end bit for bit alike.
TEST(ContactSolver, JointsInBlocksEndWhereTheSerialJointPassEnds) {
    World world(twoThreadsAwake());
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(BoxDef{{60, 0.5f, 60}});
    ground.position = {0, -0.5f, 0};
    const BodyId groundId = world.createBody(ground);
    BodyDef box;
    box.shape = world.createShape(BoxDef{{0.3f, 0.3f, 0.3f}});
    for (int k = 0; k < 150; ++k) {  // hinged pairs of boxes lying on the ground, one island each
        const float x = -30.0f + 2.0f * static_cast<float>(k % 30), z = -10.0f + 4.0f * static_cast<float>(k / 30);
        box.position = {x, 0.3f, z};
        const BodyId a = world.createBody(box);
        box.position = {x + 0.6f, 0.3f, z};
        const BodyId b = world.createBody(box);
        HingeJointDef hinge;
        hinge.bodyA = a, hinge.bodyB = b;
        hinge.localAnchorA = {0.3f, 0, 0}, hinge.localAnchorB = {-0.3f, 0, 0};
        hinge.localAxisA = hinge.localAxisB = {0, 0, 1};
        world.createJoint(hinge);
        world.applyLinearImpulse(b, {0, 2.0f + 0.1f * static_cast<float>(k % 7), 0});
    }
    BodyDef link;
    link.shape = world.createShape(SphereDef{0.1f});
    BodyId previous = groundId;
    for (int k = 0; k < 20; ++k) {  // a chain hung from the ground box's far corner, touching nothing
        link.position = {50.0f + 0.3f * static_cast<float>(k + 1), 10.0f, 50.0f};
        const BodyId current = world.createBody(link);
        DistanceJointDef rod;
        rod.bodyA = previous, rod.bodyB = current;
        rod.localAnchorA = previous == groundId ? Vec3{50.0f, 10.5f, 50.0f} : Vec3{};
        world.createJoint(rod);
        previous = current;
    }
    for (int i = 0; i < 4; ++i) world.step(1.0f / 60.0f);

    World::Impl& w = detail::WorldAccess::of(world);
    const float h = 1.0f / 60.0f;
    detail::ContactSolver blocked, together;
    blocked.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool, &w.jointCoupling, &w.islands);
    together.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, h, *w.pool, &w.jointCoupling);
    ASSERT_GE(blocked.blocks().size(), 1u);
    blocked.loadBodies(w.bodies.moving, *w.pool);
    together.loadBodies(w.bodies.moving, *w.pool);
    detail::JointSolver blockedJoints, togetherJoints;
    blockedJoints.prepare(w.joints, w.bodies, blocked, w.jointCoupling, w.settings, h, *w.pool, &w.islands);
    togetherJoints.prepare(w.joints, w.bodies, together, w.jointCoupling, w.settings, h, *w.pool);

    auto jointPass = [&](std::uint32_t segment, int pass) {
        if (pass == 0)
            blockedJoints.beginSubstep(blocked.bodies(), true, segment);
        else
            blockedJoints.solve(blocked.bodies(), true, segment);
    };
    const detail::JointPass pass = jointPass;
    blocked.solveVelocities(true, *w.pool, 8, /*warmStartFirst=*/true, &pass);
    togetherJoints.beginSubstep(together.bodies(), true, 0);  // without islands every joint is in segment 0
    together.warmStart(*w.pool);
    for (int i = 0; i < 8; ++i) {
        togetherJoints.solve(together.bodies(), true, 0);
        together.solveVelocities(true, *w.pool);
    }

    ASSERT_EQ(blockedJoints.rows().size(), togetherJoints.rows().size());
    for (std::size_t j = 0; j < blockedJoints.rows().size(); ++j) {
        const detail::JointRow &x = blockedJoints.rows()[j], &y = togetherJoints.rows()[j];
        const float a[4] = {x.linearImpulse.x, x.linearImpulse.y, x.axialImpulse, x.angularImpulse1};
        const float b[4] = {y.linearImpulse.x, y.linearImpulse.y, y.axialImpulse, y.angularImpulse1};
        EXPECT_EQ(std::memcmp(a, b, sizeof a), 0) << "joint " << j;
    }
    EXPECT_EQ(compareVelocities(blocked, together, w.bodies.moving.size()), 320u);
}

/// Random velocity, motion and pseudo-velocity rows and masses, with the still row at n - 2 and the scratch row at
/// n - 1.
struct Rows {
    std::vector<BodyRow> data[3];
    std::vector<detail::MassRow> mass;
    explicit Rows(std::size_t n, std::mt19937& rng) {
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        for (auto& d : data) {
            d.resize(n);
            for (BodyRow& r : d) r = {{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
            d[n - 2] = BodyRow{};
        }
        test::fillRandomMassRows(mass, n - 1, static_cast<std::int32_t>(n - 2), rng);
        mass.push_back(detail::MassRow{});  // the scratch row is never read for masses
    }
    BodyRows rows() {
        return {data[0].data(), data[1].data(), data[2].data(), mass.data(),
                static_cast<std::int32_t>(data[0].size() - 1)};
    }
};

TEST(ContactSolver, WideKernelsAgreeWithScalarKernelsBitForBit) {
    std::mt19937 rng(42);
    const std::int32_t bodies = 2 * static_cast<std::int32_t>(kBatchLanes);
    for (int trial = 0; trial < 20; ++trial) {
        ContactBatch wide;
        test::fillRandomBatch(wide, rng, bodies);
        ContactBatch scalar = wide;
        detail::ContactBatchExtras wideExtras;
        test::fillRandomExtras(wideExtras, rng);
        detail::ContactBatchExtras scalarExtras = wideExtras;
        std::mt19937 rowRng(trial);
        Rows wideRows(bodies + 2, rowRng);
        Rows scalarRows = wideRows;
        detail::SolveParams params;
        params.invH = 240.0f;
        params.useBias = trial % 2 == 0;
        BodyRows w = wideRows.rows(), s = scalarRows.rows();
        detail::contact_kernels::warmStart<simd::FloatW>(wide, 0, w);
        detail::contact_kernels::solve<simd::FloatW, true>(wide, 0, w, params, &wideExtras);
        detail::contact_kernels::solvePositions<simd::FloatW>(wide, wideExtras, 0, w, params);
        detail::contact_kernels::restitution<simd::FloatW>(wide, wideExtras, 0, w, 1.0f);
        for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
            detail::contact_kernels::warmStart<float>(scalar, lane, s);
        for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
            detail::contact_kernels::solve<float, true>(scalar, lane, s, params, &scalarExtras);
        for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
            detail::contact_kernels::solvePositions<float>(scalar, scalarExtras, lane, s, params);
        for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
            detail::contact_kernels::restitution<float>(scalar, scalarExtras, lane, s, 1.0f);
        // Every row but the scratch row (which absorbs writes for the still body in any order) must match.
        for (int a = 0; a < 3; ++a)
            for (std::int32_t r = 0; r <= bodies; ++r)
                ASSERT_TRUE(sameRow(wideRows.data[a][r], scalarRows.data[a][r])) << "array " << a << " row " << r;
        ASSERT_EQ(std::memcmp(&wide, &scalar, sizeof wide), 0) << "trial " << trial;
        ASSERT_EQ(std::memcmp(&wideExtras, &scalarExtras, sizeof wideExtras), 0) << "trial " << trial;
    }
}

// A large island is cut in two slabs, each solved whole by one task, and the manifolds that cross the cut: no dynamic
// body is in both slabs, every manifold crossing the cut has one dynamic body on each side, and every constraint is
// in exactly one of them.
TEST(ContactSolver, LargeIslandsAreCutIntoSlabsThatShareNoBody) {
    SKIP_UNLESS_CORE_BATCHES_THIS_WIDE();
    World world(twoThreadsAwake());
    buildPyramid(world, 12);  // 4,324 manifolds in one island
    world.step(1.0f / 60.0f);
    World::Impl& w = detail::WorldAccess::of(world);
    detail::ContactSolver solver;
    // The first prepare colours the island whole: whether to cut it follows from how its colours filled then (17
    // batches a colour here, under the 64 that pay for a colour's dispatch).
    solver.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, 1.0f / 60.0f, *w.pool, nullptr, &w.islands);
    ASSERT_TRUE(solver.slabs().empty());
    solver.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, 1.0f / 60.0f, *w.pool, nullptr, &w.islands);
    ASSERT_EQ(solver.slabs().size(), 2u);
    ASSERT_GT(solver.largeIslands().colorCount, 0u) << "a cut through a pyramid crosses some contacts";
    std::vector<int> slabOfRow(solver.bodies().count, -1);
    std::size_t lanes[3] = {};
    const auto forEachLane = [&](detail::ContactSolver::ColorSpan span, auto&& visit) {
        for (std::uint32_t c = span.firstColor; c < span.firstColor + span.colorCount; ++c) {
            const auto range = solver.colorRanges()[c];
            for (std::uint32_t bi = range.firstBatch; bi < range.firstBatch + range.batchCount; ++bi) {
                const ContactBatch& b = solver.batches()[bi];
                for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
                    if (b.bodyA[lane] != b.bodyB[lane]) visit(b.bodyA[lane], b.bodyB[lane]);
            }
        }
    };
    const auto dynamic = [&](std::int32_t row) {
        return solver.bodies().mass[static_cast<std::size_t>(row)].inverseMass > 0;
    };
    for (int slab = 0; slab < 2; ++slab)
        forEachLane(solver.slabs()[static_cast<std::size_t>(slab)], [&](std::int32_t a, std::int32_t b) {
            ++lanes[slab];
            for (const std::int32_t row : {a, b}) {
                if (!dynamic(row)) continue;
                int& owner = slabOfRow[static_cast<std::size_t>(row)];
                EXPECT_TRUE(owner == -1 || owner == slab) << "row " << row << " in both slabs";
                owner = slab;
            }
        });
    forEachLane(solver.largeIslands(), [&](std::int32_t a, std::int32_t b) {
        ++lanes[2];
        ASSERT_TRUE(dynamic(a) && dynamic(b)) << "a contact with the ground lies in its body's slab";
        const int slabA = slabOfRow[static_cast<std::size_t>(a)], slabB = slabOfRow[static_cast<std::size_t>(b)];
        EXPECT_TRUE(slabA != slabB || slabA == -1) << "a crossing manifold within one slab";
    });
    EXPECT_EQ(lanes[0] + lanes[1] + lanes[2], solver.stats().constraints);
    EXPECT_LT(lanes[2] * 10, solver.stats().constraints) << "a cut crosses few contacts";
    EXPECT_LT(lanes[0], 2 * lanes[1]);
    EXPECT_LT(lanes[1], 2 * lanes[0]);
}

}  // namespace
}  // namespace rubble
