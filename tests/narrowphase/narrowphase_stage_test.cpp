// The narrow-phase stage end to end: broad-phase candidates of every supported shape pair become manifolds exactly
// when GJK (a second algorithm) finds the shapes within the margin; the output is the same on 1 and 2 threads.
// Hulls against meshes: tests/narrowphase/hull_triangle_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <unordered_map>

#include "bounds/bounds.h"
#include "broadphase/broadphase_stage.h"
#include "core/parallel.h"
#include "narrowphase/gjk.h"
#include "narrowphase/narrowphase_stage.h"
#include "storage/body_storage.h"
#include "support/random_poses.h"
#include "support/stage_scene.h"
#include "support/test_shapes.h"

using namespace rubble;
using rubble::test::randomRotation;
using rubble::test::StageScene;
using namespace rubble::detail;

TEST(NarrowPhaseStage, ManifoldsExactlyWhereGjkFindsTheShapesWithinTheMargin) {
    StageScene scene;
    BroadPhaseStage broad;
    const std::uint32_t ball = scene.addShape(SphereDef{0.5f}), cube = scene.addShape(BoxDef{{0.5f, 0.3f, 0.4f}}),
                        pill = scene.addShape(CapsuleDef{0.3f, 0.5f}), ground = scene.addShape(BoxDef{{20, 0.5f, 20}}),
                        rock = scene.addShape(ConvexHullDef{
                            {{0, 0, 0}, {0.9f, 0, 0.1f}, {0.1f, 0.7f, 0}, {0, 0.2f, 0.8f}, {0.6f, 0.6f, 0.5f}}});
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> xz(-6, 6), y(-0.2f, 4);
    const std::uint32_t kinds[] = {ball, cube, pill, rock};
    for (int i = 0; i < 800; ++i) {
        // Drawn one per statement: the order a function's arguments are evaluated in differs between compilers.
        const Vec3 origin{xz(rng), y(rng), xz(rng)};
        scene.addMoving(kinds[i % 4], origin, randomRotation(rng));
    }
    scene.addStatic(ground, {0, -0.5f, 0}, broad);

    const float margin = 0.02f;
    CandidatePairs candidates;
    const Contacts contacts = runStages(scene, broad, 2, margin, candidates);
    ASSERT_GT(contacts.manifolds.size(), 100u) << "the scene must produce contacts to prove anything";

    // Index the manifolds by body pair (order-free) to look them up per candidate.
    auto key = [](std::uint32_t a, bool as, std::uint32_t b, bool bs) {
        std::uint64_t x = (std::uint64_t{a} << 1) | as, z = (std::uint64_t{b} << 1) | bs;
        return x < z ? (x << 32) | z : (z << 32) | x;
    };
    std::unordered_map<std::uint64_t, std::size_t> found;
    for (std::size_t k = 0; k < contacts.pairs.size(); ++k) {
        const ContactPair& p = contacts.pairs[k];
        EXPECT_LE(scene.shapeOf(p.a, p.aStatic).kind, scene.shapeOf(p.b, p.bStatic).kind) << "A has the lower kind";
        EXPECT_NEAR(length(contacts.manifolds[k].normal), 1.0f, 1e-5f);
        found[key(p.a, p.aStatic, p.b, p.bStatic)] = k;
    }

    int checked = 0;
    auto check = [&](std::uint32_t a, bool as, std::uint32_t b, bool bs) {
        const Shape& sa = scene.shapeOf(a, as);
        const Shape& sb = scene.shapeOf(b, bs);
        const GjkResult g = gjkDistance(gjkShapeOf(sa, scene.poseOf(a, as)), gjkShapeOf(sb, scene.poseOf(b, bs)));
        const auto it = found.find(key(a, as, b, bs));
        // Distances within 1e-4 m of the margin may go either way (float kernels against a double GJK).
        if (g.status == GjkStatus::Separated && g.distance > margin + 1e-4f) {
            EXPECT_EQ(it, found.end()) << "a manifold for shapes " << g.distance << " m apart";
        } else if (g.status != GjkStatus::Separated || g.distance < margin - 1e-4f) {
            ASSERT_NE(it, found.end()) << "no manifold for shapes " << g.distance << " m apart";
            if (g.status == GjkStatus::Separated) {
                // Apart but within the margin: the deepest point's depth is minus the distance, and the normal is
                // GJK's separating direction, turned round when the stage ordered the pair the other way.
                const Manifold& m = contacts.manifolds[it->second];
                float deepest = -1e9f;
                for (int p = 0; p < m.pointCount; ++p) deepest = std::max(deepest, m.points[p].depth);
                EXPECT_NEAR(deepest, -g.distance, 2e-4f);
                const ContactPair& order = contacts.pairs[it->second];
                const bool sameOrder = order.a == a && order.aStatic == as;
                EXPECT_GT(dot(m.normal, sameOrder ? g.normal : -g.normal), 0.99f)
                    << "kinds " << int(sa.kind) << "-" << int(sb.kind);
            }
        }
        ++checked;
    };
    for (const BodyPair& p : candidates.moving) check(p.a, false, p.b, false);
    for (const BodyPair& p : candidates.statics) check(p.a, false, p.b, true);
    EXPECT_GT(checked, 500);
}

TEST(NarrowPhaseStage, OutputDoesNotDependOnTheThreadCount) {
    // Moving bodies of every batched and one-at-a-time kind (and compounds) with random velocities and spins, so
    // that every pair has its own speculative margin, over a ground box and a mesh: pairs, normals, points, depths
    // and feature ids must be the same bits on 1, 2 and 3 threads.
    auto run = [](int threads) {
        StageScene scene;
        BroadPhaseStage broad;
        CompoundDef compoundDef;
        compoundDef.children.push_back({SphereDef{0.3f}, {{-0.4f, 0, 0}, {}}});
        compoundDef.children.push_back({BoxDef{{0.3f, 0.2f, 0.3f}}, {{0.4f, 0, 0}, {}}});
        TriangleMeshDef meshDef;
        for (int r = 0; r <= 8; ++r)
            for (int c = 0; c <= 8; ++c) meshDef.vertices.push_back({2.0f * float(c) - 8, -9, 2.0f * float(r) - 8});
        for (std::uint32_t r = 0; r < 8; ++r)
            for (std::uint32_t c = 0; c < 8; ++c) {
                const std::uint32_t a = r * 9 + c, b = a + 1, d = a + 9, e = d + 1;
                meshDef.indices.insert(meshDef.indices.end(), {a, d, e, a, e, b});
            }
        const std::uint32_t ball = scene.addShape(SphereDef{0.5f}), cube = scene.addShape(BoxDef{}),
                            pill = scene.addShape(CapsuleDef{0.3f, 0.5f}), compound = scene.addShape(compoundDef),
                            ground = scene.addShape(BoxDef{{10, 0.5f, 10}}), mesh = scene.addShape(meshDef);
        scene.addStatic(ground, {0, 8.5f, 0}, broad);
        scene.addStatic(mesh, {0, 0, 0}, broad);
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(-8, 8), speed(-3, 3);
        const std::uint32_t kinds[] = {ball, cube, pill, cube, compound};
        for (int i = 0; i < 4000; ++i) {
            const Vec3 origin{u(rng), u(rng) * 1.1f, u(rng)};
            const Quat rotation = randomRotation(rng);
            const Vec3 velocity{speed(rng), speed(rng), speed(rng)};
            scene.addMoving(kinds[i % 5], origin, rotation, velocity, {speed(rng), speed(rng), speed(rng)});
        }
        CandidatePairs candidates;
        return runStages(scene, broad, threads, 0.02f, candidates);
    };
    const Contacts one = run(1);
    ASSERT_GT(one.manifolds.size(), 1000u);
    bool meshContact = false, staticContact = false;
    for (const ContactPair& p : one.pairs) {
        meshContact = meshContact || p.triangle != ~0u;
        staticContact = staticContact || (p.bStatic && p.triangle == ~0u);
    }
    EXPECT_TRUE(meshContact && staticContact) << "the scene must touch the mesh and the ground box";
    for (const int threads : {2, 3}) {
        const Contacts other = run(threads);
        ASSERT_EQ(one.manifolds.size(), other.manifolds.size());
        ASSERT_EQ(one.pointCount, other.pointCount);
        for (std::size_t k = 0; k < one.manifolds.size(); ++k) {
            const ContactPair &x = one.pairs[k], &y = other.pairs[k];
            ASSERT_TRUE(x.a == y.a && x.b == y.b && x.aStatic == y.aStatic && x.bStatic == y.bStatic &&
                        x.triangle == y.triangle && x.childA == y.childA && x.childB == y.childB)
                << k;
            const Manifold &a = one.manifolds[k], &b = other.manifolds[k];
            ASSERT_EQ(a.pointCount, b.pointCount);
            ASSERT_EQ(std::memcmp(&a.normal, &b.normal, sizeof(Vec3)), 0) << k;
            for (int p = 0; p < a.pointCount; ++p) {
                ASSERT_EQ(std::memcmp(&a.points[p], &b.points[p], sizeof(ContactPoint)), 0) << k << " " << p;
            }
        }
    }
}

TEST(NarrowPhaseStage, FastApproachGetsSpeculativePointsBeforeTheBodiesMeet) {
    // Pairs 0.5 m apart (surface to surface) closing at 50 m/s would pass through each other within one 1/60 s
    // step: they must get a manifold now, with its deepest point at minus the gap. The same pairs closing at
    // 1 m/s get nothing (they cannot meet this step). One pair per path: sphere-sphere (SIMD lanes), box-box (SIMD
    // axis tests), sphere-capsule and a sphere falling on a static ground box (one pair at a time).
    const float gap = 0.5f, margin = 0.02f;
    struct Result {
        int manifolds = 0;
        float deepest[4] = {-1e9f, -1e9f, -1e9f, -1e9f};
        Vec3 normal[4];
    };
    auto run = [&](float speed, int threads) {
        StageScene scene;
        BroadPhaseStage broad;
        const std::uint32_t ball = scene.addShape(SphereDef{0.5f}), cube = scene.addShape(BoxDef{}),
                            pill = scene.addShape(CapsuleDef{0.5f, 0.5f}),
                            ground = scene.addShape(BoxDef{{5, 0.5f, 5}});
        // Along x, B approaching A (A at rest for the first two, both moving for the capsule pair).
        scene.addMoving(ball, {0, 0, 0}, {});
        scene.addMoving(ball, {1 + gap, 0, 0}, {}, {-speed, 0, 0});
        scene.addMoving(cube, {0, 0, 10}, {});
        scene.addMoving(cube, {1 + gap, 0, 10}, {}, {-speed, 0, 0});
        scene.addMoving(ball, {0, 0, 20}, {}, {0.5f * speed, 0, 0});
        scene.addMoving(pill, {1 + gap, 0, 20}, {}, {-0.5f * speed, 0, 0});
        scene.addStatic(ground, {0, -20.5f, 0}, broad);
        scene.addMoving(ball, {0, -19.5f + gap, 0}, {}, {0, -speed, 0});
        CandidatePairs candidates;
        const Contacts contacts = runStages(scene, broad, threads, margin, candidates);
        Result r;
        r.manifolds = static_cast<int>(contacts.manifolds.size());
        for (std::size_t k = 0; k < contacts.manifolds.size(); ++k) {
            const Manifold& m = contacts.manifolds[k];
            const ContactPair& p = contacts.pairs[k];
            const int which = p.bStatic ? 3 : static_cast<int>(p.a / 2);
            for (int i = 0; i < m.pointCount; ++i) r.deepest[which] = std::max(r.deepest[which], m.points[i].depth);
            r.normal[which] = m.normal;
        }
        return r;
    };
    const Result fast = run(50, 1), fast2 = run(50, 2);
    ASSERT_EQ(fast.manifolds, 4);
    for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(fast.deepest[k], -gap, 1e-5f) << "pair " << k;
        EXPECT_EQ(fast.deepest[k], fast2.deepest[k]) << "pair " << k;
    }
    EXPECT_NEAR(fast.normal[0].x, 1, 1e-6f);
    EXPECT_NEAR(fast.normal[1].x, 1, 1e-6f);
    EXPECT_NEAR(fast.normal[2].x, 1, 1e-6f);
    EXPECT_NEAR(fast.normal[3].y, -1, 1e-6f);  // from the sphere (A) down to the ground (B)
    EXPECT_EQ(run(1, 1).manifolds, 0);
    EXPECT_EQ(run(1, 2).manifolds, 0);
}

TEST(NarrowPhaseStage, MarginGrowsWithTheClosingSpeedAndTheSpinOnly) {
    // Two cubes 3 cm apart, face to face: beyond the 2 cm margin at rest, and when both move together (no closing
    // speed); within it when they close at 1 m/s (margin 2 cm + 1/60 m) or when one spins at 10 rad/s (its corners
    // sweep 10/60 rad times their 0.87 m reach).
    const float gap = 0.03f;
    auto manifolds = [&](Vec3 vA, Vec3 vB, Vec3 wB) {
        StageScene scene;
        BroadPhaseStage broad;
        const std::uint32_t cube = scene.addShape(BoxDef{});
        scene.addMoving(cube, {0, 0, 0}, {}, vA);
        scene.addMoving(cube, {1 + gap, 0, 0}, {}, vB, wB);
        CandidatePairs candidates;
        const Contacts contacts = runStages(scene, broad, 1, 0.02f, candidates);
        EXPECT_EQ(candidates.moving.size(), 1u) << "the broad phase must hand the pair on in every case";
        return contacts.manifolds.size();
    };
    EXPECT_EQ(manifolds({}, {}, {}), 0u);
    EXPECT_EQ(manifolds({5, 0, 0}, {5, 0, 0}, {}), 0u);
    EXPECT_EQ(manifolds({}, {-1, 0, 0}, {}), 1u);
    EXPECT_EQ(manifolds({0.5f, 0, 0}, {-0.5f, 0, 0}, {}), 1u);
    EXPECT_EQ(manifolds({}, {}, {0, 10, 0}), 1u);
}

TEST(NarrowPhaseStage, BodiesOnAFlatMeshTouchItWithTheFaceNormalEvenOverInternalEdges) {
    // A flat 8 x 8 grid mesh, two triangles per cell. Bodies rest on it at positions that put their contacts
    // exactly on internal edges and vertices; the mesh's active-edge masks must make every normal the face's.
    StageScene scene;
    BroadPhaseStage broad;
    const TriangleMeshDef grid = rubble::test::flatGridMesh(8);
    const std::uint32_t mesh = scene.addShape(grid);
    const std::uint32_t ball = scene.addShape(SphereDef{0.5f}), cube = scene.addShape(BoxDef{{0.5f, 0.5f, 0.5f}}),
                        pill = scene.addShape(CapsuleDef{0.3f, 0.5f});
    scene.addStatic(mesh, {0, 0, 0}, broad);
    const float sink = 0.01f;  // slightly into the floor
    const float xs[] = {-2.0f, -1.0f, 0.0f, 0.5f, 1.25f, 2.0f};
    for (float x : xs)
        for (float z : xs) {
            scene.addMoving(ball, {x, 0.5f - sink, z}, {});
            scene.addMoving(cube, {x + 0.01f, 0.5f - sink, z + 0.013f}, {});
            scene.addMoving(pill, {x, 0.3f - sink, z}, Quat::fromAxisAngle({0, 0, 1}, 1.5707964f));  // lying
        }
    CandidatePairs candidates;
    const Contacts contacts = runStages(scene, broad, 2, 0.02f, candidates);
    int meshContacts = 0;
    for (std::size_t k = 0; k < contacts.pairs.size(); ++k) {
        if (!contacts.pairs[k].bStatic) continue;
        ++meshContacts;
        const Vec3 n = contacts.manifolds[k].normal;  // from the body to the triangle: straight down
        EXPECT_NEAR(n.y, -1.0f, 1e-4f) << "pair " << k << " triangle " << contacts.pairs[k].triangle;
        for (int p = 0; p < contacts.manifolds[k].pointCount; ++p)
            EXPECT_NEAR(contacts.manifolds[k].points[p].depth, sink, 1e-4f);
    }
    // Every body touches the floor through one manifold: its triangles' manifolds share the face normal and are
    // merged (mesh_manifolds.h).
    EXPECT_EQ(meshContacts, 108);
}

TEST(NarrowPhaseStage, CompoundChildrenCollideLikeTheSameShapesAsSeparateBodies) {
    // A sphere and a turned box joined in a compound, tilted and sunk into a ground box, against the same two
    // shapes placed as separate bodies at the children's world poses: the manifolds must agree (up to the
    // rounding of the compound's origin, which is stored through its centre of mass).
    const Transform sphereLocal{{-1, 0, 0}, {}};
    const Transform boxLocal{{1, 0.1f, 0}, Quat::fromAxisAngle({0, 1, 0}, 0.5f)};
    const Transform body{{0.3f, 0.1f, -0.2f}, Quat::fromAxisAngle({0, 0, 1}, -0.2f)};

    auto run = [&](bool asCompound, std::vector<ContactPair>& pairs) {
        StageScene scene;
        BroadPhaseStage broad;
        const std::uint32_t ground = scene.addShape(BoxDef{{10, 0.5f, 10}});
        scene.addStatic(ground, {0, -0.5f, 0}, broad);
        if (asCompound) {
            CompoundDef compound;
            compound.children.push_back({SphereDef{0.5f}, sphereLocal});
            compound.children.push_back({BoxDef{{0.3f, 0.3f, 0.3f}}, boxLocal});
            scene.addMoving(scene.addShape(compound), body.position, body.rotation);
        } else {
            scene.addMoving(scene.addShape(SphereDef{0.5f}), apply(body, sphereLocal.position), body.rotation);
            scene.addMoving(scene.addShape(BoxDef{{0.3f, 0.3f, 0.3f}}), apply(body, boxLocal.position),
                            body.rotation * boxLocal.rotation);
        }
        CandidatePairs candidates;
        Contacts contacts = runStages(scene, broad, 1, 0.02f, candidates);
        pairs = contacts.pairs;
        return contacts.manifolds;
    };
    std::vector<ContactPair> compoundPairs, separatePairs;
    const std::vector<Manifold> compound = run(true, compoundPairs), separate = run(false, separatePairs);
    ASSERT_EQ(compound.size(), 2u);
    ASSERT_EQ(separate.size(), 2u);
    EXPECT_EQ(compoundPairs[0].childA, 0);  // the sphere child, against the ground (B)
    EXPECT_EQ(compoundPairs[1].childA, 1);  // the box child against the ground box: same kind, candidate order
    for (int k = 0; k < 2; ++k) {
        ASSERT_EQ(compound[k].pointCount, separate[k].pointCount) << k;
        EXPECT_NEAR(compound[k].normal.y, separate[k].normal.y, 1e-5f);
        for (int p = 0; p < compound[k].pointCount; ++p) {
            EXPECT_NEAR(compound[k].points[p].depth, separate[k].points[p].depth, 1e-5f) << k << " " << p;
            EXPECT_NEAR(compound[k].points[p].position.x, separate[k].points[p].position.x, 1e-5f);
            EXPECT_NEAR(compound[k].points[p].position.z, separate[k].points[p].position.z, 1e-5f);
        }
    }
}
