// The triangle reach tests (narrowphase/triangle_reach.h) and the box kernel's SAT in lanes (boxTriangleAxes) against
// the exact triangle kernels and against their own scalar form, on thousands of random bodies each with a batch of
// nearby random triangles.
#include "narrowphase/triangle_reach.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "narrowphase/triangle_test_helpers.h"
#include "shapes/mesh_adjacency.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using rubble::test::randomPointOn;
using rubble::test::randomRotation;
using rubble::test::randomTriangle;
using rubble::test::randomUnit;

/// A batch of triangles in SoA form, padded as the wide tests read it (the padding repeats the last triangle).
struct Batch {
    std::vector<TriangleVertices> triangles;
    std::vector<float> lanes[9];
    std::unique_ptr<bool[]> wide, scalar;

    explicit Batch(std::vector<TriangleVertices> t) : triangles(std::move(t)) {
        const std::size_t padded = triangleLanesPadded(triangles.size());
        for (std::size_t k = 0; k < padded; ++k) {
            const TriangleVertices& tri = triangles[std::min(k, triangles.size() - 1)];
            for (int v = 0; v < 3; ++v) {
                lanes[3 * v].push_back(tri[v].x);
                lanes[3 * v + 1].push_back(tri[v].y);
                lanes[3 * v + 2].push_back(tri[v].z);
            }
        }
        wide = std::make_unique<bool[]>(padded);
        scalar = std::make_unique<bool[]>(padded);
    }
    TriangleLanes view() const {
        return {{lanes[0].data(), lanes[3].data(), lanes[6].data()},
                {lanes[1].data(), lanes[4].data(), lanes[7].data()},
                {lanes[2].data(), lanes[5].data(), lanes[8].data()}};
    }
};

/// Triangles around a body at `center` of size `size`: some touching, some just out of reach, some far.
std::vector<TriangleVertices> trianglesAround(Vec3 center, float size, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0, 1);
    std::uniform_int_distribution<int> count(1, 40);
    std::vector<TriangleVertices> out;
    for (int k = count(rng); k > 0; --k) {
        TriangleVertices t = randomTriangle(rng);
        const Vec3 shift = center - randomPointOn(t, rng) + randomUnit(rng) * (size * 2.0f * u(rng));
        for (Vec3& v : t) v += shift;
        out.push_back(t);
    }
    return out;
}

struct Tally {
    int contacts = 0, rejected = 0, kept = 0;
    ~Tally() {
        std::printf("%d triangles: %d rejected, %d kept, %d contacts\n", rejected + kept, rejected, kept, contacts);
    }
};

/// Every triangle the exact kernel gives a contact must be in reach; the wide and scalar forms agree bit for bit.
template <class Kernel>
void check(const Batch& batch, Kernel kernel, Tally& tally, int body) {
    const std::size_t n = batch.triangles.size();
    for (std::size_t k = 0; k < n; ++k) {
        ASSERT_EQ(batch.wide[k], batch.scalar[k]) << "body " << body << " triangle " << k;
        Manifold m;
        const int count = kernel(batch.triangles[k], m);
        if (count > 0) {
            ++tally.contacts;
            EXPECT_TRUE(batch.wide[k]) << "body " << body << " triangle " << k << ": a contact marked out of reach";
        }
        (batch.wide[k] ? tally.kept : tally.rejected) += 1;
    }
}

/// Enough contacts to mean something, a good share of the triangles rejected (or the tests would not be worth running),
/// and, the tests being exact distances with a small slack, almost everything kept touching.
void expectManyContactsAndWorthwhileRejections(const Tally& tally) {
    EXPECT_GT(tally.contacts, 10000);
    EXPECT_GT(tally.rejected, tally.kept / 4);
    EXPECT_LT(tally.kept - tally.contacts, tally.kept / 50);
}

// The wide tests may never reject a triangle that the exact kernel gives a contact (they are necessary conditions
// with a slack of 1e-3 of the reach plus 1e-5 of the coordinates), and must agree exactly with their scalar form
// (the same template over float). They must also reject a good share of the triangles, or they would not be worth
// running: the bodies here have triangles scattered up to twice their size away.
TEST(TriangleReach, SphereNeverRejectsAContactAndMatchesScalar) {
    std::mt19937 rng(101);
    std::uniform_real_distribution<float> u(0, 1);
    Tally tally;
    for (int body = 0; body < 3000; ++body) {
        const Vec3 c{4 * u(rng) - 2, 4 * u(rng) - 2, 4 * u(rng) - 2};
        const float radius = 0.05f + 0.5f * u(rng), margin = body % 5 == 0 ? 0.0f : 0.1f * u(rng);
        Batch batch(trianglesAround(c, radius + margin, rng));
        sphereTrianglesInReach(c, radius, margin, batch.view(), batch.triangles.size(), batch.wide.get());
        sphereTrianglesInReachScalar(c, radius, margin, batch.view(), batch.triangles.size(), batch.scalar.get());
        check(
            batch,
            [&](const TriangleVertices& t, Manifold& m) {
                return collideSphereTriangle(c, radius, t, kAllEdgesActive, margin, m);
            },
            tally, body);
    }
    expectManyContactsAndWorthwhileRejections(tally);
}

TEST(TriangleReach, CapsuleNeverRejectsAContactAndMatchesScalar) {
    std::mt19937 rng(202);
    std::uniform_real_distribution<float> u(0, 1);
    Tally tally;
    for (int body = 0; body < 3000; ++body) {
        const Vec3 c{4 * u(rng) - 2, 4 * u(rng) - 2, 4 * u(rng) - 2};
        const float radius = 0.05f + 0.4f * u(rng), margin = body % 5 == 0 ? 0.0f : 0.1f * u(rng);
        const float halfHeight = body % 7 == 0 ? 0.0f : 0.8f * u(rng);  // some of zero length
        const CapsuleSegment capsule = capsuleSegmentOf({c, randomRotation(rng)}, halfHeight, radius);
        Batch batch(trianglesAround(c, radius + halfHeight + margin, rng));
        capsuleTrianglesInReach(capsule, margin, batch.view(), batch.triangles.size(), batch.wide.get());
        capsuleTrianglesInReachScalar(capsule, margin, batch.view(), batch.triangles.size(), batch.scalar.get());
        check(
            batch,
            [&](const TriangleVertices& t, Manifold& m) {
                return collideCapsuleTriangle(capsule, t, kAllEdgesActive, margin, m);
            },
            tally, body);
        // Told the triangle is in reach, the kernel skips its quick rejections and gives the same manifold.
        for (std::size_t k = 0; k < batch.triangles.size(); ++k) {
            if (!batch.wide[k]) continue;
            Manifold full, told;
            const int count = collideCapsuleTriangle(capsule, batch.triangles[k], kAllEdgesActive, margin, full);
            ASSERT_EQ(count, collideCapsuleTriangle(capsule, batch.triangles[k], kAllEdgesActive, margin, told, true));
            EXPECT_EQ(std::memcmp(&full, &told, sizeof full), 0) << body << " " << k;
        }
    }
    expectManyContactsAndWorthwhileRejections(tally);
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool sameBits(Vec3 a, Vec3 b) { return sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z); }

// The box kernel's SAT in lanes (boxTriangleAxes, triangle_pairs.h) is the kernel's own template: its choices equal
// the scalar form's (the normals compare equal; a zero component can differ in sign, which negation in lanes and in
// float treat differently), and the kernel given them (collideBoxTriangle with an axis) makes exactly the manifold,
// bit for bit, that the one-pair kernel makes, including under the ghost rule (random active-edge flags).
TEST(BoxTriangleAxes, MatchScalarAndTheOnePairKernel) {
    std::mt19937 rng(303);
    std::uniform_real_distribution<float> u(0, 1);
    std::uniform_int_distribution<int> flags(0, 7);
    int contacts = 0, apart = 0;
    for (int body = 0; body < 3000; ++body) {
        const Vec3 c{4 * u(rng) - 2, 4 * u(rng) - 2, 4 * u(rng) - 2};
        const Vec3 half{0.05f + 0.5f * u(rng), 0.05f + 0.5f * u(rng), 0.05f + 0.5f * u(rng)};
        const float margin = body % 5 == 0 ? 0.0f : 0.1f * u(rng);
        const TriangleBox box = triangleBox({c, randomRotation(rng)}, half);
        const Batch batch(trianglesAround(c, length(half) + margin, rng));
        const std::size_t n = batch.triangles.size();
        std::vector<BoxTriangleAxis> wide(triangleLanesPadded(n)), scalar(n);
        boxTriangleAxes(box, margin, batch.view(), n, wide.data());
        boxTriangleAxesScalar(box, margin, batch.view(), n, scalar.data());
        for (std::size_t k = 0; k < n; ++k) {
            const BoxTriangleAxis &w = wide[k], &s = scalar[k];
            ASSERT_EQ(w.kind, s.kind) << body << " " << k;
            if (w.kind < 0) {
                ++apart;
                continue;
            }
            ASSERT_TRUE(w.boxAxis == s.boxAxis && w.triEdge == s.triEdge && w.n.x == s.n.x && w.n.y == s.n.y &&
                        w.n.z == s.n.z)
                << body << " " << k << " kind " << w.kind << " axes " << w.boxAxis << "/" << s.boxAxis << " edges "
                << w.triEdge << "/" << s.triEdge << " n " << w.n.x << " " << w.n.y << " " << w.n.z << " / " << s.n.x
                << " " << s.n.y << " " << s.n.z;
            const auto active = static_cast<std::uint8_t>(flags(rng));
            Manifold given, own;
            const int count = collideBoxTriangle(box, batch.triangles[k], active, margin, w, given);
            ASSERT_EQ(count, collideBoxTriangle(box, batch.triangles[k], active, margin, own)) << body << " " << k;
            contacts += count > 0 ? 1 : 0;
            if (count == 0) continue;
            EXPECT_TRUE(sameBits(given.normal, own.normal)) << body << " " << k;
            for (int p = 0; p < count; ++p) {
                EXPECT_TRUE(sameBits(given.points[p].position, own.points[p].position) &&
                            sameBits(given.points[p].depth, own.points[p].depth) &&
                            given.points[p].feature == own.points[p].feature)
                    << body << " " << k << " point " << p;
            }
        }
        // A triangle the SAT finds apart gets no contact from the one-pair kernel either.
        for (std::size_t k = 0; k < n; ++k) {
            if (wide[k].kind >= 0) continue;
            Manifold m;
            EXPECT_EQ(collideBoxTriangle(box, batch.triangles[k], kAllEdgesActive, margin, m), 0) << body << " " << k;
        }
    }
    EXPECT_GT(contacts, 10000);
    EXPECT_GT(apart, 5000);
}

// Far from the origin (10 km) the tests work relative to the triangle or the body, like the kernels.
TEST(TriangleReach, TenKilometresFromOrigin) {
    const Vec3 far{10000.0f, 0.0f, -10000.0f};
    const TriangleVertices tri{far + Vec3{-1, 0, -1}, far + Vec3{-1, 0, 1}, far + Vec3{1, 0, 0}};
    Batch batch({tri});
    for (const float height : {0.49f, 0.55f}) {  // the sphere (radius 0.5, margin 0.02) touches, then not
        sphereTrianglesInReach(far + Vec3{0, height, 0}, 0.5f, 0.02f, batch.view(), 1, batch.wide.get());
        EXPECT_EQ(batch.wide[0], height < 0.52f) << height;
        const CapsuleSegment capsule{far + Vec3{0, height + 0.3f, 0}, {0, 0.3f, 0}, 0.5f};
        capsuleTrianglesInReach(capsule, 0.02f, batch.view(), 1, batch.wide.get());
        EXPECT_EQ(batch.wide[0], height < 0.52f) << height;
        const TriangleBox box = triangleBox({far + Vec3{0, height, 0}, Quat{}}, {0.5f, 0.5f, 0.5f});
        BoxTriangleAxis axes[64];  // a whole SIMD batch
        boxTriangleAxes(box, 0.02f, batch.view(), 1, axes);
        EXPECT_EQ(axes[0].kind >= 0, height < 0.52f) << height;
    }
}

// Non-finite input is never marked out of reach: the exact kernels see it and refuse it (the box SAT refuses it
// itself, as its kernel does).
TEST(TriangleReach, NonFiniteIsLeftToTheKernels) {
    const TriangleVertices tri{Vec3{0, 0, 0}, Vec3{0, 0, 1}, Vec3{NAN, 0, 0}};
    Batch batch({tri});
    sphereTrianglesInReach({0, 5, 0}, 0.5f, 0.02f, batch.view(), 1, batch.wide.get());
    EXPECT_TRUE(batch.wide[0]);
    capsuleTrianglesInReach({{0, 5, 0}, {0, 0.3f, 0}, 0.5f}, 0.02f, batch.view(), 1, batch.wide.get());
    EXPECT_TRUE(batch.wide[0]);
    BoxTriangleAxis axes[64];  // a whole SIMD batch
    boxTriangleAxes(triangleBox({{0, 5, 0}, Quat{}}, {0.5f, 0.5f, 0.5f}), 0.02f, batch.view(), 1, axes);
    EXPECT_EQ(axes[0].kind, -1);  // the kernel's own SAT refuses it
}

}  // namespace
