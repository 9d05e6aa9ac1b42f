// Closed-form contact kernels against independent answers:
//  - libccd (tests/narrowphase/ccd_oracle.h) for clearly overlapping pairs (see compare below): depth along our
//    normal exact to 1e-4 m by libccd's intersection test; depth at most libccd's GJK+EPA / MPR penetration plus
//    2e-3 m (EPA approximates round surfaces by a polytope and stops at its own tolerance, so it is the looser side);
//    normal within 11 degrees (dot > 0.98) where the depths agree within 2e-4 m.
//  - our GJK (itself checked against analytic distances in gjk_test.cpp) for speculative pairs: -depth equals the
//    distance within 2e-5 m, the normal within 1e-4 and the point within 5e-5 m.
//  - batched SIMD and the scalar instantiation of the same kernels: bit for bit (only + - * / sqrt min max select,
//    -ffp-contract=off), and the per-pair Manifold functions bit for bit with both.
//  - hand-made degenerate cases with exact expected answers.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "narrowphase/ccd_oracle.h"
#include "narrowphase/convex_pairs.h"
#include "narrowphase/gjk.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using rubble::test::OracleShape;

constexpr float kMargin = 0.05f;
constexpr double kOracleDepthTolerance = 2e-3;
// A direction error t changes the depth between round shapes by only ~R t^2 / 2, so libccd's directions are loose
// where its depths are tight: normals are compared where the depths agree within 2e-4 m, to within 11 degrees.
constexpr double kOracleNormalDepthBand = 2e-4;
constexpr double kOracleNormalDot = 0.98;

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> n(0.0f, 1.0f);
    Quat q{n(rng), n(rng), n(rng), n(rng)};
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    return {q.x / len, q.y / len, q.z / len, q.w / len};
}

Vec3 randomPoint(std::mt19937& rng, float extent) {
    std::uniform_real_distribution<float> u(-extent, extent);
    return {u(rng), u(rng), u(rng)};
}

float randomSize(std::mt19937& rng) { return std::uniform_real_distribution<float>(0.1f, 1.0f)(rng); }

OracleShape oracleSphere(Vec3 c, float r) {
    OracleShape s;
    s.kind = OracleShape::Kind::Sphere;
    s.radius = r;
    rubble::test::setPose(s, {c, {}});
    return s;
}
OracleShape oracleCapsule(const Transform& pose, float halfHeight, float r) {
    OracleShape s;
    s.kind = OracleShape::Kind::Capsule;
    s.radius = r;
    s.halfHeight = halfHeight;
    rubble::test::setPose(s, pose);
    return s;
}
OracleShape oracleBox(const Transform& pose, Vec3 h) {
    OracleShape s;
    s.kind = OracleShape::Kind::Box;
    s.half[0] = h.x, s.half[1] = h.y, s.half[2] = h.z;
    rubble::test::setPose(s, pose);
    return s;
}

GjkShape gjkSphere(Vec3 c, float r) {
    GjkShape g;
    g.radius = r;
    g.pose.position = c;
    return g;
}
GjkShape gjkCapsule(const Transform& pose, float halfHeight, float r) {
    GjkShape g;
    g.core = GjkShape::Core::Segment;
    g.radius = r;
    g.halfHeight = halfHeight;
    g.pose = pose;
    return g;
}
GjkShape gjkBox(const Transform& pose, Vec3 h) {
    GjkShape g;
    g.core = GjkShape::Core::Box;
    g.halfExtents = h;
    g.pose = pose;
    return g;
}

double dotD(Vec3 a, const double b[3]) { return a.x * b[0] + a.y * b[1] + a.z * b[2]; }

/// Statistics of one comparison run, so a test fails when the random poses stopped covering the cases.
struct Coverage {
    int oracle = 0, speculative = 0;
};

OracleShape moved(OracleShape s, const double dir[3], double distance) {
    for (int i = 0; i < 3; ++i) s.pos[i] += dir[i] * distance;
    return s;
}

/// Compares a manifold with the oracles: libccd (overlap) or our GJK (speculative).
/// Overlap: libccd's MPR intersection test (exact to ~1e-7) must say that moving B along our normal by depth + kBand
/// separates the shapes and by depth - kBand does not, so the depth along our normal is exact to kBand; and the depth
/// must not exceed libccd's own penetration answers (GJK+EPA and MPR, each used only when moving B by it separates
/// the shapes: EPA on round shapes sometimes returns a degenerate zero) by more than kOracleDepthTolerance, so no
/// other direction is clearly shorter. Where the depths agree, the normals must too.
void compare(const Manifold& m, int count, const OracleShape& oa, const OracleShape& ob, const GjkShape& ga,
             const GjkShape& gb, bool coreApart, Coverage& cov, int i) {
    constexpr double kBand = 1e-4;
    if (count > 0 && m.points[0].depth > 0.02f && coreApart) {
        float deepest = m.points[0].depth;
        for (int k = 1; k < count; ++k) deepest = std::max(deepest, m.points[k].depth);
        const double n[3] = {m.normal.x, m.normal.y, m.normal.z};
        EXPECT_FALSE(rubble::test::oracleMprIntersect(oa, moved(ob, n, deepest + kBand))) << i;
        EXPECT_TRUE(rubble::test::oracleMprIntersect(oa, moved(ob, n, deepest - kBand))) << i;
        double best = INFINITY;
        const double* bestDir = nullptr;
        const auto epa = rubble::test::oraclePenetration(oa, ob);
        const auto mpr = rubble::test::oracleMprPenetration(oa, ob);
        for (const auto* pen : {&epa, &mpr})
            if (pen->hit && pen->depth < best &&
                std::fabs(pen->dir[0] * pen->dir[0] + pen->dir[1] * pen->dir[1] + pen->dir[2] * pen->dir[2] - 1) <
                    1e-6 &&
                !rubble::test::oracleMprIntersect(oa, moved(ob, pen->dir, pen->depth + kBand)))
                best = pen->depth, bestDir = pen->dir;
        ASSERT_NE(bestDir, nullptr) << i;
        EXPECT_LT(deepest, best + kOracleDepthTolerance) << i;
        if (std::fabs(deepest - best) < kOracleNormalDepthBand) {
            EXPECT_GT(dotD(m.normal, bestDir), kOracleNormalDot) << i;
        }
        ++cov.oracle;
    }
    const GjkResult g = gjkDistance(ga, gb);
    if (g.status == GjkStatus::Separated && g.distance < kMargin - 1e-4f) {
        ASSERT_EQ(count, 1) << i << " d " << g.distance;
        EXPECT_NEAR(-m.points[0].depth, g.distance, 2e-5f) << i;
        EXPECT_NEAR(dot(m.normal, g.normal), 1.0f, 1e-4f) << i;
        EXPECT_NEAR(length(m.points[0].position - g.pointB), 0.0f, 5e-5f) << i;
        ++cov.speculative;
    } else if (g.status == GjkStatus::Separated && g.distance > kMargin + 1e-4f) {
        EXPECT_EQ(count, 0) << i;
    }
}

TEST(ConvexPairs, SpheresAgreeWithOracles) {
    std::mt19937 rng(1);
    Coverage cov;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 ca = randomPoint(rng, 1.0f), cb = randomPoint(rng, 1.0f);
        const float ra = randomSize(rng), rb = randomSize(rng);
        Manifold m;
        const int n = collideSpheres(ca, ra, cb, rb, kMargin, m);
        compare(m, n, oracleSphere(ca, ra), oracleSphere(cb, rb), gjkSphere(ca, ra), gjkSphere(cb, rb),
                length(cb - ca) > 0.01f, cov, i);
        if (n) {
            EXPECT_NEAR(length(m.points[0].position - cb), rb, 1e-6f);
        }
    }
    EXPECT_GT(cov.oracle, 500);
    EXPECT_GT(cov.speculative, 20);
}

TEST(ConvexPairs, SphereCapsulesAgreeWithOracles) {
    std::mt19937 rng(2);
    Coverage cov;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 ca = randomPoint(rng, 1.5f);
        const float ra = randomSize(rng);
        const Transform pose{randomPoint(rng, 1.5f), randomRotation(rng)};
        const float hh = randomSize(rng), rb = 0.5f * randomSize(rng);
        const CapsuleSegment b = capsuleSegmentOf(pose, hh, rb);
        Manifold m;
        const int n = collideSphereCapsule(ca, ra, b, kMargin, m);
        const float axisDistance = ra + rb - (n ? m.points[0].depth : 0.0f);
        compare(m, n, oracleSphere(ca, ra), oracleCapsule(pose, hh, rb), gjkSphere(ca, ra), gjkCapsule(pose, hh, rb),
                axisDistance > 0.01f, cov, i);
    }
    EXPECT_GT(cov.oracle, 300);
    EXPECT_GT(cov.speculative, 20);
}

TEST(ConvexPairs, CapsulesAgreeWithOracles) {
    std::mt19937 rng(3);
    Coverage cov;
    for (int i = 0; i < 4000; ++i) {
        const Transform pa{randomPoint(rng, 1.5f), randomRotation(rng)};
        Transform pb{randomPoint(rng, 1.5f), randomRotation(rng)};
        if (i % 8 == 0) pb.rotation = pa.rotation;  // exactly parallel
        const float ha = randomSize(rng), hb = randomSize(rng), ra = 0.5f * randomSize(rng),
                    rb = 0.5f * randomSize(rng);
        Manifold m;
        const int n = collideCapsules(capsuleSegmentOf(pa, ha, ra), capsuleSegmentOf(pb, hb, rb), kMargin, m);
        // Axes closer than 1 cm: the kernel's depth is rA + rB along a chosen normal, not the minimum translation.
        const GjkResult core = gjkDistance(gjkCapsule(pa, ha, 0), gjkCapsule(pb, hb, 0));
        const bool apart = core.status == GjkStatus::Separated && core.distance > 0.01f;
        if (n == 2) {
            // Parallel: both points lie on B's surface, with the normal perpendicular to A's axis.
            const Vec3 axisA = rotate(pa.rotation, Vec3{0, 1, 0});
            EXPECT_NEAR(dot(m.normal, axisA), 0.0f, 1e-5f) << i;
            EXPECT_NEAR(m.points[0].depth, m.points[1].depth, 2e-5f) << i;
            continue;
        }
        compare(m, n, oracleCapsule(pa, ha, ra), oracleCapsule(pb, hb, rb), gjkCapsule(pa, ha, ra),
                gjkCapsule(pb, hb, rb), apart, cov, i);
    }
    EXPECT_GT(cov.oracle, 300);
    EXPECT_GT(cov.speculative, 20);
}

TEST(ConvexPairs, SphereBoxesAgreeWithOracles) {
    std::mt19937 rng(4);
    Coverage cov;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 ca = randomPoint(rng, 1.5f);
        const float ra = randomSize(rng);
        const Transform pose{randomPoint(rng, 1.0f), randomRotation(rng)};
        const Vec3 h{randomSize(rng), randomSize(rng), randomSize(rng)};
        Manifold m;
        const int n = collideSphereBox(ca, ra, pose, h, kMargin, m);
        compare(m, n, oracleSphere(ca, ra), oracleBox(pose, h), gjkSphere(ca, ra), gjkBox(pose, h), true, cov, i);
    }
    EXPECT_GT(cov.oracle, 500);
    EXPECT_GT(cov.speculative, 20);
}

// ---- Batched SIMD against scalar ---------------------------------------------------------------------------------

/// Output arrays for n pairs.
struct Outputs {
    std::vector<float> nx, ny, nz, px, py, pz, depth, qx, qy, qz, depth1;
    std::vector<std::uint32_t> feature, feature1;
    std::vector<std::int32_t> count;
    explicit Outputs(std::size_t n)
        : nx(n),
          ny(n),
          nz(n),
          px(n),
          py(n),
          pz(n),
          depth(n),
          qx(n),
          qy(n),
          qz(n),
          depth1(n),
          feature(n),
          feature1(n),
          count(n) {}
    PairContacts view() {
        return {nx.data(),      ny.data(),    nz.data(), px.data(), py.data(), pz.data(),     depth.data(),
                feature.data(), count.data(), qx.data(), qy.data(), qz.data(), depth1.data(), feature1.data()};
    }
};

void expectBitEqual(const std::vector<float>& a, const std::vector<float>& b, const char* what) {
    for (std::size_t i = 0; i < a.size(); ++i)
        ASSERT_EQ(std::bit_cast<std::uint32_t>(a[i]), std::bit_cast<std::uint32_t>(b[i]))
            << what << "[" << i << "] " << a[i] << " vs " << b[i];
}

void expectSame(const Outputs& a, const Outputs& b, bool second) {
    expectBitEqual(a.nx, b.nx, "nx");
    expectBitEqual(a.ny, b.ny, "ny");
    expectBitEqual(a.nz, b.nz, "nz");
    expectBitEqual(a.px, b.px, "px");
    expectBitEqual(a.py, b.py, "py");
    expectBitEqual(a.pz, b.pz, "pz");
    expectBitEqual(a.depth, b.depth, "depth");
    EXPECT_EQ(a.feature, b.feature);
    EXPECT_EQ(a.count, b.count);
    if (second) {
        expectBitEqual(a.qx, b.qx, "qx");
        expectBitEqual(a.qy, b.qy, "qy");
        expectBitEqual(a.qz, b.qz, "qz");
        expectBitEqual(a.depth1, b.depth1, "depth1");
        EXPECT_EQ(a.feature1, b.feature1);
    }
}

/// The Manifold of pair i as the batched output describes it.
void expectManifoldMatches(const Manifold& m, int count, const Outputs& o, std::size_t i) {
    ASSERT_EQ(count, o.count[i]) << i;
    if (count == 0) return;
    EXPECT_EQ(m.normal, (Vec3{o.nx[i], o.ny[i], o.nz[i]})) << i;
    EXPECT_EQ(m.points[0].position, (Vec3{o.px[i], o.py[i], o.pz[i]})) << i;
    EXPECT_EQ(m.points[0].depth, o.depth[i]) << i;
    EXPECT_EQ(m.points[0].feature, o.feature[i]) << i;
    if (count > 1) {
        EXPECT_EQ(m.points[1].position, (Vec3{o.qx[i], o.qy[i], o.qz[i]})) << i;
        EXPECT_EQ(m.points[1].depth, o.depth1[i]) << i;
    }
}

constexpr std::size_t kBatch = 1003;  // not a multiple of the lane count: the scalar tail runs too

struct SoA3 {
    std::vector<float> x, y, z;
    explicit SoA3(std::size_t n) : x(n), y(n), z(n) {}
    void set(std::size_t i, Vec3 v) { x[i] = v.x, y[i] = v.y, z[i] = v.z; }
    Vec3 get(std::size_t i) const { return {x[i], y[i], z[i]}; }
};

TEST(ConvexPairs, BatchedSpheresMatchScalarBitForBit) {
    std::mt19937 rng(11);
    SoA3 a(kBatch), b(kBatch);
    std::vector<float> ra(kBatch), rb(kBatch);
    for (std::size_t i = 0; i < kBatch; ++i) {
        a.set(i, randomPoint(rng, 1.0f));
        b.set(i, i % 17 == 0 ? a.get(i) : randomPoint(rng, 1.0f));  // some coincident centres
        ra[i] = randomSize(rng), rb[i] = randomSize(rng);
    }
    const SpherePairs in{a.x.data(), a.y.data(), a.z.data(), ra.data(), b.x.data(), b.y.data(), b.z.data(), rb.data()};
    Outputs wide(kBatch), scalar(kBatch);
    collideSpheresBatch(in, kBatch, kMargin, wide.view());
    collideSpheresBatchScalar(in, kBatch, kMargin, scalar.view());
    expectSame(wide, scalar, false);
    for (std::size_t i = 0; i < kBatch; ++i) {
        Manifold m;
        expectManifoldMatches(m, collideSpheres(a.get(i), ra[i], b.get(i), rb[i], kMargin, m), wide, i);
    }
}

TEST(ConvexPairs, BatchedSphereCapsulesMatchScalarBitForBit) {
    std::mt19937 rng(12);
    SoA3 a(kBatch), b(kBatch), h(kBatch);
    std::vector<float> ra(kBatch), rb(kBatch);
    for (std::size_t i = 0; i < kBatch; ++i) {
        const CapsuleSegment c = capsuleSegmentOf({randomPoint(rng, 1.0f), randomRotation(rng)},
                                                  i % 13 == 0 ? 0.0f : randomSize(rng), 0.5f * randomSize(rng));
        b.set(i, c.center), h.set(i, c.halfAxis), rb[i] = c.radius;
        a.set(i, i % 11 == 0 ? c.center + c.halfAxis * 0.5f : randomPoint(rng, 1.0f));  // some on the axis
        ra[i] = randomSize(rng);
    }
    const SphereCapsulePairs in{a.x.data(), a.y.data(), a.z.data(), ra.data(),  b.x.data(), b.y.data(),
                                b.z.data(), h.x.data(), h.y.data(), h.z.data(), rb.data()};
    Outputs wide(kBatch), scalar(kBatch);
    collideSphereCapsulesBatch(in, kBatch, kMargin, wide.view());
    collideSphereCapsulesBatchScalar(in, kBatch, kMargin, scalar.view());
    expectSame(wide, scalar, false);
    for (std::size_t i = 0; i < kBatch; ++i) {
        Manifold m;
        expectManifoldMatches(m, collideSphereCapsule(a.get(i), ra[i], {b.get(i), h.get(i), rb[i]}, kMargin, m), wide,
                              i);
    }
}

TEST(ConvexPairs, BatchedCapsulesMatchScalarBitForBit) {
    std::mt19937 rng(13);
    SoA3 a(kBatch), ah(kBatch), b(kBatch), bh(kBatch);
    std::vector<float> ra(kBatch), rb(kBatch);
    int twoPoints = 0;
    for (std::size_t i = 0; i < kBatch; ++i) {
        const Transform pa{randomPoint(rng, 1.0f), randomRotation(rng)};
        Transform pb{randomPoint(rng, 1.0f), randomRotation(rng)};
        if (i % 5 == 0) pb.rotation = pa.rotation;
        if (i % 23 == 0) pb.position = pa.position;
        const CapsuleSegment ca = capsuleSegmentOf(pa, i % 7 == 0 ? 0.0f : randomSize(rng), 0.5f * randomSize(rng));
        const CapsuleSegment cb = capsuleSegmentOf(pb, i % 9 == 0 ? 0.0f : randomSize(rng), 0.5f * randomSize(rng));
        a.set(i, ca.center), ah.set(i, ca.halfAxis), ra[i] = ca.radius;
        b.set(i, cb.center), bh.set(i, cb.halfAxis), rb[i] = cb.radius;
    }
    const CapsulePairs in{a.x.data(), a.y.data(), a.z.data(), ah.x.data(), ah.y.data(), ah.z.data(), ra.data(),
                          b.x.data(), b.y.data(), b.z.data(), bh.x.data(), bh.y.data(), bh.z.data(), rb.data()};
    Outputs wide(kBatch), scalar(kBatch);
    collideCapsulesBatch(in, kBatch, kMargin, wide.view());
    collideCapsulesBatchScalar(in, kBatch, kMargin, scalar.view());
    expectSame(wide, scalar, true);
    for (std::size_t i = 0; i < kBatch; ++i) {
        Manifold m;
        const int n = collideCapsules({a.get(i), ah.get(i), ra[i]}, {b.get(i), bh.get(i), rb[i]}, kMargin, m);
        expectManifoldMatches(m, n, wide, i);
        twoPoints += n == 2;
    }
    EXPECT_GT(twoPoints, 10);
}

TEST(ConvexPairs, BatchedSphereBoxesMatchScalarBitForBit) {
    std::mt19937 rng(14);
    SoA3 a(kBatch), b(kBatch), e(kBatch);
    std::vector<float> ra(kBatch), qx(kBatch), qy(kBatch), qz(kBatch), qw(kBatch);
    for (std::size_t i = 0; i < kBatch; ++i) {
        const Quat q = i % 3 == 0 ? Quat{} : randomRotation(rng);
        const Vec3 c = randomPoint(rng, 1.0f);
        const Vec3 h{randomSize(rng), randomSize(rng), randomSize(rng)};
        b.set(i, c), e.set(i, h);
        qx[i] = q.x, qy[i] = q.y, qz[i] = q.z, qw[i] = q.w;
        // Some centres exactly on a face, an edge or a vertex of an axis-aligned box, some at its centre.
        const int special = static_cast<int>(i % 12);
        Vec3 p = randomPoint(rng, 1.5f);
        if (i % 3 == 0 && special == 0) p = c + Vec3{h.x, 0.1f * h.y, 0};
        if (i % 3 == 0 && special == 3) p = c + Vec3{h.x, -h.y, 0};
        if (i % 3 == 0 && special == 6) p = c + Vec3{-h.x, h.y, h.z};
        if (i % 3 == 0 && special == 9) p = c;
        a.set(i, p);
        ra[i] = randomSize(rng);
    }
    const SphereBoxPairs in{a.x.data(), a.y.data(), a.z.data(), ra.data(), b.x.data(), b.y.data(), b.z.data(),
                            qx.data(),  qy.data(),  qz.data(),  qw.data(), e.x.data(), e.y.data(), e.z.data()};
    Outputs wide(kBatch), scalar(kBatch);
    collideSphereBoxesBatch(in, kBatch, kMargin, wide.view());
    collideSphereBoxesBatchScalar(in, kBatch, kMargin, scalar.view());
    expectSame(wide, scalar, false);
    for (std::size_t i = 0; i < kBatch; ++i) {
        Manifold m;
        const int n = collideSphereBox(a.get(i), ra[i], {b.get(i), {qx[i], qy[i], qz[i], qw[i]}}, e.get(i), kMargin, m);
        expectManifoldMatches(m, n, wide, i);
    }
}

TEST(ConvexPairs, BatchedKernelsTakeEachPairsOwnMargin) {
    // The stage's speculative margins: each pair's margin from the batch's array, in lanes and in the tail, exactly
    // as the per-pair kernel with that margin; and the margin decides (pairs apart by more than the uniform margin
    // but within their own are reported).
    std::mt19937 rng(15);
    std::uniform_real_distribution<float> marginOf(0.0f, 0.6f);
    SoA3 a(kBatch), ah(kBatch), b(kBatch), bh(kBatch);
    std::vector<float> ra(kBatch), rb(kBatch), margins(kBatch);
    for (std::size_t i = 0; i < kBatch; ++i) {
        const CapsuleSegment ca =
            capsuleSegmentOf({randomPoint(rng, 1.5f), randomRotation(rng)}, randomSize(rng), 0.5f * randomSize(rng));
        const CapsuleSegment cb =
            capsuleSegmentOf({randomPoint(rng, 1.5f), randomRotation(rng)}, randomSize(rng), 0.5f * randomSize(rng));
        a.set(i, ca.center), ah.set(i, ca.halfAxis), ra[i] = ca.radius;
        b.set(i, cb.center), bh.set(i, cb.halfAxis), rb[i] = cb.radius;
        margins[i] = marginOf(rng);
    }
    int beyondUniform = 0;
    {
        SpherePairs in{a.x.data(), a.y.data(), a.z.data(), ra.data(), b.x.data(), b.y.data(), b.z.data(), rb.data()};
        in.margin = margins.data();
        Outputs wide(kBatch), scalar(kBatch);
        collideSpheresBatch(in, kBatch, kMargin, wide.view());
        collideSpheresBatchScalar(in, kBatch, kMargin, scalar.view());
        expectSame(wide, scalar, false);
        for (std::size_t i = 0; i < kBatch; ++i) {
            Manifold m;
            const int n = collideSpheres(a.get(i), ra[i], b.get(i), rb[i], margins[i], m);
            expectManifoldMatches(m, n, wide, i);
            beyondUniform += n > 0 && m.points[0].depth < -kMargin;
        }
    }
    {
        CapsulePairs in{a.x.data(), a.y.data(), a.z.data(), ah.x.data(), ah.y.data(), ah.z.data(), ra.data(),
                        b.x.data(), b.y.data(), b.z.data(), bh.x.data(), bh.y.data(), bh.z.data(), rb.data()};
        in.margin = margins.data();
        Outputs wide(kBatch), scalar(kBatch);
        collideCapsulesBatch(in, kBatch, kMargin, wide.view());
        collideCapsulesBatchScalar(in, kBatch, kMargin, scalar.view());
        expectSame(wide, scalar, true);
        for (std::size_t i = 0; i < kBatch; ++i) {
            Manifold m;
            const int n = collideCapsules({a.get(i), ah.get(i), ra[i]}, {b.get(i), bh.get(i), rb[i]}, margins[i], m);
            expectManifoldMatches(m, n, wide, i);
            beyondUniform += n > 0 && m.points[0].depth < -kMargin;
        }
    }
    EXPECT_GT(beyondUniform, 20);
}

// ---- Degenerate and hand-made cases --------------------------------------------------------------------------

TEST(ConvexPairs, CoincidentSpheresPushAlongPlusY) {
    Manifold m;
    ASSERT_EQ(collideSpheres({1, 2, 3}, 0.5f, {1, 2, 3}, 0.25f, kMargin, m), 1);
    EXPECT_EQ(m.normal, (Vec3{0, 1, 0}));
    EXPECT_EQ(m.points[0].depth, 0.75f);
    EXPECT_EQ(m.points[0].position, (Vec3{1, 1.75f, 3}));
    // Separated beyond the margin: nothing; within it: a speculative point.
    EXPECT_EQ(collideSpheres({0, 0, 0}, 0.5f, {2, 0, 0}, 0.5f, kMargin, m), 0);
    ASSERT_EQ(collideSpheres({0, 0, 0}, 0.5f, {1.04f, 0, 0}, 0.5f, kMargin, m), 1);
    EXPECT_NEAR(m.points[0].depth, -0.04f, 1e-6f);
    EXPECT_EQ(m.points[0].feature, 0u);
}

TEST(ConvexPairs, SphereCentreOnBoxFacesEdgesAndVertices) {
    const Transform box{{0, 0, 0}, {}};
    const Vec3 h{1, 2, 3};
    Manifold m;
    // On the +x face: pushed out along +x, so the normal A->B is -x; depth is the radius.
    ASSERT_EQ(collideSphereBox({1, 0.5f, 0}, 0.25f, box, h, kMargin, m), 1);
    EXPECT_EQ(m.normal, (Vec3{-1, 0, 0}));
    EXPECT_EQ(m.points[0].depth, 0.25f);
    EXPECT_EQ(m.points[0].position, (Vec3{1, 0.5f, 0}));
    EXPECT_EQ(m.points[0].feature, 2u);  // +x face
    // On the edge x = +1, y = -2: a tie between two faces goes to x.
    ASSERT_EQ(collideSphereBox({1, -2, 0}, 0.25f, box, h, kMargin, m), 1);
    EXPECT_EQ(m.normal, (Vec3{-1, 0, 0}));
    EXPECT_EQ(m.points[0].feature, 2u + 1u * 3u);  // +x, -y edge
    // On the vertex (-1, 2, 3).
    ASSERT_EQ(collideSphereBox({-1, 2, 3}, 0.25f, box, h, kMargin, m), 1);
    EXPECT_EQ(m.normal, (Vec3{1, 0, 0}));
    EXPECT_EQ(m.points[0].feature, 1u + 2u * 3u + 2u * 9u);
    // At the box centre: least penetration through the x faces, the + one.
    ASSERT_EQ(collideSphereBox({0, 0, 0}, 0.25f, box, h, kMargin, m), 1);
    EXPECT_EQ(m.normal, (Vec3{-1, 0, 0}));
    EXPECT_EQ(m.points[0].depth, 1.25f);
    // Outside, off a vertex: the closest point is the vertex.
    ASSERT_EQ(collideSphereBox({2, 3, 4}, 1.8f, box, h, kMargin, m), 1);
    EXPECT_EQ(m.points[0].position, (Vec3{1, 2, 3}));
    EXPECT_NEAR(m.points[0].depth, 1.8f - std::sqrt(3.0f), 1e-6f);
    // The feature id of a face contact does not change as the centre crosses the face.
    Manifold outside, inside;
    collideSphereBox({0.3f, 2.01f, 0.2f}, 0.25f, box, h, kMargin, outside);
    collideSphereBox({0.3f, 1.99f, 0.2f}, 0.25f, box, h, kMargin, inside);
    EXPECT_EQ(outside.points[0].feature, inside.points[0].feature);
    EXPECT_EQ(outside.normal, inside.normal);
}

TEST(ConvexPairs, ParallelCapsulesGiveTwoPointsAndDoNotRock) {
    // B lies on A along x, shifted: the overlap is x in [-0.5, 1], both points equally deep.
    const Quat alongX = Quat::fromAxisAngle({0, 0, 1}, -1.5707964f);
    const CapsuleSegment a = capsuleSegmentOf({{0, 0, 0}, alongX}, 1.0f, 0.5f);
    const CapsuleSegment b = capsuleSegmentOf({{0.5f, 0.95f, 0}, alongX}, 1.0f, 0.5f);
    Manifold m;
    ASSERT_EQ(collideCapsules(a, b, kMargin, m), 2);
    EXPECT_NEAR(m.normal.y, 1.0f, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.05f, 1e-5f);
    EXPECT_NEAR(m.points[1].depth, 0.05f, 1e-5f);
    EXPECT_NEAR(std::min(m.points[0].position.x, m.points[1].position.x), -0.5f, 1e-5f);
    EXPECT_NEAR(std::max(m.points[0].position.x, m.points[1].position.x), 1.0f, 1e-5f);
    EXPECT_NEAR(m.points[0].position.y, 0.45f, 1e-5f);
    EXPECT_NE(m.points[0].feature, m.points[1].feature);
    // Slightly tilted (0.2 degrees): still two points, with depths that follow the tilt.
    const Quat tilted = Quat::fromAxisAngle({0, 0, 1}, -1.5707964f + 0.0035f);
    ASSERT_EQ(collideCapsules(a, capsuleSegmentOf({{0.5f, 0.95f, 0}, tilted}, 1.0f, 0.5f), kMargin, m), 2);
    EXPECT_GT(std::fabs(m.points[0].depth - m.points[1].depth), 1e-3f);
    // Collinear overlapping axes: a deterministic normal perpendicular to the axes.
    ASSERT_EQ(collideCapsules(a, capsuleSegmentOf({{0.5f, 0, 0}, alongX}, 1.0f, 0.5f), kMargin, m), 2);
    EXPECT_NEAR(m.normal.x, 0.0f, 1e-6f);
    EXPECT_NEAR(length(m.normal), 1.0f, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 1.0f, 1e-6f);
}

TEST(ConvexPairs, CrossingCapsulesAndZeroHeightCapsules) {
    const CapsuleSegment a = capsuleSegmentOf({{0, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, 1.5707964f)}, 1.0f, 0.5f);
    const CapsuleSegment b = capsuleSegmentOf({{0, 0.9f, 0}, Quat::fromAxisAngle({1, 0, 0}, 1.5707964f)}, 1.0f, 0.5f);
    Manifold m;
    ASSERT_EQ(collideCapsules(a, b, kMargin, m), 1);
    EXPECT_NEAR(m.normal.y, 1.0f, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.1f, 1e-6f);
    EXPECT_EQ(m.points[0].feature, 0u);  // interior against interior
    // Intersecting axes: normal of the plane of both axes, oriented A->B.
    ASSERT_EQ(collideCapsules(a, capsuleSegmentOf({{0, 0, 0}, Quat::fromAxisAngle({1, 0, 0}, 1.5707964f)}, 1, 0.5f),
                              kMargin, m),
              1);
    EXPECT_NEAR(std::fabs(m.normal.y), 1.0f, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 1.0f, 1e-6f);
    // Zero half height on both sides: exactly the sphere-sphere answer.
    Manifold s;
    const CapsuleSegment p = capsuleSegmentOf({{0.1f, 0.2f, 0.3f}, {}}, 0.0f, 0.4f);
    const CapsuleSegment q = capsuleSegmentOf({{0.5f, 0.1f, 0.2f}, {}}, 0.0f, 0.3f);
    ASSERT_EQ(collideCapsules(p, q, kMargin, m), 1);
    ASSERT_EQ(collideSpheres(p.center, p.radius, q.center, q.radius, kMargin, s), 1);
    EXPECT_NEAR(m.points[0].depth, s.points[0].depth, 1e-6f);
    EXPECT_NEAR(dot(m.normal, s.normal), 1.0f, 1e-6f);
    // A sphere against a zero-height capsule likewise.
    ASSERT_EQ(collideSphereCapsule(p.center, p.radius, q, kMargin, m), 1);
    EXPECT_EQ(m.points[0].depth, s.points[0].depth);
}

TEST(ConvexPairs, HugeCoordinatesGiveTheSameContactsAsNearTheOrigin) {
    // Offsets and local coordinates chosen so that every world coordinate is exact in float (multiples of 2^-10
    // below 2^14): relative vectors are then identical, and so are depths and normals.
    const Vec3 far{10240.0f, -10240.0f, 10240.0f};
    std::mt19937 rng(21);
    std::uniform_int_distribution<int> u(-1024, 1024);
    const auto grid = [&] { return Vec3{u(rng) / 1024.0f, u(rng) / 1024.0f, u(rng) / 1024.0f}; };
    for (int i = 0; i < 500; ++i) {
        const Vec3 c0 = grid(), c1 = grid(), h0 = grid() * 0.5f, h1 = grid() * 0.5f;
        Manifold near, away;
        const int n = collideCapsules({c0, h0, 0.5f}, {c1, h1, 0.4f}, kMargin, near);
        ASSERT_EQ(collideCapsules({c0 + far, h0, 0.5f}, {c1 + far, h1, 0.4f}, kMargin, away), n);
        for (int k = 0; k < n; ++k) {
            EXPECT_EQ(near.points[k].depth, away.points[k].depth);
            EXPECT_NEAR(length(away.points[k].position - far - near.points[k].position), 0.0f, 2e-3f);
        }
        if (n) {
            EXPECT_EQ(near.normal, away.normal);
        }
        const int s = collideSphereBox(c0, 0.5f, {c1, {}}, {0.5f, 0.25f, 0.75f}, kMargin, near);
        ASSERT_EQ(collideSphereBox(c0 + far, 0.5f, {c1 + far, {}}, {0.5f, 0.25f, 0.75f}, kMargin, away), s);
        if (s) {
            EXPECT_EQ(near.points[0].depth, away.points[0].depth);
            EXPECT_EQ(near.normal, away.normal);
        }
        const int t = collideSpheres(c0, 0.5f, c1, 0.6f, kMargin, near);
        ASSERT_EQ(collideSpheres(c0 + far, 0.5f, c1 + far, 0.6f, kMargin, away), t);
        if (t) {
            EXPECT_EQ(near.points[0].depth, away.points[0].depth);
        }
    }
}

}  // namespace
