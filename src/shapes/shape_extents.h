#pragma once
// Facts about a shape's extent: its box at a pose, how far it reaches from its centre of mass (what a turn can
// move), how far in its surface lies (what a body can travel before it could pass through something thin), and
// the per-shape numbers the bounds stage gathers.
#include "rubble/math.h"
#include "shapes/shape.h"

namespace rubble::detail {

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

/// Tight world box of a shape at a pose (for static bodies: meshes and hulls transform their vertices).
Aabb worldBounds(const Shape& shape, const Transform& pose);

}  // namespace rubble::detail
