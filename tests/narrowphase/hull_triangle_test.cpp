// Hull-triangle kernel (collideHullTriangle in src/narrowphase/triangle_pairs.*) and its place in the stage.
//
// Second algorithms and tolerances ("size" = the larger of the hull's largest vertex distance from its centroid and
// the triangle's longest edge, about 1 to 3 m here):
// - brute-force SAT in double over the triangle normal (towards the hull's centroid, the kernel's two-sided rule),
//   both directions of every hull face normal and of every hull-edge x triangle-edge cross product (no Gauss-map
//   pruning: a check of the pruning). Overlap (margin 0): the kernel hits exactly when that SAT finds no separating
//   axis, except within |separation| < 1e-4 * size (float against double). Depth within 1e-4 * size and normal
//   within 1e-2 rad of its best axis where the pair clearly penetrates (> 1e-2 * size) and the best axis is clear:
//   no axis more than 1e-3 rad away comes within 6% + 1e-3 * size of it (the kernel's hysteresis, 5% + 1e-4 * size,
//   may pick any such by design), nor does the far-side triangle normal (pushing the hull through the triangle,
//   which the two-sided rule never does).
// - libccd (tests/narrowphase/ccd_oracle.h: MPR and GJK+EPA in double, its own support functions), on every clear
//   penetration (> 0.02 m) that is not a push-through pose, the box-triangle test's check: moving the triangle along
//   our normal by the separation along it + 1e-4 m separates them (MPR), no point is deeper than that separation
//   + 1e-4 m, it is at most 6% + 2e-3 m above libccd's best penetration (the hysteresis), and all points lie on the
//   triangle within 1e-4 m. MPR's overlap answer must agree with the kernel outside the 1e-4 * size band (up to 3
//   MPR misses allowed, as in hull_pairs_test.cpp).
// - the box-triangle kernel, with the box given as an 8-vertex hull: the box's 13 axes include every axis the hull
//   kernel keeps, so a box hit implies a hull hit, and a hull hit without a box hit is speculative only (depth <= 0,
//   margin 0.05). Where both hit and the double SAT's best axis is clear as above: normals within 4.5e-3 rad
//   (cosine > 0.99999) and deepest depths within 1e-5 m.
// - GJK (src/narrowphase/gjk.h), margin 0.05: a miss only where GJK's distance exceeds the margin - 1e-4 m (every
//   separating axis bounds the distance from below). Every manifold proves its claim: the separation along its
//   normal (double, from the vertices) is within the margin + 1e-5 m, and no point is deeper than that separation
//   allows + 1e-5 m. Where the normal is GJK's direction (cosine > 0.99999: the closest features make a face of the
//   Minkowski difference), the deepest point's depth is minus GJK's distance within 1e-4 m. Elsewhere (a hull vertex
//   beside a triangle edge) the clipped points carry the gap along the normal at their own places, which can exceed
//   the distance by millimetres; the test counts those cases rather than bounding them.
// - analytic cases (coplanar faces, parallel edges, an edge on a side plane, a contact beside the incident face,
//   resting on a quad, margins): depths and positions within 1e-5 m, normals within 1e-6. 10 km from the origin with
//   dyadic inputs: the same depths within 1e-5 m, normals within 1e-6, feature ids equal, positions within 2e-3 m
//   (the float spacing there is 1e-3 m).
// - ghost bumps: hulls resting, tipped onto an edge or standing on a vertex over a flat 10 x 10 grid, exactly over
//   internal edges and vertices, get normals equal to (0, -1, 0) within 1e-4 per component; the same poses with all
//   edges active show normals tilted by more than 1e-2, so the test can fail.
// - feature ids: the same set after a 1 mm / 1 mrad nudge, for the triangle's face as the reference and the hull's.
// - the stage: hulls and compounds with a hull child over a bumpy mesh (its own adjacency) meet the GJK checks
//   above through NarrowPhaseStage (a manifold wherever GJK puts a hull within the margin - 1e-4 m); hulls and a
//   compound's hull child resting on a flat mesh and a flat heightfield over internal edges and vertices get only
//   the face normal (within 1e-4) and the sink depth (within 1e-4 m); a compound's hull child collides exactly like
//   the same hull as a separate body.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "bounds/bounds.h"
#include "broadphase/broadphase_stage.h"
#include "core/parallel.h"
#include "narrowphase/ccd_oracle.h"
#include "narrowphase/gjk.h"
#include "narrowphase/hull_pairs.h"
#include "narrowphase/mesh_manifolds.h"
#include "narrowphase/narrowphase_stage.h"
#include "narrowphase/triangle_pairs.h"
#include "narrowphase/triangle_test_helpers.h"
#include "shapes/mesh_adjacency.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"
#include "support/stage_scene.h"
#include "support/test_shapes.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using namespace rubble::test;

constexpr std::uint8_t kAll = kAllEdgesActive;

// ---- Helpers ----------------------------------------------------------------------------------------------------

/// A built hull with its adjacency, its vertex centroid at the origin (MPR starts from the shape's centre).
struct TestHull {
    ConvexHull hull;
    HullAdjacency adjacency;
};

TestHull makeHull(const std::vector<Vec3>& points) {
    ConvexHull first = *buildShape(ConvexHullDef{points}).hull;
    // Centred on the hull's own vertices (the cloud's interior points are dropped by the hull builder).
    Vec3 hc{};
    for (const Vec3& p : first.vertices) hc += p;
    hc = hc / static_cast<float>(first.vertices.size());
    for (Vec3& p : first.vertices) p -= hc;
    TestHull h{*buildShape(ConvexHullDef{first.vertices}).hull, {}};
    h.adjacency = buildHullAdjacency(h.hull);
    return h;
}

TestHull randomHull(std::mt19937& rng, int points, float scale) {
    return makeHull(randomHullCloud(rng, points, scale));
}

/// A rock: a flat pentagonal bottom face, a narrower pentagon above it turned a little, and a ridge on top.
TestHull rock() {
    std::vector<Vec3> p;
    for (int k = 0; k < 5; ++k) {
        const float a = 6.2831853f * float(k) / 5 + 0.3f;
        p.push_back({0.45f * std::cos(a), -0.3f, 0.4f * std::sin(a)});
        p.push_back({0.3f * std::cos(a + 0.2f), 0.1f, 0.28f * std::sin(a + 0.2f)});
    }
    p.push_back({0.1f, 0.35f, 0.05f});
    p.push_back({-0.15f, 0.3f, -0.05f});
    return makeHull(p);
}

/// An octahedron (tip-down and edge-down poses rest on a vertex or an edge).
TestHull octahedron(float r) { return makeHull({{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}}); }

float maxDepth(const Manifold& m, int count) {
    float d = -INFINITY;
    for (int k = 0; k < count; ++k) d = std::max(d, m.points[k].depth);
    return d;
}

float lowestY(const ConvexHull& h, const Quat& q) {
    float lo = INFINITY;
    for (const Vec3& v : h.vertices) lo = std::min(lo, rotate(q, v).y);
    return lo;
}

OracleShape oracleHull(const ConvexHull& h, const Transform& t) {
    OracleShape s;
    s.kind = OracleShape::Kind::Hull;
    s.points = h.vertices;
    setPose(s, t);
    return s;
}

OracleShape oracleTriangle(const TriangleVertices& tri) {
    OracleShape s;
    s.kind = OracleShape::Kind::Hull;
    const Vec3 c = (tri[0] + tri[1] + tri[2]) / 3.0f;
    s.points = {tri[0] - c, tri[1] - c, tri[2] - c};
    s.pos[0] = c.x, s.pos[1] = c.y, s.pos[2] = c.z;
    return s;
}

// Double-precision vectors for the brute-force SAT.

/// Brute-force SAT of a posed hull (A) against a triangle (B), in double: the best separation (A -> B), the best
/// among axes more than 1e-3 rad away from its axis (a competitor: the kernel's hysteresis may pick it), and the
/// separation along the triangle normal on the far side (pushing the hull through, which the kernel never does).
struct SatResult {
    double sep = -INFINITY, runnerUp = -INFINITY, farSide = -INFINITY;
    D3 axis{0, 0, 0};
    /// Poses the kernel answers by design differently: pushing through is about as shallow as the best ...
    bool pushThrough(double size) const { return farSide > sep - (0.06 * std::fabs(sep) + 1e-3 * size); }
    /// ... or another axis is within the hysteresis (5% + 1e-4 size, with room for float) of the best.
    bool ambiguous(double size) const {
        return pushThrough(size) || runnerUp > sep - (0.06 * std::fabs(sep) + 1e-3 * size);
    }
};
SatResult bruteSat(const ConvexHull& h, const Transform& pose, const TriangleVertices& tri) {
    std::vector<D3> v;
    D3 centroid{0, 0, 0};
    for (const Vec3& p : h.vertices) {
        v.push_back(rotd(pose, p) + d3(pose.position));
        centroid = centroid + v.back();
    }
    centroid = {centroid.x / v.size(), centroid.y / v.size(), centroid.z / v.size()};
    const D3 t[3] = {d3(tri[0]), d3(tri[1]), d3(tri[2])};
    std::vector<std::pair<double, D3>> axes;
    auto eval = [&](D3 n, bool both) {
        const double len = lend(n);
        if (len < 1e-12) return;
        n = {n.x / len, n.y / len, n.z / len};
        for (int s = 0; s < (both ? 2 : 1); ++s) {
            double hiA = -INFINITY, loB = INFINITY;
            for (const D3& p : v) hiA = std::max(hiA, dotd(n, p));
            for (const D3& p : t) loB = std::min(loB, dotd(n, p));
            axes.push_back({loB - hiA, n});
            n = {-n.x, -n.y, -n.z};
        }
    };
    D3 faceN = crossd(t[1] - t[0], t[2] - t[0]);
    if (dotd(faceN, centroid - t[0]) >= 0) faceN = {-faceN.x, -faceN.y, -faceN.z};
    eval({-faceN.x, -faceN.y, -faceN.z}, false);
    const double farSide = axes.back().first;
    axes.pop_back();
    eval(faceN, false);
    for (const Vec3& n : h.faceNormals) eval(rotd(pose, n), true);
    for (std::size_t k = 0; k + 1 < h.edges.size(); k += 2) {
        const D3 d = v[h.edges[k + 1]] - v[h.edges[k]];
        for (int j = 0; j < 3; ++j) {
            const D3 e = t[(j + 1) % 3] - t[j];
            const D3 c = crossd(d, e);
            if (lend(c) <= 1e-3 * lend(d) * lend(e)) continue;  // as the kernel: parallel edges are face-covered
            eval(c, true);
        }
    }
    SatResult r;
    r.farSide = farSide;
    for (auto& [s, n] : axes)
        if (s > r.sep) r.sep = s, r.axis = n;
    for (auto& [s, n] : axes)
        if (dotd(n, r.axis) < std::cos(1e-3)) r.runnerUp = std::max(r.runnerUp, s);
    return r;
}

float sizeOf(const TestHull& h, const TriangleVertices& tri) {
    float longest = 0;
    for (int e = 0; e < 3; ++e) longest = std::max(longest, length(tri[(e + 1) % 3] - tri[e]));
    return std::max(h.adjacency.size, longest);
}

/// Collides a hull with every triangle of `mesh` and gathers the manifolds.
std::vector<Manifold> hullAgainstMesh(const TestHull& h, const Transform& pose, const TriangleMesh& mesh,
                                      const MeshAdjacency* adj, float margin) {
    std::vector<Manifold> out;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        Manifold m;
        if (collideHullTriangle(h.hull, h.adjacency, pose, triangleOf(mesh, t), adj ? adj->activeEdges[t] : kAll,
                                margin, m) > 0)
            out.push_back(m);
    }
    return out;
}

const TriangleVertices kFloor{Vec3{0, 0, 0}, Vec3{0, 0, 4}, Vec3{4, 0, 4}};  // y = 0, counter-clockwise from +y

// ---- Random poses against independent answers --------------------------------------------------------------------

TEST(HullTriangle, RandomPosesAgreeWithBruteForceSatAndLibccd) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<TestHull> hulls;
    for (int k = 0; k < 24; ++k) hulls.push_back(randomHull(rng, 6 + k % 14, 0.3f + 0.5f * u(rng)));
    int hits = 0, checked = 0, ties = 0, band = 0, mprDisagree = 0, oracleCompared = 0;
    for (int i = 0; i < 5000; ++i) {
        const TestHull& h = hulls[i % hulls.size()];
        const TriangleVertices tri = randomTriangle(rng);
        const Transform pose{randomPointOn(tri, rng) + randomUnit(rng) * (0.9f * u(rng)), randomRotation(rng)};
        Manifold m;
        const int count = collideHullTriangle(h.hull, h.adjacency, pose, tri, kAll, 0.0f, m);
        ASSERT_TRUE(finiteManifold(m, count));
        ASSERT_LE(count, 4);
        const float size = sizeOf(h, tri);
        const SatResult sat = bruteSat(h.hull, pose, tri);
        if (std::fabs(sat.sep) < 1e-4 * size) {
            ++band;
            continue;
        }
        EXPECT_EQ(count > 0, sat.sep < 0) << i << " sat " << sat.sep;
        const OracleShape body = oracleHull(h.hull, pose);
        if (rubble::test::oracleMprIntersect(body, oracleTriangle(tri)) != (count > 0)) ++mprDisagree;
        if (count == 0) continue;
        ++hits;
        EXPECT_NEAR(length(m.normal), 1.0f, 1e-5f);
        if (sat.pushThrough(size)) {
            ++ties;
            continue;
        }
        oracleCompared += compareWithOracle(m, count, body, tri, {2e-3, 0.06, false, false}, i);
        const double pen = -sat.sep;
        if (pen < 1e-2 * size) continue;
        if (sat.ambiguous(size)) {
            ++ties;
            continue;
        }
        ++checked;
        EXPECT_NEAR(maxDepth(m, count), pen, 1e-4 * size) << i;
        EXPECT_GT(dotd(d3(m.normal), sat.axis), std::cos(1e-2)) << i;
    }
    EXPECT_LE(mprDisagree, 3);
    EXPECT_GT(hits, 2000);
    EXPECT_GT(checked, 500);
    EXPECT_GT(oracleCompared, 1000);
    std::printf(
        "hull-triangle: %d hits, %d clear cases checked, %d near-ties or push-through poses skipped, %d in band, %d "
        "against libccd, "
        "%d MPR disagreements\n",
        hits, checked, ties, band, oracleCompared, mprDisagree);
}

TEST(HullTriangle, BoxAsHullAgreesWithBoxTriangleKernel) {
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> u(0, 1);
    const float margin = 0.05f;
    int both = 0, checked = 0;
    for (int i = 0; i < 1500; ++i) {
        const TriangleVertices tri = randomTriangle(rng);
        const Vec3 half{0.1f + 0.6f * u(rng), 0.1f + 0.6f * u(rng), 0.1f + 0.6f * u(rng)};
        const TestHull box = makeHull(boxCorners(half));
        const Transform pose{randomPointOn(tri, rng) + randomUnit(rng) * (0.9f * u(rng)), randomRotation(rng)};
        Manifold mb, mh;
        const int cb = collideBoxTriangle(pose, half, tri, kAll, margin, mb);
        const int ch = collideHullTriangle(box.hull, box.adjacency, pose, tri, kAll, margin, mh);
        // Every axis the hull kernel keeps is one of the box kernel's, so a box hit implies a hull hit ...
        if (cb > 0) {
            EXPECT_GT(ch, 0) << i;
        }
        // ... and where the box is apart the hull may only be apart or within the margin (a non-face edge axis of
        // the box's 9 can prove a larger gap than the pruned set when the shapes are apart).
        if (ch > 0 && cb == 0) {
            EXPECT_LE(maxDepth(mh, ch), 0.0f) << i;
        }
        if (cb == 0 || ch == 0) continue;
        ++both;
        const SatResult sat = bruteSat(box.hull, pose, tri);
        const float size = sizeOf(box, tri);
        if (sat.sep > 0 || sat.ambiguous(size)) continue;
        ++checked;
        EXPECT_GT(dot(mh.normal, mb.normal), 0.99999f) << i;
        EXPECT_NEAR(maxDepth(mh, ch), maxDepth(mb, cb), 1e-5f) << i;
    }
    EXPECT_GT(both, 800);
    EXPECT_GT(checked, 400);
}

/// Separation (A -> B) of a posed hull and a triangle along unit n, in double from their vertices.
double separationAlongD(const ConvexHull& h, const Transform& pose, const TriangleVertices& tri, Vec3 n) {
    const D3 nd = d3(n);
    double hiA = -INFINITY, loB = INFINITY;
    for (const Vec3& p : h.vertices) hiA = std::max(hiA, dotd(nd, rotd(pose, p) + d3(pose.position)));
    for (const Vec3& p : tri) loB = std::min(loB, dotd(nd, d3(p)));
    return loB - hiA;
}

/// GJK distance between a posed hull and a triangle (the triangle as a three-point core).
GjkResult hullTriangleGjk(const ConvexHull& h, const Transform& pose, const TriangleVertices& tri) {
    GjkShape a, b;
    a.pose = pose;
    a.core = GjkShape::Core::Points, a.points = h.vertices.data();
    a.pointCount = static_cast<std::uint32_t>(h.vertices.size());
    b.core = GjkShape::Core::Points, b.points = tri.data(), b.pointCount = 3;
    return gjkDistance(a, b);
}

/// The checks of a manifold against GJK that hold for every pose (see the top of the file). Returns 1 when the pose
/// was apart but within the margin and the manifold's normal is GJK's direction (then the gap must be exact).
struct GjkTally {
    int within = 0, exactDirection = 0, exactGap = 0, misses = 0, satOnly = 0;
};
void checkAgainstGjk(const Manifold& m, int count, const ConvexHull& h, const Transform& pose,
                     const TriangleVertices& tri, float margin, GjkTally& tally, int i) {
    const GjkResult g = hullTriangleGjk(h, pose, tri);
    if (count == 0) {
        ++tally.misses;
        // Whatever axis proved the miss bounds the distance from below.
        EXPECT_EQ(g.status, GjkStatus::Separated) << i;
        EXPECT_GT(g.distance, margin - 1e-4f) << i;
        return;
    }
    // The manifold's claim holds: the shapes are within the margin along its normal, and no point is deeper than
    // the shapes allow along it.
    const double along = separationAlongD(h, pose, tri, m.normal);
    EXPECT_LE(along, margin + 1e-5) << i;
    for (int k = 0; k < count; ++k) EXPECT_LE(m.points[k].depth, -along + 1e-5) << i;
    if (g.status != GjkStatus::Separated) return;
    if (g.distance > margin + 1e-4f) ++tally.satOnly;
    if (g.distance > margin - 1e-4f) return;
    ++tally.within;
    if (dot(m.normal, g.normal) < 0.99999f) return;
    ++tally.exactDirection;
    EXPECT_NEAR(maxDepth(m, count), -g.distance, 1e-4f) << i;
    tally.exactGap += std::fabs(maxDepth(m, count) + g.distance) < 1e-4f;
}

TEST(HullTriangle, SpeculativeContactsAgainstGjk) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<TestHull> hulls;
    for (int k = 0; k < 12; ++k) hulls.push_back(randomHull(rng, 8 + k, 0.5f));
    const float margin = 0.05f;
    GjkTally tally;
    for (int i = 0; i < 4000; ++i) {
        const TestHull& h = hulls[i % hulls.size()];
        const TriangleVertices tri = randomTriangle(rng);
        const Transform pose{randomPointOn(tri, rng) + randomUnit(rng) * (0.3f + 0.6f * u(rng)), randomRotation(rng)};
        Manifold m;
        const int count = collideHullTriangle(h.hull, h.adjacency, pose, tri, kAll, margin, m);
        checkAgainstGjk(m, count, h.hull, pose, tri, margin, tally, i);
    }
    EXPECT_GT(tally.within, 300);
    EXPECT_GT(tally.exactDirection, tally.within / 2);
    EXPECT_GT(tally.misses, 1000);
    std::printf(
        "speculative: %d apart within the margin, %d along GJK's direction (gap exact), %d misses, %d beyond "
        "the margin by GJK but not by the SAT\n",
        tally.within, tally.exactDirection, tally.misses, tally.satOnly);
}

// ---- Analytic and degenerate cases ------------------------------------------------------------------------------

TEST(HullTriangle, DegenerateTrianglesAndNonFiniteInputGiveNoContact) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const TestHull h = rock();
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
        EXPECT_EQ(collideHullTriangle(h.hull, h.adjacency, {{1, 0, 1}, {}}, t, kAll, 0.1f, m), 0);
        EXPECT_EQ(m.pointCount, 0);
    }
    Manifold m;
    EXPECT_EQ(collideHullTriangle(h.hull, h.adjacency, {{nan, 0, 1}, {}}, kFloor, kAll, 0.1f, m), 0);
    EXPECT_EQ(collideHullTriangle(h.hull, h.adjacency, {{1, 0, 3}, {nan, 0, 0, 1}}, kFloor, kAll, 0.1f, m), 0);
}

TEST(HullTriangle, FaceCoplanarWithTheTriangle) {
    // A prism whose bottom face is exactly the triangle (0, 0, 0), (0, 0, 2), (2, 0, 2) (inside kFloor), sunk by
    // `sink`: the normal is the floor's, and the points are the bottom face's corners.
    const TestHull prism = makeHull({{0, 0, 0}, {0, 0, 2}, {2, 0, 2}, {0, 1, 0}, {0, 1, 2}, {2, 1, 2}});
    Vec3 centre{};
    for (const Vec3& p : std::vector<Vec3>{{0, 0, 0}, {0, 0, 2}, {2, 0, 2}}) centre += p / 3.0f;
    centre.y = 0.5f;  // makeHull centred the prism on its vertex centroid
    for (float sink : {0.0f, 0.01f}) {
        const Transform pose{centre - Vec3{0, sink, 0}, {}};
        for (const TriangleVertices& tri : {kFloor, TriangleVertices{Vec3{0, 0, 0}, Vec3{0, 0, 2}, Vec3{2, 0, 2}}}) {
            Manifold m;
            const int count = collideHullTriangle(prism.hull, prism.adjacency, pose, tri, kAll, 0.0f, m);
            ASSERT_EQ(count, 3) << sink;
            expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
            std::set<std::uint32_t> ids;
            for (int k = 0; k < count; ++k) {
                EXPECT_NEAR(m.points[k].depth, sink, 1e-5f);
                EXPECT_NEAR(m.points[k].position.y, 0.0f, 1e-5f);
                const Vec3 p = m.points[k].position;
                const bool corner = length(p - Vec3{0, 0, 0}) < 1e-4f || length(p - Vec3{0, 0, 2}) < 1e-4f ||
                                    length(p - Vec3{2, 0, 2}) < 1e-4f;
                EXPECT_TRUE(corner) << p.x << " " << p.z;
                // The bottom face's own vertices (bit 15 clear), not crossing points that rounding made next to them.
                EXPECT_EQ(m.points[k].feature & 0x8000u, 0u);
                ids.insert(m.points[k].feature);
            }
            EXPECT_EQ(ids.size(), 3u);
        }
    }
}

TEST(HullTriangle, ParallelEdges) {
    // A cube turned 45 degrees about z: its bottom edge runs along z, parallel to the floor's edge 0 (x = 0).
    const TestHull cube = makeHull(boxCorners({0.5f, 0.5f, 0.5f}));
    const Quat q = Quat::fromAxisAngle({0, 0, 1}, 0.78539816f);
    const float reach = -lowestY(cube.hull, q);
    // Inside the face: the two ends of the edge, at the sink depth, face normal.
    {
        const Transform pose{{1, reach - 0.01f, 2}, q};
        Manifold m;
        ASSERT_EQ(collideHullTriangle(cube.hull, cube.adjacency, pose, kFloor, kAll, 0.0f, m), 2);
        expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
        for (int k = 0; k < 2; ++k) {
            EXPECT_NEAR(m.points[k].depth, 0.01f, 1e-5f);
            EXPECT_NEAR(m.points[k].position.x, 1.0f, 1e-5f);
            EXPECT_NEAR(std::fabs(m.points[k].position.z - 2.0f), 0.5f, 1e-5f);
        }
    }
    // Exactly over the floor's edge 0: parallel edges, no edge-edge axis. With the edge inactive (a flat
    // neighbour), the face normal; active (the mesh border), a valid push-out along a finite normal.
    {
        const Transform pose{{0, reach - 0.01f, 2}, q};
        Manifold m;
        ASSERT_EQ(collideHullTriangle(cube.hull, cube.adjacency, pose, kFloor, 0b110, 0.0f, m), 2);
        expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
        for (int k = 0; k < 2; ++k) EXPECT_NEAR(m.points[k].depth, 0.01f, 1e-5f);
        const int count = collideHullTriangle(cube.hull, cube.adjacency, pose, kFloor, kAll, 0.0f, m);
        ASSERT_GE(count, 1);
        ASSERT_TRUE(finiteManifold(m, count));
        const OracleShape body = oracleHull(cube.hull, pose);
        const double n[3] = {m.normal.x, m.normal.y, m.normal.z};
        const double along = separationAlong(body, oracleTriangle(kFloor), n);
        EXPECT_NEAR(maxDepth(m, count), along, 1e-5);
        EXPECT_FALSE(oracleMprIntersect(body, moved(oracleTriangle(kFloor), n, along + 1e-4)));
    }
}

TEST(HullTriangle, EdgeOnASidePlaneGivesItsVerticesNotTwins) {
    // A cube turned about x so that its bottom edge runs along x exactly over the floor's edge 1 (z = 4), its lower
    // face towards +z (outside the triangle) slightly the more level one, so that it is the incident face. Clipping
    // that face by edge 1's side plane crosses it right next to the edge's own vertices; the manifold must hold the
    // two vertices once each (the twins are merged), at the sink depth and with the face normal (edge 1 inactive).
    const TestHull cube = makeHull(boxCorners({0.5f, 0.5f, 0.5f}));
    const Quat q = Quat::fromAxisAngle({1, 0, 0}, 0.78539816f + 0.01f);
    const float reach = -lowestY(cube.hull, q);
    const Transform pose{{2.0f, reach - 0.01f, 4.0f}, q};
    // The lowest vertices sit at z = 4 up to rounding: shift so that they do exactly.
    Vec3 low = rotate(q, cube.hull.vertices[0]);
    for (const Vec3& v : cube.hull.vertices) low = rotate(q, v).y < low.y - 1e-6f ? rotate(q, v) : low;
    const Transform exact{{pose.position.x, pose.position.y, 4.0f - low.z}, q};
    Manifold m;
    const int count = collideHullTriangle(cube.hull, cube.adjacency, exact, kFloor, 0b101, 0.0f, m);
    ASSERT_EQ(count, 2);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    for (int k = 0; k < count; ++k) {
        EXPECT_NEAR(m.points[k].depth, 0.01f, 1e-5f);
        EXPECT_NEAR(m.points[k].position.z, 4.0f, 1e-5f);
        EXPECT_NEAR(std::fabs(m.points[k].position.x - 2.0f), 0.5f, 1e-5f);
    }
    EXPECT_NE(m.points[0].feature, m.points[1].feature);
}

TEST(HullTriangle, ContactBesideTheIncidentFaceIsKept) {
    // A cube rolled 30 degrees about z, its lowest edge 5 cm outside the floor's edge 0 (x = 0, inactive: a flat
    // neighbour) and 10 cm below the plane, so that its steeper lower face cuts into this triangle. The face normal is
    // forced, and the incident face (the more level one) lies wholly beside the triangle: clipping keeps nothing,
    // and the deepest vertex over its closest triangle point must still be reported.
    const TestHull cube = makeHull(boxCorners({0.5f, 0.5f, 0.5f}));
    const Quat q = Quat::fromAxisAngle({0, 0, 1}, -0.5235988f);
    int lowest = 0;
    for (int i = 0; i < 8; ++i)
        if (rotate(q, cube.hull.vertices[i]).y < rotate(q, cube.hull.vertices[lowest]).y) lowest = i;
    const Vec3 low = rotate(q, cube.hull.vertices[lowest]);
    const Transform pose{Vec3{-0.05f, -0.1f, 2.0f} - Vec3{low.x, low.y, 0}, q};
    // The scenario holds: the most level face through the lowest vertex lies at x < 0.
    int level = -1;
    for (std::uint32_t f = 0; f < cube.hull.faceCount(); ++f)
        for (std::uint32_t k = cube.hull.faceStart[f]; k < cube.hull.faceStart[f + 1]; ++k)
            if (int(cube.hull.faceVertices[k]) == lowest &&
                (level < 0 || rotate(q, cube.hull.faceNormals[f]).y < rotate(q, cube.hull.faceNormals[level]).y))
                level = int(f);
    ASSERT_GE(level, 0);
    for (std::uint32_t k = cube.hull.faceStart[level]; k < cube.hull.faceStart[level + 1]; ++k)
        ASSERT_LT(apply(pose, cube.hull.vertices[cube.hull.faceVertices[k]]).x, 0.0f);
    Manifold m;
    const int count = collideHullTriangle(cube.hull, cube.adjacency, pose, kFloor, 0b110, 0.0f, m);
    ASSERT_EQ(count, 1);
    expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
    EXPECT_NEAR(m.points[0].depth, 0.1f, 1e-5f);
    EXPECT_NEAR(m.points[0].position.x, 0.0f, 1e-5f);
    EXPECT_NEAR(m.points[0].position.y, 0.0f, 1e-5f);
}

TEST(HullTriangle, RestingOnQuadAndSpeculativeMargin) {
    const TriangleMesh quad = gridMesh(1, 4.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(quad);
    const TestHull r = rock();
    const float bottom = -lowestY(r.hull, {});
    for (float gap : {-0.01f, 0.03f}) {
        const Transform pose{{2.0f, bottom + gap, 2.0f}, Quat::fromAxisAngle({0, 1, 0}, 0.4f)};
        for (float margin : {0.0f, 0.05f}) {
            const auto manifolds = hullAgainstMesh(r, pose, quad, &adj, margin);
            if (gap > margin) {
                EXPECT_TRUE(manifolds.empty());
                continue;
            }
            ASSERT_EQ(manifolds.size(), 2u) << gap;  // across the diagonal: both triangles
            for (const Manifold& m : manifolds) {
                ASSERT_GE(m.pointCount, 3);
                expectVecNear(m.normal, {0, -1, 0}, 1e-6f);
                for (int k = 0; k < m.pointCount; ++k) {
                    EXPECT_NEAR(m.points[k].depth, -gap, 1e-5f);
                    EXPECT_NEAR(m.points[k].position.y, 0.0f, 1e-6f);
                }
            }
        }
    }
}

TEST(HullTriangle, TenKilometresFromOrigin) {
    // Dyadic offsets and positions: every input is exact in float at 10 km, so depths and normals must be as exact
    // as near the origin; only the output positions round to the float spacing there (about 1e-3 m).
    const Vec3 o{10000.0f, 0.0f, -10000.0f};
    const TriangleVertices far{kFloor[0] + o, kFloor[1] + o, kFloor[2] + o};
    std::mt19937 rng(3);
    const TestHull hulls[] = {rock(), makeHull(boxCorners({0.25f, 0.25f, 0.25f})), octahedron(0.4f),
                              randomHull(rng, 14, 0.5f)};
    int compared = 0;
    for (const TestHull& h : hulls) {
        for (int k = 0; k < 40; ++k) {
            const Quat q = randomRotation(rng);
            const float reach = -lowestY(h.hull, q);
            // On the 1/1024 grid, exact at 10 km.
            const Vec3 at{std::round((1.5f + 0.05f * k) * 1024) / 1024, std::round((reach - 0.02f) * 1024) / 1024,
                          std::round((2.5f + 0.03f * k) * 1024) / 1024};
            Manifold near, away;
            const int cn = collideHullTriangle(h.hull, h.adjacency, {at, q}, kFloor, kAll, 0.01f, near);
            const int ca = collideHullTriangle(h.hull, h.adjacency, {at + o, q}, far, kAll, 0.01f, away);
            ASSERT_EQ(cn, ca);
            if (cn == 0) continue;
            ++compared;
            expectVecNear(away.normal, near.normal, 1e-6f);
            for (int p = 0; p < cn; ++p) {
                EXPECT_NEAR(away.points[p].depth, near.points[p].depth, 1e-5f);
                EXPECT_EQ(away.points[p].feature, near.points[p].feature);
                expectVecNear(away.points[p].position - o, near.points[p].position, 2e-3f);
            }
        }
    }
    EXPECT_GT(compared, 100);
}

// ---- Ghost bumps and feature ids --------------------------------------------------------------------------------

/// Largest deviation of any normal from (0, -1, 0) over hulls resting on a flat 10 x 10 grid at positions exactly
/// over internal edges and vertices (and a few off them), in resting, tip-down and edge-down poses.
struct Sweep {
    float worst = 0;
    int manifolds = 0;
};

Sweep sweepGrid(bool useAdjacency) {
    const TriangleMesh grid = gridMesh(10, 1.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(grid);
    const TestHull shapes[] = {rock(), octahedron(0.5f), makeHull(boxCorners({0.5f, 0.3f, 0.4f}))};
    // Poses: as built (rock: flat bottom; octahedron: tip down), yawed, and tipped onto an edge.
    const Quat poses[] = {Quat{}, Quat::fromAxisAngle({0, 1, 0}, 0.3f),
                          Quat::fromAxisAngle({0, 0, 1}, 0.3f) * Quat::fromAxisAngle({0, 1, 0}, 0.7f),
                          Quat::fromAxisAngle({1, 0, 0}, 0.78539816f)};
    Sweep s;
    for (const TestHull& h : shapes) {
        for (const Quat& q : poses) {
            const float reach = -lowestY(h.hull, q);
            for (int ix = 0; ix <= 8; ++ix) {
                for (int iz = 0; iz <= 4; ++iz) {
                    const float x = 4.0f + ix * 0.25f + (iz == 3 ? 0.0137f : 0.0f), z = 4.0f + iz * 0.5f;
                    for (float gap : {-0.01f, 0.0f, 0.02f}) {
                        const Transform pose{{x, reach + gap, z}, q};
                        for (std::uint32_t t = 0; t < grid.triangleCount(); ++t) {
                            Manifold m;
                            const int count = collideHullTriangle(h.hull, h.adjacency, pose, triangleOf(grid, t),
                                                                  useAdjacency ? adj.activeEdges[t] : kAll, 0.05f, m);
                            if (count == 0) continue;
                            EXPECT_TRUE(finiteManifold(m, count));
                            ++s.manifolds;
                            s.worst = std::max(
                                {s.worst, std::fabs(m.normal.x), std::fabs(m.normal.y + 1), std::fabs(m.normal.z)});
                        }
                    }
                }
            }
        }
    }
    return s;
}

TEST(HullTriangle, NoGhostBumpsOnFlatGrid) {
    const Sweep with = sweepGrid(true);
    EXPECT_GT(with.manifolds, 1000);
    EXPECT_LT(with.worst, 1e-4f);
    const Sweep without = sweepGrid(false);
    EXPECT_GT(without.worst, 1e-2f);  // the same poses bump without adjacency: the test can fail
}

TEST(HullTriangle, FeatureIdsSurviveSmallMotion) {
    const TriangleMesh quad = gridMesh(1, 4.0f, [](int, int) { return 0.0f; });
    const MeshAdjacency adj = buildMeshAdjacency(quad);
    const TestHull r = rock();
    auto ids = [&](const Transform& pose, const TriangleMesh& mesh, std::uint32_t& kinds) {
        std::vector<std::uint32_t> out;
        for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
            Manifold m;
            const int count = collideHullTriangle(r.hull, r.adjacency, pose, triangleOf(mesh, t),
                                                  mesh.triangleCount() == 2 ? adj.activeEdges[t] : kAll, 0.02f, m);
            for (int i = 0; i < count; ++i) {
                out.push_back(t << 30 ^ m.points[i].feature);
                kinds |= 1u << (m.points[i].feature >> 30);
            }
        }
        std::sort(out.begin(), out.end());
        return out;
    };
    auto nudge = [](const Transform& p) {
        return Transform{p.position + Vec3{0.001f, -0.0005f, -0.001f},
                         Quat::fromAxisAngle({1, 0, 0}, 1e-3f) * Quat::fromAxisAngle({0, 1, 0}, 1e-3f) * p.rotation};
    };
    // Resting across the quad's diagonal: the triangle faces are the reference (kind 0), points clipped by the
    // diagonal's side planes.
    {
        const float bottom = -lowestY(r.hull, {});
        const Transform pose{{2.0f, bottom - 0.01f, 2.0f}, Quat::fromAxisAngle({0, 1, 0}, 0.4f)};
        std::uint32_t kinds = 0;
        const auto before = ids(pose, quad, kinds);
        EXPECT_GE(before.size(), 6u);
        EXPECT_EQ(kinds, 1u);
        EXPECT_EQ(ids(nudge(pose), quad, kinds), before);
    }
    // A steep triangle's corner poking into the rock's bottom face: the rock's face is the reference (kind 1).
    {
        TriangleMesh spike;
        spike.vertices = {{0.05f, -0.02f, 0.0f}, {-0.3f, -0.9f, 0.2f}, {0.35f, -0.9f, 0.25f}};
        spike.indices = {0, 1, 2};
        // The bottom face at y = -0.03: the spike's tip 1 cm into it.
        const Transform at{{0, -0.03f - lowestY(r.hull, {}), 0}, {}};
        std::uint32_t kinds = 0;
        const auto before = ids(at, spike, kinds);
        ASSERT_FALSE(before.empty());
        EXPECT_EQ(kinds, 2u);
        EXPECT_EQ(ids(nudge(at), spike, kinds), before);
    }
}

// ---- In the stage -----------------------------------------------------------------------------------------------

/// The stages over a scene with one broad phase that keeps the scene's statics.
struct Scene : rubble::test::StageScene {
    BroadPhaseStage broad;

    void addStatic(std::uint32_t shape, Vec3 p) { StageScene::addStatic(shape, p, broad); }
    Transform movingPose(std::uint32_t i) const { return poseOf(i, false); }
    Contacts run(float margin, CandidatePairs& candidates, int threads = 2) {
        return rubble::test::runStages(*this, broad, threads, margin, candidates);
    }
};

TriangleMeshDef bumpyGrid(int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> h(-0.25f, 0.25f);
    TriangleMeshDef def;
    for (int r = 0; r <= n; ++r)
        for (int c = 0; c <= n; ++c)
            def.vertices.push_back({float(c) - n / 2.0f, (r + c) % 3 == 0 ? 0.0f : h(rng), float(r) - n / 2.0f});
    const auto at = [&](int c, int r) { return std::uint32_t(r * (n + 1) + c); };
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c)
            def.indices.insert(def.indices.end(),
                               {at(c, r), at(c, r + 1), at(c + 1, r + 1), at(c, r), at(c + 1, r + 1), at(c + 1, r)});
    return def;
}

TEST(HullTriangle, StageManifoldsWhereGjkFindsHullsWithinTheMarginOfMeshTriangles) {
    std::mt19937 rng(41);
    Scene scene;
    const TriangleMeshDef gridDef = bumpyGrid(12, rng);
    const std::uint32_t mesh = scene.addShape(gridDef);
    scene.addStatic(mesh, {0, 0, 0});
    std::vector<std::uint32_t> kinds;
    for (int k = 0; k < 3; ++k) {
        std::uniform_real_distribution<float> u(-1, 1);
        std::vector<Vec3> cloud;
        for (int p = 0; p < 8 + 6 * k; ++p) cloud.push_back(Vec3{u(rng), u(rng), u(rng)} * (0.3f + 0.1f * k));
        kinds.push_back(scene.addShape(ConvexHullDef{cloud}));
    }
    CompoundDef compound;
    compound.children.push_back({SphereDef{0.3f}, {{-0.5f, 0, 0}, {}}});
    compound.children.push_back({ConvexHullDef{boxCorners({0.3f, 0.2f, 0.25f})}, {{0.4f, 0, 0}, {}}});
    kinds.push_back(scene.addShape(compound));
    std::uniform_real_distribution<float> xz(-5.5f, 5.5f), y(-0.3f, 0.9f);
    for (int i = 0; i < 600; ++i)
        scene.addMoving(kinds[i % kinds.size()], {xz(rng), y(rng), xz(rng)}, randomRotation(rng));

    const float margin = 0.02f;
    CandidatePairs candidates;
    const Contacts contacts = scene.run(margin, candidates);
    std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint16_t>, std::size_t> found;
    std::multimap<std::pair<std::uint32_t, std::uint16_t>, std::size_t> ofBody;
    for (std::size_t k = 0; k < contacts.pairs.size(); ++k) {
        const ContactPair& p = contacts.pairs[k];
        if (p.bStatic && p.triangle != ~0u) found[{p.a, p.triangle, p.childA}] = k, ofBody.insert({{p.a, p.childA}, k});
    }
    int merged = 0;
    const TriangleMesh& m = *scene.shapes[mesh].mesh;
    int checked = 0, hullJobs = 0;
    GjkTally tally;
    for (const MeshPair& p : candidates.meshes) {
        const Shape& body = scene.shapes[scene.storage.moving.shape[p.moving]];
        const Transform pose = scene.movingPose(p.moving);
        for (std::uint32_t k = 0; k < p.triangleCount; ++k) {
            const std::uint32_t t = candidates.meshTriangles[p.firstTriangle + k];
            const TriangleVertices tri{m.vertices[m.indices[3 * t]], m.vertices[m.indices[3 * t + 1]],
                                       m.vertices[m.indices[3 * t + 2]]};
            const std::size_t children = body.kind == ShapeKind::Compound ? body.children.size() : 1;
            for (std::size_t c = 0; c < children; ++c) {
                const bool isCompound = body.kind == ShapeKind::Compound;
                const Shape& part = isCompound ? *body.children[c].shape : body;
                const Transform partPose = isCompound ? Transform{apply(pose, body.children[c].local.position),
                                                                  pose.rotation * body.children[c].local.rotation}
                                                      : pose;
                const auto it = found.find({p.moving, t, isCompound ? std::uint16_t(c) : kNoChild});
                ++checked;
                if (part.kind != ShapeKind::ConvexHull) continue;
                ++hullJobs;
                const Manifold none;
                const Manifold& mf = it == found.end() ? none : contacts.manifolds[it->second];
                if (mf.pointCount == 0) {
                    // A triangle the kernel touches whose manifold shares its normal with another of the same body
                    // is merged into that one (mesh_manifolds.h): the body has a manifold along that normal.
                    Manifold own;
                    const std::uint8_t active = m.activeEdges.empty() ? kAllEdgesActive : m.activeEdges[t];
                    if (collideHullTriangle(*part.hull, buildHullAdjacency(*part.hull), partPose, tri, active, margin,
                                            own) > 0) {
                        bool alongIt = false;
                        const auto [from, to] =
                            ofBody.equal_range({p.moving, isCompound ? std::uint16_t(c) : kNoChild});
                        for (auto at = from; at != to; ++at)
                            alongIt =
                                alongIt || dot(contacts.manifolds[at->second].normal, own.normal) >= kMergeNormalCosine;
                        EXPECT_TRUE(alongIt) << hullJobs;
                        ++merged;
                        continue;
                    }
                }
                checkAgainstGjk(mf, mf.pointCount, *part.hull, partPose, tri, margin, tally, hullJobs);
            }
        }
    }
    EXPECT_GT(hullJobs, 1000);
    EXPECT_GT(tally.within, 30);
    EXPECT_GT(tally.exactDirection, tally.within / 2);
    std::printf(
        "stage: %d jobs, %d hull jobs, %d apart within the margin (%d along GJK's direction, gap exact), %d "
        "beyond the margin by GJK but not by the SAT, %d merged into another triangle's manifold\n",
        checked, hullJobs, tally.within, tally.exactDirection, tally.satOnly, merged);
}

TEST(HullTriangle, StageHullsOnFlatMeshAndHeightfieldGetOnlyTheFaceNormal) {
    // Rocks and a compound with a hull child rest, sunk 1 cm, on a flat 8 x 8 mesh and a flat 8 x 8 heightfield at
    // positions that put their contacts exactly over internal edges and vertices, in several turns: through the stage
    // (each static shape's own active-edge masks) every manifold must have the face normal and the sink depth.
    Scene scene;
    const TriangleMeshDef grid = rubble::test::flatGridMesh(8);
    HeightfieldDef field;
    field.rows = field.columns = 9;
    field.heights.assign(81, 0.0f);
    scene.addStatic(scene.addShape(grid), {0, 0, 0});
    scene.addStatic(scene.addShape(field), {10, 0, -4});  // covers x in [10, 18], z in [-4, 4]
    const std::vector<Vec3> rockPoints = rock().hull.vertices;
    const std::uint32_t rockShape = scene.addShape(ConvexHullDef{rockPoints});
    CompoundDef compound;
    compound.children.push_back({SphereDef{0.2f}, {{0, 1.0f, 0}, {}}});
    compound.children.push_back({ConvexHullDef{rockPoints}, {}});
    const std::uint32_t compoundShape = scene.addShape(compound);
    const float sink = 0.01f, bottom = -lowestY(rock().hull, {});
    int bodies = 0;
    for (float base : {0.0f, 14.0f})
        for (float dx : {-2.0f, -1.0f, 0.5f, 1.0f})
            for (float dz : {-2.0f, 0.0f, 0.5f, 2.0f}) {
                const Quat yaw = Quat::fromAxisAngle({0, 1, 0}, 0.4f * float(bodies));
                scene.addMoving(bodies % 2 ? compoundShape : rockShape, {base + dx, bottom - sink, dz}, yaw);
                ++bodies;
            }
    CandidatePairs candidates;
    const Contacts contacts = scene.run(0.02f, candidates);
    int meshContacts = 0, fieldContacts = 0;
    for (std::size_t k = 0; k < contacts.pairs.size(); ++k) {
        const ContactPair& p = contacts.pairs[k];
        if (!p.bStatic) continue;
        (p.b == 0 ? meshContacts : fieldContacts) += 1;
        const Manifold& m = contacts.manifolds[k];
        EXPECT_NEAR(m.normal.y, -1.0f, 1e-4f) << "pair " << k << " triangle " << p.triangle;
        for (int q = 0; q < m.pointCount; ++q) EXPECT_NEAR(m.points[q].depth, sink, 1e-4f);
    }
    // One manifold per body: its triangles' manifolds share the face normal and are merged (mesh_manifolds.h).
    EXPECT_EQ(meshContacts, bodies / 2);
    EXPECT_EQ(fieldContacts, bodies / 2);
}

TEST(HullTriangle, CompoundHullChildAgainstMeshLikeASeparateHull) {
    // A compound of a sphere and a turned hull over a flat mesh, against the same hull as a separate body at the
    // child's world pose: the hull child's manifolds must be the same (up to the rounding of the compound's origin,
    // stored through its centre of mass), with the face normal everywhere.
    TriangleMeshDef grid;
    for (int r = 0; r <= 6; ++r)
        for (int c = 0; c <= 6; ++c) grid.vertices.push_back({float(c) - 3, 0, float(r) - 3});
    for (std::uint32_t r = 0; r < 6; ++r)
        for (std::uint32_t c = 0; c < 6; ++c) {
            const std::uint32_t a = r * 7 + c, b = a + 1, d = a + 7, e = d + 1;
            grid.indices.insert(grid.indices.end(), {a, d, e, a, e, b});
        }
    const std::vector<Vec3> rockPoints = rock().hull.vertices;
    const Transform hullLocal{{0.6f, 0.0f, 0.1f}, Quat::fromAxisAngle({0, 1, 0}, 0.5f)};
    const float bottom = -lowestY(rock().hull, {});
    // The body origin sits so that the hull child's bottom face is 5 mm into the floor, over an internal vertex.
    const Transform body{{-0.6f, bottom - 0.005f, -0.1f}, {}};

    auto run = [&](bool asCompound, std::vector<ContactPair>& pairs) {
        Scene scene;
        scene.addStatic(scene.addShape(grid), {0, 0, 0});
        if (asCompound) {
            CompoundDef compound;
            compound.children.push_back({SphereDef{0.2f}, {{-0.6f, 1.0f, 0}, {}}});
            compound.children.push_back({ConvexHullDef{rockPoints}, hullLocal});
            scene.addMoving(scene.addShape(compound), body.position, body.rotation);
        } else {
            scene.addMoving(scene.addShape(ConvexHullDef{rockPoints}), apply(body, hullLocal.position),
                            body.rotation * hullLocal.rotation);
        }
        CandidatePairs candidates;
        Contacts contacts = scene.run(0.02f, candidates, 1);
        pairs = contacts.pairs;
        return contacts.manifolds;
    };
    std::vector<ContactPair> compoundPairs, separatePairs;
    const std::vector<Manifold> compound = run(true, compoundPairs), separate = run(false, separatePairs);
    ASSERT_EQ(compound.size(), separate.size());
    ASSERT_EQ(compound.size(), 1u) << "the triangles' manifolds share the face normal and are merged";
    for (std::size_t k = 0; k < compound.size(); ++k) {
        EXPECT_EQ(compoundPairs[k].childA, 1);
        EXPECT_EQ(compoundPairs[k].triangle, separatePairs[k].triangle);
        expectVecNear(compound[k].normal, {0, -1, 0}, 1e-6f);
        ASSERT_EQ(compound[k].pointCount, separate[k].pointCount) << k;
        for (int p = 0; p < compound[k].pointCount; ++p) {
            EXPECT_EQ(compound[k].points[p].feature, separate[k].points[p].feature);
            EXPECT_NEAR(compound[k].points[p].depth, separate[k].points[p].depth, 1e-5f) << k << " " << p;
            expectVecNear(compound[k].points[p].position, separate[k].points[p].position, 1e-5f);
        }
    }
}

}  // namespace
