// Polytope contact kernels (src/narrowphase/hull_pairs.*): random hulls from the engine's hull builder against
// libccd (GJK/EPA/MPR in double precision, support functions in ccd_oracle.h) and against a brute-force
// double-precision SAT over every face and every edge pair (no Gauss-map pruning: a check of the pruning), the
// box-box kernel as a second algorithm on boxes given as hulls, analytic capsule-box resting cases, speculative
// margins, feature-id stability and 10 km coordinates.
//
// Tolerances ("size" = the larger shape's largest vertex distance from its centre):
// - overlap: the kernel (margin 0) and libccd agree except within |SAT separation| < 1e-4 * size (hulls; from the
//   brute-force SAT) or where the answer flips when the capsule radius is grown or shrunk by 1e-4 * size;
// - depth: within 1e-4 * size of the brute-force double SAT and 1e-3 * size of EPA, normal within 1e-2 rad of the
//   brute-force SAT axis, checked where the pair clearly penetrates (depth > 1e-2 * size) and the best axis is
//   clear (every axis more than 0.02 rad away is at least 6% + 1e-3 * size shallower; at near-ties the kernel's
//   hysteresis may keep a slightly worse face, by design);
// - for every hit: the reported normal is a valid push-out direction: moving B along it by the reported depth
//   + 1e-3 * size + 6% of the depth separates the shapes (libccd MPR; independent of ties);
// - box as hull vs box-box kernel: same hit, deepest depth within 1e-4 * size, normal within 4.5e-3 rad, same point
//   count, on clear cases;
// - capsule-box (closed-form candidate axes) vs capsule-hull on the box's corners (GJK): same hit, deepest depth
//   within 1e-4 * size, normals within 0.999 (cosine), on every pose;
// - zero-length capsule vs the sphere-box kernel: same hit, depth within 1e-5, normal within 1e-5 (1 - cosine),
//   point within 1e-4.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <set>
#include <vector>

#include "narrowphase/box_box.h"
#include "narrowphase/ccd_oracle.h"
#include "narrowphase/hull_pairs.h"
#include "shapes/shape.h"
#include "support/test_shapes.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using namespace rubble::test;

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
    const float n = std::sqrt(x * x + y * y + z * z + w * w);
    return {x / n, y / n, z / n, w / n};
}

ConvexHull randomHull(std::mt19937& rng, int points, float scale) {
    const Shape shape = buildShape(ConvexHullDef{randomHullCloud(rng, points, scale)});
    return *shape.hull;
}

ConvexHull boxHull(Vec3 h) { return *buildShape(ConvexHullDef{boxCorners(h)}).hull; }

/// World vertices, face normals and edges of a posed hull, in double.
struct WorldHull {
    std::vector<D3> v, n;
    std::vector<std::pair<int, int>> e;
};
WorldHull worldHull(const ConvexHull& h, const Transform& t) {
    WorldHull w;
    const D3 p = d3(t.position);
    for (const Vec3& x : h.vertices) {
        const D3 r = rotd(t, x);
        w.v.push_back({r.x + p.x, r.y + p.y, r.z + p.z});
    }
    for (const Vec3& n : h.faceNormals) w.n.push_back(rotd(t, n));
    for (std::size_t k = 0; k + 1 < h.edges.size(); k += 2)
        w.e.push_back({static_cast<int>(h.edges[k]), static_cast<int>(h.edges[k + 1])});
    return w;
}

/// Brute-force SAT in double over all face normals and all edge pairs: separation along the best axis (A -> B,
/// computed from full supports, so every axis gives a valid bound) and the best separation among axes more than
/// 0.02 rad away from it.
struct SatResult {
    double sep = -INFINITY, runnerUp = -INFINITY;
    D3 axis{0, 0, 0};
};
SatResult bruteSat(const WorldHull& a, const WorldHull& b) {
    std::vector<std::pair<double, D3>> axes;
    auto eval = [&](D3 n) {
        const double len = lend(n);
        if (len < 1e-9) return;
        n = {n.x / len, n.y / len, n.z / len};
        for (int s = 0; s < 2; ++s) {
            double hiA = -INFINITY, loB = INFINITY;
            for (const D3& p : a.v) hiA = std::max(hiA, dotd(n, p));
            for (const D3& p : b.v) loB = std::min(loB, dotd(n, p));
            axes.push_back({loB - hiA, n});
            n = {-n.x, -n.y, -n.z};
        }
    };
    for (const D3& n : a.n) eval(n);
    for (const D3& n : b.n) eval(n);
    for (auto [i, j] : a.e)
        for (auto [k, l] : b.e) {
            const D3 da = a.v[j] - a.v[i], db = b.v[l] - b.v[k];
            const D3 c = crossd(da, db);
            if (lend(c) < 1e-3 * lend(da) * lend(db)) continue;  // as the kernel: parallel edges are face-covered
            eval(c);
        }
    SatResult r;
    for (auto& [s, n] : axes)
        if (s > r.sep) r.sep = s, r.axis = n;
    for (auto& [s, n] : axes)
        if (dotd(n, r.axis) < std::cos(0.02)) r.runnerUp = std::max(r.runnerUp, s);
    return r;
}

OracleShape oracleHull(const ConvexHull& h, const Transform& t) {
    OracleShape s;
    s.kind = OracleShape::Kind::Hull;
    s.points = h.vertices;
    test::setPose(s, t);
    return s;
}

/// Whether moving B by `distance` along unit n (A -> B) separates the shapes (libccd MPR).
bool separatesAfterMove(const OracleShape& a, OracleShape b, D3 n, double distance) {
    b.pos[0] += n.x * distance, b.pos[1] += n.y * distance, b.pos[2] += n.z * distance;
    return !test::oracleMprIntersect(a, b);
}

float maxDepth(const Manifold& m) {
    float d = -INFINITY;
    for (int k = 0; k < m.pointCount; ++k) d = std::max(d, m.points[k].depth);
    return d;
}

float hullSize(const ConvexHull& h) {
    Vec3 c{};
    for (const Vec3& p : h.vertices) c += p;
    c = c / static_cast<float>(h.vertices.size());
    float s = 0;
    for (const Vec3& p : h.vertices) s = std::max(s, length(p - c));
    return s;
}

// ---------------------------------------------------------------------------------------------------------------

TEST(HullPairs, AdjacencyOfBuiltHulls) {
    std::mt19937 rng(7);
    for (int it = 0; it < 50; ++it) {
        const ConvexHull h = randomHull(rng, 8 + it % 20, 1.0f);
        const HullAdjacency adj = buildHullAdjacency(h);
        ASSERT_EQ(adj.edges.size() * 2, h.edges.size());
        for (std::uint32_t f = 0; f < h.faceCount(); ++f) {
            for (const Vec3& v : h.vertices) EXPECT_LE(dot(h.faceNormals[f], v), h.faceOffsets[f] + 1e-5f);
            for (std::uint32_t k = h.faceStart[f]; k < h.faceStart[f + 1]; ++k)
                EXPECT_NEAR(dot(h.faceNormals[f], h.vertices[h.faceVertices[k]]), h.faceOffsets[f], 1e-5f);
        }
        for (const HullEdge& e : adj.edges) {
            // The edge direction is parallel to n0 x n1 (face0 holds v0 -> v1 counter-clockwise).
            const Vec3 d = h.vertices[e.v1] - h.vertices[e.v0];
            const Vec3 c = cross(h.faceNormals[e.face0], h.faceNormals[e.face1]);
            EXPECT_NE(e.face0, e.face1);
            EXPECT_GT(dot(d, c), 0.99f * length(d) * length(c));
        }
    }
}

TEST(HullPairs, RandomHullsAgreeWithLibccdAndBruteForceSat) {
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1);
    std::uniform_int_distribution<int> count(12, 24);
    int disagree = 0, band = 0, checked = 0, ties = 0, hits = 0, pushOutFailures = 0;
    for (int it = 0; it < 3000; ++it) {
        const ConvexHull a = randomHull(rng, count(rng), 0.8f), b = randomHull(rng, count(rng), 0.8f);
        const Transform pa{{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::max(length(dir), 1e-3f);
        const float sa = hullSize(a), sb = hullSize(b), size = std::max(sa, sb);
        // Offsets from half to all of the sum of the sizes: contacts from deep to grazing and misses.
        const Transform pb{pa.position + dir * ((0.5f + 0.5f * frac(rng)) * (sa + sb)), randomRotation(rng)};
        Manifold m;
        const bool hit = collideHulls(a, pa, b, pb, 0.0f, m);
        const OracleShape oa = oracleHull(a, pa), ob = oracleHull(b, pb);
        const bool oracle = test::oracleMprIntersect(oa, ob);
        const SatResult sat = bruteSat(worldHull(a, pa), worldHull(b, pb));
        if (std::fabs(sat.sep) < 1e-4 * size) {
            ++band;
            continue;
        }
        if (hit != oracle) ++disagree;
        EXPECT_EQ(hit, sat.sep < 0) << "pair " << it << " sat " << sat.sep;
        if (!hit) continue;
        ++hits;
        ASSERT_GE(m.pointCount, 1);
        ASSERT_LE(m.pointCount, 4);
        EXPECT_NEAR(length(m.normal), 1.0f, 1e-5f);
        const float depth = maxDepth(m);
        // Push-out check, independent of ties: the reported normal and depth separate the hulls.
        const D3 n = d3(m.normal);
        if (!separatesAfterMove(oa, ob, n, depth + 1e-3 * size + 0.06 * std::fabs(depth))) ++pushOutFailures;
        const double pen = -sat.sep;
        if (pen < 1e-2 * size) continue;
        if (sat.sep - sat.runnerUp < 0.06 * pen + 1e-3 * size) {
            ++ties;
            continue;
        }
        ++checked;
        EXPECT_NEAR(depth, pen, 1e-4 * size + 1e-5) << "pair " << it;
        EXPECT_GT(dotd(n, sat.axis), std::cos(1e-2))
            << "pair " << it << " pen " << pen << " runner-up " << sat.runnerUp;
        const test::OraclePenetration epa = test::oraclePenetration(oa, ob);
        EXPECT_TRUE(epa.hit);
        EXPECT_NEAR(depth, epa.depth, 1e-3 * size) << "pair " << it;
        for (int k = 0; k < m.pointCount; ++k) EXPECT_GE(m.points[k].depth, -1e-5f);
    }
    // MPR and the double SAT must agree outside the band; allow a handful of oracle failures.
    EXPECT_LE(disagree, 3);
    EXPECT_EQ(pushOutFailures, 0);
    EXPECT_GT(hits, 600);
    EXPECT_GT(checked, 150);
    std::printf("hull-hull: %d hits, %d clear cases checked, %d near-ties skipped, %d in band, %d MPR disagreements\n",
                hits, checked, ties, band, disagree);
}

TEST(HullPairs, BoxAsHullMatchesBoxBoxKernel) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1), half(0.1f, 1.0f);
    int checked = 0;
    for (int it = 0; it < 1500; ++it) {
        const Vec3 ha{half(rng), half(rng), half(rng)}, hb{half(rng), half(rng), half(rng)};
        const Transform pa{{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::max(length(dir), 1e-3f);
        const Transform pb{pa.position + dir * (0.8f * frac(rng) * (length(ha) + length(hb))), randomRotation(rng)};
        const ConvexHull hullA = boxHull(ha), hullB = boxHull(hb);
        const float size = std::max(length(ha), length(hb));
        const SatResult sat = bruteSat(worldHull(hullA, pa), worldHull(hullB, pb));
        if (std::fabs(sat.sep) < 1e-4 * size) continue;
        Manifold mBox, mBoxHull, mHulls;
        const bool hBox = collideBoxes(pa, ha, pb, hb, 0.0f, mBox);
        const bool hBoxHull = collideBoxHull(pa, ha, hullB, pb, 0.0f, mBoxHull);
        const bool hHulls = collideHulls(hullA, pa, hullB, pb, 0.0f, mHulls);
        EXPECT_EQ(hBox, hBoxHull) << it;
        EXPECT_EQ(hBox, hHulls) << it;
        if (!hBox || !hBoxHull || !hHulls) continue;
        if (-sat.sep < 1e-2 * size || sat.sep - sat.runnerUp < -0.06 * sat.sep + 1e-3 * size) continue;
        ++checked;
        for (const Manifold* m : {&mBoxHull, &mHulls}) {
            EXPECT_NEAR(maxDepth(*m), maxDepth(mBox), 1e-4f * size) << it;
            EXPECT_GT(dot(m->normal, mBox.normal), 0.99999f) << it;  // 4.5e-3 rad
            EXPECT_EQ(m->pointCount, mBox.pointCount) << it;
        }
    }
    EXPECT_GT(checked, 300);
}

/// A hull resting with face `f` down on a ground box (top at y = 0.5), sunk by `sink`, yawed and tilted.
Transform restingPose(const ConvexHull& h, int f, float sink, Vec3 at, Quat perturb) {
    // Rotate the face normal onto -y.
    const Vec3 n = h.faceNormals[f];
    const Vec3 axis = cross(n, {0, -1, 0});
    const float s = length(axis), c = -n.y;
    const Quat q = s > 1e-6f ? Quat::fromAxisAngle(axis, std::atan2(s, c)) : (c > 0 ? Quat{} : Quat{1, 0, 0, 0});
    const Quat rot = perturb * q;
    const float offset = h.faceOffsets[f];  // the face lies at distance offset below the origin after rotation
    return {{at.x, at.y + 0.5f + offset - sink, at.z}, rot};
}

TEST(HullPairs, RestingHullOnBoxHasStableFeatureIds) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    const Vec3 groundHalf{20, 0.5f, 20};
    for (int it = 0; it < 40; ++it) {
        const ConvexHull h = randomHull(rng, 16, 0.6f);
        // The largest face goes down.
        int f = 0;
        for (int k = 1; k < static_cast<int>(h.faceCount()); ++k)
            if (h.faceStart[k + 1] - h.faceStart[k] > h.faceStart[f + 1] - h.faceStart[f]) f = k;
        const Vec3 at{5 * u(rng), 0, 5 * u(rng)};
        for (const Vec3 origin : {Vec3{0, 0, 0}, Vec3{10000, 0, -10000}}) {
            const Transform ground{origin, {}};
            Manifold ref;
            const Transform p0 = restingPose(h, f, 0.01f, at + origin, {});
            ASSERT_TRUE(collideBoxHull(ground, groundHalf, h, p0, 0.02f, ref));
            EXPECT_NEAR(ref.normal.y, 1.0f, 1e-5f);
            ASSERT_GE(ref.pointCount, 3);
            std::set<std::uint32_t> ids;
            for (int k = 0; k < ref.pointCount; ++k) {
                ids.insert(ref.points[k].feature);
                EXPECT_NEAR(ref.points[k].depth, 0.01f, 2e-4f);
                EXPECT_NEAR(ref.points[k].position.y - origin.y, 0.5f - 0.01f, 2e-3f);
            }
            for (int trial = 0; trial < 20; ++trial) {
                const Quat wobble = Quat::fromAxisAngle({u(rng), u(rng), u(rng)}, 2e-4f);
                Transform p = restingPose(h, f, 0.01f, at + origin, wobble);
                p.position += Vec3{1e-4f * u(rng), 1e-4f * u(rng), 1e-4f * u(rng)};
                Manifold m;
                ASSERT_TRUE(collideBoxHull(ground, groundHalf, h, p, 0.02f, m));
                ASSERT_EQ(m.pointCount, ref.pointCount);
                std::set<std::uint32_t> got;
                for (int k = 0; k < m.pointCount; ++k) got.insert(m.points[k].feature);
                EXPECT_EQ(got, ids) << "hull " << it << " trial " << trial;
            }
        }
    }
}

TEST(HullPairs, FarFromOriginMatchesOrigin) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1);
    for (int it = 0; it < 300; ++it) {
        const ConvexHull a = randomHull(rng, 16, 0.8f), b = randomHull(rng, 16, 0.8f);
        const Transform pa{{0, 0, 0}, randomRotation(rng)};
        // Offsets on the float grid at 10 km (2^-10), so that both placements describe exactly the same pair.
        auto grid = [](float x) { return std::round(x * 1024.0f) / 1024.0f; };
        const Transform pb{{grid(0.8f * u(rng)), grid(0.8f * u(rng)), grid(0.8f * u(rng))}, randomRotation(rng)};
        const Vec3 far{10000, -10000, 10000};
        Manifold m0, m1;
        const bool h0 = collideHulls(a, pa, b, pb, 0.0f, m0);
        const bool h1 =
            collideHulls(a, {pa.position + far, pa.rotation}, b, {pb.position + far, pb.rotation}, 0.0f, m1);
        ASSERT_EQ(h0, h1);
        if (!h0) continue;
        ASSERT_EQ(m0.pointCount, m1.pointCount);
        EXPECT_GT(dot(m0.normal, m1.normal), 1 - 1e-6f);
        for (int k = 0; k < m0.pointCount; ++k) {
            EXPECT_EQ(m0.points[k].feature, m1.points[k].feature);
            EXPECT_NEAR(m0.points[k].depth, m1.points[k].depth, 1e-6f);
            // Positions round only once, to the float spacing at 10 km (~1e-3).
            EXPECT_LT(length(m1.points[k].position - far - m0.points[k].position), 2e-3f);
        }
    }
}

/// Bitwise equality of two manifolds (the hint may only save time, never change a bit of the answer).
void expectSameManifold(const Manifold& m0, const Manifold& m1, const char* what, int it) {
    ASSERT_EQ(m0.pointCount, m1.pointCount) << what << " " << it;
    if (m0.pointCount == 0) return;
    EXPECT_EQ(std::memcmp(&m0.normal, &m1.normal, sizeof(Vec3)), 0) << what << " " << it;
    for (int k = 0; k < m0.pointCount; ++k) {
        EXPECT_EQ(std::memcmp(&m0.points[k].position, &m1.points[k].position, sizeof(Vec3)), 0) << what << " " << it;
        EXPECT_EQ(std::memcmp(&m0.points[k].depth, &m1.points[k].depth, sizeof(float)), 0) << what << " " << it;
        EXPECT_EQ(m0.points[k].feature, m1.points[k].feature) << what << " " << it;
    }
}

// A pair moved as over consecutive steps (1 cm and 0.01 rad each), with the hint of its last call, then with a hint
// from another pair (stale indices, foreign kinds): the manifold must equal the hint-less one bit for bit, and the
// separated calls the hint answered alone must be the common case.
TEST(HullPairs, SatHintNeverChangesTheAnswer) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1);
    int separated = 0, answeredByHint = 0;
    SatHint foreign;
    for (int it = 0; it < 200; ++it) {
        const ConvexHull a = randomHull(rng, 32, 1.0f), b = randomHull(rng, 24, 0.8f);
        const HullAdjacency adjA = buildHullAdjacency(a), adjB = buildHullAdjacency(b);
        Transform pa{{0, 0, 0}, randomRotation(rng)};
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::fmax(length(dir), 1e-3f);
        Transform pb{dir * ((0.6f + 0.6f * frac(rng)) * (hullSize(a) + hullSize(b))), randomRotation(rng)};
        const Vec3 step = Vec3{u(rng), u(rng), u(rng)} * 0.01f;
        const Quat turn = Quat::fromAxisAngle(Vec3{u(rng), u(rng), u(rng)} + Vec3{0, 0, 1e-3f}, 0.01f);
        SatHint hint;
        for (int s = 0; s < 8; ++s) {
            const float margin = s % 2 ? 0.02f : 0.1f;
            Manifold plain, hinted, stale;
            const bool hit = collideHulls(a, adjA, pa, b, adjB, pb, margin, plain);
            const SatHint before = hint;
            const bool hitHinted = collideHulls(a, adjA, pa, b, adjB, pb, margin, hinted, &hint);
            SatHint other = foreign;
            const bool hitStale = collideHulls(a, adjA, pa, b, adjB, pb, margin, stale, &other);
            ASSERT_EQ(hit, hitHinted) << it << " step " << s;
            ASSERT_EQ(hit, hitStale) << it << " step " << s;
            expectSameManifold(plain, hinted, "hinted", it);
            expectSameManifold(plain, stale, "stale", it);
            if (!hit) {
                ++separated;
                EXPECT_TRUE(hint.separated) << it << " step " << s;
                // The hint answered alone when it named the axis it was given.
                if (before.separated && hint.kind == before.kind && hint.a == before.a && hint.b == before.b)
                    ++answeredByHint;
            }
            foreign = hint;
            pb = {pb.position + step - dir * 0.01f, turn * pb.rotation};
            pa = {pa.position, conjugate(turn) * pa.rotation};
        }
    }
    EXPECT_GT(separated, 200);
    EXPECT_GT(answeredByHint, separated / 2);
}

// The face scans and the edge pairs test only the faces and edges that can reach the cone of axes along which the
// hulls could be apart by more than what matters (HullAdjacency::inradius). An inradius of zero turns that off: the
// manifolds must be the same bit for bit with and without it, over poses from deep overlap to apart, hull-hull and
// box-hull, and among them many that an edge pair decides.
TEST(HullPairs, AxisConesNeverChangeTheAnswer) {
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1);
    int touching = 0, edgeContacts = 0;
    for (int it = 0; it < 400; ++it) {
        const ConvexHull a = randomHull(rng, 8 + it % 40, 1.0f), b = randomHull(rng, 6 + it % 30, 0.7f);
        const HullAdjacency adjA = buildHullAdjacency(a), adjB = buildHullAdjacency(b);
        HullAdjacency allA = adjA, allB = adjB;
        allA.inradius = allB.inradius = 0;
        ASSERT_GT(adjA.inradius, 0.0f) << it;
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::fmax(length(dir), 1e-3f);
        const Transform pa{{0.3f * u(rng), 0, 0}, randomRotation(rng)};
        const Transform pb{pa.position + dir * ((0.1f + 0.9f * frac(rng)) * (hullSize(a) + hullSize(b))),
                           randomRotation(rng)};
        const float margin = it % 2 ? 0.02f : 0.1f;
        Manifold culled, all;
        const bool hit = collideHulls(a, adjA, pa, b, adjB, pb, margin, culled);
        ASSERT_EQ(hit, collideHulls(a, allA, pa, b, allB, pb, margin, all)) << it;
        expectSameManifold(all, culled, "hull-hull", it);
        touching += hit;
        edgeContacts += hit && culled.points[0].feature >> 30 == 2;
        const Vec3 half{0.2f + frac(rng), 0.2f + frac(rng), 0.2f + frac(rng)};
        const bool boxHit = collideBoxHull(pa, half, b, adjB, pb, margin, culled);
        ASSERT_EQ(boxHit, collideBoxHull(pa, half, b, allB, pb, margin, all)) << it;
        expectSameManifold(all, culled, "box-hull", it);
        touching += boxHit;
        edgeContacts += boxHit && culled.points[0].feature >> 30 == 2;
    }
    EXPECT_GT(touching, 300);
    EXPECT_GT(edgeContacts, 40);
}

// Contact-feature reuse (SatHint, featureDrift): pairs that settle and slide as in a pile (each call B moves up to
// 4 mm and turns 0.005 rad relative to A), each computed with the feature kept from its last call and by the whole
// search. Where both touch, the deepest point of the reused contact lies within the drift (plus 2 mm for the
// motion of one call) of the search's; where the search finds the pair apart by more than the margin, the reused
// contact's points are no deeper than the drift below the margin: a feature only ever stays while its own
// separation is within the drift of what the search found for it. With a drift of zero the answer is the
// search's, bit for bit. Most calls must be answered by the reused feature (else this tests nothing).
TEST(HullPairs, FeatureReuseStaysCloseToTheSearch) {
    constexpr float kDrift = 0.005f;
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1);
    int calls = 0, reused = 0;
    float worstDepth = 0;
    for (int it = 0; it < 150; ++it) {
        const ConvexHull a = randomHull(rng, 32, 1.0f), b = randomHull(rng, 32, 1.0f);
        const HullAdjacency adjA = buildHullAdjacency(a), adjB = buildHullAdjacency(b);
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::fmax(length(dir), 1e-3f);
        const Transform pa{{0, 0, 0}, randomRotation(rng)};
        Transform pb{dir * (0.9f * (hullSize(a) + hullSize(b))), randomRotation(rng)};
        // Bring B to first touch along -dir, then let it wander.
        Manifold probe;
        for (int k = 0; k < 400 && !collideHulls(a, adjA, pa, b, adjB, pb, 0.0f, probe); ++k)
            pb.position = pb.position - dir * 0.005f;
        SatHint kept, exact;
        for (int s = 0; s < 40; ++s) {
            const float margin = 0.02f;
            Manifold fromFeature, searched, bitForBit;
            const std::uint8_t reusesBefore = kept.reuses;
            const SatHint keptBefore = kept;
            const bool hitFeature = collideHulls(a, adjA, pa, b, adjB, pb, margin, fromFeature, &kept, kDrift);
            const bool hitSearch = collideHulls(a, adjA, pa, b, adjB, pb, margin, searched, &exact);
            SatHint noDrift = keptBefore;
            ASSERT_EQ(hitSearch, collideHulls(a, adjA, pa, b, adjB, pb, margin, bitForBit, &noDrift, 0.0f));
            expectSameManifold(searched, bitForBit, "no drift", it);
            ++calls;
            const bool answeredByFeature = hitFeature && kept.reuses == reusesBefore + 1;
            reused += answeredByFeature;
            const auto deepest = [](const Manifold& m) {
                float d = -INFINITY;
                for (int k = 0; k < m.pointCount; ++k) d = std::fmax(d, m.points[k].depth);
                return d;
            };
            if (hitFeature && hitSearch) {
                const float gap = std::fabs(deepest(fromFeature) - deepest(searched));
                worstDepth = std::fmax(worstDepth, gap);
                EXPECT_LE(gap, kDrift + 0.002f) << it << " step " << s;
            } else if (hitFeature) {
                EXPECT_LE(deepest(fromFeature), -margin + kDrift + 0.002f) << it << " step " << s;
            }
            const Vec3 slide{u(rng), u(rng), u(rng)};
            pb = {pb.position + slide * 0.004f / std::sqrt(3.0f) - dir * 0.0005f,
                  Quat::fromAxisAngle(Vec3{u(rng), u(rng), u(rng)} + Vec3{0, 0, 1e-3f}, 0.005f) * pb.rotation};
        }
    }
    std::printf("feature reuse: %d of %d calls answered by the kept feature; worst deepest-point gap %.4f m\n", reused,
                calls, worstDepth);
    EXPECT_GT(reused, calls / 3);
}

TEST(HullPairs, SpeculativeMargin) {
    const ConvexHull cube = boxHull({0.5f, 0.5f, 0.5f});
    const Transform ground{{0, 0, 0}, {}};
    const Transform above{{0.3f, 0.5f + 0.5f + 0.03f, -0.2f}, Quat::fromAxisAngle({0, 1, 0}, 0.3f)};
    Manifold m;
    EXPECT_FALSE(collideBoxHull(ground, {2, 0.5f, 2}, cube, above, 0.02f, m));
    EXPECT_EQ(m.pointCount, 0);
    ASSERT_TRUE(collideBoxHull(ground, {2, 0.5f, 2}, cube, above, 0.05f, m));
    EXPECT_EQ(m.pointCount, 4);
    for (int k = 0; k < m.pointCount; ++k) EXPECT_NEAR(m.points[k].depth, -0.03f, 1e-5f);
    ASSERT_TRUE(collideHulls(cube, ground, cube, {{0.2f, 1.03f, 0}, {}}, 0.05f, m));
    EXPECT_EQ(m.pointCount, 4);
    EXPECT_NEAR(m.normal.y, 1.0f, 1e-6f);
    for (int k = 0; k < m.pointCount; ++k) EXPECT_NEAR(m.points[k].depth, -0.03f, 1e-5f);
    // Edge-on-edge above the margin band: one speculative point.
    const Transform edgeA{{0, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, 0.785398f)};
    const Transform edgeB{{0, 2 * 0.7071068f + 0.01f, 0}, Quat::fromAxisAngle({1, 0, 0}, 0.785398f) * Quat{}};
    ASSERT_TRUE(collideHulls(cube, edgeA, cube, edgeB, 0.05f, m));
    EXPECT_EQ(m.pointCount, 1);
    EXPECT_NEAR(m.points[0].depth, -0.01f, 1e-4f);
    EXPECT_NEAR(m.normal.y, 1.0f, 1e-4f);
    EXPECT_EQ(m.points[0].feature >> 30, 2u);
}

// ---- Capsules ---------------------------------------------------------------------------------------------------

CapsuleSegment capsuleAt(Vec3 c, Vec3 halfAxis, float r) { return {c, halfAxis, r}; }

TEST(CapsuleBox, LyingFlatGivesTwoPoints) {
    const Vec3 half{2, 0.5f, 2};
    for (const Vec3 origin : {Vec3{0, 0, 0}, Vec3{-10000, 0, 10000}}) {
        const Transform box{origin, {}};
        Manifold m;
        // Shallow (cores apart: GJK path) and deep (cores overlap: SAT path).
        for (const float sink : {0.01f, 0.2f, 0.4f}) {
            ASSERT_TRUE(collideCapsuleBox(
                capsuleAt(origin + Vec3{0.3f, 0.5f + 0.25f - sink, 0.1f}, {0.5f, 0, 0}, 0.25f), box, half, 0.02f, m));
            ASSERT_EQ(m.pointCount, 2) << sink;
            EXPECT_NEAR(m.normal.y, -1.0f, 1e-5f);
            for (int k = 0; k < 2; ++k) {
                EXPECT_NEAR(m.points[k].depth, sink, 2e-5f);
                EXPECT_NEAR(m.points[k].position.y - origin.y, 0.5f, 1e-3f);
            }
            EXPECT_NEAR(std::fabs(m.points[0].position.x - m.points[1].position.x), 1.0f, 2e-3f);
        }
        // Hanging over the +x edge: the far end is clipped at x = 2.
        ASSERT_TRUE(
            collideCapsuleBox(capsuleAt(origin + Vec3{2.0f, 0.74f, 0}, {0.5f, 0, 0}, 0.25f), box, half, 0.02f, m));
        ASSERT_EQ(m.pointCount, 2);
        const float xs[2] = {m.points[0].position.x - origin.x, m.points[1].position.x - origin.x};
        EXPECT_NEAR(std::min(xs[0], xs[1]), 1.5f, 2e-3f);
        EXPECT_NEAR(std::max(xs[0], xs[1]), 2.0f, 2e-3f);
        EXPECT_NE(m.points[0].feature, m.points[1].feature);
    }
}

TEST(CapsuleBox, StandingOnEndGivesOnePoint) {
    const Transform box{{0, 0, 0}, {}};
    Manifold m;
    for (const float sink : {0.01f, 0.3f}) {
        ASSERT_TRUE(collideCapsuleBox(capsuleAt({0.2f, 0.5f + 0.5f + 0.25f - sink, -0.3f}, {0, 0.5f, 0}, 0.25f), box,
                                      {2, 0.5f, 2}, 0.02f, m));
        ASSERT_EQ(m.pointCount, 1);
        EXPECT_NEAR(m.normal.y, -1.0f, 1e-5f);
        EXPECT_NEAR(m.points[0].depth, sink, 2e-5f);
        EXPECT_NEAR(m.points[0].position.x, 0.2f, 1e-5f);
        EXPECT_NEAR(m.points[0].position.z, -0.3f, 1e-5f);
    }
    // Slightly tilted: still one point (the upper end is far outside the margin).
    const Vec3 tilted = rotate(Quat::fromAxisAngle({1, 0, 0}, 0.1f), {0, 0.5f, 0});
    ASSERT_TRUE(collideCapsuleBox(capsuleAt({0, 0.5f + tilted.y + 0.25f - 0.01f, 0}, tilted, 0.25f), box, {2, 0.5f, 2},
                                  0.02f, m));
    EXPECT_EQ(m.pointCount, 1);
}

TEST(CapsuleBox, EdgeAndCornerContacts) {
    const Transform box{{0, 0, 0}, {}};
    const Vec3 half{1, 0.5f, 1};
    Manifold m;
    // Across the top +x edge (capsule along z, beside and above the edge): one point on the edge.
    ASSERT_TRUE(collideCapsuleBox(capsuleAt({1.1f, 0.7f, 0}, {0, 0, 0.5f}, 0.25f), box, half, 0.0f, m));
    // The closest points on the edge form a segment parallel to the capsule: GJK returns one of them.
    ASSERT_GE(m.pointCount, 1);
    const float expected = 0.25f - std::sqrt(0.1f * 0.1f + 0.2f * 0.2f);
    EXPECT_NEAR(m.points[0].depth, expected, 1e-5f);
    EXPECT_NEAR(m.points[0].position.x, 1.0f, 1e-5f);
    EXPECT_NEAR(m.points[0].position.y, 0.5f, 1e-5f);
    EXPECT_NEAR(m.normal.x, -0.1f / std::sqrt(0.05f), 1e-4f);
    // End cap on a corner.
    ASSERT_TRUE(collideCapsuleBox(capsuleAt({1.1f, 1.2f, 1.1f}, {0, 0.5f, 0}, 0.25f), box, half, 0.0f, m));
    ASSERT_EQ(m.pointCount, 1);
    EXPECT_NEAR(m.points[0].depth, 0.25f - std::sqrt(0.01f + 0.04f + 0.01f), 1e-5f);
    // Speculative: lying flat 0.05 above the face.
    EXPECT_FALSE(collideCapsuleBox(capsuleAt({0, 0.8f, 0}, {0.5f, 0, 0}, 0.25f), box, half, 0.02f, m));
    ASSERT_TRUE(collideCapsuleBox(capsuleAt({0, 0.8f, 0}, {0.5f, 0, 0}, 0.25f), box, half, 0.1f, m));
    ASSERT_EQ(m.pointCount, 2);
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(m.points[k].depth, -0.05f, 1e-5f);
    // Capsule through the box along an axis (cores overlap deeply).
    ASSERT_TRUE(collideCapsuleBox(capsuleAt({0, 0.3f, 0}, {0, 0, 2}, 0.1f), box, half, 0.0f, m));
    EXPECT_NEAR(m.normal.y, -1.0f, 1e-5f);
    EXPECT_NEAR(maxDepth(m), 0.3f, 1e-5f);  // out through the top face: 0.5 - (0.3 - 0.1)
}

TEST(CapsuleBox, RestingFeatureIdsStable) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    const Transform box{{0, 0, 0}, {}};
    Manifold ref;
    ASSERT_TRUE(collideCapsuleBox(capsuleAt({0.3f, 0.74f, 0.2f}, {0.5f, 0, 0}, 0.25f), box, {2, 0.5f, 2}, 0.02f, ref));
    ASSERT_EQ(ref.pointCount, 2);
    for (int trial = 0; trial < 50; ++trial) {
        const Vec3 ha = rotate(Quat::fromAxisAngle({u(rng), u(rng), u(rng)}, 2e-4f), {0.5f, 0, 0});
        Manifold m;
        ASSERT_TRUE(
            collideCapsuleBox(capsuleAt(Vec3{0.3f, 0.74f, 0.2f} + Vec3{u(rng), u(rng), u(rng)} * 1e-4f, ha, 0.25f), box,
                              {2, 0.5f, 2}, 0.02f, m));
        ASSERT_EQ(m.pointCount, 2);
        EXPECT_EQ(m.points[0].feature, ref.points[0].feature);
        EXPECT_EQ(m.points[1].feature, ref.points[1].feature);
    }
}

OracleShape oracleCapsule(const CapsuleSegment& c, double inflate) {
    OracleShape s;
    s.kind = OracleShape::Kind::Capsule;
    const float h = length(c.halfAxis);
    s.halfHeight = h;
    s.radius = c.radius;
    s.inflate = inflate;
    const Quat q =
        h > 0 ? Quat::fromAxisAngle(cross({0, 1, 0}, c.halfAxis), std::acos(std::clamp(c.halfAxis.y / h, -1.0f, 1.0f)))
              : Quat{};
    test::setPose(s, {c.center, q});
    return s;
}

TEST(CapsuleBox, RandomPosesAgreeWithLibccd) {
    std::mt19937 rng(77);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1), half(0.1f, 1.0f);
    int hits = 0, checked = 0, band = 0, disagree = 0, pushOutFailures = 0, capsuleHullMismatch = 0, ties = 0;
    for (int it = 0; it < 3000; ++it) {
        const Vec3 hb{half(rng), half(rng), half(rng)};
        const Transform pb{{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        const float hh = 0.8f * frac(rng), radius = 0.05f + 0.5f * frac(rng);
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::max(length(dir), 1e-3f);
        const float size = std::max(length(hb), hh + radius);
        const Vec3 axis = rotate(randomRotation(rng), {0, hh, 0});
        const CapsuleSegment cap{pb.position + dir * (1.1f * frac(rng) * (length(hb) + hh + radius)), axis, radius};
        Manifold m;
        const bool hit = collideCapsuleBox(cap, pb, hb, 0.0f, m);
        OracleShape ob;
        ob.kind = OracleShape::Kind::Box;
        ob.half[0] = hb.x, ob.half[1] = hb.y, ob.half[2] = hb.z;
        test::setPose(ob, pb);
        const double tol = 1e-4 * size;
        const bool grown = test::oracleMprIntersect(oracleCapsule(cap, tol), ob);
        const bool shrunk = test::oracleMprIntersect(oracleCapsule(cap, -std::min<double>(tol, radius)), ob);
        if (grown != shrunk) {
            ++band;
            continue;
        }
        if (hit != grown) ++disagree;
        // The hull of the box's corners must give the same answer through collideCapsuleHull.
        Manifold mh;
        const ConvexHull bh = boxHull(hb);
        const bool hitHull = collideCapsuleHull(cap, bh, pb, 0.0f, mh);
        if (hitHull != hit ||
            (hit && (std::fabs(maxDepth(mh) - maxDepth(m)) > 1e-4f * size || dot(mh.normal, m.normal) < 0.999f)))
            ++capsuleHullMismatch;
        if (!hit) continue;
        ++hits;
        ASSERT_GE(m.pointCount, 1);
        ASSERT_LE(m.pointCount, 2);
        const OracleShape oa = oracleCapsule(cap, 0);
        const float depth = maxDepth(m);
        if (!separatesAfterMove(oa, ob, d3(m.normal), depth + 1e-3 * size + 0.06 * std::fabs(depth))) {
            ++pushOutFailures;
            ADD_FAILURE() << "pair " << it << ": not separated by moving the depth " << depth << " along the normal";
        }
        if (depth < 1e-2 * size) continue;
        // Where the cores overlap the kernel runs a SAT with hysteresis: skip near-ties there (double SAT of the
        // segment against the box over the box faces and segment x edge axes; the capsule adds its radius).
        WorldHull segment;
        segment.v = {d3(cap.center - cap.halfAxis), d3(cap.center + cap.halfAxis)};
        segment.e = {{0, 1}};
        const SatResult core = bruteSat(segment, worldHull(bh, pb));
        const double pen = radius - core.sep;
        if (core.sep < 1e-3 * size && core.sep - core.runnerUp < 0.06 * pen + 1e-3 * size) {
            ++ties;
            continue;
        }
        const test::OraclePenetration epa = test::oracleMprPenetration(oa, ob);
        const test::OraclePenetration gjkEpa = test::oraclePenetration(oa, ob);
        // Check depth only where the two libccd methods agree with each other (EPA and MPR differ on a few poses).
        if (!epa.hit || !gjkEpa.hit || std::fabs(epa.depth - gjkEpa.depth) > 1e-4 * size) continue;
        ++checked;
        EXPECT_NEAR(depth, std::min(epa.depth, gjkEpa.depth), 1e-3 * size) << it;
    }
    EXPECT_LE(disagree, 3);
    EXPECT_EQ(pushOutFailures, 0);
    EXPECT_EQ(capsuleHullMismatch, 0);
    EXPECT_GT(checked, 300);
    std::printf("capsule-box: %d hits, %d depths checked, %d near-ties skipped, %d in band, %d MPR disagreements\n",
                hits, checked, ties, band, disagree);
}

// The capsule-box kernel's closed-form core distance (segment against box, hull_pairs.cpp) against GJK on the hull of
// the box's corners (collideCapsuleHull), for speculative gaps as well as overlaps: the margin is wide enough that
// every pose gets a manifold. Tolerance 1e-4 of the size: both are exact up to float rounding of unit-size inputs,
// GJK's termination tolerance is well below that.
TEST(CapsuleBox, CoreDistanceAgreesWithGjk) {
    std::mt19937 rng(4242);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1), half(0.05f, 1.0f);
    int separated = 0;
    for (int it = 0; it < 5000; ++it) {
        const Vec3 hb{half(rng), half(rng), half(rng)};
        const Transform pb{{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        // Some capsules are axis-aligned with the box (flat on a face, along an edge), where the distance is flat in
        // the segment parameter.
        const float hh = it % 4 == 0 ? 0.0f : 0.8f * frac(rng), radius = 0.02f + 0.3f * frac(rng);
        const Quat capsuleTurn =
            it % 3 == 0 ? pb.rotation * Quat{0, 0, std::sqrt(0.5f), std::sqrt(0.5f)} : randomRotation(rng);
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::max(length(dir), 1e-3f);
        const float size = std::max(length(hb), hh + radius);
        const CapsuleSegment cap{pb.position + dir * (1.6f * frac(rng) * (length(hb) + hh + radius)),
                                 rotate(capsuleTurn, {0, hh, 0}), radius};
        const float margin = 4.0f;
        Manifold m, mh;
        ASSERT_TRUE(collideCapsuleBox(cap, pb, hb, margin, m)) << it;
        ASSERT_TRUE(collideCapsuleHull(cap, boxHull(hb), pb, margin, mh)) << it;
        separated += maxDepth(m) < 0 ? 1 : 0;
        EXPECT_NEAR(maxDepth(m), maxDepth(mh), 1e-4f * size) << it;
        EXPECT_GT(dot(m.normal, mh.normal), 0.999f) << it;
    }
    EXPECT_GT(separated, 2500);
}

}  // namespace

namespace {

TEST(HullPairs, CapsuleHullRandomPosesAgreeWithLibccd) {
    std::mt19937 rng(2024);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1);
    std::uniform_int_distribution<int> count(12, 24);
    int hits = 0, checked = 0, band = 0, disagree = 0, ties = 0, pushOutFailures = 0;
    for (int it = 0; it < 2000; ++it) {
        const ConvexHull h = randomHull(rng, count(rng), 0.8f);
        const Transform ph{{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        const float hh = 0.8f * frac(rng), radius = 0.05f + 0.4f * frac(rng);
        const float hs = hullSize(h), size = std::max(hs, hh + radius);
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::max(length(dir), 1e-3f);
        const CapsuleSegment cap{ph.position + dir * ((0.3f + 0.8f * frac(rng)) * (hs + hh + radius)),
                                 rotate(randomRotation(rng), {0, hh, 0}), radius};
        Manifold m;
        const bool hit = collideCapsuleHull(cap, h, ph, 0.0f, m);
        const OracleShape ob = oracleHull(h, ph);
        const double tol = 1e-4 * size;
        const bool grown = test::oracleMprIntersect(oracleCapsule(cap, tol), ob);
        const bool shrunk = test::oracleMprIntersect(oracleCapsule(cap, -std::min<double>(tol, radius)), ob);
        if (grown != shrunk) {
            ++band;
            continue;
        }
        if (hit != grown) ++disagree;
        if (!hit) continue;
        ++hits;
        ASSERT_GE(m.pointCount, 1);
        ASSERT_LE(m.pointCount, 2);
        const OracleShape oa = oracleCapsule(cap, 0);
        const float depth = maxDepth(m);
        if (!separatesAfterMove(oa, ob, d3(m.normal), depth + 1e-3 * size + 0.06 * std::fabs(depth))) {
            ++pushOutFailures;
            ADD_FAILURE() << "pair " << it << ": not separated by moving the depth " << depth << " along the normal";
        }
        if (depth < 1e-2 * size) continue;
        WorldHull segment;
        segment.v = {d3(cap.center - cap.halfAxis), d3(cap.center + cap.halfAxis)};
        segment.e = {{0, 1}};
        const SatResult core = bruteSat(segment, worldHull(h, ph));
        const double pen = radius - core.sep;
        if (core.sep < 1e-3 * size && core.sep - core.runnerUp < 0.06 * pen + 1e-3 * size) {
            ++ties;
            continue;
        }
        const test::OraclePenetration mpr = test::oracleMprPenetration(oa, ob);
        const test::OraclePenetration epa = test::oraclePenetration(oa, ob);
        if (!mpr.hit || !epa.hit || std::fabs(mpr.depth - epa.depth) > 1e-4 * size) continue;
        ++checked;
        EXPECT_NEAR(depth, std::min(mpr.depth, epa.depth), 1e-3 * size) << it;
    }
    EXPECT_LE(disagree, 3);
    EXPECT_EQ(pushOutFailures, 0);
    EXPECT_GT(checked, 150);
    std::printf("capsule-hull: %d hits, %d depths checked, %d near-ties skipped, %d in band, %d MPR disagreements\n",
                hits, checked, ties, band, disagree);
}

}  // namespace

namespace {

// A capsule of zero length is a sphere: the closed-form sphere-box kernel (convex_pairs.h) is a second algorithm.
TEST(CapsuleBox, ZeroLengthCapsuleMatchesSphereBox) {
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(-1, 1), half(0.2f, 1.0f), rad(0.05f, 0.5f);
    int hits = 0;
    for (int it = 0; it < 2000; ++it) {
        const Vec3 h{half(rng), half(rng), half(rng)};
        const Transform box{{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        const float r = rad(rng);
        // Centres outside the box (inside, the sphere kernel's face choice is a separate convention).
        const Vec3 local{1.6f * h.x * u(rng), 1.6f * h.y * u(rng), 1.6f * h.z * u(rng)};
        if (std::fabs(local.x) < h.x && std::fabs(local.y) < h.y && std::fabs(local.z) < h.z) continue;
        const Vec3 c = apply(box, local);
        Manifold ms, mc;
        const int ns = collideSphereBox(c, r, box, h, 0.01f, ms);
        const bool hc = collideCapsuleBox({c, {0, 0, 0}, r}, box, h, 0.01f, mc);
        ASSERT_EQ(ns > 0, hc) << it;
        if (!hc) continue;
        ++hits;
        ASSERT_EQ(mc.pointCount, 1);
        EXPECT_NEAR(mc.points[0].depth, ms.points[0].depth, 1e-5f) << it;
        EXPECT_GT(dot(mc.normal, ms.normal), 1 - 1e-5f) << it;
        EXPECT_LT(length(mc.points[0].position - ms.points[0].position), 1e-4f) << it;
    }
    EXPECT_GT(hits, 200);
}

}  // namespace

// Two equal cubes stacked face to face with a small twist about the normal: every point of the overlap is equally
// deep, and the overlap is an octagon whose vertices sit near the corners and near the edge midpoints. The four
// points kept must be near the corners (their quadrilateral covers nearly the whole face), whatever the twist; a
// point from an edge middle leaves a corner unsupported and the upper cube rocks. Exact area of the overlap: the
// square less four triangles; the kept quadrilateral must cover at least 97% of it (a midpoint costs 25%).
TEST(HullPairs, FacesRestingFlatKeepTheirCorners) {
    const ConvexHull cube = boxHull({0.5f, 0.5f, 0.5f});
    for (const float twist : {1e-6f, 1e-4f, 1e-2f, 0.05f, -0.03f}) {
        const Transform lower{{0, 0.5f, 0}, {}};
        const Transform upper{{0, 1.4995f, 0}, {0, std::sin(twist / 2), 0, std::cos(twist / 2)}};
        Manifold boxes, hulls;
        ASSERT_TRUE(collideBoxes(lower, {0.5f, 0.5f, 0.5f}, upper, {0.5f, 0.5f, 0.5f}, 0.02f, boxes));
        ASSERT_TRUE(collideHulls(cube, lower, cube, upper, 0.02f, hulls));
        for (const Manifold* m : {&boxes, &hulls}) {
            ASSERT_EQ(m->pointCount, 4) << twist;
            // Area of the kept points' convex quadrilateral in the xz plane, points ordered by angle.
            std::vector<std::pair<float, Vec3>> byAngle;
            for (int i = 0; i < 4; ++i)
                byAngle.push_back(
                    {std::atan2(m->points[i].position.z, m->points[i].position.x), m->points[i].position});
            std::sort(byAngle.begin(), byAngle.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
            double area = 0;
            for (int i = 0; i < 4; ++i) {
                const Vec3 p = byAngle[i].second, q = byAngle[(i + 1) % 4].second;
                area += 0.5 * (double(p.x) * q.z - double(q.x) * p.z);
            }
            // The overlap of two unit squares turned by t about their common centre: 1 - (1 - cos t)/sin t, to
            // first order 1 - t/2 (four corner triangles).
            const double t = std::fabs(double(twist));
            const double overlap = t < 1e-9 ? 1.0 : 1.0 - (1.0 - std::cos(t)) / std::sin(t);
            EXPECT_GT(area, 0.97 * overlap) << "twist " << twist << (m == &boxes ? " (box-box)" : " (hull-hull)");
        }
    }
}
