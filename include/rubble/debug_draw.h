#pragma once
// Debug drawing: World::debugDraw describes what the world holds (shapes at their poses, boxes, contacts, sleeping
// state) through this small interface, which a viewer or a game implements with its own renderer.
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
    /// Colour bodies by island. Islands are not built yet: until they are, this flag draws nothing extra
    /// (see islandOf in src/debug_draw.cpp, the hook the islands stage fills).
    kDrawIslands = 1u << 5,
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
};

struct DebugDrawOptions {
    std::uint32_t flags = kDrawDefault;
    /// When set, only bodies whose bounds overlap this box, and only triangles whose bounds overlap it, are drawn.
    std::optional<Vec3> regionMin, regionMax;
    /// Cap on mesh and heightfield triangles per call (big terrains are drawn partly rather than stall a frame).
    std::uint32_t maxTriangles = 50000;
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
