// Box-box contact kernel (src/narrowphase/box_box.*): random poses against libccd (GJK + EPA in double precision,
// with box support functions written here) as an independent oracle, analytic resting manifolds, speculative
// margins, feature-id stability and far-from-origin precision.
//
// Tolerances ("size" = the larger box's largest half extent):
// - overlap: kernel (margin 0) and libccd's GJK intersect must agree except within |SAT depth| < 1e-4 * size, where
//   float rounding of the kernel (and GJK's own tolerance) may legitimately decide either way;
// - depth within 1e-3 * size and normal within 1e-2 rad of EPA, checked only where the boxes clearly penetrate
//   (depth > 1e-2 * size) and the minimum axis is unique (runner-up axis, computed here in double, at least
//   6% + 1e-3 * size shallower, just beyond the kernel's 5% + 1e-4 * size hysteresis): at near-ties the kernel
//   deliberately keeps a face axis (hysteresis), and EPA's answer may legitimately be either axis;
// - reported points lie within both boxes grown by 1e-3 * size (box A also by the point's gap when speculative).
#include <ccd/ccd.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <random>
#include <set>
#include <vector>

#include "narrowphase/box_box.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

struct Box {
    Transform pose;
    Vec3 half;
};

// ---------------------------------------------------------------------------------------------------------------
// libccd oracle, in double precision.

struct CcdBox {
    double c[3];
    double m[3][3];  // columns = box axes
    double h[3];
};

CcdBox toCcd(const Box& b) {
    const double x = b.pose.rotation.x, y = b.pose.rotation.y, z = b.pose.rotation.z, w = b.pose.rotation.w;
    const double n = std::sqrt(x * x + y * y + z * z + w * w);
    const double qx = x / n, qy = y / n, qz = z / n, qw = w / n;
    CcdBox o{{b.pose.position.x, b.pose.position.y, b.pose.position.z},
             {{1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)},
              {2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)},
              {2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)}},
             {b.half.x, b.half.y, b.half.z}};
    return o;
}

void ccdBoxSupport(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
    const auto* b = static_cast<const CcdBox*>(obj);
    double s[3];
    for (int k = 0; k < 3; ++k) {
        const double dl = b->m[0][k] * dir->v[0] + b->m[1][k] * dir->v[1] + b->m[2][k] * dir->v[2];
        s[k] = dl < 0 ? -b->h[k] : b->h[k];
    }
    for (int r = 0; r < 3; ++r) out->v[r] = b->c[r] + b->m[r][0] * s[0] + b->m[r][1] * s[1] + b->m[r][2] * s[2];
}

/// How far B must move along unit direction `dir` (A to B) to separate: max of A along dir - min of B along dir.
double overlapAlong(const CcdBox& a, const CcdBox& b, const double dir[3]) {
    ccd_vec3_t d, sa, sb;
    for (int k = 0; k < 3; ++k) d.v[k] = dir[k];
    ccdBoxSupport(&a, &d, &sa);
    for (int k = 0; k < 3; ++k) d.v[k] = -dir[k];
    ccdBoxSupport(&b, &d, &sb);
    const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    return ((sa.v[0] - sb.v[0]) * dir[0] + (sa.v[1] - sb.v[1]) * dir[1] + (sa.v[2] - sb.v[2]) * dir[2]) / len;
}

ccd_t ccdSettings() {
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccdBoxSupport;
    ccd.support2 = ccdBoxSupport;
    ccd.max_iterations = 1000;
    ccd.epa_tolerance = 1e-9;
    return ccd;
}

// ---------------------------------------------------------------------------------------------------------------
// Independent double-precision SAT, only to find near-ties between axes (which cases to skip) and the overlap band.

struct SatAxes {
    std::vector<double> seps;  // separation along every non-degenerate axis, sorted descending
};

SatAxes satSeparations(const CcdBox& a, const CcdBox& b) {
    double axes[15][3];
    int n = 0;
    for (int i = 0; i < 3; ++i) {
        for (int r = 0; r < 3; ++r) axes[n][r] = a.m[r][i];
        ++n;
        for (int r = 0; r < 3; ++r) axes[n][r] = b.m[r][i];
        ++n;
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double u[3] = {a.m[0][i], a.m[1][i], a.m[2][i]}, v[3] = {b.m[0][j], b.m[1][j], b.m[2][j]};
            double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
            const double len = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            if (len < 1e-3) continue;  // as the kernel: near-parallel edges are covered by the face axes
            for (int r = 0; r < 3; ++r) axes[n][r] = c[r] / len;
            ++n;
        }
    SatAxes out;
    for (int k = 0; k < n; ++k) {
        const double* l = axes[k];
        auto radius = [&](const CcdBox& x) {
            double r = 0;
            for (int i = 0; i < 3; ++i) r += x.h[i] * std::fabs(x.m[0][i] * l[0] + x.m[1][i] * l[1] + x.m[2][i] * l[2]);
            return r;
        };
        const double t = (b.c[0] - a.c[0]) * l[0] + (b.c[1] - a.c[1]) * l[1] + (b.c[2] - a.c[2]) * l[2];
        out.seps.push_back(std::fabs(t) - radius(a) - radius(b));
    }
    std::sort(out.seps.begin(), out.seps.end(), std::greater<>());
    return out;
}

// ---------------------------------------------------------------------------------------------------------------
// Helpers.

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
        const float n = std::sqrt(x * x + y * y + z * z + w * w);
        if (n > 1e-3f) return {x / n, y / n, z / n, w / n};
    }
}

Vec3 randomHalf(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.1f, 1.0f);
    Vec3 h{u(rng), u(rng), u(rng)};
    if (std::uniform_int_distribution<int>(0, 2)(rng) == 0) {  // 1:20 aspect ratio: a plank or a slab
        const int axis = std::uniform_int_distribution<int>(0, 2)(rng);
        const bool slab = std::uniform_int_distribution<int>(0, 1)(rng) == 1;
        const float big = u(rng) * 2, small = big / 20;
        h = slab ? Vec3{big, big, big} : Vec3{small, small, small};
        h[axis] = slab ? small : big;
    }
    return h;
}

float maxHalf(Vec3 h) { return std::max(h.x, std::max(h.y, h.z)); }

/// p in the local frame of pose.
Vec3 toLocal(const Transform& pose, Vec3 p) { return rotate(conjugate(pose.rotation), p - pose.position); }

bool insideGrown(const Box& b, Vec3 p, float grow) {
    const Vec3 l = toLocal(b.pose, p);
    return std::fabs(l.x) <= b.half.x + grow && std::fabs(l.y) <= b.half.y + grow && std::fabs(l.z) <= b.half.z + grow;
}

float angleBetween(Vec3 a, Vec3 b) {
    const float c = dot(a, b) / (length(a) * length(b));
    return std::acos(std::clamp(c, -1.0f, 1.0f));
}

Manifold collide(const Box& a, const Box& b, float margin, bool* hit = nullptr) {
    Manifold m;
    const bool h = collideBoxes(a.pose, a.half, b.pose, b.half, margin, m);
    if (hit) *hit = h;
    return m;
}

std::set<std::uint32_t> features(const Manifold& m) {
    std::set<std::uint32_t> f;
    for (int k = 0; k < m.pointCount; ++k) f.insert(m.points[k].feature);
    return f;
}

/// Finds a point of m near p (within tol); nullptr if none.
const ContactPoint* pointNear(const Manifold& m, Vec3 p, float tol) {
    for (int k = 0; k < m.pointCount; ++k)
        if (length(m.points[k].position - p) <= tol) return &m.points[k];
    return nullptr;
}

const float kPi = std::numbers::pi_v<float>;

Box ground() { return {{{0, 0, 0}, {}}, {5, 0.5f, 5}}; }
Box unitCube(Vec3 position, Quat rotation = {}) { return {{position, rotation}, {0.5f, 0.5f, 0.5f}}; }

// ---------------------------------------------------------------------------------------------------------------
// Random poses against libccd.

TEST(BoxBox, RandomPosesAgreeWithLibccd) {
    std::mt19937 rng(20240611);
    std::uniform_real_distribution<float> unit(-1, 1), frac(0, 1);
    const ccd_t ccd = ccdSettings();
    int overlapDisagree = 0, bandSkipped = 0, depthChecked = 0, tieSkipped = 0, hits = 0, oracleInconsistent = 0;
    const int kPoses = 6000;
    for (int n = 0; n < kPoses; ++n) {
        Box a{{{unit(rng) * 5, unit(rng) * 5, unit(rng) * 5}, randomRotation(rng)}, randomHalf(rng)};
        Box b{{{}, randomRotation(rng)}, randomHalf(rng)};
        Vec3 dir{unit(rng), unit(rng), unit(rng)};
        dir = dir / std::max(length(dir), 1e-3f);
        b.pose.position = a.pose.position + dir * (frac(rng) * (length(a.half) + length(b.half)));
        const float size = std::max(maxHalf(a.half), maxHalf(b.half));

        const CcdBox ca = toCcd(a), cb = toCcd(b);
        const SatAxes sat = satSeparations(ca, cb);
        const double satDepth = -sat.seps[0];
        const bool ccdHit = ccdGJKIntersect(&ca, &cb, &ccd) != 0;

        bool hit = false;
        const Manifold m = collide(a, b, 0, &hit);
        if (hit != ccdHit) {
            if (std::fabs(satDepth) < 1e-4 * size) {
                ++bandSkipped;
            } else {
                ++overlapDisagree;
                ADD_FAILURE() << "pose " << n << ": kernel " << hit << ", libccd " << ccdHit << ", SAT depth "
                              << satDepth;
            }
        }
        if (!hit) {
            EXPECT_EQ(m.pointCount, 0);
            continue;
        }
        ++hits;
        ASSERT_GE(m.pointCount, 1);
        ASSERT_LE(m.pointCount, 4);
        EXPECT_NEAR(length(m.normal), 1.0f, 1e-5f);
        float deepest = -INFINITY;
        for (int k = 0; k < m.pointCount; ++k) {
            const ContactPoint& p = m.points[k];
            EXPECT_GE(p.depth, 0.0f) << "pose " << n;
            deepest = std::max(deepest, p.depth);
            EXPECT_TRUE(insideGrown(a, p.position, 1e-3f * size + std::fabs(p.depth)))
                << "pose " << n << " local " << toLocal(a.pose, p.position).x << " " << toLocal(a.pose, p.position).y
                << " " << toLocal(a.pose, p.position).z << " half " << a.half.x << " " << a.half.y << " " << a.half.z
                << " depth " << p.depth << " feature " << std::hex << p.feature << std::dec << " sat " << satDepth;
            EXPECT_TRUE(insideGrown(b, p.position, 1e-3f * size)) << "pose " << n;
        }

        // Depth and normal against EPA where the answer is clear and unique.
        const bool clear = satDepth > 1e-2 * size;
        const bool unique = sat.seps.size() > 1 && (sat.seps[0] - sat.seps[1]) > 0.06 * satDepth + 1e-3 * size;
        if (!clear) continue;
        if (!unique) {
            ++tieSkipped;
            continue;
        }
        ccd_real_t depth;
        ccd_vec3_t ccdDir, pos;
        ASSERT_EQ(ccdGJKPenetration(&ca, &cb, &ccd, &depth, &ccdDir, &pos), 0);
        const double overlapAlongOracle = overlapAlong(ca, cb, ccdDir.v);
        const double ourDir[3] = {m.normal.x, m.normal.y, m.normal.z};
        // Our normal is a real separating direction with our depth (checked with the double support functions),
        // and no direction found by the oracle needs less translation.
        EXPECT_NEAR(overlapAlong(ca, cb, ourDir), deepest, 1e-3 * size) << "pose " << n;
        EXPECT_LE(deepest, overlapAlongOracle + 1e-3 * size) << "pose " << n;
        if (std::fabs(overlapAlongOracle - depth) > 1e-3 * size) {
            ++oracleInconsistent;  // EPA stopped early: its direction needs more than its depth to separate
            continue;
        }
        ++depthChecked;
        EXPECT_NEAR(deepest, depth, 1e-3 * size) << "pose " << n;
        const Vec3 oracleNormal{float(ccdDir.v[0]), float(ccdDir.v[1]), float(ccdDir.v[2])};
        EXPECT_LT(angleBetween(m.normal, oracleNormal), 1e-2f) << "pose " << n;
    }
    std::printf(
        "[ box-box ] %d poses, %d overlapping, overlap disagreements %d (+%d inside the 1e-4*size band), "
        "depth/normal checked on %d, %d near-ties skipped, %d EPA answers not self-consistent\n",
        kPoses, hits, overlapDisagree, bandSkipped, depthChecked, tieSkipped, oracleInconsistent);
    EXPECT_GT(depthChecked, kPoses / 10);
}

TEST(BoxBox, SeparatedBeyondMarginGivesNothing) {
    Manifold m;
    m.pointCount = 3;
    EXPECT_FALSE(collideBoxes({{0, 0, 0}, {}}, {0.5f, 0.5f, 0.5f}, {{3, 0, 0}, {}}, {0.5f, 0.5f, 0.5f}, 0.1f, m));
    EXPECT_EQ(m.pointCount, 0);
}

// ---------------------------------------------------------------------------------------------------------------
// Resting boxes with known manifolds.

TEST(BoxBox, CubeRestingFlatOnGround) {
    const float d = 0.01f;
    const Manifold m = collide(ground(), unitCube({0, 1 - d, 0}), 0);
    ASSERT_EQ(m.pointCount, 4);
    EXPECT_LT(angleBetween(m.normal, {0, 1, 0}), 1e-6f);
    for (float x : {-0.5f, 0.5f})
        for (float z : {-0.5f, 0.5f}) {
            const ContactPoint* p = pointNear(m, {x, 0.5f - d, z}, 1e-5f);
            ASSERT_NE(p, nullptr) << x << " " << z;
            EXPECT_NEAR(p->depth, d, 1e-6f);
            EXPECT_EQ(p->feature >> kBoxFeatureKindShift, kBoxFeatureFaceA);
        }
    EXPECT_EQ(features(m).size(), 4u);
}

TEST(BoxBox, CubeAsBodyAOnGroundUsesItsOwnFace) {
    // Equal face depths: A's face wins, so the points are the cube's corners on the ground's surface (B).
    const float d = 0.01f;
    const Manifold m = collide(unitCube({0, 1 - d, 0}), ground(), 0);
    ASSERT_EQ(m.pointCount, 4);
    EXPECT_LT(angleBetween(m.normal, {0, -1, 0}), 1e-6f);
    for (float x : {-0.5f, 0.5f})
        for (float z : {-0.5f, 0.5f}) {
            const ContactPoint* p = pointNear(m, {x, 0.5f, z}, 1e-5f);
            ASSERT_NE(p, nullptr) << x << " " << z;
            EXPECT_NEAR(p->depth, d, 1e-6f);
        }
}

TEST(BoxBox, CubeRotated45AboutYRestingFlat) {
    const float d = 0.02f;
    const Quat q = Quat::fromAxisAngle({0, 1, 0}, kPi / 4);
    const Manifold m = collide(ground(), unitCube({0.3f, 1 - d, -0.2f}, q), 0);
    ASSERT_EQ(m.pointCount, 4);
    EXPECT_LT(angleBetween(m.normal, {0, 1, 0}), 1e-6f);
    for (float x : {-0.5f, 0.5f})
        for (float z : {-0.5f, 0.5f}) {
            const Vec3 corner = Vec3{0.3f, 0, -0.2f} + rotate(q, {x, 0, z}) + Vec3{0, 0.5f - d, 0};
            const ContactPoint* p = pointNear(m, corner, 1e-5f);
            ASSERT_NE(p, nullptr) << x << " " << z;
            EXPECT_NEAR(p->depth, d, 1e-6f);
        }
}

TEST(BoxBox, CubeEdgeOnGround) {
    // Rotated 45 degrees about z: resting on its bottom edge (along z), two points at the edge's ends.
    const float d = 0.01f;
    const float h = 0.5f * std::numbers::sqrt2_v<float>;
    const Manifold m = collide(ground(), unitCube({0, 0.5f + h - d, 0}, Quat::fromAxisAngle({0, 0, 1}, kPi / 4)), 0);
    ASSERT_EQ(m.pointCount, 2);
    EXPECT_LT(angleBetween(m.normal, {0, 1, 0}), 1e-6f);
    for (float z : {-0.5f, 0.5f}) {
        const ContactPoint* p = pointNear(m, {0, 0.5f - d, z}, 1e-5f);
        ASSERT_NE(p, nullptr) << z;
        EXPECT_NEAR(p->depth, d, 1e-5f);
    }
}

TEST(BoxBox, CubeTiltedOntoAnEdge) {
    // Rotated 30 degrees about z: the lowest edge is the (-x, -y) one, at depth d below the ground's top; the
    // incident face's other edge is 0.5 higher, far outside the margin: two points.
    const float d = 0.015f;
    const Quat q = Quat::fromAxisAngle({0, 0, 1}, kPi / 6);
    const Vec3 low = rotate(q, {-0.5f, -0.5f, 0});  // centre of the lowest edge relative to the cube's centre
    const Vec3 centre{0, 0.5f - d - low.y, 0};
    const Manifold m = collide(ground(), unitCube(centre, q), 0.001f);
    ASSERT_EQ(m.pointCount, 2);
    EXPECT_LT(angleBetween(m.normal, {0, 1, 0}), 1e-6f);
    for (float z : {-0.5f, 0.5f}) {
        const ContactPoint* p = pointNear(m, {centre.x + low.x, 0.5f - d, z}, 1e-5f);
        ASSERT_NE(p, nullptr) << z;
        EXPECT_NEAR(p->depth, d, 1e-5f);
    }
}

TEST(BoxBox, ExactlyTouchingFacesGiveDepthZero) {
    bool hit = false;
    const Manifold m = collide(ground(), unitCube({0.25f, 1, 0}), 0, &hit);
    EXPECT_TRUE(hit);
    ASSERT_EQ(m.pointCount, 4);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(m.points[k].depth, 0.0f);
}

TEST(BoxBox, CrossingEdgesGiveOnePointAtTheirClosestPoints) {
    // A's top edge runs along x, B's bottom edge along z; they cross above the origin.
    const float d = 0.01f;
    const float h = 0.5f * std::numbers::sqrt2_v<float>;
    const Box a = unitCube({0, 0, 0}, Quat::fromAxisAngle({1, 0, 0}, kPi / 4));
    const Box b = unitCube({0.1f, 2 * h - d, -0.05f}, Quat::fromAxisAngle({0, 0, 1}, kPi / 4));
    const Manifold m = collide(a, b, 0);
    ASSERT_EQ(m.pointCount, 1);
    EXPECT_LT(angleBetween(m.normal, {0, 1, 0}), 1e-5f);
    EXPECT_NEAR(m.points[0].depth, d, 1e-5f);
    EXPECT_EQ(m.points[0].feature >> kBoxFeatureKindShift, kBoxFeatureEdgeEdge);
    // On B's edge (x = 0.1, y = h - d, along z) where it passes over A's edge (y = h, z = 0, along x).
    const Vec3 expected{0.1f, h - d, 0};
    EXPECT_LT(length(m.points[0].position - expected), 1e-5f);
}

TEST(BoxBox, ParallelEdgesTouchingAlongASegment) {
    // Both cubes rotated 45 degrees about x (edges along x), B above A and shifted by 0.5 along x: the edges overlap
    // on x in [0, 0.5]. The normal is one of A's 45-degree face normals (an edge-on-edge line contact has no better
    // normal, and the near-parallel edge axes are skipped); every point lies on the shared segment.
    const float delta = 0.01f;
    const float h = 0.5f * std::numbers::sqrt2_v<float>;
    const Quat q = Quat::fromAxisAngle({1, 0, 0}, kPi / 4);
    const Manifold m = collide(unitCube({0, 0, 0}, q), unitCube({0.5f, 2 * h - delta, 0}, q), 0);
    ASSERT_GE(m.pointCount, 2);
    EXPECT_NEAR(std::fabs(m.normal.y), std::sqrt(0.5f), 1e-5f);
    EXPECT_GT(m.normal.y, 0);
    EXPECT_NEAR(m.normal.x, 0, 1e-6f);
    float minX = 1, maxX = -1;
    for (int k = 0; k < m.pointCount; ++k) {
        const ContactPoint& p = m.points[k];
        EXPECT_NEAR(p.depth, delta * std::sqrt(0.5f), 1e-5f);
        EXPECT_NEAR(p.position.y, h - delta / 2, delta / 2 + 1e-5f);  // on B, inside the sliver
        minX = std::min(minX, p.position.x), maxX = std::max(maxX, p.position.x);
    }
    EXPECT_NEAR(minX, 0.0f, 1e-5f);
    EXPECT_NEAR(maxX, 0.5f, 1e-5f);
}

TEST(BoxBox, CoplanarFacesOfEqualBoxesSideBySide) {
    // Two equal cubes side by side, overlapping by d along x, shifted by 0.5 along z: their tops and bottoms are
    // coplanar. Four points on the shared square x = 0.5 - d, z in [0, 0.5].
    const float d = 0.01f;
    const Manifold m = collide(unitCube({0, 0, 0}), unitCube({1 - d, 0, 0.5f}), 0);
    ASSERT_EQ(m.pointCount, 4);
    EXPECT_LT(angleBetween(m.normal, {1, 0, 0}), 1e-6f);
    for (float y : {-0.5f, 0.5f})
        for (float z : {0.0f, 0.5f}) {
            const ContactPoint* p = pointNear(m, {0.5f - d, y, z}, 1e-5f);
            ASSERT_NE(p, nullptr) << y << " " << z;
            EXPECT_NEAR(p->depth, d, 1e-6f);
        }
}

TEST(BoxBox, IncidentFaceLargerThanReferenceIsReducedToFour) {
    // A small cube tilted slightly resting on a big box: take the big box as A and a cube rotated by a small angle
    // about an oblique axis; the clipped polygon is the cube's face (4 points). Then make the reference small: a big
    // slab on a small cube, where the slab's face is clipped by the cube's 4 side planes (up to 8 points -> 4).
    const Quat tilt = Quat::fromAxisAngle({1, 0, 1}, 0.02f) * Quat::fromAxisAngle({0, 1, 0}, 0.4f);
    const Box slab{{{0.1f, 1.0f - 0.01f, 0.05f}, tilt}, {2, 0.5f, 2}};
    const Box cube = unitCube({0, 0, 0});
    const Manifold m = collide(cube, slab, 0.05f);
    ASSERT_EQ(m.pointCount, 4);
    // The deepest clipped point must be among the four.
    float deepest = -INFINITY;
    for (int k = 0; k < 4; ++k) deepest = std::max(deepest, m.points[k].depth);
    const Manifold big = collide(cube, slab, 10.0f);  // a huge margin keeps every clipped point
    for (int k = 0; k < big.pointCount; ++k) EXPECT_LE(big.points[k].depth, deepest + 1e-6f);
    // The four points span a large part of the cube's unit top face.
    float area2 = 0;
    for (int k = 0; k < 4; ++k) {
        const Vec3 p = m.points[k].position, q = m.points[(k + 1) % 4].position;
        area2 += p.x * q.z - q.x * p.z;
    }
    EXPECT_GT(std::fabs(area2) / 2, 0.8f);
}

// ---------------------------------------------------------------------------------------------------------------
// Speculative contacts.

TEST(BoxBox, SpeculativeWithinMargin) {
    const Box a = ground(), b = unitCube({0, 1.01f, 0});
    bool hit = false;
    Manifold m = collide(a, b, 0.02f, &hit);
    EXPECT_TRUE(hit);
    ASSERT_EQ(m.pointCount, 4);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(m.points[k].depth, -0.01f, 1e-6f);
    m = collide(a, b, 0.005f, &hit);
    EXPECT_FALSE(hit);
    EXPECT_EQ(m.pointCount, 0);
}

TEST(BoxBox, SpeculativeEdgeEdge) {
    const float h = 0.5f * std::numbers::sqrt2_v<float>;
    const Box a = unitCube({0, 0, 0}, Quat::fromAxisAngle({1, 0, 0}, kPi / 4));
    const Box b = unitCube({0, 2 * h + 0.01f, 0}, Quat::fromAxisAngle({0, 0, 1}, kPi / 4));
    Manifold m = collide(a, b, 0.02f);
    ASSERT_EQ(m.pointCount, 1);
    EXPECT_NEAR(m.points[0].depth, -0.01f, 1e-5f);
    bool hit = true;
    m = collide(a, b, 0.005f, &hit);
    EXPECT_FALSE(hit);
}

// ---------------------------------------------------------------------------------------------------------------
// Temporal coherence and precision.

TEST(BoxBox, FeatureIdsStableUnderTinyPerturbations) {
    // A resting cube jittered by up to 5e-4 rad and 1e-4 m around a pose tilted by 2e-3 rad, with the cube as A or
    // as B. The ground's face is the reference throughout: with the cube as A, A's own face would win only within
    // the hysteresis (tilts below about 1e-4 rad for this 10 m ground), which the base tilt keeps away from.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    const Quat tilt = Quat::fromAxisAngle({1, 0, 1}, 2e-3f);
    for (const Quat base : {tilt, tilt * Quat::fromAxisAngle({0, 1, 0}, 0.7f)}) {
        for (const bool cubeIsA : {false, true}) {
            const auto pose = [&] {
                const Quat q = Quat::fromAxisAngle({u(rng), u(rng), u(rng)}, 5e-4f) * base;
                return unitCube({0.2f + 1e-4f * u(rng), 0.99f + 1e-4f * u(rng), -0.1f}, q);
            };
            const auto run = [&](const Box& cube) {
                return cubeIsA ? collide(cube, ground(), 0.01f) : collide(ground(), cube, 0.01f);
            };
            const Manifold reference = run(pose());
            ASSERT_EQ(reference.pointCount, 4);
            EXPECT_EQ(reference.points[0].feature >> kBoxFeatureKindShift,
                      cubeIsA ? kBoxFeatureFaceB : kBoxFeatureFaceA);
            const auto ids = features(reference);
            EXPECT_EQ(ids.size(), 4u);
            for (int step = 0; step < 200; ++step) {
                const Manifold m = run(pose());
                ASSERT_EQ(m.pointCount, 4);
                EXPECT_EQ(features(m), ids) << "step " << step;
                EXPECT_LT(angleBetween(m.normal, reference.normal), 1e-6f);
            }
        }
    }
}

TEST(BoxBox, HugeCoordinatesGiveTheSameManifoldAsAtTheOrigin) {
    // Both boxes 10 km from the origin. The kernel only subtracts the two centres in world space (exact for
    // nearby floats), so normals, depths and ids match the origin case exactly; positions differ by the rounding
    // of the final world-space sum: half a float spacing at 10 km (2^-11 m ~ 0.5 mm), hence 1e-3.
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> unit(-1, 1), frac(0, 1);
    const Vec3 far{10000, -10000, 10000};
    int compared = 0;
    for (int n = 0; n < 2000; ++n) {
        Box a{{far + Vec3{unit(rng), unit(rng), unit(rng)}, randomRotation(rng)}, randomHalf(rng)};
        Box b{{far + Vec3{unit(rng), unit(rng), unit(rng)} * 1.5f, randomRotation(rng)}, randomHalf(rng)};
        Box a0 = a, b0 = b;
        a0.pose.position = a.pose.position - far;  // exact: the centres are representable relative to `far`
        b0.pose.position = b.pose.position - far;
        bool hit = false, hit0 = false;
        const Manifold m = collide(a, b, 0.01f, &hit), m0 = collide(a0, b0, 0.01f, &hit0);
        ASSERT_EQ(hit, hit0);
        ASSERT_EQ(m.pointCount, m0.pointCount);
        if (!hit) continue;
        ++compared;
        EXPECT_LT(length(m.normal - m0.normal), 1e-6f);
        for (int k = 0; k < m.pointCount; ++k) {
            EXPECT_NEAR(m.points[k].depth, m0.points[k].depth, 1e-6f);
            EXPECT_EQ(m.points[k].feature, m0.points[k].feature);
            EXPECT_LT(length((m.points[k].position - far) - m0.points[k].position), 1e-3f);
        }
    }
    EXPECT_GT(compared, 200);
}

TEST(BoxBox, RestingCubeFarFromOrigin) {
    const float d = 0.01f;
    const Vec3 far{10000, 0, -10000};
    Box g = ground();
    g.pose.position = far;
    const Manifold m = collide(g, unitCube(far + Vec3{0, 1 - d, 0}), 0);
    ASSERT_EQ(m.pointCount, 4);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(m.points[k].depth, d, 1e-6f);
    EXPECT_LT(angleBetween(m.normal, {0, 1, 0}), 1e-6f);
}

// ---------------------------------------------------------------------------------------------------------------
// The batched form: axis tests in SIMD lanes, clipping per pair.

TEST(BoxBox, BatchedGivesExactlyThePerPairManifolds) {
    // Resting, edge-on, deep, barely touching and separated pairs mixed in one batch, each with its own margin, and
    // batch lengths that leave a scalar tail: every manifold must equal collideBoxes' bit for bit (normal, points,
    // depths, feature ids), so the stage's results do not depend on which path a pair took.
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> unit(-1, 1), frac(0, 1);
    std::vector<Box> as, bs;
    std::vector<float> margins;
    for (int n = 0; n < 1000; ++n) {
        Box a, b;
        switch (n % 4) {
            case 0:  // resting on a ground box, slightly tilted
                a = ground();
                b = unitCube({2 * unit(rng), 0.99f + 0.02f * frac(rng), 2 * unit(rng)},
                             Quat::fromAxisAngle({unit(rng), 0, unit(rng)}, 1e-3f * unit(rng)) *
                                 Quat::fromAxisAngle({0, 1, 0}, kPi * unit(rng)));
                break;
            case 1:  // stacked cubes, exactly aligned or yawed
                a = unitCube({0, 0, 0});
                b = unitCube({0.3f * unit(rng), 1.0f - 0.01f * frac(rng), 0.3f * unit(rng)},
                             n % 8 == 1 ? Quat{} : Quat::fromAxisAngle({0, 1, 0}, unit(rng)));
                // Centred and turned by exactly 45 degrees: the clipped face is a symmetric octagon whose points tie
                // in the reduction's distances, so the first of equal candidates must win in lanes as one by one.
                if (n % 16 == 5)
                    b = unitCube({0, 1.0f - 0.01f * frac(rng), 0}, Quat::fromAxisAngle({0, 1, 0}, kPi / 4));
                break;
            default:  // random sizes and rotations, overlapping, touching or apart
                a = {{{unit(rng), unit(rng), unit(rng)}, randomRotation(rng)}, randomHalf(rng)};
                b = {{a.pose.position + Vec3{unit(rng), unit(rng), unit(rng)} * 1.2f, randomRotation(rng)},
                     randomHalf(rng)};
                break;
        }
        as.push_back(a);
        bs.push_back(b);
        margins.push_back(n % 3 == 0 ? 0.0f : 0.3f * frac(rng));
    }
    std::vector<float> soa[21];
    for (std::size_t k = 0; k < as.size(); ++k) {
        const float values[21] = {as[k].pose.position.x, as[k].pose.position.y, as[k].pose.position.z,
                                  as[k].pose.rotation.x, as[k].pose.rotation.y, as[k].pose.rotation.z,
                                  as[k].pose.rotation.w, as[k].half.x,          as[k].half.y,
                                  as[k].half.z,          bs[k].pose.position.x, bs[k].pose.position.y,
                                  bs[k].pose.position.z, bs[k].pose.rotation.x, bs[k].pose.rotation.y,
                                  bs[k].pose.rotation.z, bs[k].pose.rotation.w, bs[k].half.x,
                                  bs[k].half.y,          bs[k].half.z,          margins[k]};
        for (int f = 0; f < 21; ++f) soa[f].push_back(values[f]);
    }
    for (auto& field : soa) field.resize(field.size() + 16, field.back());  // readable past the end (padded)
    const BoxPairs in{soa[0].data(),  soa[1].data(),  soa[2].data(),  soa[3].data(),  soa[4].data(),  soa[5].data(),
                      soa[6].data(),  soa[7].data(),  soa[8].data(),  soa[9].data(),  soa[10].data(), soa[11].data(),
                      soa[12].data(), soa[13].data(), soa[14].data(), soa[15].data(), soa[16].data(), soa[17].data(),
                      soa[18].data(), soa[19].data(), soa[20].data()};
    int contacts = 0, edges = 0, separated = 0;
    for (const std::size_t n : {as.size(), std::size_t{37}, std::size_t{5}}) {
        // Padded: the arrays go on past n, so the tail may run in lanes too.
        std::vector<Manifold> batched(n), scalar(n), padded(n);
        collideBoxesBatch(in, n, batched.data());
        collideBoxesBatchScalar(in, n, scalar.data());
        collideBoxesBatch(in, n, padded.data(), nullptr, /*padded=*/true);
        for (std::size_t k = 0; k < n; ++k) {
            Manifold one;
            collideBoxes(as[k].pose, as[k].half, bs[k].pose, bs[k].half, margins[k], one);
            for (const Manifold* m : {&batched[k], &scalar[k], &padded[k]}) {
                ASSERT_EQ(m->pointCount, one.pointCount) << "pair " << k;
                if (one.pointCount == 0) continue;
                EXPECT_EQ(std::memcmp(&m->normal, &one.normal, sizeof(Vec3)), 0) << "pair " << k;
                for (int p = 0; p < one.pointCount; ++p) {
                    EXPECT_EQ(std::memcmp(&m->points[p].position, &one.points[p].position, sizeof(Vec3)), 0);
                    EXPECT_EQ(std::memcmp(&m->points[p].depth, &one.points[p].depth, sizeof(float)), 0);
                    EXPECT_EQ(m->points[p].feature, one.points[p].feature) << "pair " << k;
                }
            }
            if (n != as.size()) continue;
            if (one.pointCount == 0)
                ++separated;
            else if (one.points[0].feature >> kBoxFeatureKindShift == kBoxFeatureEdgeEdge)
                ++edges;
            else
                ++contacts;
        }
    }
    // The mix must exercise every path.
    EXPECT_GT(contacts, 300);
    EXPECT_GT(edges, 20);
    EXPECT_GT(separated, 50);
}

}  // namespace
