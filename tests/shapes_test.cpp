// Shape definitions: validation messages, closed-form and numerically integrated mass properties, compounds,
// principal axes and the public computeMassProperties.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "rubble/error.h"
#include "shapes/shape.h"

namespace rubble::detail {
namespace {

constexpr double kPi = std::numbers::pi;

std::string errorOf(const ShapeDef& def) {
    try {
        buildShape(def);
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

Eigen::Matrix3d toEigen(const Mat3& m) {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
    return r;
}

Eigen::Matrix3d rotationOf(Quat q) { return Eigen::Quaterniond(q.w, q.x, q.y, q.z).toRotationMatrix(); }

void expectMassNear(const MassProperties& a, const MassProperties& b, double rel) {
    EXPECT_NEAR(a.mass, b.mass, rel * b.mass);
    const double scale = std::max({double(b.inertia(0, 0)), double(b.inertia(1, 1)), double(b.inertia(2, 2))});
    const double size = std::sqrt(scale / b.mass);
    EXPECT_NEAR(a.centerOfMass.x, b.centerOfMass.x, rel * size);
    EXPECT_NEAR(a.centerOfMass.y, b.centerOfMass.y, rel * size);
    EXPECT_NEAR(a.centerOfMass.z, b.centerOfMass.z, rel * size);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(a.inertia(i, j), b.inertia(i, j), rel * scale) << i << "," << j;
}

TEST(ShapeValidation, WhatTheNarrowPhaseCannotRepresentIsRefusedAtCreation) {
    // A prism whose caps have 40 sides: clipping holds two faces' sides in 64 points, so a face may have 32.
    ConvexHullDef prism;
    for (int k = 0; k < 40; ++k) {
        const float a = 6.2831853f * static_cast<float>(k) / 40.0f;
        for (const float y : {-0.5f, 0.5f}) prism.points.push_back({std::cos(a), y, std::sin(a)});
    }
    EXPECT_EQ(errorOf(prism),
              "ConvexHullDef: a face of the hull has 40 sides, more than 32 (docs/limits.md): use "
              "fewer points around its rim");
    prism.points.resize(2 * 32);  // the first 32 rim points: caps of 32 sides are fine
    EXPECT_EQ(errorOf(prism), "no error");

    ConvexHullDef ball;  // 5,000 points on a sphere, every one a hull vertex
    for (int k = 0; k < 5000; ++k) {
        const float y = 1.0f - 2.0f * (static_cast<float>(k) + 0.5f) / 5000.0f, r = std::sqrt(1.0f - y * y);
        const float a = 2.3999632f * static_cast<float>(k);
        ball.points.push_back({r * std::cos(a), y, r * std::sin(a)});
    }
    EXPECT_EQ(errorOf(ball), "ConvexHullDef: the hull has 5000 vertices, more than 4096 (docs/limits.md)");

    ConvexHullDef speck{{{0, 0, 0}, {1e-5f, 0, 0}, {0, 1e-5f, 0}, {0, 0, 1e-5f}}};
    EXPECT_EQ(errorOf(speck),
              "ConvexHullDef: the hull's half extent 5e-06 m and reach from its origin 1e-05 m must "
              "lie in [0.0001, 10000] m (docs/limits.md)");

    // 70,000 x 70,000 samples make 9.8e9 triangles: counted in 64 bits (32 would wrap to 1.2e9) and refused before
    // the heights are looked at.
    HeightfieldDef huge;
    huge.rows = huge.columns = 70000;
    EXPECT_EQ(errorOf(huge),
              "HeightfieldDef: rows and columns make 9799720002 triangles, more than 16777216 (docs/limits.md)");

    TriangleMeshDef far;
    far.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 0, 2e5f}};
    far.indices = {0, 1, 2};
    EXPECT_EQ(errorOf(far),
              "TriangleMeshDef: vertices[2] (0, 0, 200000) lies farther than 100000 m from the origin "
              "on an axis (docs/limits.md)");
}

TEST(ShapeValidation, BadDefinitionsNameDefinitionFieldAndValue) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(errorOf(SphereDef{0}), "SphereDef: radius must be in [0.0001, 10000] m (got 0; docs/limits.md)");
    EXPECT_EQ(errorOf(SphereDef{1e-20f}), "SphereDef: radius must be in [0.0001, 10000] m (got 1e-20; docs/limits.md)");
    EXPECT_EQ(errorOf(SphereDef{inf}), "SphereDef: radius is not finite (inf)");
    EXPECT_EQ(errorOf(BoxDef{{1, -1, 1}}),
              "BoxDef: halfExtents.y must be in [0.0001, 10000] m (got -1; docs/limits.md)");
    EXPECT_EQ(errorOf(BoxDef{{1, 1, 2e4f}}),
              "BoxDef: halfExtents.z must be in [0.0001, 10000] m (got 20000; docs/limits.md)");
    EXPECT_EQ(errorOf(BoxDef{{1, 1, nan}}), "BoxDef: halfExtents.z is not finite (nan)");
    EXPECT_EQ(errorOf(CapsuleDef{0.5f, -0.25f}),
              "CapsuleDef: halfHeight must be in [0, 10000] m (got -0.25; docs/limits.md)");
    EXPECT_EQ(errorOf(CapsuleDef{-1, 1}), "CapsuleDef: radius must be in [0.0001, 10000] m (got -1; docs/limits.md)");
    EXPECT_EQ(errorOf(ConvexHullDef{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {nan, 0, 1}}}),
              "ConvexHullDef: points[3] is not finite (nan, 0, 1)");
    EXPECT_EQ(errorOf(ConvexHullDef{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 2, 0}, {3, 1, 0}}}),
              "ConvexHullDef: the 6 points are coplanar: a hull needs volume");
    EXPECT_EQ(errorOf(ConvexHullDef{{{0, 0, 0}, {1, 0, 0}}}), "ConvexHullDef: needs at least 4 points (got 2)");

    TriangleMeshDef mesh;
    mesh.vertices.resize(10);
    mesh.indices = {0, 1, 2, 3, 4, 5, 6, 12, 8};
    EXPECT_EQ(errorOf(mesh), "TriangleMeshDef: indices[7] = 12 is out of range (10 vertices)");
    mesh.indices = {0, 1, 2, 3};
    EXPECT_EQ(errorOf(mesh), "TriangleMeshDef: indices has 4 values, not a multiple of 3");
    mesh.indices.clear();
    EXPECT_EQ(errorOf(mesh), "TriangleMeshDef: needs at least one triangle (indices is empty)");
    mesh.indices = {0, 1, 2};
    mesh.vertices[4] = {0, inf, 0};
    EXPECT_EQ(errorOf(mesh), "TriangleMeshDef: vertices[4] is not finite (0, inf, 0)");

    CompoundDef compound;
    EXPECT_EQ(errorOf(compound), "CompoundDef: children is empty: a compound needs at least one child");
    compound.children.assign(65536, {SphereDef{1}, {}});
    EXPECT_EQ(errorOf(compound),
              "CompoundDef: children has 65536 shapes, more than 65535 (contacts name a child in "
              "16 bits; docs/limits.md)");
    compound.children = {{SphereDef{1}, {}}, {BoxDef{}, {}}, {BoxDef{{0, 1, 1}}, {}}};
    EXPECT_EQ(errorOf(compound),
              "CompoundDef: children[2]: BoxDef: halfExtents.x must be in [0.0001, 10000] m (got 0; docs/limits.md)");
    compound.children = {{SphereDef{1}, {{0, 0, 0}, {0, 0, 0, 0}}}};
    EXPECT_EQ(errorOf(compound),
              "CompoundDef: children[0]: local.rotation is a zero quaternion: it must be a rotation");
    compound.children = {{SphereDef{1}, {{0, nan, 0}, {}}}};
    EXPECT_EQ(errorOf(compound), "CompoundDef: children[0]: local.position is not finite (0, nan, 0)");
    // Finite but beyond the coordinate limit: the body's centre of mass would lie beyond it too (a fuzz finding).
    compound.children = {{SphereDef{1}, {}}, {BoxDef{}, {{0, 0, 3e38f}, {}}}};
    EXPECT_EQ(errorOf(compound),
              "CompoundDef: children[1]: local.position (0, 0, 3e+38) lies farther than 100000 m "
              "from the compound's origin on an axis (docs/limits.md)");

    HeightfieldDef field;
    field.rows = 1;
    field.columns = 3;
    EXPECT_EQ(errorOf(field), "HeightfieldDef: rows must be >= 2 (got 1)");
    field.rows = 2;
    field.heights = {0, 0, 0, 0, 0};
    EXPECT_EQ(errorOf(field), "HeightfieldDef: heights has 5 values but rows * columns = 6");
    field.heights = {0, 0, 0, 0, nan, 0};
    EXPECT_EQ(errorOf(field), "HeightfieldDef: heights[4] is not finite (nan)");
    field.heights = {0, 0, 0, 0, 0, 0};
    field.spacing = {0, 1, 1};
    EXPECT_EQ(errorOf(field), "HeightfieldDef: spacing.x must be > 0 (got 0)");
}

TEST(ShapeValidation, EdgeCasesThatAreAllowed) {
    EXPECT_NO_THROW(buildShape(CapsuleDef{0.5f, 0}));  // a capsule of zero half-height is a sphere
    const Shape capsule = buildShape(CapsuleDef{0.5f, 0});
    const Shape sphere = buildShape(SphereDef{0.5f});
    expectMassNear(capsule.unitMass, sphere.unitMass, 1e-6);
    TriangleMeshDef degenerate{{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {0, 1, 2, 0, 0, 0}};  // zero-area triangles stay
    const Shape mesh = buildShape(degenerate);
    EXPECT_EQ(mesh.mesh->triangleCount(), 2u);
    EXPECT_TRUE(mesh.staticOnly());
    EXPECT_EQ(mesh.unitMass.mass, 0);
}

TEST(ShapeBounds, LocalBoundsPerKind) {
    auto expectBox = [](const Aabb& b, Vec3 lo, Vec3 hi) {
        EXPECT_NEAR(b.min.x, lo.x, 1e-5f);
        EXPECT_NEAR(b.min.y, lo.y, 1e-5f);
        EXPECT_NEAR(b.min.z, lo.z, 1e-5f);
        EXPECT_NEAR(b.max.x, hi.x, 1e-5f);
        EXPECT_NEAR(b.max.y, hi.y, 1e-5f);
        EXPECT_NEAR(b.max.z, hi.z, 1e-5f);
    };
    expectBox(buildShape(SphereDef{2}).localBounds, {-2, -2, -2}, {2, 2, 2});
    expectBox(buildShape(CapsuleDef{0.5f, 1}).localBounds, {-0.5f, -1.5f, -0.5f}, {0.5f, 1.5f, 0.5f});
    expectBox(buildShape(BoxDef{{1, 2, 3}}).localBounds, {-1, -2, -3}, {1, 2, 3});
    // A capsule lying along x at (5, 0, 0) and a box turned 90 degrees about y.
    CompoundDef c;
    c.children.push_back({CapsuleDef{0.5f, 1}, {{5, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, float(kPi / 2))}});
    c.children.push_back({BoxDef{{1, 2, 3}}, {{0, 0, 0}, Quat::fromAxisAngle({0, 1, 0}, float(kPi / 2))}});
    expectBox(buildShape(c).localBounds, {-3, -2, -1}, {6.5f, 2, 1});
    HeightfieldDef field{3, 4, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, -1}, {2, 0.5f, 3}};
    expectBox(buildShape(field).localBounds, {0, -0.5f, 0}, {6, 5, 6});
}

TEST(MassProperties, SphereAndBoxClosedForms) {
    // Closed forms: sphere m = 4/3 pi r^3, I = 2/5 m r^2; box m = abc, I_xx = m/12 (b^2 + c^2), full lengths.
    // Tolerance 1e-6 relative (float storage).
    const MassProperties s = buildShape(SphereDef{1.5f}).unitMass;
    const double ms = 4.0 / 3.0 * kPi * 1.5 * 1.5 * 1.5;
    EXPECT_NEAR(s.mass, ms, 1e-6 * ms);
    EXPECT_NEAR(s.inertia(1, 1), 0.4 * ms * 2.25, 1e-6 * ms);
    EXPECT_EQ(s.inertia(0, 1), 0);
    const MassProperties b = buildShape(BoxDef{{0.5f, 1, 2}}).unitMass;
    EXPECT_NEAR(b.mass, 8, 8e-6);
    EXPECT_NEAR(b.inertia(0, 0), 8.0 / 12 * (4 + 16), 1e-5);
    EXPECT_NEAR(b.inertia(1, 1), 8.0 / 12 * (1 + 16), 1e-5);
    EXPECT_NEAR(b.inertia(2, 2), 8.0 / 12 * (1 + 4), 1e-5);
    EXPECT_EQ(b.centerOfMass, Vec3{});
}

// Midpoint voxel estimate of a solid's mass properties over `bounds`, n cells per axis.
MassProperties voxelEstimate(const std::function<bool(double, double, double)>& inside, Vec3 lo, Vec3 hi, int n) {
    const double dx = (double(hi.x) - lo.x) / n, dy = (double(hi.y) - lo.y) / n, dz = (double(hi.z) - lo.z) / n;
    double m0 = 0;
    Eigen::Vector3d m1 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d m2 = Eigen::Matrix3d::Zero();
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                const Eigen::Vector3d p(lo.x + (i + 0.5) * dx, lo.y + (j + 0.5) * dy, lo.z + (k + 0.5) * dz);
                if (!inside(p.x(), p.y(), p.z())) continue;
                m0 += 1;
                m1 += p;
                m2 += p * p.transpose();
            }
    const double cell = dx * dy * dz;
    const Eigen::Vector3d com = m1 / m0;
    const Eigen::Matrix3d central = cell * (m2 - m0 * com * com.transpose());
    const Eigen::Matrix3d inertia = central.trace() * Eigen::Matrix3d::Identity() - central;
    MassProperties mp;
    mp.mass = float(m0 * cell);
    mp.centerOfMass = {float(com.x()), float(com.y()), float(com.z())};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) mp.inertia(i, j) = float(inertia(i, j));
    return mp;
}

TEST(MassProperties, CapsuleMatchesVoxelIntegration) {
    // 160^3 voxel midpoint estimate of the solid (points within r of the axis segment). Its error for these
    // smooth solids is ~1e-3 relative, so the formulas (hemisphere centroid shift + parallel axis) must agree to
    // 0.5% in mass and each inertia entry (relative to the largest moment). Getting the hemisphere term wrong
    // (e.g. no 3r/8 shift) changes I_xx by several percent for these proportions.
    for (auto [r, h] : {std::pair{0.5f, 1.0f}, {1.0f, 0.25f}, {0.2f, 2.0f}}) {
        const MassProperties m = buildShape(CapsuleDef{r, h}).unitMass;
        const auto inside = [r = double(r), h = double(h)](double x, double y, double z) {
            const double dy = std::max(0.0, std::abs(y) - h);
            return x * x + z * z + dy * dy <= r * r;
        };
        const MassProperties ref = voxelEstimate(inside, {-r, -h - r, -r}, {r, h + r, r}, 160);
        SCOPED_TRACE(::testing::Message() << "r=" << r << " h=" << h);
        expectMassNear(m, ref, 5e-3);
    }
}

TEST(MassProperties, TwoBoxesSideBySideEqualOneLongBox) {
    CompoundDef c;
    c.children.push_back({BoxDef{{0.5f, 0.5f, 0.25f}}, {{-0.5f, 2, 0}, {}}});
    c.children.push_back({BoxDef{{0.5f, 0.5f, 0.25f}}, {{0.5f, 2, 0}, {}}});
    MassProperties expected = buildShape(BoxDef{{1, 0.5f, 0.25f}}).unitMass;
    expected.centerOfMass = {0, 2, 0};
    expectMassNear(buildShape(c).unitMass, expected, 1e-5);  // same solid: float round-off only
}

TEST(MassProperties, RotatedChildInertiaRotates) {
    // A single box child turned and moved equals the hull of its turned and moved corners (a different code path:
    // polyhedral integration) to 1e-5 relative; a 90 degree turn about z swaps I_xx and I_yy exactly.
    const Vec3 h{1, 0.25f, 0.5f};
    const Quat q = Quat::fromAxisAngle({1, 2, -0.5f}, 0.7f);
    const Transform t{{3, -1, 2}, q};
    CompoundDef c;
    c.children.push_back({BoxDef{h}, t});
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i)
        corners.push_back(apply(t, {i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z}));
    expectMassNear(buildShape(c).unitMass, buildShape(ConvexHullDef{corners}).unitMass, 1e-5);

    CompoundDef turned;
    turned.children.push_back({BoxDef{h}, {{}, Quat::fromAxisAngle({0, 0, 1}, float(kPi / 2))}});
    const MassProperties box = buildShape(BoxDef{h}).unitMass, rot = buildShape(turned).unitMass;
    EXPECT_NEAR(rot.inertia(0, 0), box.inertia(1, 1), 1e-5);
    EXPECT_NEAR(rot.inertia(1, 1), box.inertia(0, 0), 1e-5);
    EXPECT_NEAR(rot.inertia(0, 1), 0, 1e-5);
}

TEST(MassProperties, CompoundOfMixedChildrenMatchesParallelAxisByHand) {
    // Sphere at +x and capsule at -x: COM and inertia from the parallel-axis theorem written out here.
    CompoundDef c;
    c.children.push_back({SphereDef{0.5f}, {{2, 0, 0}, {}}});
    c.children.push_back({CapsuleDef{0.25f, 0.5f}, {{-1, 0, 0}, {}}});
    const MassProperties s = buildShape(SphereDef{0.5f}).unitMass, k = buildShape(CapsuleDef{0.25f, 0.5f}).unitMass;
    const double m = s.mass + k.mass, cx = (2.0 * s.mass - 1.0 * k.mass) / m;
    const double ds = 2 - cx, dk = -1 - cx;
    const MassProperties got = buildShape(c).unitMass;
    EXPECT_NEAR(got.mass, m, 1e-6 * m);
    EXPECT_NEAR(got.centerOfMass.x, cx, 1e-6);
    EXPECT_NEAR(got.inertia(0, 0), s.inertia(0, 0) + k.inertia(0, 0), 1e-6);
    EXPECT_NEAR(got.inertia(1, 1), s.inertia(1, 1) + k.inertia(1, 1) + s.mass * ds * ds + k.mass * dk * dk, 1e-5);
}

TEST(MassProperties, PrincipalAxesReconstructInertia) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1, 1);
    for (int trial = 0; trial < 50; ++trial) {
        // Random inertia = rotated box inertia; every fifth case has two equal moments.
        Vec3 h{0.2f + std::abs(u(rng)), 0.2f + std::abs(u(rng)), 0.2f + std::abs(u(rng))};
        if (trial % 5 == 0) h.z = h.x;
        CompoundDef c;
        c.children.push_back({BoxDef{h}, {{}, Quat::fromAxisAngle({u(rng), u(rng), u(rng)}, 3 * u(rng))}});
        const Mat3 inertia = buildShape(c).unitMass.inertia;
        const PrincipalInertia p = principalAxes(inertia);
        EXPECT_NEAR(std::sqrt(p.rotation.x * p.rotation.x + p.rotation.y * p.rotation.y + p.rotation.z * p.rotation.z +
                              p.rotation.w * p.rotation.w),
                    1.0, 1e-6);
        const Eigen::Matrix3d r = rotationOf(p.rotation);
        EXPECT_NEAR(r.determinant(), 1.0, 1e-5);
        const Eigen::Matrix3d rebuilt =
            r * Eigen::Vector3d(p.moments.x, p.moments.y, p.moments.z).asDiagonal() * r.transpose();
        const Eigen::Matrix3d original = toEigen(inertia);
        EXPECT_LE((rebuilt - original).cwiseAbs().maxCoeff(), 1e-5 * original.cwiseAbs().maxCoeff()) << trial;
    }
    const PrincipalInertia d = principalAxes(Mat3::diagonal({3, 1, 2}));
    EXPECT_NEAR(d.moments.x + d.moments.y + d.moments.z, 6, 1e-6);
    EXPECT_NEAR(std::min({d.moments.x, d.moments.y, d.moments.z}), 1, 1e-6);
}

TEST(MassProperties, PublicComputeScalesAndRefusesStaticShapes) {
    const MassProperties m = computeMassProperties(BoxDef{{1, 1, 1}}, 250);
    EXPECT_NEAR(m.mass, 2000, 1e-3);
    EXPECT_NEAR(m.inertia(0, 0), 2000.0 / 12 * 8, 1e-2);
    auto message = [](const ShapeDef& def, float density) {
        try {
            computeMassProperties(def, density);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(message(SphereDef{1}, 0),
              "computeMassProperties: density must be in [0.001, 1e+06] kg/m^3 (got 0; docs/limits.md)");
    EXPECT_EQ(message(SphereDef{1}, NAN), "computeMassProperties: density is not finite (nan)");
    EXPECT_EQ(message(TriangleMeshDef{{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, {0, 1, 2}}, 1),
              "computeMassProperties: TriangleMeshDef is static-only and has no mass properties");
    EXPECT_EQ(message(HeightfieldDef{2, 2, {0, 0, 0, 0}}, 1),
              "computeMassProperties: HeightfieldDef is static-only and has no mass properties");
    EXPECT_EQ(message(SphereDef{-1}, 1), "SphereDef: radius must be in [0.0001, 10000] m (got -1; docs/limits.md)");
}

}  // namespace
}  // namespace rubble::detail
