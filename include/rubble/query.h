#pragma once
// Scene queries of a World: rays (closest hit or every hit), swept spheres and shapes, and overlap tests, answered
// against the bodies' current poses through the broad phase's structures. The World members that run them are in
// include/rubble/world.h ("Queries").
#include <cstdint>
#include <functional>

#include "rubble/id.h"
#include "rubble/math.h"

namespace rubble {

/// RayHit::triangle and ::child of a hit on a body that has no triangles or children.
inline constexpr std::uint32_t kNoIndex = ~0u;

/// Which bodies a query sees, and how it treats triangles and start points inside shapes.
/// A body is seen when its category is in `mask` and `category` is in the body's mask (CollisionFilter's rule
/// between two bodies, so a body whose mask is 0 is invisible to queries), its type is included, it is not
/// `ignore`, and `accept` (when set) returns true.
struct QueryFilter {
    std::uint32_t category = 0xFFFFFFFFu;  ///< the query's own category bits
    std::uint32_t mask = 0xFFFFFFFFu;      ///< categories of bodies the query sees
    bool includeStatic = true;
    bool includeKinematic = true;
    bool includeDynamic = true;
    bool includeSensors = false;  ///< sensors (BodyDef::sensor) are not obstacles: queries skip them by default
    BodyId ignore;                ///< a body to skip (the shooter, the character itself); null for none
    /// Last test, for bodies that passed the others and whose bounding box the query reaches; false skips the body.
    /// Runs on the querying thread, in no particular order, possibly more than once per body.
    std::function<bool(BodyId)> accept;
    /// Triangles of meshes and heightfields are one-sided: rays and casts hit them from the front (counter-clockwise)
    /// side only, so a ray from under a terrain passes up through it. True hits back faces too.
    bool hitBackFaces = false;
    /// Solid shapes (all but meshes and heightfields) are solid: a ray that starts inside one, or a cast shape that
    /// starts overlapping one (or a triangle), hits it at distance 0 with normal = -direction and point = the start.
    /// False skips such shapes instead (a ray that starts inside a box then does not hit that box at all).
    bool hitFromInside = true;
};

/// Where a ray enters a body's surface.
struct RayHit {
    BodyId body;
    Vec3 point;          ///< world point on the surface
    Vec3 normal;         ///< unit surface normal at `point`, facing the ray (dot(normal, direction) <= 0)
    float distance = 0;  ///< from the origin along the unit direction, m
    /// Triangle of a mesh (TriangleMeshDef order) or heightfield: the cell at row r, column c is split along its
    /// (x0, z0)-(x1, z1) diagonal into triangles 2 (r (columns - 1) + c) and that + 1. kNoIndex for other shapes.
    std::uint32_t triangle = kNoIndex;
    std::uint32_t child = kNoIndex;  ///< child of a compound (CompoundDef::children order), else kNoIndex
};

/// Where a swept sphere or shape first touches a body.
struct ShapeCastHit {
    BodyId body;
    Vec3 point;          ///< contact point on the hit body's surface at the time of impact, world
    Vec3 normal;         ///< unit normal of the hit body's surface there, pointing back at the cast shape
    float distance = 0;  ///< how far the shape travelled along the unit direction before touching, m
    std::uint32_t triangle = kNoIndex;   ///< as RayHit::triangle, on the hit body
    std::uint32_t child = kNoIndex;      ///< compound child of the hit body, as RayHit::child
    std::uint32_t castChild = kNoIndex;  ///< child of a compound cast shape that touched, else kNoIndex
};

}  // namespace rubble
