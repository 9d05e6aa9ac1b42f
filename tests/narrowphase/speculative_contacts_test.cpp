// Speculative contacts of polytopes (box-box, box-hull, hull-hull): for shapes apart by less than the margin, the
// deepest point's depth is minus their distance and the normal is the direction between their closest points. The
// oracle is brute force in double: the least distance over every vertex against every face (as triangles) and every
// edge against every edge, both ways. The separating-axis test alone gets this right only where the closest
// features are a face and a vertex, or two edges meeting inside both; from a vertex or an edge's end the best axis
// understates the distance and points elsewhere. Shapes are placed with GJK (moved in along its normal until apart by
// a random gap), which only chooses the poses.
//
// Tolerances: depth within 2e-5 m + 0.5% of the distance (the kernels accept a face contact whose deepest point is
// that close to the best axis's separation; 2e-5 m covers float rounding of poses about 1 m across), normal within
// 0.99 (cosine; the 0.5% bound on the depth alone keeps it above 0.995), distances in (2e-4, margin - 1e-4) m:
// nearer than 1e-4 times their size (up to 1.4 m here) the kernels count the shapes as touching and keep a face
// contact, whose normal may then be far from the direction between the closest points (which is noise there).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "narrowphase/box_box.h"
#include "narrowphase/ccd_oracle.h"
#include "narrowphase/gjk.h"
#include "narrowphase/hull_pairs.h"
#include "narrowphase/triangle_pairs.h"
#include "shapes/mesh_adjacency.h"
#include "shapes/shape.h"
#include "support/random_poses.h"
#include "support/test_shapes.h"

namespace {

using namespace rubble;
using namespace rubble::detail;
using namespace rubble::test;

constexpr float kMargin = 0.02f;

ConvexHull boxHull(Vec3 half) { return *buildShape(ConvexHullDef{boxCorners(half)}).hull; }

/// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection 5.1.5), in double.
D3 closestOnTriangle(D3 p, D3 a, D3 b, D3 c) {
    const D3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dotd(ab, ap), d2 = dotd(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const D3 bp = p - b;
    const double d3 = dotd(ab, bp), d4 = dotd(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const D3 cp = p - c;
    const double d5 = dotd(ab, cp), d6 = dotd(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

/// Closest points of segments p1q1 and p2q2 (Ericson 5.1.9), in double.
void closestOnSegments(D3 p1, D3 q1, D3 p2, D3 q2, D3& c1, D3& c2) {
    const D3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = dotd(d1, d1), e = dotd(d2, d2), f = dotd(d2, r), c = dotd(d1, r), b = dotd(d1, d2);
    const double denom = a * e - b * b;
    double s = denom > 1e-18 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
    double t = (b * s + f) / e;
    if (t < 0)
        t = 0, s = std::clamp(-c / a, 0.0, 1.0);
    else if (t > 1)
        t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    c1 = p1 + d1 * s, c2 = p2 + d2 * t;
}

struct Polytope {
    std::vector<D3> vertices;
    std::vector<std::array<int, 3>> triangles;
    std::vector<std::pair<int, int>> edges;
};

Polytope posed(const ConvexHull& h, const Transform& t) {
    Polytope p;
    const D3 o = d3(t.position);
    for (const Vec3& v : h.vertices) p.vertices.push_back(rotd(t, v) + o);
    for (std::uint32_t f = 0; f < h.faceCount(); ++f)
        for (std::uint32_t k = h.faceStart[f] + 1; k + 1 < h.faceStart[f + 1]; ++k)
            p.triangles.push_back(
                {int(h.faceVertices[h.faceStart[f]]), int(h.faceVertices[k]), int(h.faceVertices[k + 1])});
    for (std::size_t e = 0; e + 1 < h.edges.size(); e += 2) p.edges.emplace_back(int(h.edges[e]), int(h.edges[e + 1]));
    return p;
}

struct Closest {
    double distance = INFINITY;
    D3 normal;  ///< from A to B
};

/// Distance of two disjoint convex polytopes: the least over vertex-face (both ways) and edge-edge feature pairs.
Closest bruteForceDistance(const Polytope& a, const Polytope& b) {
    Closest best;
    const auto consider = [&](D3 onA, D3 onB) {
        const D3 d = onB - onA;
        const double l = lend(d);
        if (l < best.distance) best.distance = l, best.normal = d * (1 / l);
    };
    for (const D3& v : a.vertices)
        for (const auto& t : b.triangles)
            consider(v, closestOnTriangle(v, b.vertices[t[0]], b.vertices[t[1]], b.vertices[t[2]]));
    for (const D3& v : b.vertices)
        for (const auto& t : a.triangles)
            consider(closestOnTriangle(v, a.vertices[t[0]], a.vertices[t[1]], a.vertices[t[2]]), v);
    for (const auto& ea : a.edges)
        for (const auto& eb : b.edges) {
            D3 ca, cb;
            closestOnSegments(a.vertices[ea.first], a.vertices[ea.second], b.vertices[eb.first], b.vertices[eb.second],
                              ca, cb);
            consider(ca, cb);
        }
    return best;
}

float deepestOf(const Manifold& m) {
    float d = -INFINITY;
    for (int p = 0; p < m.pointCount; ++p) d = std::max(d, m.points[p].depth);
    return d;
}

struct Tally {
    int checked = 0, depthOff = 0, normalOff = 0;

    /// Compares contact `m` (`hit`: the kernel reported one) of pose n with the brute force's `truth`: the deepest
    /// point's depth within 2e-5 m + 0.5% of the distance, the normal within cosine 0.99.
    void compare(bool hit, const Manifold& m, const Closest& truth, int n) {
        EXPECT_TRUE(hit) << "pose " << n << ": no contact for shapes " << truth.distance << " m apart";
        if (!hit) return;
        ++checked;
        const double deepest = deepestOf(m);
        const bool depthOk = std::fabs(deepest + truth.distance) <= 2e-5 + 0.005 * truth.distance;
        const double alignment = dotd(d3(m.normal), truth.normal);
        const bool normalOk = alignment > 0.99;
        depthOff += !depthOk;
        normalOff += !normalOk;
        EXPECT_TRUE(depthOk) << "pose " << n << ": deepest " << deepest << ", distance " << truth.distance
                             << ", feature " << std::hex << m.points[0].feature << std::dec;
        EXPECT_TRUE(normalOk) << "pose " << n << ": normal . the closest points' direction " << alignment
                              << ", deepest " << deepest << ", distance " << truth.distance << ", feature " << std::hex
                              << m.points[0].feature << std::dec;
    }

    /// Prints the counts for `pair` and requires enough pairs to have been compared.
    void report(const char* pair) const {
        std::printf("[ %s ] %d speculative pairs, %d depths and %d normals off the brute force\n", pair, checked,
                    depthOff, normalOff);
        EXPECT_GT(checked, 1500);
    }
};

/// Places B at a random distance below the margin from A, collides with `collide` and compares with the brute
/// force over hulls `ha`, `hb` (the shapes' vertices and faces), counting into `t`. GJK on the shapes places B.
template <class Collide>
void compareWithBruteForce(std::mt19937& rng, int poses, const Shape& shapeA, const Shape& shapeB, const ConvexHull& ha,
                           const ConvexHull& hb, Collide&& collide, Tally& t) {
    std::uniform_real_distribution<float> gap(0.0f, kMargin);
    for (int n = 0; n < poses; ++n) {
        const Transform pa{{0, 0, 0}, randomRotation(rng)};
        Transform pb{{0, 0, 0}, randomRotation(rng)};
        pb.position = randomDirection(rng) * 4.0f;
        // Move B in along the direction between closest points until it is `target` apart: a few steps converge.
        const float target = gap(rng);
        for (int it = 0; it < 8; ++it) {
            const GjkResult g = gjkDistance(gjkShapeOf(shapeA, pa), gjkShapeOf(shapeB, pb));
            if (g.status != GjkStatus::Separated || std::fabs(g.distance - target) < 1e-6f) break;
            pb.position = pb.position - g.normal * (g.distance - target);
        }
        const Closest truth = bruteForceDistance(posed(ha, pa), posed(hb, pb));
        if (truth.distance < 2e-4 || truth.distance > kMargin - 1e-4) continue;
        Manifold m;
        t.compare(collide(pa, pb, m), m, truth, n);
    }
}

TEST(SpeculativeContacts, BoxBoxApartWithinTheMarginAgreesWithBruteForce) {
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> half(0.1f, 0.8f);
    Tally all;
    for (int round = 0; round < 40; ++round) {
        const Vec3 ha{half(rng), half(rng), half(rng)};
        const Vec3 hb{half(rng), half(rng), half(rng)};
        const Shape boxA = buildShape(BoxDef{ha}), boxB = buildShape(BoxDef{hb});
        compareWithBruteForce(
            rng, 60, boxA, boxB, boxHull(ha), boxHull(hb),
            [&](const Transform& pa, const Transform& pb, Manifold& m) {
                return collideBoxes(pa, ha, pb, hb, kMargin, m);
            },
            all);
    }
    all.report("box-box");
}

TEST(SpeculativeContacts, HullPairsApartWithinTheMarginAgreeWithBruteForce) {
    std::mt19937 rng(43);
    Tally all;
    for (int round = 0; round < 40; ++round) {
        const Shape sa = buildShape(ConvexHullDef{rubble::test::randomHullCloud(rng, 12, 0.5f)});
        const Shape sb = buildShape(ConvexHullDef{rubble::test::randomHullCloud(rng, 12, 0.5f)});
        compareWithBruteForce(
            rng, 60, sa, sb, *sa.hull, *sb.hull,
            [&](const Transform& pa, const Transform& pb, Manifold& m) {
                return collideHulls(*sa.hull, pa, *sb.hull, pb, kMargin, m);
            },
            all);
    }
    all.report("hull-hull");
}

TEST(SpeculativeContacts, BoxHullApartWithinTheMarginAgreesWithBruteForce) {
    std::mt19937 rng(47);
    std::uniform_real_distribution<float> half(0.1f, 0.8f);
    Tally all;
    for (int round = 0; round < 40; ++round) {
        const Vec3 ha{half(rng), half(rng), half(rng)};
        const Shape box = buildShape(BoxDef{ha});
        const Shape sb = buildShape(ConvexHullDef{rubble::test::randomHullCloud(rng, 12, 0.5f)});
        compareWithBruteForce(
            rng, 60, box, sb, boxHull(ha), *sb.hull,
            [&](const Transform& pa, const Transform& pb, Manifold& m) {
                return collideBoxHull(pa, ha, *sb.hull, pb, kMargin, m);
            },
            all);
    }
    all.report("box-hull");
}

/// A random triangle about the origin, sides about 0.3 to 1.5 m.
TriangleVertices randomTriangle(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-0.75f, 0.75f);
    TriangleVertices t;
    do {
        for (Vec3& v : t) v = {u(rng), u(rng), u(rng)};
    } while (length(cross(t[1] - t[0], t[2] - t[0])) < 0.05f);
    return t;
}

Polytope triangleOf(const TriangleVertices& t) {
    Polytope p;
    for (const Vec3& v : t) p.vertices.push_back(d3(v));
    p.triangles.push_back({0, 1, 2});
    p.edges = {{0, 1}, {1, 2}, {2, 0}};
    return p;
}

/// As compareWithBruteForce, for body A against a lone triangle B (every edge active, so the ghost rule keeps every
/// normal): A is placed at a random gap below the margin from the triangle, which stays where it was made. The same
/// pose against the triangle with every edge inactive (inside a flat mesh) must keep the face normal: the ghost rule
/// (triangle_pairs.h) stands over the closest points.
template <class Collide>
void compareWithTriangle(std::mt19937& rng, int poses, const Shape& shapeA, const ConvexHull& ha, Collide&& collide,
                         Tally& t) {
    std::uniform_real_distribution<float> gap(0.0f, kMargin);
    for (int n = 0; n < poses; ++n) {
        const TriangleVertices tri = randomTriangle(rng);
        GjkShape triangle;
        triangle.core = GjkShape::Core::Points;
        triangle.points = tri.data();
        triangle.pointCount = 3;
        Transform pa{randomDirection(rng) * 4.0f, randomRotation(rng)};
        const float target = gap(rng);
        for (int it = 0; it < 8; ++it) {
            const GjkResult g = gjkDistance(gjkShapeOf(shapeA, pa), triangle);
            if (g.status != GjkStatus::Separated || std::fabs(g.distance - target) < 1e-6f) break;
            pa.position = pa.position + g.normal * (g.distance - target);
        }
        // Triangle edges reach 2.6 m here: nearer than 1e-4 of that the kernels count the shapes as touching.
        const Closest truth = bruteForceDistance(posed(ha, pa), triangleOf(tri));
        if (truth.distance < 3e-4 || truth.distance > kMargin - 1e-4) continue;
        Manifold inside;
        if (collide(pa, tri, std::uint8_t{0}, inside) > 0) {
            const Vec3 c = cross(tri[1] - tri[0], tri[2] - tri[0]);
            const Vec3 face = c / length(c);
            EXPECT_GT(std::fabs(dot(inside.normal, face)), 0.99999f) << "pose " << n << ": ghost rule";
        }
        Manifold m;
        t.compare(collide(pa, tri, kAllEdgesActive, m) > 0, m, truth, n);
    }
}

TEST(SpeculativeContacts, BoxTriangleApartWithinTheMarginAgreesWithBruteForce) {
    std::mt19937 rng(53);
    std::uniform_real_distribution<float> half(0.1f, 0.8f);
    Tally all;
    for (int round = 0; round < 40; ++round) {
        const Vec3 ha{half(rng), half(rng), half(rng)};
        const Shape box = buildShape(BoxDef{ha});
        compareWithTriangle(
            rng, 60, box, boxHull(ha),
            [&](const Transform& pa, const TriangleVertices& tri, std::uint8_t edges, Manifold& m) {
                return collideBoxTriangle(pa, ha, tri, edges, kMargin, m);
            },
            all);
    }
    all.report("box-triangle");
}

TEST(SpeculativeContacts, HullTriangleApartWithinTheMarginAgreesWithBruteForce) {
    std::mt19937 rng(59);
    Tally all;
    for (int round = 0; round < 40; ++round) {
        const Shape hull = buildShape(ConvexHullDef{rubble::test::randomHullCloud(rng, 12, 0.5f)});
        const HullAdjacency adjacency = buildHullAdjacency(*hull.hull);
        compareWithTriangle(
            rng, 60, hull, *hull.hull,
            [&](const Transform& pa, const TriangleVertices& tri, std::uint8_t edges, Manifold& m) {
                return collideHullTriangle(*hull.hull, adjacency, pa, tri, edges, kMargin, m);
            },
            all);
    }
    all.report("hull-triangle");
}

}  // namespace
