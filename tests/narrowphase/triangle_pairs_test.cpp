// Sphere-, capsule- and box-triangle kernels (src/narrowphase/triangle_pairs.*) and mesh adjacency
// (src/shapes/mesh_adjacency.*).
//
// Checks and tolerances (sizes about 1 m):
//  - libccd oracle (tests/narrowphase/ccd_oracle.h; the triangle is a three-point hull about its centroid) for
//    clearly penetrating random poses (deepest point > 0.02 m), all edges active. "Separation along n" is computed
//    here from the oracle's double-precision support functions. Sphere and capsule (poses whose segment does not
//    pierce the triangle, where the minimum is unique): moving the triangle along our normal by that separation
//    + 1e-4 m separates the shapes by libccd's MPR test and by - 1e-4 m does not (so it is the exact penetration
//    along our normal), the deepest point's depth equals it within 1e-4 m, it exceeds libccd's best penetration
//    (GJK+EPA or MPR, whichever verifiably separates) by at most 2e-3 m, and where the two agree within 2e-4 m the
//    normals agree to dot > 0.98 (EPA approximates round shapes by polytopes, as in convex_pairs_test.cpp). Box:
//    the separation along our normal is at most 6% + 2e-3 m above libccd's best (the SAT keeps the triangle face
//    within 5% + 1e-4 size, by design, so our normal need not be the exact minimum), no point is deeper than it
//    + 1e-4 m, at most 4 points. All points lie on the triangle within 1e-4 m (distance computed independently).
//  - analytic cases (face, exactly on an edge, exactly on a vertex, capsule lying on a face, box on a quad):
//    depths and positions within 1e-5 m, normals within 1e-6.
//  - 10 km from the origin: with dyadic inputs (exact in float there) the same answers within 1e-5 m.
//  - ghost bumps: every normal of a box or sphere sliding over a flat 10 x 10 grid mesh equals -(0, 1, 0) (from
//    the body to the floor) within 1e-4 per component; the same poses with all edges active must show normals
//    tilted by more than 1e-2, so the test can fail. The same for a sphere over a flat heightfield with
//    heightfieldActiveEdges().
//  - box feature ids: the same set after a 1 mm / 1 mrad nudge of a resting box.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "broadphase/static_bvh.h"
#include "narrowphase/ccd_oracle.h"
#include "narrowphase/triangle_pairs.h"
#include "narrowphase/triangle_test_helpers.h"
#include "shapes/mesh_adjacency.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using namespace rubble::test;

constexpr std::uint8_t kAll = kAllEdgesActive;

// ---- Mesh adjacency ---------------------------------------------------------------------------------------------

TEST(MeshAdjacency, FlatGridInternalEdgesFlatBoundaryNone) {
    const int n = 10;
    const TriangleMesh mesh = gridMesh(n, 1.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(mesh);
    int boundary = 0;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        EXPECT_EQ(adj.activeEdges[t] & 7, [&] {
            int m = 0;
            for (int e = 0; e < 3; ++e) m |= adj.neighbour(t, e) == kNoNeighbour ? 1 << e : 0;
            return m;
        }()) << t;
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t u = adj.neighbour(t, e);
            if (u == kNoNeighbour) {
                EXPECT_EQ(adj.kind(t, e), EdgeKind::Boundary);
                ++boundary;
                continue;
            }
            EXPECT_EQ(adj.kind(t, e), EdgeKind::Flat) << t << " " << e;
            // Symmetric: u lists t across one of its edges.
            EXPECT_TRUE(adj.neighbour(u, 0) == t || adj.neighbour(u, 1) == t || adj.neighbour(u, 2) == t);
        }
    }
    EXPECT_EQ(boundary, 4 * n);
}

TEST(MeshAdjacency, RidgeConvexValleyConcave) {
    for (float peak : {0.5f, -0.5f}) {
        // Two cells side by side along x; the middle column (x = 1) raised (ridge) or lowered (valley).
        const TriangleMesh mesh = gridMesh(2, 1.0f, [&](int c, int) { return c == 1 ? peak : 0.0f; });
        const MeshAdjacency adj = buildMeshAdjacency(mesh);
        int ridgeEdges = 0, flatEdges = 0;
        for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
            for (int e = 0; e < 3; ++e) {
                const Vec3 a = mesh.vertices[mesh.indices[3 * t + e]];
                const Vec3 b = mesh.vertices[mesh.indices[3 * t + (e + 1) % 3]];
                if (adj.neighbour(t, e) == kNoNeighbour) {
                    EXPECT_EQ(adj.kind(t, e), EdgeKind::Boundary);
                } else if (a.x == 1 && b.x == 1) {  // the ridge or valley line
                    EXPECT_EQ(adj.kind(t, e), peak > 0 ? EdgeKind::Convex : EdgeKind::Concave) << t << " " << e;
                    const bool active = (adj.activeEdges[t] >> e) & 1;
                    EXPECT_EQ(active, peak > 0);
                    ++ridgeEdges;
                } else {  // diagonals and the lines between the two rows of cells are coplanar
                    EXPECT_EQ(adj.kind(t, e), EdgeKind::Flat) << t << " " << e;
                    ++flatEdges;
                }
            }
        }
        EXPECT_EQ(ridgeEdges, 4);  // two segments of the ridge, seen from both sides
        EXPECT_GT(flatEdges, 0);
    }
}

TEST(MeshAdjacency, HeightfieldAgreesWithMesh) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.3f, 0.3f);
    const int n = 6;
    Heightfield field;
    field.rows = field.columns = n + 1;
    field.spacingX = field.spacingZ = 1;
    for (int i = 0; i < (n + 1) * (n + 1); ++i) field.heights.push_back(i % 5 == 0 ? 0.0f : u(rng));
    const TriangleMesh mesh = gridMesh(n, 1.0f, [&](int c, int r) { return field.heights[r * (n + 1) + c]; });
    const MeshAdjacency adj = buildMeshAdjacency(mesh);
    int kinds[4] = {0, 0, 0, 0};
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto nb = heightfieldNeighbours(field, t);
        const auto k = heightfieldEdgeKinds(field, t);
        for (int e = 0; e < 3; ++e) {
            EXPECT_EQ(nb[e], adj.neighbour(t, e)) << t << " " << e;
            EXPECT_EQ(k[e], adj.kind(t, e)) << t << " " << e;
            ++kinds[int(k[e])];
        }
        EXPECT_EQ(heightfieldActiveEdges(field, t), adj.activeEdges[t]);
    }
    EXPECT_GT(kinds[int(EdgeKind::Convex)], 0);
    EXPECT_GT(kinds[int(EdgeKind::Concave)], 0);
    EXPECT_GT(kinds[int(EdgeKind::Boundary)], 0);
}

TEST(MeshAdjacency, ZeroAreaTrianglesAreSkipped) {
    TriangleMesh mesh;
    mesh.vertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {2, 0, 2}, {1, 0, 0}};
    mesh.indices = {0, 1, 2, 0, 2, 3, 0, 2, 4};  // triangle 1 is collinear (0, 1-1, 2-2 on one line)
    const MeshAdjacency adj = buildMeshAdjacency(mesh);
    EXPECT_EQ(adj.neighbour(1, 0), kNoNeighbour);
    EXPECT_EQ(adj.neighbour(0, 2), 2u);  // edge (2, 0) shared by triangles 0 and 2 only
    EXPECT_EQ(adj.kind(0, 2), EdgeKind::Flat);
}

// ---- Analytic cases ---------------------------------------------------------------------------------------------

// A large triangle in the plane y = 0, counter-clockwise seen from +y.
const TriangleVertices kFloor{Vec3{0, 0, 0}, Vec3{0, 0, 4}, Vec3{4, 0, 4}};

TEST(TrianglePairs, SphereRestingOnFace) {
    Manifold m;
    ASSERT_EQ(collideSphereTriangle({1, 0.45f, 2.5f}, 0.5f, kFloor, kAll, 0.0f, m), 1);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.05f, 1e-5f);
    expectVecNear(m.points[0].position, {1, 0, 2.5f}, 1e-5f);
    EXPECT_EQ(m.points[0].feature, 0u);
    // From below: two-sided, the normal flips.
    ASSERT_EQ(collideSphereTriangle({1, -0.45f, 2.5f}, 0.5f, kFloor, kAll, 0.0f, m), 1);
    expectVecNear(m.normal, {0, 1, 0}, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.05f, 1e-5f);
}

TEST(TrianglePairs, SphereCentreExactlyOnEdgeAndVertex) {
    Manifold m;
    // Centre exactly on the diagonal edge (2, 0, 2), and exactly on vertex (0, 0, 0): face normal, depth = radius.
    for (Vec3 c : {Vec3{2, 0, 2}, Vec3{0, 0, 0}, Vec3{0, 0, 2}}) {
        for (std::uint8_t flags : {kAll, std::uint8_t(0)}) {
            ASSERT_EQ(collideSphereTriangle(c, 0.5f, kFloor, flags, 0.0f, m), 1);
            EXPECT_TRUE(finiteManifold(m, 1));
            expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
            EXPECT_NEAR(m.points[0].depth, 0.5f, 1e-6f);
            expectVecNear(m.points[0].position, c, 1e-6f);
        }
    }
    // Centre above an edge: closest point straight below, normal -y whatever the flags.
    ASSERT_EQ(collideSphereTriangle({2, 0.3f, 2}, 0.5f, kFloor, kAll, 0.0f, m), 1);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.2f, 1e-6f);
    EXPECT_EQ(m.points[0].feature, 3u);  // edge 2: vertex 2 -> vertex 0
}

TEST(TrianglePairs, SphereVertexRegionFollowsActiveFlags) {
    Manifold m;
    const Vec3 c{-0.3f, 0.1f, -0.3f};  // beyond vertex 0
    ASSERT_EQ(collideSphereTriangle(c, 0.5f, kFloor, kAll, 0.0f, m), 1);
    const float len = std::sqrt(0.3f * 0.3f * 2 + 0.01f);
    expectVecNear(m.normal, Vec3{0.3f, -0.1f, 0.3f} / len, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.5f - len, 1e-6f);
    EXPECT_EQ(m.points[0].feature, 4u);
    // Edges 0 and 2 (the two at vertex 0) inactive: face normal, depth from the plane, and the point under the
    // centre (where the sphere touches the plane along that normal), not at the vertex: the solver's lever arm must
    // run through the centre, or pushing turns the sphere.
    ASSERT_EQ(collideSphereTriangle(c, 0.5f, kFloor, 0b010, 0.0f, m), 1);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.4f, 1e-6f);
    expectVecNear(m.points[0].position, {-0.3f, 0, -0.3f}, 1e-6f);
    // Only one of them inactive: the vertex stays active.
    ASSERT_EQ(collideSphereTriangle(c, 0.5f, kFloor, 0b001, 0.0f, m), 1);
    EXPECT_GT(std::fabs(m.normal.x), 0.1f);
}

TEST(TrianglePairs, CapsuleLyingOnFaceGivesTwoPoints) {
    Manifold m;
    const CapsuleSegment cap{{2.5f, 0.28f, 3.0f}, {1.0f, 0, 0}, 0.3f};  // along x, ends at x = 1.5 and 3.5
    ASSERT_EQ(collideCapsuleTriangle(cap, kFloor, kAll, 0.0f, m), 2);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].depth, 0.02f, 1e-5f);
    expectVecNear(m.points[0].position, {1.5f, 0, 3}, 1e-5f);
    expectVecNear(m.points[1].position, {3.0f, 0, 3}, 1e-5f);  // clipped by the diagonal x = z
    EXPECT_NE(m.points[0].feature, m.points[1].feature);
    // Standing upright: one point under the lower end.
    const CapsuleSegment up{{1, 0.75f, 3}, {0, 0.5f, 0}, 0.3f};
    ASSERT_EQ(collideCapsuleTriangle(up, kFloor, kAll, 0.0f, m), 1);
    EXPECT_NEAR(m.points[0].depth, 0.05f, 1e-5f);
    expectVecNear(m.points[0].position, {1, 0, 3}, 1e-5f);
    // Pierced through the face: pushed out by the lower end.
    const CapsuleSegment through{{1, 0.2f, 3}, {0, 0.5f, 0}, 0.3f};
    ASSERT_EQ(collideCapsuleTriangle(through, kFloor, kAll, 0.0f, m), 1);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.6f, 1e-5f);
}

/// Collides a box with every triangle of `mesh` (flags from adjacency or all active) and gathers the manifolds.
std::vector<Manifold> boxAgainstMesh(const Transform& pose, Vec3 half, const TriangleMesh& mesh,
                                     const MeshAdjacency* adj, float margin) {
    std::vector<Manifold> out;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        Manifold m;
        if (collideBoxTriangle(pose, half, triangleOf(mesh, t), adj ? adj->activeEdges[t] : kAll, margin, m) > 0)
            out.push_back(m);
    }
    return out;
}

TEST(TrianglePairs, BoxRestingOnQuad) {
    const TriangleMesh quad = gridMesh(1, 4.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(quad);
    const Vec3 half{0.5f, 0.25f, 0.75f};
    // On one triangle only: exactly the four bottom corners.
    {
        const Transform pose{{3.0f, 0.24f, 1.0f}, {}};
        Manifold m;
        ASSERT_EQ(collideBoxTriangle(pose, half, triangleOf(quad, 1), adj.activeEdges[1], 0.0f, m), 4);
        expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
        for (int i = 0; i < 4; ++i) {
            EXPECT_NEAR(m.points[i].depth, 0.01f, 1e-5f);
            EXPECT_NEAR(std::fabs(m.points[i].position.x - 3.0f), 0.5f, 1e-5f);
            EXPECT_NEAR(std::fabs(m.points[i].position.z - 1.0f), 0.75f, 1e-5f);
            EXPECT_NEAR(m.points[i].position.y, 0.0f, 1e-6f);
        }
    }
    // Across the diagonal, rotated: each triangle gives up to four points, all at the same depth, on the floor
    // and inside the box's footprint.
    const Transform pose{{2.0f, 0.24f, 2.0f}, Quat::fromAxisAngle({0, 1, 0}, 0.4f)};
    const auto manifolds = boxAgainstMesh(pose, half, quad, &adj, 0.0f);
    ASSERT_EQ(manifolds.size(), 2u);
    for (const Manifold& m : manifolds) {
        ASSERT_GE(m.pointCount, 3);
        ASSERT_LE(m.pointCount, 4);
        expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
        for (int i = 0; i < m.pointCount; ++i) {
            EXPECT_NEAR(m.points[i].depth, 0.01f, 1e-5f);
            EXPECT_NEAR(m.points[i].position.y, 0.0f, 1e-6f);
            const Vec3 local = rotate(conjugate(pose.rotation), m.points[i].position - pose.position);
            EXPECT_LE(std::fabs(local.x), half.x + 1e-5f);
            EXPECT_LE(std::fabs(local.z), half.z + 1e-5f);
        }
    }
}

TEST(TrianglePairs, SpeculativeMargin) {
    Manifold m;
    // 0.05 m gaps; margin 0.1 reports them with depth -0.05, margin 0.01 does not.
    ASSERT_EQ(collideSphereTriangle({1, 0.55f, 3}, 0.5f, kFloor, kAll, 0.1f, m), 1);
    EXPECT_NEAR(m.points[0].depth, -0.05f, 1e-5f);
    EXPECT_EQ(collideSphereTriangle({1, 0.55f, 3}, 0.5f, kFloor, kAll, 0.01f, m), 0);

    const CapsuleSegment cap{{2.5f, 0.35f, 3.0f}, {0.5f, 0, 0}, 0.3f};
    ASSERT_EQ(collideCapsuleTriangle(cap, kFloor, kAll, 0.1f, m), 2);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].depth, -0.05f, 1e-5f);
    EXPECT_EQ(collideCapsuleTriangle(cap, kFloor, kAll, 0.01f, m), 0);

    const Transform pose{{2.5f, 0.3f, 3.0f}, {}};
    ASSERT_EQ(collideBoxTriangle(pose, {0.25f, 0.25f, 0.25f}, kFloor, kAll, 0.1f, m), 4);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].depth, -0.05f, 1e-5f);
    EXPECT_EQ(collideBoxTriangle(pose, {0.25f, 0.25f, 0.25f}, kFloor, kAll, 0.01f, m), 0);
}

TEST(TrianglePairs, DegenerateTrianglesGiveNoContact) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const TriangleVertices bad[] = {
        {Vec3{0, 0, 0}, Vec3{0, 0, 0}, Vec3{0, 0, 0}},        // a point
        {Vec3{0, 0, 0}, Vec3{1, 0, 1}, Vec3{2, 0, 2}},        // collinear
        {Vec3{0, 0, 0}, Vec3{1, 0, 1}, Vec3{0, 0, 0}},        // repeated vertex
        {Vec3{0, 0, 0}, Vec3{1, 0, 1}, Vec3{2, 1e-7f, 2}},    // sliver
        {Vec3{0, 0, 0}, Vec3{nan, 0, 1}, Vec3{1, 0, 0}},      // NaN
        {Vec3{0, 0, 0}, Vec3{INFINITY, 0, 1}, Vec3{1, 0, 0}}  // Inf
    };
    for (const TriangleVertices& t : bad) {
        Manifold m;
        EXPECT_EQ(collideSphereTriangle({1, 0, 1}, 0.5f, t, kAll, 0.1f, m), 0);
        EXPECT_EQ(m.pointCount, 0);
        EXPECT_EQ(collideCapsuleTriangle({{1, 0, 1}, {0.5f, 0, 0}, 0.3f}, t, kAll, 0.1f, m), 0);
        EXPECT_EQ(collideBoxTriangle({{1, 0, 1}, {}}, {0.5f, 0.5f, 0.5f}, t, kAll, 0.1f, m), 0);
    }
    // A NaN body never produces a contact either.
    Manifold m;
    EXPECT_EQ(collideSphereTriangle({nan, 0, 1}, 0.5f, kFloor, kAll, 0.1f, m), 0);
    EXPECT_EQ(collideCapsuleTriangle({{nan, 0, 1}, {0.5f, 0, 0}, 0.3f}, kFloor, kAll, 0.1f, m), 0);
    EXPECT_EQ(collideBoxTriangle({{nan, 0, 1}, {}}, {0.5f, 0.5f, 0.5f}, kFloor, kAll, 0.1f, m), 0);
}

TEST(TrianglePairs, TenKilometresFromOrigin) {
    // Dyadic offsets: every input is exact in float at 10 km, so the answers must be as exact as near the origin.
    const Vec3 o{10000.0f, 0.0f, -10000.0f};
    const TriangleVertices far{kFloor[0] + o, kFloor[1] + o, kFloor[2] + o};
    Manifold m;
    ASSERT_EQ(collideSphereTriangle(Vec3{1, 0.4375f, 2.5f} + o, 0.5f, far, kAll, 0.0f, m), 1);
    EXPECT_NEAR(m.points[0].depth, 0.0625f, 1e-5f);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    ASSERT_EQ(collideCapsuleTriangle({Vec3{2.5f, 0.25f, 3.0f} + o, {1.0f, 0, 0}, 0.3125f}, far, kAll, 0.0f, m), 2);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].depth, 0.0625f, 1e-5f);
    const Transform pose{Vec3{2.5f, 0.1875f, 3.0f} + o, Quat::fromAxisAngle({0, 1, 0}, 0.3f)};
    ASSERT_EQ(collideBoxTriangle(pose, {0.25f, 0.25f, 0.25f}, far, kAll, 0.0f, m), 4);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].depth, 0.0625f, 1e-5f);
}

TEST(TrianglePairs, ConvexRidgeKeepsEdgeNormal) {
    // A roof: the column x = 1 raised by 0.5. Triangle 1 (cell 0, x in [0, 1]) has the ridge as its edge 1. A sphere
    // just past the ridge touches that edge: convex, so its edge normal stays; forced inactive, the face normal.
    const TriangleMesh roof = gridMesh(2, 1.0f, [](int c, int) { return c == 1 ? 0.5f : 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(roof);
    ASSERT_EQ(adj.kind(1, 1), EdgeKind::Convex);
    const Vec3 c{1.25f, 0.8f, 0.5f};
    Manifold m;
    ASSERT_EQ(collideSphereTriangle(c, 0.5f, triangleOf(roof, 1), adj.activeEdges[1], 0.0f, m), 1);
    EXPECT_EQ(m.points[0].feature, 2u);
    const Vec3 toRidge = Vec3{1, 0.5f, 0.5f} - c;
    expectVecNear(m.normal, toRidge / length(toRidge), 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.5f - length(toRidge), 1e-6f);
    ASSERT_EQ(collideSphereTriangle(c, 0.5f, triangleOf(roof, 1), 0, 0.0f, m), 1);
    expectVecNear(m.normal, Vec3{0.5f, -1, 0} / length(Vec3{0.5f, -1, 0}), 1e-6f);
}

TEST(TrianglePairs, BoxFeatureIdsSurviveSmallMotion) {
    const TriangleMesh quad = gridMesh(1, 4.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(quad);
    const Vec3 half{0.5f, 0.25f, 0.75f};
    auto ids = [&](const Transform& pose) {
        std::vector<std::uint32_t> out;
        for (std::uint32_t t = 0; t < 2; ++t) {
            Manifold m;
            const int count = collideBoxTriangle(pose, half, triangleOf(quad, t), adj.activeEdges[t], 0.02f, m);
            for (int i = 0; i < count; ++i) out.push_back(t << 16 ^ m.points[i].feature);
        }
        std::sort(out.begin(), out.end());
        return out;
    };
    const Transform pose{{2.0f, 0.24f, 2.0f}, Quat::fromAxisAngle({0, 1, 0}, 0.4f)};
    const auto before = ids(pose);
    EXPECT_GE(before.size(), 6u);
    const Transform nudged{{2.001f, 0.2395f, 1.999f},
                           Quat::fromAxisAngle({1, 0, 0}, 1e-3f) * Quat::fromAxisAngle({0, 1, 0}, 0.401f)};
    EXPECT_EQ(ids(nudged), before);
}

TEST(TrianglePairs, BoxDeepInTriangleIsNotDroppedByANonSupportingEdgeAxis) {
    // Regression: the box kernel took the best of all 9 edge axes in either direction. Here that was a direction in
    // which the triangle edge is not the triangle's support, so the closest points of the two edges lay 5 cm apart
    // and the only candidate point fell below -margin: a box 0.2 m deep got no contact at all. Only the direction
    // in which the triangle edge supports the axis (the pair is a face of the Minkowski difference) may be chosen.
    const TriangleVertices tri{Vec3{-0x1.b809bap-1f, -0x1.09d23cp-1f, 0x1.a28f44p-1f},
                               Vec3{0x1.2a4dap-1f, 0x1.2feba8p-1f, -0x1.d15fe4p-1f},
                               Vec3{-0x1.006b7p-1f, 0x1.999168p-1f, -0x1.456918p-3f}};
    const Vec3 half{0x1.c1f928p-2f, 0x1.23976p-2f, 0x1.c14ffep-4f};
    const Transform pose{{-0x1.30fa5ap-2f, 0x1.73914cp-1f, -0x1.9821f8p-2f},
                         {-0x1.8ccd5ap-1f, 0x1.296dfap-2f, 0x1.ba63e6p-2f, -0x1.6edf1ep-2f}};
    Manifold m;
    const int count = collideBoxTriangle(pose, half, tri, kAll, 0.05f, m);
    ASSERT_GE(count, 1);
    float deepest = -INFINITY;
    for (int k = 0; k < count; ++k) deepest = std::max(deepest, m.points[k].depth);
    // libccd: the box's best push-out is 0.195 m; the kernel's (hysteresis allows 5% more) must separate them.
    OracleShape box;
    box.kind = OracleShape::Kind::Box;
    box.half[0] = half.x, box.half[1] = half.y, box.half[2] = half.z;
    setPose(box, pose);
    compareWithOracle(m, count, box, tri, {2e-3, 0.06, false, false}, 0);
    EXPECT_GT(deepest, 0.19f);
}

TEST(TrianglePairs, NoGhostBumpsOnFlatHeightfield) {
    Heightfield field;
    field.rows = field.columns = 11;
    field.heights.assign(121, 0.0f);
    float worst = 0, worstWithout = 0;
    int manifolds = 0;
    for (int ix = 0; ix <= 48; ++ix) {
        for (int iz = 0; iz <= 12; ++iz) {
            const Vec3 c{3.0f + ix * 0.0833f, 0.49f, 4.0f + iz * 0.1667f};
            for (std::uint32_t t = 0; t < heightfieldTriangleCount(field); ++t) {
                const TriangleVertices tri = heightfieldTriangle(field, t);
                Manifold m;
                if (collideSphereTriangle(c, 0.5f, tri, heightfieldActiveEdges(field, t), 0.05f, m) > 0) {
                    ++manifolds;
                    worst = std::max({worst, std::fabs(m.normal.x), std::fabs(m.normal.z)});
                }
                if (collideSphereTriangle(c, 0.5f, tri, kAll, 0.05f, m) > 0)
                    worstWithout = std::max({worstWithout, std::fabs(m.normal.x), std::fabs(m.normal.z)});
            }
        }
    }
    EXPECT_GT(manifolds, 1000);
    EXPECT_LT(worst, 1e-4f);
    EXPECT_GT(worstWithout, 1e-2f);
}

// ---- Against libccd ---------------------------------------------------------------------------------------------

TEST(TrianglePairs, SphereMatchesLibccd) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    int compared = 0;
    for (int i = 0; i < 2000; ++i) {
        const TriangleVertices tri = randomTriangle(rng);
        const float r = 0.2f + 0.6f * u(rng);
        const Vec3 c = randomPointOn(tri, rng) + randomUnit(rng) * (0.9f * r * u(rng)) +
                       (i % 3 == 0 ? randomUnit(rng) * 0.5f : Vec3{});
        Manifold m;
        const int count = collideSphereTriangle(c, r, tri, kAll, 0.0f, m);
        ASSERT_TRUE(finiteManifold(m, count));
        if (distanceToTriangle(c, tri) < 0.02) continue;  // either side is a right answer
        OracleShape s;
        s.kind = OracleShape::Kind::Sphere;
        s.radius = r;
        s.pos[0] = c.x, s.pos[1] = c.y, s.pos[2] = c.z;
        compared += compareWithOracle(m, count, s, tri, {2e-3, 0, true, true}, i);
    }
    EXPECT_GT(compared, 1000);
}

TEST(TrianglePairs, CapsuleMatchesLibccd) {
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> u(0, 1);
    int compared = 0;
    for (int i = 0; i < 2000; ++i) {
        const TriangleVertices tri = randomTriangle(rng);
        const float r = 0.2f + 0.5f * u(rng), hh = 0.1f + 0.6f * u(rng);
        const Quat q = randomRotation(rng);
        const Vec3 c = randomPointOn(tri, rng) + randomUnit(rng) * (0.9f * r * u(rng) + 0.3f * u(rng));
        const CapsuleSegment cap = capsuleSegmentOf({c, q}, hh, r);
        Manifold m;
        const int count = collideCapsuleTriangle(cap, tri, kAll, 0.0f, m);
        ASSERT_TRUE(finiteManifold(m, count));
        // Only where the segment stays clear of the triangle (then the answer is radius - distance, unique);
        // a segment through the triangle is pushed out along the face normal by design (not the minimum).
        double clear = INFINITY;
        for (int k = 0; k <= 20; ++k)
            clear = std::min(clear, distanceToTriangle(cap.center + cap.halfAxis * (k / 10.0f - 1.0f), tri));
        {  // does the segment pierce the triangle between the samples?
            const Vec3 nrm = cross(tri[1] - tri[0], tri[2] - tri[0]);
            const Vec3 p0 = cap.center - cap.halfAxis, p1 = cap.center + cap.halfAxis;
            const double h0 = dot(nrm, p0 - tri[0]), h1 = dot(nrm, p1 - tri[0]);
            if ((h0 < 0) != (h1 < 0)) {
                const Vec3 x = p0 + (p1 - p0) * float(h0 / (h0 - h1));
                clear = std::min(clear, distanceToTriangle(x, tri));
            }
        }
        if (clear < 0.02) continue;
        OracleShape s;
        s.kind = OracleShape::Kind::Capsule;
        s.radius = r;
        s.halfHeight = hh;
        rubble::test::setPose(s, {c, q});
        compared += compareWithOracle(m, count, s, tri, {2e-3, 0, true, true}, i);
    }
    EXPECT_GT(compared, 500);
}

// The sphere and capsule kernels first reject triangles out of reach by a few separating planes (face, edge sides,
// segment x edge) before their closest-point search. Near the edge of the reach, a contact must come out exactly
// when the distance (double precision, the segment densely sampled: the distance is 1-Lipschitz along it, so the
// sampled minimum is within half a sample spacing of the true one) is within radius + margin. Tolerance 1e-4 m
// beyond the sampling bound: the kernels' float rounding on coordinates of about 1 m is far below it, a wrongly
// placed plane is far above it.
TEST(TrianglePairs, SphereAndCapsuleGiveContactsExactlyWithinReach) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(0, 1);
    constexpr int kSamples = 800;
    constexpr double kTolerance = 1e-4;
    int touching = 0, apart = 0;
    for (int i = 0; i < 6000; ++i) {
        const TriangleVertices tri = randomTriangle(rng);
        const float r = 0.1f + 0.4f * u(rng), margin = 0.05f * u(rng);
        const float hh = i % 4 == 0 ? 0.0f : 0.6f * u(rng);  // every fourth a sphere
        const Vec3 c = randomPointOn(tri, rng) + randomUnit(rng) * ((r + hh + margin) * 1.3f * u(rng));
        const CapsuleSegment cap = capsuleSegmentOf({c, randomRotation(rng)}, hh, r);
        double upper = INFINITY;
        for (int k = 0; k <= kSamples; ++k)
            upper = std::min(upper, distanceToTriangle(cap.center + cap.halfAxis * (2.0f * k / kSamples - 1.0f), tri));
        const double lower = upper - length(cap.halfAxis) / kSamples;
        const double reach = double(r) + margin;
        Manifold m;
        const int count = hh == 0 ? collideSphereTriangle(c, r, tri, kAll, margin, m)
                                  : collideCapsuleTriangle(cap, tri, kAll, margin, m);
        if (upper < reach - kTolerance) {
            ++touching;
            EXPECT_GT(count, 0) << "case " << i << ": distance " << upper << " within reach " << reach;
        } else if (lower > reach + kTolerance) {
            ++apart;
            EXPECT_EQ(count, 0) << "case " << i << ": distance " << lower << " beyond reach " << reach;
        }
    }
    EXPECT_GT(touching, 1000);
    EXPECT_GT(apart, 1000);
}

TEST(TrianglePairs, BoxMatchesLibccd) {
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> u(0, 1);
    int compared = 0;
    for (int i = 0; i < 2000; ++i) {
        const TriangleVertices tri = randomTriangle(rng);
        const Vec3 half{0.1f + 0.6f * u(rng), 0.1f + 0.6f * u(rng), 0.1f + 0.6f * u(rng)};
        const Quat q = randomRotation(rng);
        const Vec3 c = randomPointOn(tri, rng) + randomUnit(rng) * (0.8f * u(rng));
        Manifold m;
        const int count = collideBoxTriangle({c, q}, half, tri, kAll, 0.0f, m);
        ASSERT_TRUE(finiteManifold(m, count));
        ASSERT_LE(count, 4);
        OracleShape s;
        s.kind = OracleShape::Kind::Box;
        s.half[0] = half.x, s.half[1] = half.y, s.half[2] = half.z;
        rubble::test::setPose(s, {c, q});
        compared += compareWithOracle(m, count, s, tri, {2e-3, 0.06, false, false}, i);
    }
    EXPECT_GT(compared, 1000);
}

// ---- Ghost bumps ------------------------------------------------------------------------------------------------

/// Largest deviation of any normal from (0, -1, 0) over a sweep of poses across a flat 10 x 10 grid.
struct Sweep {
    float worst = 0;
    int manifolds = 0;
};

Sweep sweepGrid(bool box, bool useAdjacency) {
    const TriangleMesh grid = gridMesh(10, 1.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(grid);
    Sweep s;
    auto record = [&](const Manifold& m, int count) {
        if (count == 0) return;
        EXPECT_TRUE(finiteManifold(m, count));
        ++s.manifolds;
        s.worst = std::max({s.worst, std::fabs(m.normal.x), std::fabs(m.normal.y + 1), std::fabs(m.normal.z)});
    };
    const float margin = 0.05f;
    // Positions every 1/8 cell (exactly over edges and vertices at whole numbers and diagonals) plus odd offsets.
    for (int ix = 0; ix <= 32; ++ix) {
        for (int iz = 0; iz <= 8; ++iz) {
            const float x = 3.0f + ix * 0.125f + (iz % 3 == 2 ? 0.0137f : 0.0f);
            const float z = 4.0f + iz * 0.25f;
            for (float gap : {-0.01f, 0.0f, 0.02f}) {
                for (std::uint32_t t = 0; t < grid.triangleCount(); ++t) {
                    const TriangleVertices tri = triangleOf(grid, t);
                    const std::uint8_t flags = useAdjacency ? adj.activeEdges[t] : kAll;
                    Manifold m;
                    if (box) {
                        for (int pose = 0; pose < 3; ++pose) {
                            const Vec3 half{0.5f, 0.3f, 0.4f};
                            Quat q = Quat::fromAxisAngle({0, 1, 0}, 0.3f * pose);
                            float lift = half.y;
                            if (pose == 2) {  // rolling: tilted onto an edge
                                q = Quat::fromAxisAngle({0, 0, 1}, 0.3f) * q;
                                lift = std::fabs(rotate(q, {half.x, -half.y, half.z}).y);
                                lift = 0;
                                for (int k = 0; k < 8; ++k) {
                                    const Vec3 corner{k & 1 ? half.x : -half.x, k & 2 ? half.y : -half.y,
                                                      k & 4 ? half.z : -half.z};
                                    lift = std::max(lift, -rotate(q, corner).y);
                                }
                            }
                            record(m, collideBoxTriangle({{x, lift + gap, z}, q}, half, tri, flags, margin, m));
                        }
                    } else {
                        record(m, collideSphereTriangle({x, 0.5f + gap, z}, 0.5f, tri, flags, margin, m));
                    }
                }
            }
        }
    }
    return s;
}

TEST(TrianglePairs, NoGhostBumpsSphereOnFlatGrid) {
    const Sweep with = sweepGrid(false, true);
    EXPECT_GT(with.manifolds, 1000);
    EXPECT_LT(with.worst, 1e-4f);
    const Sweep without = sweepGrid(false, false);
    EXPECT_GT(without.worst, 1e-2f);  // the same poses bump without adjacency: the test can fail
}

TEST(TrianglePairs, NoGhostBumpsBoxOnFlatGrid) {
    const Sweep with = sweepGrid(true, true);
    EXPECT_GT(with.manifolds, 1000);
    EXPECT_LT(with.worst, 1e-4f);
    const Sweep without = sweepGrid(true, false);
    EXPECT_GT(without.worst, 1e-2f);
}

}  // namespace
