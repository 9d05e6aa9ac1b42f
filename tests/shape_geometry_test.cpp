// World::shapeGeometry: what a renderer reads back must describe the shape the engine collides with. Hull triangles
// are checked against the hull's own definition (every triangle on a face plane of the cube it came from, outward,
// covering the surface area 6 a^2), heightfield triangles against the heights given and the terrain height query.
#include <gtest/gtest.h>

#include <cmath>
#include <variant>

#include "rubble/error.h"
#include "rubble/shape_geometry.h"
#include "rubble/world.h"

using namespace rubble;

namespace {

float triangleArea(Vec3 a, Vec3 b, Vec3 c) { return 0.5f * length(cross(b - a, c - a)); }

}  // namespace

TEST(ShapeGeometry, PrimitivesReportTheirSizes) {
    World world;
    const ShapeGeometry sphere = world.shapeGeometry(world.createShape(SphereDef{0.7f}));
    EXPECT_EQ(sphere.type, ShapeType::Sphere);
    EXPECT_EQ(sphere.radius, 0.7f);
    const ShapeGeometry box = world.shapeGeometry(world.createShape(BoxDef{{1, 2, 3}}));
    EXPECT_EQ(box.type, ShapeType::Box);
    EXPECT_EQ(box.halfExtents, (Vec3{1, 2, 3}));
    EXPECT_EQ(box.boundsMax, (Vec3{1, 2, 3}));
    const ShapeGeometry capsule = world.shapeGeometry(world.createShape(CapsuleDef{0.3f, 0.9f}));
    EXPECT_EQ(capsule.type, ShapeType::Capsule);
    EXPECT_EQ(capsule.radius, 0.3f);
    EXPECT_EQ(capsule.halfHeight, 0.9f);
    EXPECT_TRUE(capsule.vertices.empty());
}

TEST(ShapeGeometry, HullTrianglesCoverTheCubeSurfaceFacingOutward) {
    // A cube of side 2 given with interior and duplicate points: the hull keeps 8 corners, 6 square faces.
    ConvexHullDef def;
    for (int i = 0; i < 8; ++i)
        def.points.push_back({(i & 1) ? 1.f : -1.f, (i & 2) ? 1.f : -1.f, (i & 4) ? 1.f : -1.f});
    def.points.push_back({0, 0, 0});
    def.points.push_back({1, 1, 1});
    World world;
    const ShapeGeometry g = world.shapeGeometry(world.createShape(def));
    ASSERT_EQ(g.type, ShapeType::ConvexHull);
    EXPECT_EQ(g.vertices.size(), 8u);
    ASSERT_EQ(g.indices.size(), 12u * 3);  // two triangles per face
    float area = 0;
    for (std::size_t t = 0; t < g.indices.size(); t += 3) {
        const Vec3 a = g.vertices[g.indices[t]], b = g.vertices[g.indices[t + 1]], c = g.vertices[g.indices[t + 2]];
        area += triangleArea(a, b, c);
        const Vec3 n = cross(b - a, c - a);
        const Vec3 centre = (a + b + c) / 3.0f;
        EXPECT_GT(dot(n, centre), 0) << "triangle " << t / 3 << " faces inwards";
        // On a face plane: one coordinate is +-1 at all three corners.
        const bool onFace = (std::fabs(a.x) == 1 && a.x == b.x && b.x == c.x) ||
                            (std::fabs(a.y) == 1 && a.y == b.y && b.y == c.y) ||
                            (std::fabs(a.z) == 1 && a.z == b.z && b.z == c.z);
        EXPECT_TRUE(onFace) << "triangle " << t / 3;
    }
    EXPECT_NEAR(area, 24.0f, 1e-4f);  // 6 faces of 2 x 2
}

TEST(ShapeGeometry, CompoundChildrenKeepTheirPoses) {
    CompoundDef def;
    def.children.push_back({BoxDef{{0.5f, 0.5f, 0.5f}}, {{1, 0, 0}, {}}});
    def.children.push_back({SphereDef{0.25f}, {{-1, 2, 0}, Quat::fromAxisAngle({0, 0, 1}, 0.5f)}});
    World world;
    const ShapeGeometry g = world.shapeGeometry(world.createShape(def));
    ASSERT_EQ(g.type, ShapeType::Compound);
    ASSERT_EQ(g.children.size(), 2u);
    EXPECT_EQ(g.children[0].geometry.type, ShapeType::Box);
    EXPECT_EQ(g.children[0].local.position, (Vec3{1, 0, 0}));
    EXPECT_EQ(g.children[1].geometry.type, ShapeType::Sphere);
    EXPECT_EQ(g.children[1].geometry.radius, 0.25f);
    EXPECT_EQ(g.children[1].local.position, (Vec3{-1, 2, 0}));
}

TEST(ShapeGeometry, MeshComesBackAsGiven) {
    TriangleMeshDef def;
    def.vertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {1, 0, 1}};
    def.indices = {0, 1, 2, 2, 1, 3};
    World world;
    const ShapeGeometry g = world.shapeGeometry(world.createShape(def));
    EXPECT_EQ(g.type, ShapeType::TriangleMesh);
    EXPECT_EQ(g.indices, def.indices);
    ASSERT_EQ(g.vertices.size(), def.vertices.size());
    for (std::size_t i = 0; i < def.vertices.size(); ++i) EXPECT_EQ(g.vertices[i], def.vertices[i]);
}

TEST(ShapeGeometry, HeightfieldTrianglesFaceUpAndMatchTheTerrainHeight) {
    HeightfieldDef def;
    def.rows = 4;
    def.columns = 5;
    def.spacing = {0.5f, 2.0f, 0.75f};
    for (std::uint32_t r = 0; r < def.rows; ++r)
        for (std::uint32_t c = 0; c < def.columns; ++c)
            def.heights.push_back(0.1f * static_cast<float>(r * r) - 0.2f * static_cast<float>(c));
    World world;
    const ShapeId shape = world.createShape(def);
    BodyDef body;
    body.type = BodyType::Static;
    body.shape = shape;
    world.createBody(body);
    const ShapeGeometry g = world.shapeGeometry(shape);
    ASSERT_EQ(g.type, ShapeType::Heightfield);
    ASSERT_EQ(g.indices.size(), 3u * 2 * (def.rows - 1) * (def.columns - 1));
    for (std::size_t t = 0; t < g.indices.size(); t += 3) {
        const Vec3 a = g.vertices[g.indices[t]], b = g.vertices[g.indices[t + 1]], c = g.vertices[g.indices[t + 2]];
        EXPECT_GT(cross(b - a, c - a).y, 0) << "triangle " << t / 3 << " does not face +y";
        // Each vertex is a sample: its height is the given one times the y scale (exact: one multiplication).
        for (Vec3 v : {a, b, c}) {
            const auto column = static_cast<std::uint32_t>(std::lround(v.x / def.spacing.x));
            const auto row = static_cast<std::uint32_t>(std::lround(v.z / def.spacing.z));
            EXPECT_FLOAT_EQ(v.y, def.heights[row * def.columns + column] * def.spacing.y);
        }
        // The centroid lies on the surface the engine's own height query reports.
        const Vec3 m = (a + b + c) / 3.0f;
        float h = 0;
        ASSERT_TRUE(world.terrainHeightAt(m.x, m.z, h));
        EXPECT_NEAR(h, m.y, 1e-5f);
    }
}

TEST(ShapeGeometry, StaleShapeIsRefused) {
    World world;
    const ShapeId shape = world.createShape(SphereDef{1});
    world.destroyShape(shape);
    EXPECT_THROW(world.shapeGeometry(shape), Error);
    EXPECT_THROW(world.shapeGeometry(ShapeId{}), Error);
}
