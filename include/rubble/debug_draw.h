#pragma once
// Debug drawing: World::debugDraw describes what the world holds (shapes at their poses, boxes, contacts, sleeping
// state, broad-phase cells, joints) through this small interface, which a viewer or a game implements with its own
// renderer.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "rubble/math.h"

namespace rubble {

struct DebugColor {
    std::uint8_t r = 255, g = 255, b = 255, a = 255;
    friend constexpr bool operator==(DebugColor x, DebugColor y) {
        return x.r == y.r && x.g == y.g && x.b == y.b && x.a == y.a;
    }
};

/// What World::debugDraw draws (bits of DebugDrawOptions::flags).
enum DebugDrawFlags : std::uint32_t {
    kDrawShapes = 1u << 0,         ///< every body's shape at its pose, coloured by body type
    kDrawMeshTriangles = 1u << 1,  ///< triangles of static meshes and heightfields (limited, see DebugDrawOptions)
    kDrawAabbs = 1u << 2,          ///< tight world bounding box of every body
    kDrawContacts = 1u << 3,       ///< the last step's contact points and their normals
    kDrawSleeping = 1u << 4,       ///< sleeping bodies take DebugDrawColors::asleep (needs shapes)
    /// Colour moving bodies by the island the last step put them in (bodies added since keep their type's colour).
    kDrawIslands = 1u << 5,
    /// The broad phase of the last step, from the boxes it was given (swept by the step's motion, so cells lag the
    /// bodies' current poses by one step). When the multi-resolution grid found the moving pairs: every occupied
    /// cell, coloured by level (DebugDrawColors::gridLevels). Sweep-and-prune has no cells (it sorts boxes along an
    /// axis; the kDrawAabbs boxes are its whole input), so nothing is drawn for the moving bodies then, and
    /// Profile::broadPhase says which ran. In both cases the static BVH's top node boxes, down to
    /// DebugDrawOptions::broadphaseTreeDepth levels below the root.
    kDrawBroadphaseCells = 1u << 6,
    /// Each unbroken joint: its two world anchors (points) and the line between them, coloured by joint type; a
    /// hinge adds its axis through anchor A and, with its limit on, the limit arc about the axis and a spoke at the
    /// current hinge angle.
    kDrawJoints = 1u << 7,
    kDrawDefault = kDrawShapes | kDrawMeshTriangles | kDrawContacts | kDrawSleeping,
};

struct DebugDrawColors {
    DebugColor staticBody{150, 150, 150};
    DebugColor kinematicBody{90, 140, 255};
    DebugColor dynamicBody{255, 170, 60};
    DebugColor asleep{130, 90, 200};
    DebugColor frozen{255, 0, 0};
    DebugColor aabb{60, 220, 90};
    DebugColor contactPoint{255, 255, 0};
    DebugColor contactNormal{255, 60, 60};
    /// Grid cells by level, finest first, repeating past the last entry.
    std::array<DebugColor, 4> gridLevels{{{80, 200, 255}, {120, 255, 140}, {255, 220, 80}, {255, 110, 200}}};
    DebugColor staticBvhNode{200, 200, 255};
    DebugColor distanceJoint{255, 255, 255};
    DebugColor springJoint{60, 255, 200};
    DebugColor ballJoint{255, 140, 40};
    DebugColor hingeJoint{255, 80, 255};
};

struct DebugDrawOptions {
    std::uint32_t flags = kDrawDefault;
    /// When set, only bodies, triangles, broad-phase boxes and joints (the box of their two anchors) whose bounds
    /// overlap this box are drawn.
    std::optional<Vec3> regionMin, regionMax;
    /// Cap on mesh and heightfield triangles per call (big terrains are drawn partly rather than stall a frame).
    std::uint32_t maxTriangles = 50000;
    /// Cap on broad-phase boxes (grid cells and tree nodes) per call, so a world of 100k bodies cannot stall a frame.
    std::uint32_t maxBroadphaseBoxes = 20000;
    /// Levels of static BVH node boxes kDrawBroadphaseCells draws below the root (0: none; each level is up to 4x
    /// more).
    std::uint32_t broadphaseTreeDepth = 2;
    /// Cap on joints per call.
    std::uint32_t maxJoints = 20000;
    float jointSize = 0.3f;      ///< m, half length of a hinge's axis line and radius of its limit arc
    float normalLength = 0.25f;  ///< m, contact normals
    float pointSize = 0.05f;     ///< m, contact points
    DebugDrawColors colors;
};

/// Implement line(); the other calls have defaults made of lines and may be overridden (a renderer with instanced
/// boxes and spheres draws them as solids). Every call is in world space.
class DebugDraw {
public:
    virtual ~DebugDraw() = default;
    virtual void line(Vec3 a, Vec3 b, DebugColor color) = 0;
    /// Default: its three edges.
    virtual void triangle(Vec3 a, Vec3 b, Vec3 c, DebugColor color);
    /// Default: three short axis-aligned lines crossing at p, `size` long.
    virtual void point(Vec3 p, float size, DebugColor color);
    /// Default: the 12 edges.
    virtual void box(const Transform& pose, Vec3 halfExtents, DebugColor color);
    virtual void aabb(Vec3 min, Vec3 max, DebugColor color);
    /// Default: three great circles in the body's local planes.
    virtual void sphere(const Transform& pose, float radius, DebugColor color);
    /// Capsule along the pose's local y axis. Default: two cap circles, four side lines, two half circles per cap.
    virtual void capsule(const Transform& pose, float radius, float halfHeight, DebugColor color);
};

/// Lines in flat arrays, for a renderer to upload in one batch.
struct DebugLines {
    std::vector<Vec3> points;        ///< two per line
    std::vector<DebugColor> colors;  ///< one per line
    std::uint64_t step = 0;          ///< World::stepCount() of the world that was drawn
    std::size_t lineCount() const { return colors.size(); }
    /// Keeps the capacity, so a batch refilled every frame stops allocating.
    void clear() {
        points.clear();
        colors.clear();
    }
};

/// A DebugDraw that appends every call, as lines, to `lines`.
class DebugLineBatch : public DebugDraw {
public:
    DebugLines lines;
    void line(Vec3 a, Vec3 b, DebugColor color) override;
};

}  // namespace rubble
