// Debug draw: a recording DebugDraw checks what World::debugDraw emits for small known worlds against the bodies:
// box corners from an independent rotation (Eigen), line counts per shape kind, hull edges, triangle limits and
// region, AABBs, and the last step's contacts.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rubble/debug_draw.h"
#include "rubble/world.h"

using namespace rubble;

namespace {

struct Line {
    Vec3 a, b;
    DebugColor color;
};

/// Records lines; everything else uses DebugDraw's defaults, except where a test counts the solid calls.
class RecordingDraw : public DebugDraw {
public:
    std::vector<Line> lines;
    int triangles = 0, points = 0;
    void line(Vec3 a, Vec3 b, DebugColor color) override { lines.push_back({a, b, color}); }
    void triangle(Vec3 a, Vec3 b, Vec3 c, DebugColor color) override {
        ++triangles;
        DebugDraw::triangle(a, b, c, color);
    }
    void point(Vec3 p, float size, DebugColor color) override {
        ++points;
        DebugDraw::point(p, size, color);
    }
};

DebugDrawOptions only(std::uint32_t flags) {
    DebugDrawOptions o;
    o.flags = flags;
    return o;
}

ShapeId addBody(World& world, const ShapeDef& shape, BodyType type, Vec3 position, Quat orientation = Quat{}) {
    const ShapeId id = world.createShape(shape);
    BodyDef def;
    def.type = type;
    def.shape = id;
    def.position = position;
    def.orientation = orientation;
    world.createBody(def);
    return id;
}

bool near(Vec3 a, Eigen::Vector3f b, float tolerance) {
    return std::fabs(a.x - b.x()) <= tolerance && std::fabs(a.y - b.y()) <= tolerance &&
           std::fabs(a.z - b.z()) <= tolerance;
}

}  // namespace

TEST(DebugDraw, OneBoxIsTwelveEdgesBetweenItsCorners) {
    World world;
    const Eigen::Quaternionf r(Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()));
    const Vec3 position{1, 2, -3};
    const Eigen::Vector3f half(0.5f, 1.0f, 1.5f);
    addBody(world, BoxDef{{half.x(), half.y(), half.z()}}, BodyType::Dynamic, position,
            Quat{r.x(), r.y(), r.z(), r.w()});
    RecordingDraw draw;
    world.debugDraw(draw, only(kDrawShapes));
    ASSERT_EQ(draw.lines.size(), 12u);
    // Independent corners: position + R (+-hx, +-hy, +-hz). Every edge joins two corners that differ in one sign,
    // and together the edges cover each corner three times.
    std::vector<Eigen::Vector3f> corners;
    for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3f local((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                                    (i & 4) ? half.z() : -half.z());
        corners.push_back(Eigen::Vector3f(position.x, position.y, position.z) + r * local);
    }
    auto cornerOf = [&](Vec3 p) {
        for (int i = 0; i < 8; ++i)
            if (near(p, corners[static_cast<std::size_t>(i)], 1e-5f)) return i;
        return -1;
    };
    int uses[8] = {};
    for (const Line& l : draw.lines) {
        const int a = cornerOf(l.a), b = cornerOf(l.b);
        ASSERT_GE(a, 0);
        ASSERT_GE(b, 0);
        const int differ = a ^ b;
        EXPECT_TRUE(differ == 1 || differ == 2 || differ == 4) << a << " - " << b;
        ++uses[a], ++uses[b];
        EXPECT_EQ(l.color, DebugDrawColors{}.dynamicBody);
    }
    for (int u : uses) EXPECT_EQ(u, 3);
}

TEST(DebugDraw, EveryShapeKindAndItsBoundingBox) {
    World world;
    addBody(world, SphereDef{0.5f}, BodyType::Dynamic, {0, 5, 0});
    addBody(world, CapsuleDef{0.3f, 0.6f}, BodyType::Kinematic, {3, 5, 0});
    // A cube as a hull: 12 edges (coplanar triangles are merged into faces, so no diagonals).
    addBody(world,
            ConvexHullDef{
                {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 1}}},
            BodyType::Dynamic, {6, 5, 0});
    CompoundDef compound;
    compound.children.push_back({BoxDef{{0.2f, 0.2f, 0.2f}}, Transform{{0.5f, 0, 0}, Quat{}}});
    compound.children.push_back({BoxDef{{0.2f, 0.2f, 0.2f}}, Transform{{-0.5f, 0, 0}, Quat{}}});
    addBody(world, compound, BodyType::Dynamic, {9, 5, 0});
    RecordingDraw draw;
    world.debugDraw(draw, only(kDrawShapes));
    // Sphere: 3 circles of 16 segments; capsule: 2 cap circles (16 each), 4 sides and 4 half circles (16 each);
    // hull cube: 12; compound of two boxes: 24.
    EXPECT_EQ(draw.lines.size(), 48u + (32u + 4u + 64u) + 12u + 24u);
    // The compound's children sit at +-0.5 m along x from the body's origin.
    float minX = 1e9f, maxX = -1e9f;
    for (std::size_t i = draw.lines.size() - 24; i < draw.lines.size(); ++i)
        for (Vec3 p : {draw.lines[i].a, draw.lines[i].b}) minX = std::min(minX, p.x), maxX = std::max(maxX, p.x);
    EXPECT_NEAR(minX, 9 - 0.7f, 1e-5f);
    EXPECT_NEAR(maxX, 9 + 0.7f, 1e-5f);

    RecordingDraw boxes;
    world.debugDraw(boxes, only(kDrawAabbs));
    EXPECT_EQ(boxes.lines.size(), 4u * 12u);
    // The sphere's box: centre (0, 5, 0), half size 0.5.
    for (std::size_t i = 0; i < 12; ++i)
        for (Vec3 p : {boxes.lines[i].a, boxes.lines[i].b}) {
            EXPECT_NEAR(std::fabs(p.x), 0.5f, 1e-5f);
            EXPECT_NEAR(std::fabs(p.y - 5), 0.5f, 1e-5f);
            EXPECT_NEAR(std::fabs(p.z), 0.5f, 1e-5f);
        }
}

TEST(DebugDraw, MeshAndHeightfieldTrianglesAreLimitedByCountAndRegion) {
    World world;
    HeightfieldDef field;
    field.rows = 11;
    field.columns = 11;
    field.heights.assign(121, 0.0f);
    addBody(world, field, BodyType::Static, {0, 0, 0});  // 200 triangles over [0, 10] x [0, 10]
    TriangleMeshDef mesh;
    mesh.vertices = {{20, 0, 0}, {21, 0, 0}, {20, 0, 1}, {21, 0, 1}};
    mesh.indices = {0, 2, 1, 1, 2, 3};
    addBody(world, mesh, BodyType::Static, {0, 0, 0});

    RecordingDraw all;
    world.debugDraw(all, only(kDrawShapes | kDrawMeshTriangles));
    EXPECT_EQ(all.triangles, 202);
    EXPECT_EQ(all.lines.size(), 3u * 202u);

    DebugDrawOptions capped = only(kDrawShapes | kDrawMeshTriangles);
    capped.maxTriangles = 50;
    RecordingDraw some;
    world.debugDraw(some, capped);
    EXPECT_EQ(some.triangles, 50);

    // Cells [2, 4] x [2, 4] of the heightfield: the region touches triangles of the 4x4 cells from 1 to 4 (shared
    // edges count as overlap): 32 triangles; the mesh is outside.
    DebugDrawOptions region = only(kDrawShapes | kDrawMeshTriangles);
    region.regionMin = Vec3{2.0f, -1, 2.0f};
    region.regionMax = Vec3{4.0f, 1, 4.0f};
    RecordingDraw inside;
    world.debugDraw(inside, region);
    EXPECT_EQ(inside.triangles, 32);

    RecordingDraw none;
    world.debugDraw(none, only(kDrawShapes));  // triangles not asked for
    EXPECT_EQ(none.triangles, 0);
}

TEST(DebugDraw, ContactsOfTheLastStep) {
    WorldSettings settings;
    settings.threads = 1;
    World world(settings);
    addBody(world, BoxDef{{5, 0.5f, 5}}, BodyType::Static, {0, -0.5f, 0});
    addBody(world, BoxDef{{0.5f, 0.5f, 0.5f}}, BodyType::Dynamic, {0, 0.5f, 0});
    world.step(1.0f / 60.0f);
    const std::uint32_t points = world.lastProfile().contactPoints;
    ASSERT_EQ(points, 4u);  // a box resting on a floor: its four bottom corners
    RecordingDraw draw;
    DebugDrawOptions options = only(kDrawContacts);
    world.debugDraw(draw, options);
    EXPECT_EQ(draw.points, 4);
    // Each point: three lines of its cross, then its normal (the floor is A, so the normal points up into the box).
    ASSERT_EQ(draw.lines.size(), 4u * 4u);
    for (int p = 0; p < 4; ++p) {
        const Line& normal = draw.lines[static_cast<std::size_t>(4 * p + 3)];
        EXPECT_EQ(normal.color, DebugDrawColors{}.contactNormal);
        EXPECT_NEAR(std::fabs(normal.b.y - normal.a.y), options.normalLength, 1e-5f);
        EXPECT_NEAR(std::fabs(normal.a.x), 0.5f, 1e-3f);
        EXPECT_NEAR(std::fabs(normal.a.z), 0.5f, 1e-3f);
        EXPECT_NEAR(normal.a.y, 0.0f, 0.02f);
    }
}
