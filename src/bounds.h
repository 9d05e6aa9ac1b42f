#pragma once
// Update-bounds stage: the world AABB of every moving body, enlarged by its motion over the coming step (linear and
// rotational) and a contact margin, so that the broad phase finds pairs before they touch (speculative contacts).
#include <cstdint>
#include <vector>

#include "body_storage.h"
#include "broadphase/broadphase.h"
#include "rubble/math.h"
#include "shapes/shape.h"

namespace rubble::detail {

class TaskPool;

/// What the bounds kernel needs of a shape, relative to the centre of mass of a body using it: the centre and
/// half extents of the local box, and the radius of a sphere about that centre containing the shape. A rotated
/// box's world extent is the smaller of |R| halfExtents and the radius on each axis: both bound the shape, and
/// the radius makes spheres exact at any orientation.
struct ShapeBoundsInfo {
    float centerX = 0, centerY = 0, centerZ = 0;
    float halfX = 0, halfY = 0, halfZ = 0;
    float radius = 0;
    float reach = 0;  ///< rotationReach of the shape
    float inner = 0;  ///< innerExtent of the shape
};

/// Bounds data of a shape (static-only shapes get their local box; they never move).
ShapeBoundsInfo shapeBoundsInfo(const Shape& shape);

/// How far a rotation about the centre of mass can move the shape's surface per radian: the largest distance from
/// the centre of mass to the shape's core (the shape less its rounding), so 0 for a sphere, which turns in place,
/// and the half height (plus any centre offset) for a capsule. A bound, O(1) for every kind: boxes of hulls and
/// compounds stand in for their points. 0 for static-only shapes.
float rotationReach(const Shape& shape);

/// Smallest distance from the centre of mass to the shape's surface (a bound from below): how far the shape can move
/// before it could have passed wholly through something thin. 0 for static-only shapes.
float innerExtent(const Shape& shape);

/// Per-shape tables in SoA form, indexed by shape slot, for SIMD gathers.
struct ShapeBoundsTable {
    std::vector<float> centerX, centerY, centerZ, halfX, halfY, halfZ, radius, reach, inner;
    void set(std::uint32_t shape, const ShapeBoundsInfo& info);
};

struct BoundsParams {
    /// The step the boxes must cover: each box is swept by velocity * dt and grown by how far the angular velocity
    /// can turn the shape in dt (|w| dt times its reach, at most twice the reach).
    float dt = 1.0f / 60.0f;
    float margin = 0.0f;  ///< added on every side
};

/// Writes the world boxes of all moving bodies into `out` (resized to the body count).
void updateBounds(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                  TaskPool& pool, Bounds& out);
/// The same, one body at a time, as the reference for the SIMD path.
void updateBoundsScalar(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                        Bounds& out);

/// Tight world box of a shape at a pose (for static bodies: meshes and hulls transform their vertices).
Aabb worldBounds(const Shape& shape, const Transform& pose);

}  // namespace rubble::detail
