// GJK distance against independent answers: analytic distances (sphere-sphere, sphere-box by clamping in double,
// segment-segment by dense sampling refined by ternary search), brute-force checks of the closest points and of the
// separating gap over the vertices, and libccd's GJK intersection test as the overlap oracle.
//
// Tolerances (shapes 0.1 .. 2 m): distances within 2e-5 m of analytic answers (GJK runs in double with a relative
// stopping tolerance of 1e-6; the result is rounded to float); overlap answers must agree with libccd except within
// a 1e-4 m band around touching (libccd and GJK both stop at tolerances of that order for curved shapes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "narrowphase/ccd_oracle.h"
#include "narrowphase/gjk.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using rubble::test::OracleShape;

constexpr double kDistanceTolerance = 2e-5;
constexpr double kBand = 1e-4;

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> n(0.0f, 1.0f);
    Quat q{n(rng), n(rng), n(rng), n(rng)};
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    return {q.x / len, q.y / len, q.z / len, q.w / len};
}

/// A random shape of one kind, as GjkShape and as the oracle's independent description.
struct TestShape {
    GjkShape gjk;
    OracleShape oracle;
    std::shared_ptr<ConvexHull> hull;
};

TestShape randomShape(int kind, std::mt19937& rng, Vec3 offset = {}) {
    std::uniform_real_distribution<float> size(0.1f, 1.0f), pos(-1.5f, 1.5f), unit(-1.0f, 1.0f);
    TestShape s;
    Transform pose{{pos(rng) + offset.x, pos(rng) + offset.y, pos(rng) + offset.z}, randomRotation(rng)};
    switch (kind) {
        case 0:
            s.gjk.core = GjkShape::Core::Point;
            s.gjk.radius = size(rng);
            s.oracle.kind = OracleShape::Kind::Sphere;
            s.oracle.radius = s.gjk.radius;
            break;
        case 1:
            s.gjk.core = GjkShape::Core::Segment;
            s.gjk.radius = size(rng) * 0.5f;
            s.gjk.halfHeight = size(rng);
            s.oracle.kind = OracleShape::Kind::Capsule;
            s.oracle.radius = s.gjk.radius;
            s.oracle.halfHeight = s.gjk.halfHeight;
            break;
        case 2:
            s.gjk.core = GjkShape::Core::Box;
            s.gjk.halfExtents = {size(rng), size(rng), size(rng)};
            s.oracle.kind = OracleShape::Kind::Box;
            s.oracle.half[0] = s.gjk.halfExtents.x, s.oracle.half[1] = s.gjk.halfExtents.y,
            s.oracle.half[2] = s.gjk.halfExtents.z;
            break;
        default: {
            std::vector<Vec3> pts;
            const float scale = size(rng);
            for (int i = 0; i < 12; ++i) pts.push_back(Vec3{unit(rng), unit(rng), unit(rng)} * scale);
            s.hull = std::make_shared<ConvexHull>(buildConvexHull(pts));
            s.gjk.core = GjkShape::Core::Points;
            s.gjk.points = s.hull->vertices.data();
            s.gjk.pointCount = static_cast<std::uint32_t>(s.hull->vertices.size());
            s.oracle.kind = OracleShape::Kind::Hull;
            s.oracle.points = s.hull->vertices;
            break;
        }
    }
    s.gjk.pose = pose;
    rubble::test::setPose(s.oracle, pose);
    return s;
}

double dist(Vec3 a, Vec3 b) {
    const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// Signed distance of a world point to the shape's surface (negative inside), brute force in double.
double signedDistance(const TestShape& s, Vec3 world) {
    // To the local frame in double.
    const Quat& q = s.gjk.pose.rotation;
    const double qi[4] = {-double(q.x), -double(q.y), -double(q.z), double(q.w)};
    const double v[3] = {double(world.x) - s.gjk.pose.position.x, double(world.y) - s.gjk.pose.position.y,
                         double(world.z) - s.gjk.pose.position.z};
    double p[3];
    OracleShape::rot(qi, v, p);
    switch (s.gjk.core) {
        case GjkShape::Core::Point:
            return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - s.gjk.radius;
        case GjkShape::Core::Segment: {
            const double y = std::clamp(p[1], -double(s.gjk.halfHeight), double(s.gjk.halfHeight));
            return std::sqrt(p[0] * p[0] + (p[1] - y) * (p[1] - y) + p[2] * p[2]) - s.gjk.radius;
        }
        case GjkShape::Core::Box: {
            const double h[3] = {s.gjk.halfExtents.x, s.gjk.halfExtents.y, s.gjk.halfExtents.z};
            double out2 = 0, inside = -INFINITY;
            for (int i = 0; i < 3; ++i) {
                const double d = std::fabs(p[i]) - h[i];
                if (d > 0) out2 += d * d;
                inside = std::max(inside, d);
            }
            return out2 > 0 ? std::sqrt(out2) : inside;
        }
        case GjkShape::Core::Points: {
            double m = -INFINITY;  // max plane distance: exact inside, a lower bound outside
            for (std::uint32_t f = 0; f < s.hull->faceCount(); ++f) {
                const Vec3 n = s.hull->faceNormals[f];
                m = std::max(m, n.x * p[0] + n.y * p[1] + n.z * p[2] - s.hull->faceOffsets[f]);
            }
            return m;
        }
    }
    return 0;
}

/// Largest projection of the swept shape onto n (brute force over vertices; spheres and capsules analytically).
double maxAlong(const TestShape& s, const double n[3]) {
    double out[3];
    s.oracle.support(n, out);
    return out[0] * n[0] + out[1] * n[1] + out[2] * n[2];
}

/// Segment-segment distance by dense sampling of A's parameter and a ternary refinement of the convex distance.
double segmentDistance(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1) {
    auto toB = [&](double s) {
        const double p[3] = {a0.x + s * (double(a1.x) - a0.x), a0.y + s * (double(a1.y) - a0.y),
                             a0.z + s * (double(a1.z) - a0.z)};
        const double d[3] = {double(b1.x) - b0.x, double(b1.y) - b0.y, double(b1.z) - b0.z};
        const double w[3] = {p[0] - b0.x, p[1] - b0.y, p[2] - b0.z};
        const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double t = dd > 0 ? std::clamp((w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd, 0.0, 1.0) : 0.0;
        const double e[3] = {w[0] - t * d[0], w[1] - t * d[1], w[2] - t * d[2]};
        return std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    };
    constexpr int kSamples = 2000;
    int best = 0;
    for (int i = 1; i <= kSamples; ++i)
        if (toB(double(i) / kSamples) < toB(double(best) / kSamples)) best = i;
    double lo = std::max(0, best - 1) / double(kSamples), hi = std::min(kSamples, best + 1) / double(kSamples);
    for (int it = 0; it < 200; ++it) {
        const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
        if (toB(m1) < toB(m2))
            hi = m2;
        else
            lo = m1;
    }
    return toB(0.5 * (lo + hi));
}

TEST(Gjk, SphereSphereMatchesAnalyticDistance) {
    std::mt19937 rng(1);
    for (int i = 0; i < 4000; ++i) {
        const TestShape a = randomShape(0, rng), b = randomShape(0, rng);
        const double expected = dist(a.gjk.pose.position, b.gjk.pose.position) - a.gjk.radius - b.gjk.radius;
        const GjkResult r = gjkDistance(a.gjk, b.gjk);
        ASSERT_NE(r.status, GjkStatus::CoresOverlap) << i;
        EXPECT_NEAR(r.distance, expected, kDistanceTolerance) << i;
        EXPECT_EQ(r.status == GjkStatus::Separated, r.distance > 0);
        EXPECT_NEAR(dist(r.pointA, a.gjk.pose.position), a.gjk.radius, kDistanceTolerance);
        EXPECT_NEAR(dist(r.pointB, b.gjk.pose.position), b.gjk.radius, kDistanceTolerance);
    }
}

TEST(Gjk, SphereBoxMatchesClampedDistance) {
    std::mt19937 rng(2);
    int separated = 0;
    for (int i = 0; i < 4000; ++i) {
        const TestShape a = randomShape(0, rng), b = randomShape(2, rng);
        const double centreToBox = signedDistance(b, a.gjk.pose.position);
        const GjkResult r = gjkDistance(a.gjk, b.gjk);
        if (centreToBox < -1e-5) {
            EXPECT_EQ(r.status, GjkStatus::CoresOverlap) << i;
            continue;
        }
        if (centreToBox < 1e-5) continue;  // centre on the surface: either answer
        ASSERT_NE(r.status, GjkStatus::CoresOverlap) << i;
        EXPECT_NEAR(r.distance, centreToBox - a.gjk.radius, kDistanceTolerance) << i;
        EXPECT_NEAR(signedDistance(b, r.pointB), 0.0, kDistanceTolerance) << i;
        separated += r.status == GjkStatus::Separated;
    }
    EXPECT_GT(separated, 1000);
}

TEST(Gjk, CapsuleCapsuleMatchesSampledSegmentDistance) {
    std::mt19937 rng(3);
    for (int i = 0; i < 2000; ++i) {
        TestShape a = randomShape(1, rng), b = randomShape(1, rng);
        if (i % 10 == 0) b.gjk.pose.rotation = a.gjk.pose.rotation;  // parallel axes
        if (i % 10 == 1) a.gjk.halfHeight = 0;                       // a sphere
        const auto ends = [](const GjkShape& s, Vec3& e0, Vec3& e1) {
            const Vec3 h = rotate(s.pose.rotation, Vec3{0, s.halfHeight, 0});
            e0 = s.pose.position - h, e1 = s.pose.position + h;
        };
        Vec3 a0, a1, b0, b1;
        ends(a.gjk, a0, a1), ends(b.gjk, b0, b1);
        const double core = segmentDistance(a0, a1, b0, b1);
        const GjkResult r = gjkDistance(a.gjk, b.gjk);
        if (core < 1e-5) {
            EXPECT_EQ(r.status, GjkStatus::CoresOverlap) << i;
            continue;
        }
        ASSERT_NE(r.status, GjkStatus::CoresOverlap) << i << " core " << core;
        // Segment rounding from float endpoints is ~1e-7; the sampled reference is exact to ~1e-12.
        EXPECT_NEAR(r.distance, core - a.gjk.radius - b.gjk.radius, kDistanceTolerance) << i;
    }
}

/// Every pair of kinds: our overlap answer agrees with libccd outside a kBand band; separated answers are proven
/// minimal by brute force (closest points lie on the surfaces, and the gap along the normal equals the distance).
void checkAgainstOracle(int kindA, int kindB, Vec3 offset, unsigned seed) {
    std::mt19937 rng(seed);
    int separated = 0, overlapping = 0;
    for (int i = 0; i < 1500; ++i) {
        TestShape a = randomShape(kindA, rng, offset), b = randomShape(kindB, rng, offset);
        const GjkResult r = gjkDistance(a.gjk, b.gjk);
        if (r.status == GjkStatus::Separated && r.distance > kBand) {
            ++separated;
            EXPECT_FALSE(rubble::test::oracleIntersect(a.oracle, b.oracle)) << i << " d " << r.distance;
            EXPECT_NEAR(dist(r.pointA, r.pointB), r.distance, 1e-5 + 1e-6 * std::fabs(offset.x));
            const double slack = 2e-5 + 2e-7 * std::fabs(offset.x);
            EXPECT_NEAR(signedDistance(a, r.pointA), 0.0, slack) << i;
            EXPECT_NEAR(signedDistance(b, r.pointB), 0.0, slack) << i;
            const double n[3] = {r.normal.x, r.normal.y, r.normal.z}, m[3] = {-n[0], -n[1], -n[2]};
            const double gap = -maxAlong(b, m) - maxAlong(a, n);  // min over B minus max over A along n
            EXPECT_NEAR(gap, r.distance, slack) << i;
        } else if (r.status != GjkStatus::Separated && (r.status == GjkStatus::CoresOverlap || r.distance < -kBand)) {
            ++overlapping;
            EXPECT_TRUE(rubble::test::oracleIntersect(a.oracle, b.oracle)) << i;
        }
    }
    EXPECT_GT(separated, 100);
    EXPECT_GT(overlapping, 100);
}

TEST(Gjk, AgreesWithLibccdForEveryPairKind) {
    unsigned seed = 10;
    for (int ka = 0; ka < 4; ++ka)
        for (int kb = ka; kb < 4; ++kb) {
            SCOPED_TRACE(testing::Message() << "kinds " << ka << " " << kb);
            checkAgainstOracle(ka, kb, {}, seed++);
        }
}

TEST(Gjk, HugeCoordinatesKeepPrecision) {
    // 10 km from the origin: float positions there are quantised to ~1 mm, but the distance between the given
    // poses must still be exact to the same tolerance as near the origin (GJK works relative to A).
    checkAgainstOracle(2, 3, {10000.0f, -10000.0f, 10000.0f}, 99);
    std::mt19937 rng(5);
    for (int i = 0; i < 1000; ++i) {
        const TestShape a = randomShape(0, rng, {10000, 10000, -10000}),
                        b = randomShape(0, rng, {10000, 10000, -10000});
        const double expected = dist(a.gjk.pose.position, b.gjk.pose.position) - a.gjk.radius - b.gjk.radius;
        const GjkResult r = gjkDistance(a.gjk, b.gjk);
        EXPECT_NEAR(r.distance, expected, kDistanceTolerance) << i;
    }
}

TEST(Gjk, WarmStartGivesTheSameAnswerInFewerIterations) {
    std::mt19937 rng(6);
    int cold = 0, warm = 0;
    for (int i = 0; i < 500; ++i) {
        const TestShape a = randomShape(3, rng), b = randomShape(3, rng);
        const GjkResult r = gjkDistance(a.gjk, b.gjk);
        if (r.status != GjkStatus::Separated) continue;
        GjkSettings settings;
        settings.initialDirection = r.normal;
        const GjkResult w = gjkDistance(a.gjk, b.gjk, settings);
        ASSERT_EQ(w.status, GjkStatus::Separated);
        EXPECT_NEAR(w.distance, r.distance, kDistanceTolerance);
        cold += r.iterations, warm += w.iterations;
    }
    EXPECT_LT(warm, cold);
}

TEST(Gjk, DegenerateCases) {
    // Face-to-face boxes: many closest-point pairs; the distance is still exact.
    GjkShape a, b;
    a.core = b.core = GjkShape::Core::Box;
    a.halfExtents = b.halfExtents = {1, 1, 1};
    b.pose.position = {0.5f, 2.25f, -0.25f};
    GjkResult r = gjkDistance(a, b);
    EXPECT_EQ(r.status, GjkStatus::Separated);
    EXPECT_NEAR(r.distance, 0.25f, 1e-6f);
    EXPECT_NEAR(r.normal.y, 1.0f, 1e-6f);
    // Identical poses: cores overlap.
    b.pose.position = {};
    EXPECT_EQ(gjkDistance(a, b).status, GjkStatus::CoresOverlap);
    // Touching exactly: the cores overlap within tolerance.
    b.pose.position = {0, 2, 0};
    EXPECT_EQ(gjkDistance(a, b).status, GjkStatus::CoresOverlap);
    // Capsules of zero half height behave as spheres; crossing capsules at a right angle.
    GjkShape c, d;
    c.core = d.core = GjkShape::Core::Segment;
    c.radius = d.radius = 0.5f;
    c.halfHeight = 0;
    d.halfHeight = 2;
    d.pose.position = {0, 0, 3.5f};  // axis from z = 1.5 to z = 5.5
    d.pose.rotation = Quat::fromAxisAngle({1, 0, 0}, 1.5707964f);
    r = gjkDistance(c, d);
    EXPECT_NEAR(r.distance, 0.5f, 1e-5f);
    // Radii overlap gives an exact negative distance.
    d.pose.position = {0, 0.8f, 0};
    d.pose.rotation = Quat::fromAxisAngle({0, 0, 1}, 1.5707964f);
    r = gjkDistance(c, d);
    EXPECT_EQ(r.status, GjkStatus::RadiiOverlap);
    EXPECT_NEAR(r.distance, -0.2f, 1e-5f);
    EXPECT_NEAR(r.normal.y, 1.0f, 1e-5f);
}

TEST(Gjk, ShapeAdapterCoversPrimitivesAndHulls) {
    Shape sphere;
    sphere.kind = ShapeKind::Sphere;
    sphere.radius = 0.5f;
    Shape hullShape;
    hullShape.kind = ShapeKind::ConvexHull;
    hullShape.hull = std::make_shared<ConvexHull>(buildConvexHull(
        {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 1}}));
    const GjkResult r = gjkDistance(gjkShapeOf(sphere, {{3, 0, 0}, {}}), gjkShapeOf(hullShape, {}));
    EXPECT_EQ(r.status, GjkStatus::Separated);
    EXPECT_NEAR(r.distance, 1.5f, 1e-6f);
    EXPECT_NEAR(r.normal.x, -1.0f, 1e-6f);
}

}  // namespace
