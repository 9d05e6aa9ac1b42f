// Manifold reuse (src/narrowphase/manifold_reuse.h): the moved manifolds against closed forms, and the stage's
// reused manifolds against the ones a stage without reuse computes for the same poses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <tuple>

#include "narrowphase/manifold_reuse.h"
#include "narrowphase/narrowphase_stage.h"
#include "support/random_poses.h"
#include "support/stage_scene.h"
#include "support/test_shapes.h"

using namespace rubble;
using rubble::test::randomDirection;
using rubble::test::randomRotation;
using rubble::test::StageScene;
using namespace rubble::detail;

namespace {

Manifold twoPointManifold() {
    Manifold m;
    m.normal = {0, -1, 0};
    m.pointCount = 2;
    m.points[0] = {{0.5f, 0.0f, 0.2f}, 0.01f, 7};
    m.points[1] = {{-0.5f, 0.0f, -0.1f}, -0.005f, 9};
    return m;
}

}  // namespace

TEST(ManifoldReuse, DepthGrowsByTheApproachAlongTheNormal) {
    // A (above, normal pointing down to B) moves 3 mm down and 1 mm sideways while B stays: every depth grows by
    // exactly 3 mm (the sideways part is tangent), B's anchors (the points) and the normal stay, A's anchors move with
    // A, feature ids stay.
    const BodyPose a0{{0, 0.5f, 0}, {}}, b0{{0, -0.5f, 0}, {}};
    const BodyPose a1{{0.001f, 0.497f, 0}, {}};
    const Manifold then = twoPointManifold();
    Manifold now;
    moveManifold(then, poseChange(a0, a1), poseChange(b0, b0), 0, 0, now);
    ASSERT_EQ(now.pointCount, 2);
    EXPECT_EQ(now.normal, then.normal);
    EXPECT_LT(length(now.shiftA - Vec3{0.001f, -0.003f, 0}), 1e-7f);
    for (int i = 0; i < 2; ++i) {
        EXPECT_EQ(now.points[i].position, then.points[i].position);
        EXPECT_NEAR(now.points[i].depth, then.points[i].depth + 0.003f, 1e-7f);
        EXPECT_EQ(now.points[i].feature, then.points[i].feature);
    }
}

TEST(ManifoldReuse, ASphereSpinningInPlaceKeepsItsContact) {
    // A sphere of radius 0.5 resting 1 cm deep on a floor (B), turned 0.3 rad about its centre: its surface is
    // where it was, so point and depth stay (to float rounding), though its material points moved by 15 cm.
    const BodyPose a0{{0, 0.49f, 0}, {}}, b0{{0, -1, 0}, {}};
    const BodyPose a1{a0.position, Quat::fromAxisAngle({1, 0, 0.3f}, 0.3f)};
    Manifold then;
    then.normal = {0, -1, 0};
    then.pointCount = 1;
    then.points[0] = {{0, 0, 0}, 0.01f, 1};
    Manifold now;
    moveManifold(then, poseChange(a0, a1), poseChange(b0, b0), 0.5f, 0, now);
    EXPECT_LT(length(now.points[0].position - then.points[0].position), 1e-6f);
    EXPECT_NEAR(now.points[0].depth, 0.01f, 1e-6f);
}

TEST(ManifoldReuse, APairMovedAsOneRigidBodyKeepsItsDepthsNormalAndAnchorOffsets) {
    // Both bodies moved by the same rigid motion (turned 1.5 degrees about a tilted axis through a far point, then
    // shifted): the relative displacement is zero and every depth is unchanged but for the kept normal (below). A
    // recycled contact keeps its normal in the world and each anchor's offset from its own body's centre: B's anchors
    // move with B's centre, A's with A's (1e-5 m: float rounding of coordinates up to 12 m).
    std::mt19937 rng(3);
    const Quat turn = Quat::fromAxisAngle({0.3f, 1, -0.2f}, 0.026f);
    const Vec3 pivot{10, -2, 5}, shift{0.2f, 0.1f, -0.3f};
    auto moved = [&](Vec3 p) { return pivot + rotate(turn, p - pivot) + shift; };
    const BodyPose a0{{0, 0.5f, 0}, randomRotation(rng)}, b0{{0.2f, -0.5f, 0.1f}, randomRotation(rng)};
    const BodyPose a1{moved(a0.position), turn * a0.rotation}, b1{moved(b0.position), turn * b0.rotation};
    const PoseChange ca = poseChange(a0, a1), cb = poseChange(b0, b1);
    EXPECT_LT(relativeDisplacement(ca, cb, 1.5f), 1e-5f);
    EXPECT_TRUE(turnedLittle(ca) && turnedLittle(cb));
    const Manifold then = twoPointManifold();
    Manifold now;
    moveManifold(then, ca, cb, 0.1f, 0.2f, now);
    EXPECT_EQ(now.normal, then.normal);
    for (int i = 0; i < 2; ++i) {
        EXPECT_LT(length((now.points[i].position - b1.position) - (then.points[i].position - b0.position)), 1e-5f);
        EXPECT_LT(length((now.points[i].position + now.shiftA - a1.position) - (then.points[i].position - a0.position)),
                  1e-5f);
        // The kept normal is off the pair's turned one by the normal's tilt t (0.0088 rad: the turn's axis is nearly
        // the normal), so the cores' separation (0.29 m) measured along it is short by 0.29 (1 - cos t) = 1.1e-5 m.
        EXPECT_NEAR(now.points[i].depth, then.points[i].depth, 2e-5f);
    }
}

TEST(ManifoldReuse, OnlyPairsWhoseBodiesTurnedLittleAreRecycled) {
    // The normal is kept in the world: a body turned by more than 2 degrees, even with its partner (no relative
    // motion), must have its contact computed again.
    const BodyPose still{{0, 0, 0}, {}};
    const auto turnedBy = [&](float angle) {
        return poseChange(still, BodyPose{{0, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, angle)});
    };
    EXPECT_TRUE(turnedLittle(turnedBy(0.0f)));
    EXPECT_TRUE(turnedLittle(turnedBy(0.034f)));
    EXPECT_FALSE(turnedLittle(turnedBy(0.036f)));
    EXPECT_FALSE(turnedLittle(turnedBy(-0.5f)));
}

TEST(ManifoldReuse, RelativeDisplacementBoundsTheMotionOfEveryPointOfA) {
    // Random small motions of both bodies: for points of A within its reach, how far each moved relative to B's
    // material point at the same place never exceeds the bound, and the bound is no more than twice the worst motion
    // (it adds the motion at A's point and the turn times the reach, each of which some point of A reaches).
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> small(-1e-3f, 1e-3f), angle(0, 2e-3f);
    const float reach = 0.8f;
    for (int trial = 0; trial < 200; ++trial) {
        const BodyPose a0{{small(rng) * 1000, 1, 0}, randomRotation(rng)}, b0{{0, 0, 0.3f}, randomRotation(rng)};
        const BodyPose a1{a0.position + Vec3{small(rng), small(rng), small(rng)},
                          Quat::fromAxisAngle(randomDirection(rng), angle(rng)) * a0.rotation};
        const BodyPose b1{b0.position + Vec3{small(rng), small(rng), small(rng)},
                          Quat::fromAxisAngle(randomDirection(rng), angle(rng)) * b0.rotation};
        const PoseChange ca = poseChange(a0, a1), cb = poseChange(b0, b1);
        const float bound = relativeDisplacement(ca, cb, reach);
        float worst = 0;
        for (int k = 0; k < 400; ++k) {
            const Vec3 w = a0.position + randomDirection(rng) * reach;
            worst = std::max(worst, length(carry(ca, w) - carry(cb, w)));
        }
        EXPECT_LE(worst, bound * 1.0001f + 1e-6f) << trial;
        EXPECT_GE(worst, bound * 0.45f) << trial;
    }
}

namespace {

/// Two layers of bodies in a grid, each turned a little, sitting on a gently waving mesh and, beside it, a ground
/// box, and on each other: boxes, spheres, capsules, hulls and compounds in shallow contact, as they rest in a pile.
/// At rest, so every pair has the plain margin.
struct Pile {
    StageScene scene;
    BroadPhaseStage broad;
    std::uint32_t ground = 0, mesh = 0, topCube = 0;

    static float surface(float x, float z) { return 0.25f * std::sin(x / 1.7f) * std::cos(z / 2.3f); }

    Pile() {
        TriangleMeshDef meshDef;
        const int n = 12;
        for (int r = 0; r <= n; ++r)
            for (int c = 0; c <= n; ++c) {
                const float x = float(c) - n / 2.0f, z = float(r) - n / 2.0f;
                meshDef.vertices.push_back({x, surface(x, z), z});
            }
        for (std::uint32_t r = 0; r < std::uint32_t(n); ++r)
            for (std::uint32_t c = 0; c < std::uint32_t(n); ++c) {
                const std::uint32_t a = r * (n + 1) + c, b = a + 1, d = a + n + 1, e = d + 1;
                meshDef.indices.insert(meshDef.indices.end(), {a, d, e, a, e, b});
            }
        CompoundDef compoundDef;
        compoundDef.children.push_back({SphereDef{0.2f}, {{-0.2f, 0, 0}, {}}});
        compoundDef.children.push_back({BoxDef{{0.2f, 0.2f, 0.2f}}, {{0.2f, 0, 0}, {}}});
        std::mt19937 rng(17);
        mesh = scene.addShape(meshDef);
        ground = scene.addShape(BoxDef{{3, 0.5f, 4}});
        const std::uint32_t cube = scene.addShape(BoxDef{{0.4f, 0.4f, 0.4f}});
        topCube = scene.addShape(ConvexHullDef{rubble::test::boxCorners({0.4f, 0.4f, 0.4f})});
        const std::uint32_t pill = scene.addShape(CapsuleDef{0.25f, 0.15f}), ball = scene.addShape(SphereDef{0.4f}),
                            compound = scene.addShape(compoundDef),
                            rock = scene.addShape(ConvexHullDef{rubble::test::randomHullCloud(rng, 14, 0.45f)});
        scene.addStatic(mesh, {0, 0, 0}, broad);
        scene.addStatic(ground, {9, -0.5f, 0}, broad);  // top at y = 0, beside the mesh
        std::uniform_real_distribution<float> tilt(0, 0.05f);
        const std::uint32_t kinds[] = {cube, pill, ball, compound, rock, cube, cube};
        const float spacing = 0.79f;  // one centimetre less than the bodies' 0.8 m: neighbours just overlap
        int k = 0;
        for (int layer = 0; layer < 2; ++layer)
            for (float x = -5.4f; x < 11.5f; x += spacing)
                for (float z = -3; z < 3; z += spacing) {
                    const float floor = x < 6 ? surface(x, z) : 0.0f;
                    // One draw per statement: compilers evaluate a call's arguments in different orders.
                    const Vec3 axis = randomDirection(rng);
                    const Quat q = Quat::fromAxisAngle(axis, tilt(rng));
                    scene.addMoving(kinds[k++ % 7], {x, floor + 0.39f + spacing * float(layer), z}, q);
                }
        // Last, a cube (a hull) of its own shape sunk into the top of a body of the
        // second layer (whose tops are at least 0.18 m above their centres).
        const float x = -5.4f + 7 * spacing, z = -3 + 4 * spacing;
        scene.addMoving(topCube, {x, surface(x, z) + 0.39f + spacing + 0.15f + 0.4f, z}, {});
    }

    Contacts run(NarrowPhaseStage& stage, float reuseDistance, int threads = 2) {
        TaskPool pool(threads);
        Bounds bounds;
        CandidatePairs candidates;
        updateBounds(scene.storage.moving, scene.table, BoundsParams{1.0f / 60, kMargin}, pool, bounds);
        broad.findPairs(bounds, scene.storage, BroadPhaseKind::Auto, {}, pool, candidates);
        Contacts contacts;
        stage.run(candidates, scene.storage, scene.shapes, NarrowPhaseParams{kMargin, 1.0f / 60, reuseDistance}, pool,
                  contacts);
        return contacts;
    }

    /// Moves every moving body by a random rigid motion: a shift of up to `shift` and a turn of up to `turn` about
    /// its centre of mass.
    void jiggle(std::mt19937& rng, float shift, float turn) {
        std::uniform_real_distribution<float> u(0, 1);
        MovingBodies& m = scene.storage.moving;
        for (std::uint32_t i = 0; i < m.size(); ++i) {
            const Vec3 shiftDirection = randomDirection(rng);
            const Vec3 d = shiftDirection * (shift * u(rng));
            m.px[i] += d.x, m.py[i] += d.y, m.pz[i] += d.z;
            const Vec3 turnAxis = randomDirection(rng);
            const Quat q = Quat::fromAxisAngle(turnAxis, turn * u(rng)) * Quat{m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
            m.qx[i] = q.x, m.qy[i] = q.y, m.qz[i] = q.z, m.qw[i] = q.w;
        }
    }

    static constexpr float kMargin = 0.02f;
};

using PairKey = std::tuple<std::uint32_t, bool, std::uint32_t, bool, std::uint32_t, std::uint16_t, std::uint16_t>;
PairKey keyOf(const ContactPair& p) { return {p.a, p.aStatic, p.b, p.bStatic, p.triangle, p.childA, p.childB}; }

/// The same pairs and point counts in the same order; `check` compares each pair's two manifolds.
template <class Check>
void expectMatching(const Contacts& x, const Contacts& y, Check check) {
    ASSERT_EQ(x.manifolds.size(), y.manifolds.size());
    ASSERT_EQ(x.pointCount, y.pointCount);
    for (std::size_t k = 0; k < x.manifolds.size(); ++k) {
        ASSERT_TRUE(keyOf(x.pairs[k]) == keyOf(y.pairs[k])) << k;
        ASSERT_EQ(x.manifolds[k].pointCount, y.manifolds[k].pointCount) << k;
        check(x.manifolds[k], y.manifolds[k], k);
    }
}

void expectSameBits(const Contacts& x, const Contacts& y) {
    expectMatching(x, y, [](const Manifold& a, const Manifold& b, std::size_t k) {
        EXPECT_EQ(std::memcmp(&a.normal, &b.normal, sizeof(Vec3)), 0) << k;
        EXPECT_EQ(std::memcmp(&a.shiftA, &b.shiftA, sizeof(Vec3)), 0) << k;
        for (int p = 0; p < a.pointCount; ++p)
            EXPECT_EQ(std::memcmp(&a.points[p], &b.points[p], sizeof(ContactPoint)), 0) << k << " " << p;
    });
}

/// Feature ids the same; positions, depths and normals within `tolerance`.
void expectClose(const Contacts& x, const Contacts& y, float tolerance) {
    expectMatching(x, y, [&](const Manifold& a, const Manifold& b, std::size_t k) {
        EXPECT_LE(length(a.normal - b.normal), tolerance) << k;
        for (int p = 0; p < a.pointCount; ++p) {
            EXPECT_EQ(a.points[p].feature, b.points[p].feature) << k << " " << p;
            EXPECT_LE(length(a.points[p].position - b.points[p].position), tolerance) << k << " " << p;
            EXPECT_NEAR(a.points[p].depth, b.points[p].depth, tolerance) << k << " " << p;
        }
    });
}

}  // namespace

TEST(ManifoldReuse, PairsThatDidNotMoveGetTheManifoldsTheyWouldCompute) {
    // Up to float rounding: the reused points are recomputed from the bodies' poses (1e-6 m: coordinates up to 11 m).
    Pile pile;
    NarrowPhaseStage reusing;
    const Contacts first = pile.run(reusing, 0.001f);
    EXPECT_EQ(reusing.reusedManifolds(), 0u) << "nothing to reuse on the first run";
    ASSERT_GT(first.manifolds.size(), 300u) << "the pile must touch itself and the statics";
    const Contacts again = pile.run(reusing, 0.001f);
    // Nothing moved, so every manifold of a recycled pair is reused: all but those between spheres and capsules.
    const auto round = [&](std::uint32_t body, bool isStatic) {
        const StageScene& s = pile.scene;
        const ShapeKind k = s.shapes[isStatic ? s.storage.statics.shape[body] : s.storage.moving.shape[body]].kind;
        return k == ShapeKind::Sphere || k == ShapeKind::Capsule;
    };
    std::size_t recycledPairs = 0, roundPairs = 0;
    for (const ContactPair& p : first.pairs) {
        const bool roundPair = round(p.a, p.aStatic) && round(p.b, p.bStatic);
        roundPairs += roundPair;
        recycledPairs += !roundPair;
    }
    EXPECT_GT(roundPairs, 0u) << "the pile must have pairs that are computed every step";
    EXPECT_EQ(reusing.reusedManifolds(), recycledPairs);
    expectClose(first, again, 1e-6f);
}

TEST(ManifoldReuse, PairsThatMovedFurtherThanTheDistanceAreComputedAgain) {
    // Every body lifted by 5 mm (away from the statics) and turned by 0.1 rad about its own random axis (away from its
    // neighbours, by centimetres): beyond the 1 mm reuse distance, so the output is a fresh stage's, bit for bit.
    Pile pile;
    NarrowPhaseStage reusing;
    pile.run(reusing, 0.001f);
    MovingBodies& m = pile.scene.storage.moving;
    std::mt19937 rng(5);
    for (std::uint32_t i = 0; i < m.size(); ++i) {
        m.py[i] += 0.005f;
        const Quat q = Quat::fromAxisAngle(randomDirection(rng), 0.1f) * Quat{m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
        m.qx[i] = q.x, m.qy[i] = q.y, m.qz[i] = q.z, m.qw[i] = q.w;
    }
    const Contacts reused = pile.run(reusing, 0.001f);
    EXPECT_EQ(reusing.reusedManifolds(), 0u);
    NarrowPhaseStage fresh;
    expectSameBits(reused, pile.run(fresh, 0));
}

TEST(ManifoldReuse, ReusedManifoldsAgreeWithComputedOnesAfterSmallMotions) {
    // Each body shifted by up to 0.2 mm and turned by up to 0.3 mrad (so any pair's shapes moved less than about
    // 1 mm relative to each other): the reusing stage moves its old manifolds; a fresh stage computes them. They must
    // describe the same contacts:
    // - the same pairs, except those whose deepest point is within 1 mm of the margin (they may come or go), and
    //   those the kernels themselves find at only one of the two poses: a body sunk centimetres into the mesh can
    //   bring a corner over the next triangle with so small a motion, and a reused manifold cannot know of a new
    //   triangle. Those must be rare (at most 1% of the pairs), and a pair that both fresh answers hold must be
    //   reused;
    // - normals within 2 mrad (the relative turn, plus a kernel's choice between nearly equal axes), except where
    //   the kernels chose another face at the new pose (at most 3% of the pairs);
    // - for points with the same feature id, depths within 0.25 mm. The moved depth follows the motion to first order
    //   at the moved point; a computed point made by clipping slides along its edge instead (the reused one keeps
    //   its offset from B's centre), and where the faces in contact meet at an angle (tilts up to 0.05 rad, the
    //   mesh's slope up to 0.15) that slide changes its depth by the motion times that angle: up to about 0.3 mm;
    // - positions within 2 cm only: a clipped point on an edge nearly parallel to the side plane that cuts it
    //   slides many times as far as the bodies move (1.4 cm for a pair of the boxes).
    Pile pile;
    NarrowPhaseStage reusing;
    const Contacts before = pile.run(reusing, 0.01f);
    std::mt19937 rng(29);
    pile.jiggle(rng, 2e-4f, 3e-4f);
    const Contacts reused = pile.run(reusing, 0.01f);
    NarrowPhaseStage fresh;
    const Contacts computed = pile.run(fresh, 0);
    ASSERT_GT(reusing.reusedManifolds(), 200u);

    std::map<PairKey, std::size_t> byKey;
    for (std::size_t k = 0; k < computed.pairs.size(); ++k) byKey[keyOf(computed.pairs[k])] = k;
    auto deepest = [](const Manifold& m) {
        float d = -1e9f;
        for (int p = 0; p < m.pointCount; ++p) d = std::max(d, m.points[p].depth);
        return d;
    };
    const float guard = -Pile::kMargin + 0.001f;
    int compared = 0, points = 0, matched = 0;
    float worstDepth = 0, worstPosition = 0, worstNormal = 0;
    std::map<PairKey, bool> seen, foundBefore;
    for (const ContactPair& p : before.pairs) foundBefore[keyOf(p)] = true;
    int kernelFlips = 0, faceFlips = 0;
    for (std::size_t k = 0; k < reused.pairs.size(); ++k) {
        const PairKey key = keyOf(reused.pairs[k]);
        seen[key] = true;
        const Manifold& r = reused.manifolds[k];
        const auto it = byKey.find(key);
        if (it == byKey.end()) {
            // Reused manifolds are the ones found before the motion: this pair left the kernels' answer.
            if (deepest(r) >= guard) ++kernelFlips;
            continue;
        }
        const Manifold& c = computed.manifolds[it->second];
        ++compared;
        if (length(r.normal - c.normal) > 2e-3f) {
            // The kernels chose another face at the moved pose: of two faces of nearly equal separation, A's or B's
            // (their tilts differ by up to 0.1 rad), or a box's top or side where one box's corner meets another's.
            // The recycled manifold keeps the face chosen before, which describes the same contact.
            ++faceFlips;
            continue;
        }
        worstNormal = std::max(worstNormal, length(r.normal - c.normal));
        for (int i = 0; i < r.pointCount; ++i) {
            ++points;
            for (int j = 0; j < c.pointCount; ++j) {
                if (r.points[i].feature != c.points[j].feature) continue;
                ++matched;
                worstDepth = std::max(worstDepth, std::fabs(r.points[i].depth - c.points[j].depth));
                worstPosition = std::max(worstPosition, length(r.points[i].position - c.points[j].position));
                break;
            }
        }
    }
    for (std::size_t k = 0; k < computed.pairs.size(); ++k) {
        const PairKey key = keyOf(computed.pairs[k]);
        if (seen.count(key) || deepest(computed.manifolds[k]) < guard) continue;
        EXPECT_FALSE(foundBefore.count(key)) << "a manifold found before and after the motion that reuse lost";
        ++kernelFlips;
    }
    EXPECT_LE(kernelFlips, compared / 100) << "pairs the kernels find at only one of two poses 0.2 mm apart";
    EXPECT_LE(faceFlips, compared * 3 / 100) << "pairs the kernels give another face at two poses 0.2 mm apart";
    EXPECT_GT(compared, 300);
    EXPECT_GT(matched, points * 9 / 10) << "feature ids must mostly survive so small a motion";
    EXPECT_LT(worstNormal, 2e-3f);
    EXPECT_LT(worstDepth, 3e-4f);
    EXPECT_LT(worstPosition, 2e-2f);
    std::printf(
        "compared %d manifolds, %d of %d points by feature: worst depth %.3g m, position %.3g m, normal %.3g; %d pairs "
        "found at one pose only, %d with another face\n",
        compared, matched, points, worstDepth, worstPosition, worstNormal, kernelFlips, faceFlips);
}

TEST(ManifoldReuse, ABodyThatTookAnotherOnesSlotIsComputedAgain) {
    // The last body is removed and a new one takes its slot and dense index, with a shape that took the old shape's
    // index (both freed and reused, as the world allows) but is twice as big, at the same pose. Nothing but the
    // slot's generation tells them apart: its pairs must be computed, not reused.
    Pile pile;
    NarrowPhaseStage reusing;
    const Contacts before = pile.run(reusing, 0.001f);
    StageScene& scene = pile.scene;
    MovingBodies& m = scene.storage.moving;
    const std::uint32_t last = m.size() - 1, slot = m.slot[last];
    const Vec3 p{m.px[last], m.py[last], m.pz[last]};
    const Quat q{m.qx[last], m.qy[last], m.qz[last], m.qw[last]};
    const std::uint32_t shape = m.shape[last];
    ASSERT_EQ(shape, pile.topCube);
    scene.storage.release(scene.storage.idAt(slot));
    scene.shapes[shape] = buildShape(ConvexHullDef{rubble::test::boxCorners({0.8f, 0.6f, 0.7f})});
    scene.table.set(shape, shapeBoundsInfo(scene.shapes[shape]));
    const std::uint32_t again = scene.addMoving(shape, p, q);
    ASSERT_EQ(again, last);
    ASSERT_EQ(m.slot[again], slot);
    const Contacts reused = pile.run(reusing, 0.001f);
    EXPECT_GT(reusing.reusedManifolds(), 0u);
    NarrowPhaseStage fresh;
    const Contacts computed = pile.run(fresh, 0);
    EXPECT_TRUE(std::any_of(computed.pairs.begin(), computed.pairs.end(), [&](const ContactPair& pair) {
        return pair.a == last || pair.b == last;
    })) << "the new body must touch something for the test to prove anything";
    EXPECT_TRUE(std::any_of(before.pairs.begin(), before.pairs.end(), [&](const ContactPair& pair) {
        return pair.a == last || pair.b == last;
    })) << "and so must the old one, so that there is something to reuse wrongly";
    expectClose(reused, computed, 1e-6f);  // the other pairs did not move and are reused
}

TEST(ManifoldReuse, OutputDoesNotDependOnTheThreadCount) {
    // Three runs with small motions between them (some pairs reused, some computed, some kept from the first run):
    // the same bits on 1, 2 and 3 threads.
    auto run = [](int threads) {
        Pile pile;
        NarrowPhaseStage stage;
        std::mt19937 rng(41);
        pile.run(stage, 0.001f, threads);
        pile.jiggle(rng, 6e-4f, 6e-4f);
        pile.run(stage, 0.001f, threads);
        pile.jiggle(rng, 6e-4f, 6e-4f);
        Contacts last = pile.run(stage, 0.001f, threads);
        EXPECT_GT(stage.reusedManifolds(), 0u);
        return last;
    };
    const Contacts one = run(1);
    for (const int threads : {2, 3}) expectSameBits(one, run(threads));
}
