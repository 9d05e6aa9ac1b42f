// Update-bounds stage: every box contains its shape (checked against transformed vertices and surface samples,
// computed independently here), is tight where it can be, covers the motion of the step, and the SIMD and scalar
// paths agree bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bounds/bounds.h"
#include "core/parallel.h"
#include "rubble/world.h"

using namespace rubble;
using namespace rubble::detail;

namespace {

struct Fixture {
    std::vector<Shape> shapes;
    ShapeBoundsTable table;
    MovingBodies bodies;

    std::uint32_t addShape(const ShapeDef& def) {
        shapes.push_back(buildShape(def));
        table.set(static_cast<std::uint32_t>(shapes.size() - 1), shapeBoundsInfo(shapes.back()));
        return static_cast<std::uint32_t>(shapes.size() - 1);
    }

    /// A body whose shape origin sits at `origin` (the centre of mass is placed where the world would put it).
    void addBody(std::uint32_t shape, Vec3 origin, Quat q, Vec3 v) {
        const std::uint32_t i = bodies.pushBack();
        const Vec3 com = origin + rotate(q, shapes[shape].unitMass.centerOfMass);
        bodies.px[i] = com.x, bodies.py[i] = com.y, bodies.pz[i] = com.z;
        bodies.qx[i] = q.x, bodies.qy[i] = q.y, bodies.qz[i] = q.z, bodies.qw[i] = q.w;
        bodies.vx[i] = v.x, bodies.vy[i] = v.y, bodies.vz[i] = v.z;
        bodies.shape[i] = shape;
    }
};

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    Quat q{g(rng), g(rng), g(rng), g(rng)};
    const float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    return {q.x / n, q.y / n, q.z / n, q.w / n};
}

bool inside(const Bounds& b, std::uint32_t i, Vec3 p) {
    return b.minX[i] <= p.x && p.x <= b.maxX[i] && b.minY[i] <= p.y && p.y <= b.maxY[i] && b.minZ[i] <= p.z &&
           p.z <= b.maxZ[i];
}

/// Points on the surface of each shape in its local frame, for the containment check.
std::vector<Vec3> surfaceSamples(const Shape& s, std::mt19937& rng) {
    std::vector<Vec3> out;
    std::normal_distribution<float> g;
    auto direction = [&] {
        Vec3 d{g(rng), g(rng), g(rng)};
        return d / length(d);
    };
    switch (s.kind) {
        case ShapeKind::Sphere:
            for (int k = 0; k < 200; ++k) out.push_back(direction() * s.radius);
            break;
        case ShapeKind::Capsule:
            for (int k = 0; k < 200; ++k)
                out.push_back(direction() * s.radius + Vec3{0, (k % 2 ? 1.f : -1.f) * s.halfHeight, 0});
            break;
        case ShapeKind::Box:
            for (int k = 0; k < 8; ++k)
                out.push_back({(k & 1 ? 1.f : -1.f) * s.halfExtents.x, (k & 2 ? 1.f : -1.f) * s.halfExtents.y,
                               (k & 4 ? 1.f : -1.f) * s.halfExtents.z});
            break;
        case ShapeKind::ConvexHull:
            out = s.hull->vertices;
            break;
        case ShapeKind::Compound:
            for (const CompoundChild& c : s.children)
                for (const Vec3& p : surfaceSamples(*c.shape, rng)) out.push_back(apply(c.local, p));
            break;
        default:
            break;
    }
    return out;
}

}  // namespace

TEST(Bounds, ContainEveryShapeAtAnyOrientationAndAgreeAcrossPaths) {
    Fixture f;
    CompoundDef compound;
    compound.children.push_back(
        {BoxDef{{0.5f, 0.2f, 0.1f}}, Transform{{1, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, 0.5f)}});
    compound.children.push_back({SphereDef{0.3f}, Transform{{-1, 0.5f, 0}, {}}});
    const std::uint32_t kinds[] = {
        f.addShape(SphereDef{0.5f}), f.addShape(BoxDef{{0.3f, 0.7f, 1.1f}}), f.addShape(CapsuleDef{0.3f, 0.5f}),
        f.addShape(ConvexHullDef{{{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 3}, {1, 1, 1}}}), f.addShape(compound)};
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> pos(-50, 50), vel(-10, 10);
    for (int i = 0; i < 1001; ++i)  // not a multiple of the lane count: the scalar tail runs too
        f.addBody(kinds[i % 5], {pos(rng), pos(rng), pos(rng)}, randomRotation(rng), {vel(rng), vel(rng), vel(rng)});

    const BoundsParams params{1.0f / 60, 0.02f};
    TaskPool pool(2);
    Bounds wide, scalar;
    updateBounds(f.bodies, f.table, params, pool, wide);
    updateBoundsScalar(f.bodies, f.table, params, scalar);
    ASSERT_EQ(wide.size(), 1001u);
    for (std::uint32_t i = 0; i < wide.size(); ++i) {
        ASSERT_EQ(wide.minX[i], scalar.minX[i]);
        ASSERT_EQ(wide.maxY[i], scalar.maxY[i]);
        ASSERT_EQ(wide.maxZ[i], scalar.maxZ[i]);
    }

    for (std::uint32_t i = 0; i < wide.size(); ++i) {
        const Shape& shape = f.shapes[f.bodies.shape[i]];
        const Quat q{f.bodies.qx[i], f.bodies.qy[i], f.bodies.qz[i], f.bodies.qw[i]};
        const Vec3 com{f.bodies.px[i], f.bodies.py[i], f.bodies.pz[i]};
        const Vec3 origin = com - rotate(q, shape.unitMass.centerOfMass);
        const Vec3 travel = Vec3{f.bodies.vx[i], f.bodies.vy[i], f.bodies.vz[i]} * params.dt;
        for (const Vec3& p : surfaceSamples(shape, rng)) {
            const Vec3 start = apply(Transform{origin, q}, p);
            ASSERT_TRUE(inside(wide, i, start)) << "body " << i << " kind " << int(shape.kind);
            ASSERT_TRUE(inside(wide, i, start + travel)) << "body " << i << " does not cover its motion";
        }
    }
}

TEST(Bounds, SpheresAreExactAtAnyOrientation) {
    Fixture f;
    const std::uint32_t ball = f.addShape(SphereDef{0.5f});
    std::mt19937 rng(9);
    for (int i = 0; i < 64; ++i) f.addBody(ball, {float(i), 2, 3}, randomRotation(rng), {});
    TaskPool pool(1);
    Bounds b;
    updateBounds(f.bodies, f.table, BoundsParams{1.0f / 60, 0}, pool, b);
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        EXPECT_NEAR(b.maxX[i] - b.minX[i], 1.0f, 1e-5f);  // the diameter, not the rotated cube's diagonal
        EXPECT_NEAR(b.maxY[i] - b.minY[i], 1.0f, 1e-5f);
    }
}

TEST(Bounds, StaticWorldBoundsAreTight) {
    // A mesh's box is the box of its transformed vertices; a box at 45 degrees about y spans sqrt(2) h on x and z.
    const Shape box = buildShape(BoxDef{{1, 1, 1}});
    const Aabb turned = worldBounds(box, Transform{{5, 0, 0}, Quat::fromAxisAngle({0, 1, 0}, 3.14159265f / 4)});
    EXPECT_NEAR(turned.max.x - 5, std::sqrt(2.0f), 1e-5f);
    EXPECT_NEAR(turned.max.y, 1.0f, 1e-5f);
    TriangleMeshDef mesh;
    mesh.vertices = {{0, 0, 0}, {4, 0, 0}, {0, 1, 2}};
    mesh.indices = {0, 2, 1};
    const Aabb m = worldBounds(buildShape(mesh), Transform{{1, 1, 1}, {}});
    EXPECT_EQ(m.min.x, 1.0f);
    EXPECT_EQ(m.max.x, 5.0f);
    EXPECT_EQ(m.max.z, 3.0f);
}
