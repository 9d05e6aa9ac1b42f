// Debug draw: a recording DebugDraw checks what World::debugDraw emits for small known worlds against the bodies:
// box corners from an independent rotation (Eigen), line counts per shape kind, hull edges, triangle limits and
// region, AABBs, the last step's contacts, the broad phase's grid cells (against the cell rule applied by brute
// force to the bodies' boxes) and static tree, and joints (against anchors posed with Eigen).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
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

namespace {

struct Box {
    Vec3 min, max;
    DebugColor color;
};

/// Records aabb() calls as boxes (and the lines of everything else).
class BoxRecorder : public RecordingDraw {
public:
    std::vector<Box> boxes;
    void aabb(Vec3 min, Vec3 max, DebugColor color) override { boxes.push_back({min, max, color}); }
};

BodyId addSphere(World& world, float radius, Vec3 position) {
    BodyDef def;
    def.shape = world.createShape(SphereDef{radius});
    def.position = position;
    return world.createBody(def);
}

bool sameBox(const Box& a, const Box& b, float tolerance) {
    return a.color == b.color && std::fabs(a.min.x - b.min.x) <= tolerance &&
           std::fabs(a.min.y - b.min.y) <= tolerance && std::fabs(a.min.z - b.min.z) <= tolerance &&
           std::fabs(a.max.x - b.max.x) <= tolerance && std::fabs(a.max.y - b.max.y) <= tolerance &&
           std::fabs(a.max.z - b.max.z) <= tolerance;
}

bool inside(Vec3 min, Vec3 max, Vec3 outerMin, Vec3 outerMax, float tolerance) {
    return min.x >= outerMin.x - tolerance && min.y >= outerMin.y - tolerance && min.z >= outerMin.z - tolerance &&
           max.x <= outerMax.x + tolerance && max.y <= outerMax.y + tolerance && max.z <= outerMax.z + tolerance;
}

/// Spheres of two sizes at rest without gravity, so each body's broad-phase box is its sphere's box grown by the
/// contact margin on every side (no motion to sweep).
struct GridWorld {
    static constexpr float kSmall = 0.25f, kLarge = 2.0f;
    std::vector<Vec3> small{{0.1f, 0.2f, 0.3f},  {0.4f, 0.1f, 0.6f},  {3.3f, 0.2f, 0.3f},
                            {5.5f, 2.4f, -0.1f}, {-1.6f, 7.3f, 2.2f}, {9.1f, 0.9f, 4.7f}};
    std::vector<Vec3> large{{20.2f, 1.3f, 2.1f}, {27.9f, 9.8f, -4.4f}, {20.7f, 0.6f, 2.9f}};

    static WorldSettings settings(BroadPhaseKind kind) {
        WorldSettings s;
        s.threads = 1;
        s.gravity = {0, 0, 0};
        s.broadPhase = kind;
        return s;
    }
    void populate(World& world) const {
        for (Vec3 p : small) addSphere(world, kSmall, p);
        for (Vec3 p : large) addSphere(world, kLarge, p);
    }

    /// The occupied cells by the rule in src/broadphase/multi_resolution_grid.h, brute force: the coarsest level's
    /// cells are as large as the largest box, each finer level `ratio` (4) times smaller while it still fits the
    /// smallest box; a box lives in the finest level whose cells are not smaller than its largest extent, in the
    /// cell of its centre, counted from the smallest centre on each axis.
    std::vector<Box> expectedCells(float margin) const {
        struct Body {
            Vec3 centre;
            float extent;
        };
        std::vector<Body> bodies;
        for (Vec3 p : small) bodies.push_back({p, 2 * (kSmall + margin)});
        for (Vec3 p : large) bodies.push_back({p, 2 * (kLarge + margin)});
        double extentMin = 1e30, extentMax = 0, origin[3] = {1e30, 1e30, 1e30};
        for (const Body& b : bodies) {
            extentMin = std::min<double>(extentMin, b.extent), extentMax = std::max<double>(extentMax, b.extent);
            origin[0] = std::min<double>(origin[0], b.centre.x);
            origin[1] = std::min<double>(origin[1], b.centre.y);
            origin[2] = std::min<double>(origin[2], b.centre.z);
        }
        std::vector<double> sizes{extentMax};  // coarsest first here
        while (sizes.back() / 4 >= extentMin) sizes.push_back(sizes.back() / 4);
        std::reverse(sizes.begin(), sizes.end());  // finest first, as levels are numbered
        std::vector<Box> cells;
        const DebugDrawColors colors;
        for (const Body& b : bodies) {
            std::size_t level = 0;
            while (sizes[level] < b.extent) ++level;
            const double s = sizes[level];
            const double c[3] = {b.centre.x, b.centre.y, b.centre.z};
            double lo[3], hi[3];
            for (int a = 0; a < 3; ++a) {
                const double cell = std::floor((c[a] - origin[a]) / s);
                lo[a] = origin[a] + cell * s, hi[a] = lo[a] + s;
            }
            const Box box{{float(lo[0]), float(lo[1]), float(lo[2])},
                          {float(hi[0]), float(hi[1]), float(hi[2])},
                          colors.gridLevels[level % colors.gridLevels.size()]};
            bool seen = false;
            for (const Box& other : cells) seen = seen || sameBox(other, box, 1e-4f);
            if (!seen) cells.push_back(box);
        }
        return cells;
    }
};

}  // namespace

TEST(DebugDraw, GridCellsAreTheCellsTheBodiesBoundsOccupy) {
    const GridWorld scene;
    const WorldSettings settings = GridWorld::settings(BroadPhaseKind::Grid);
    World world(settings);
    scene.populate(world);
    world.step(1.0f / 60.0f);
    ASSERT_EQ(world.lastProfile().broadPhase, BroadPhaseKind::Grid);

    BoxRecorder draw;
    world.debugDraw(draw, only(kDrawBroadphaseCells));
    const std::vector<Box> expected = scene.expectedCells(settings.contactMargin);
    // Two levels (cells of 1.01 m for the small spheres, 4.04 m for the large), two pairs sharing a cell: 7 cells.
    ASSERT_EQ(expected.size(), 7u);
    // Tolerance: the grid bins with cells 1 + 1e-6 times the level size (4e-6 m here), and draws in float.
    ASSERT_EQ(draw.boxes.size(), expected.size());
    for (const Box& e : expected) {
        const auto matches =
            std::count_if(draw.boxes.begin(), draw.boxes.end(), [&](const Box& b) { return sameBox(b, e, 1e-4f); });
        EXPECT_EQ(matches, 1) << "cell at (" << e.min.x << ", " << e.min.y << ", " << e.min.z << ")";
    }
    EXPECT_TRUE(draw.lines.empty());  // nothing else was asked for

    // The cap and the region: a frame never draws more than it may, and only what lies in the region.
    DebugDrawOptions capped = only(kDrawBroadphaseCells);
    capped.maxBroadphaseBoxes = 3;
    BoxRecorder few;
    world.debugDraw(few, capped);
    EXPECT_EQ(few.boxes.size(), 3u);
    DebugDrawOptions region = only(kDrawBroadphaseCells);
    region.regionMin = Vec3{26, 8, -6};  // around the large sphere at (27.9, 9.8, -4.4) only
    region.regionMax = Vec3{29, 11, -3};
    BoxRecorder one;
    world.debugDraw(one, region);
    ASSERT_EQ(one.boxes.size(), 1u);
    EXPECT_EQ(one.boxes[0].color, DebugDrawColors{}.gridLevels[1]);
    EXPECT_TRUE(inside({27.9f, 9.8f, -4.4f}, {27.9f, 9.8f, -4.4f}, one.boxes[0].min, one.boxes[0].max, 0));
}

TEST(DebugDraw, SweepAndPruneHasNoCellsToDraw) {
    const GridWorld scene;
    World world(GridWorld::settings(BroadPhaseKind::SweepAndPrune));
    scene.populate(world);
    world.step(1.0f / 60.0f);
    ASSERT_EQ(world.lastProfile().broadPhase, BroadPhaseKind::SweepAndPrune);
    BoxRecorder draw;
    world.debugDraw(draw, only(kDrawBroadphaseCells));
    EXPECT_TRUE(draw.boxes.empty());
    EXPECT_TRUE(draw.lines.empty());
}

TEST(DebugDraw, StaticTreeTopLevelsBoundTheStaticBodies) {
    World world(GridWorld::settings(BroadPhaseKind::SweepAndPrune));
    // 64 static boxes on an 8 x 8 grid and one moving sphere, so the step runs the broad phase.
    std::vector<Box> statics;
    for (int i = 0; i < 8; ++i)
        for (int k = 0; k < 8; ++k) {
            const Vec3 p{3.0f * i, 0, 3.0f * k};
            addBody(world, BoxDef{{0.5f, 0.5f, 0.5f}}, BodyType::Static, p);
            statics.push_back({p - Vec3{0.5f, 0.5f, 0.5f}, p + Vec3{0.5f, 0.5f, 0.5f}, {}});
        }
    addSphere(world, 0.5f, {0, 5, 0});
    world.step(1.0f / 60.0f);

    auto draw = [&](std::uint32_t depth) {
        DebugDrawOptions o = only(kDrawBroadphaseCells);
        o.broadphaseTreeDepth = depth;
        BoxRecorder r;
        world.debugDraw(r, o);
        for (const Box& b : r.boxes) EXPECT_EQ(b.color, DebugDrawColors{}.staticBvhNode);
        return r.boxes;
    };
    EXPECT_TRUE(draw(0).empty());
    const std::vector<Box> top = draw(1), two = draw(2);
    // A four-wide tree over 64 primitives: the root has nodes below it, and they have nodes below them.
    ASSERT_FALSE(top.empty());
    ASSERT_LE(top.size(), 4u);
    ASSERT_GT(two.size(), top.size());
    // Breadth first: depth 2 begins with depth 1's boxes.
    for (std::size_t i = 0; i < top.size(); ++i) EXPECT_TRUE(sameBox(top[i], two[i], 0));
    // Every static body lies inside one of the top boxes (they partition the primitives), and every second-level
    // box inside a top one.
    for (const Box& s : statics)
        EXPECT_TRUE(std::any_of(top.begin(), top.end(),
                                [&](const Box& t) { return inside(s.min, s.max, t.min, t.max, 1e-5f); }));
    for (std::size_t i = top.size(); i < two.size(); ++i)
        EXPECT_TRUE(std::any_of(top.begin(), top.end(),
                                [&](const Box& t) { return inside(two[i].min, two[i].max, t.min, t.max, 1e-5f); }));
}

namespace {

Eigen::Vector3f toEigen(Vec3 v) { return {v.x, v.y, v.z}; }

bool hasLine(const std::vector<Line>& lines, Eigen::Vector3f a, Eigen::Vector3f b, DebugColor color, float tol) {
    return std::any_of(lines.begin(), lines.end(), [&](const Line& l) {
        return l.color == color &&
               ((near(l.a, a, tol) && near(l.b, b, tol)) || (near(l.a, b, tol) && near(l.b, a, tol)));
    });
}

}  // namespace

TEST(DebugDraw, JointLineJoinsTheWorldAnchors) {
    World world(GridWorld::settings(BroadPhaseKind::Auto));
    const Eigen::Quaternionf rA(Eigen::AngleAxisf(0.9f, Eigen::Vector3f(0, 1, 1).normalized()));
    const Eigen::Quaternionf rB(Eigen::AngleAxisf(-1.3f, Eigen::Vector3f(1, 0, 2).normalized()));
    BodyDef defA;
    defA.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    defA.position = {1, 2, 3};
    defA.orientation = Quat{rA.x(), rA.y(), rA.z(), rA.w()};
    BodyDef defB = defA;
    defB.position = {4, 1, -2};
    defB.orientation = Quat{rB.x(), rB.y(), rB.z(), rB.w()};
    DistanceJointDef rod;
    rod.bodyA = world.createBody(defA);
    rod.bodyB = world.createBody(defB);
    rod.localAnchorA = {0.5f, 0.5f, 0};
    rod.localAnchorB = {0, -0.5f, 0.5f};
    world.createJoint(rod);
    SpringJointDef spring;
    spring.bodyA = rod.bodyA;
    spring.bodyB = addSphere(world, 0.3f, {-3, 2, 0});
    spring.localAnchorA = {-0.5f, 0, 0};
    world.createJoint(spring);

    RecordingDraw draw;
    world.debugDraw(draw, only(kDrawJoints));
    // Anchors in the world from an independent rotation: position + R local.
    const Eigen::Vector3f a = Eigen::Vector3f(1, 2, 3) + rA * toEigen(rod.localAnchorA);
    const Eigen::Vector3f b = Eigen::Vector3f(4, 1, -2) + rB * toEigen(rod.localAnchorB);
    const DebugDrawColors colors;
    EXPECT_TRUE(hasLine(draw.lines, a, b, colors.distanceJoint, 1e-5f));
    const Eigen::Vector3f springA = Eigen::Vector3f(1, 2, 3) + rA * toEigen(spring.localAnchorA);
    EXPECT_TRUE(hasLine(draw.lines, springA, Eigen::Vector3f(-3, 2, 0), colors.springJoint, 1e-5f));
    // Per joint: two anchor points (three lines each) and the line between them.
    EXPECT_EQ(draw.points, 4);
    EXPECT_EQ(draw.lines.size(), 2u * 7u);

    DebugDrawOptions region = only(kDrawJoints);
    region.regionMin = Vec3{-4, 1, -1};  // holds the spring's anchors, not the rod's
    region.regionMax = Vec3{1, 3, 1};
    RecordingDraw some;
    world.debugDraw(some, region);
    EXPECT_EQ(some.points, 2);
    EXPECT_TRUE(hasLine(some.lines, springA, Eigen::Vector3f(-3, 2, 0), colors.springJoint, 1e-5f));
}

TEST(DebugDraw, HingeAxisLimitArcAndAngleSpoke) {
    World world(GridWorld::settings(BroadPhaseKind::Auto));
    BodyDef def;
    def.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    def.type = BodyType::Static;
    const BodyId frame = world.createBody(def);
    def.type = BodyType::Dynamic;
    def.position = {0, 0, 1.5f};
    const BodyId door = world.createBody(def);
    HingeJointDef hinge;
    hinge.bodyA = frame;
    hinge.bodyB = door;
    hinge.localAnchorA = {0, 0, 0.75f};
    hinge.localAnchorB = {0, 0, -0.75f};
    hinge.localAxisA = hinge.localAxisB = {0, 1, 0};
    hinge.enableLimit = true;
    hinge.lowerAngle = -0.5f;
    hinge.upperAngle = 1.2f;
    world.createJoint(hinge);
    // Turn the door 0.8 rad about the hinge line (vertical, through (0, 0, 0.75)): the hinge angle becomes 0.8.
    const float angle = 0.8f;
    const Eigen::AngleAxisf turn(angle, Eigen::Vector3f::UnitY());
    const Eigen::Vector3f pivot(0, 0, 0.75f);
    const Eigen::Vector3f doorAt = pivot + turn * (Eigen::Vector3f(0, 0, 1.5f) - pivot);
    const Eigen::Quaternionf q(turn);
    world.setTransform(door, {doorAt.x(), doorAt.y(), doorAt.z()}, Quat{q.x(), q.y(), q.z(), q.w()});

    DebugDrawOptions options = only(kDrawJoints);
    RecordingDraw draw;
    world.debugDraw(draw, options);
    const DebugColor color = DebugDrawColors{}.hingeJoint;
    // Points (2 x 3 lines), anchor line, axis line, 16 arc segments, spoke.
    ASSERT_EQ(draw.lines.size(), 6u + 1u + 1u + 16u + 1u);
    for (const Line& l : draw.lines) EXPECT_EQ(l.color, color);
    const float size = options.jointSize;
    EXPECT_TRUE(
        hasLine(draw.lines, pivot - Eigen::Vector3f(0, size, 0), pivot + Eigen::Vector3f(0, size, 0), color, 1e-5f));
    // The arc: every vertex `size` from the pivot in the plane normal to the axis, sweeping upper - lower about +y.
    const std::size_t arc = 8;
    // Evaluated to a vector: an Eigen expression returned by auto would refer to the dead temporary toEigen(p).
    auto radial = [&](Vec3 p) -> Eigen::Vector3f { return toEigen(p) - pivot; };
    for (std::size_t i = arc; i < arc + 16; ++i) {
        EXPECT_NEAR(radial(draw.lines[i].a).norm(), size, 1e-5f);
        EXPECT_NEAR(radial(draw.lines[i].a).y(), 0, 1e-5f);
    }
    auto signedAngle = [](Eigen::Vector3f from, Eigen::Vector3f to) {
        return std::atan2(from.cross(to).dot(Eigen::Vector3f::UnitY()), from.dot(to));
    };
    const Eigen::Vector3f lower = radial(draw.lines[arc].a), upper = radial(draw.lines[arc + 15].b);
    EXPECT_NEAR(signedAngle(lower, upper) + (signedAngle(lower, upper) < 0 ? 2 * std::numbers::pi_v<float> : 0),
                hinge.upperAngle - hinge.lowerAngle, 1e-4f);
    // The spoke sits at the hinge angle on the arc's scale: angle - lower past the arc's start.
    const Line& spoke = draw.lines.back();
    EXPECT_TRUE(near(spoke.a, pivot, 1e-5f));
    EXPECT_NEAR(radial(spoke.b).norm(), size, 1e-5f);
    EXPECT_NEAR(signedAngle(lower, radial(spoke.b)), angle - hinge.lowerAngle, 1e-4f);
}

TEST(DebugDraw, BrokenJointsAreNotDrawn) {
    WorldSettings settings;
    settings.threads = 1;
    World world(settings);
    BodyDef def;
    def.shape = world.createShape(SphereDef{0.5f});
    def.type = BodyType::Static;
    BallJointDef ball;
    ball.bodyA = world.createBody(def);
    def.type = BodyType::Dynamic;
    def.position = {0, -1, 0};
    ball.bodyB = world.createBody(def);
    ball.localAnchorA = {0, -0.5f, 0};
    ball.localAnchorB = {0, 0.5f, 0};
    ball.breakForce = 1e-3f;  // gravity on the hanging ball alone breaks it
    world.createJoint(ball);
    RecordingDraw before;
    world.debugDraw(before, only(kDrawJoints));
    EXPECT_EQ(before.points, 2);
    world.step(1.0f / 60.0f);
    ASSERT_EQ(world.takeBrokenJoints().size(), 1u);
    RecordingDraw after;
    world.debugDraw(after, only(kDrawJoints));
    EXPECT_TRUE(after.lines.empty());
}
