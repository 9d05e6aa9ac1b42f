#pragma once
// GJK distance between two convex shapes given by support functions (Gilbert, Johnson, Keerthi 1988; termination
// and robustness after van den Bergen, "Collision Detection in Interactive 3D Environments", and Ericson, "Real-Time
// Collision Detection" 9.5). Shapes are a core (point, segment, box or point cloud) swept by a radius, so spheres
// and capsules are exact (a point or a segment plus radius) and the radius is added outside the iteration.
//
// Scope: distance, closest points and separating direction for shapes whose cores do not overlap. When the cores
// overlap the result says so (GjkStatus::CoresOverlap) without a depth: EPA is not implemented; the narrow phase
// uses SAT or the closed-form kernels (convex_pairs.h) for penetrating pairs.
#include <cstdint>

#include "rubble/math.h"

namespace rubble::detail {

struct Shape;

/// A convex shape for GJK: core (in the local frame) swept by `radius`, placed by `pose`.
struct GjkShape {
    enum class Core : std::uint8_t { Point, Segment, Box, Points };
    Core core = Core::Point;
    float radius = 0;              ///< sphere / capsule radius (0 for boxes and hulls)
    float halfHeight = 0;          ///< Segment: from (0, -halfHeight, 0) to (0, halfHeight, 0)
    Vec3 halfExtents;              ///< Box
    const Vec3* points = nullptr;  ///< Points: hull vertices in the local frame (not owned)
    std::uint32_t pointCount = 0;
    Transform pose;
};

/// GJK view of a sphere, box, capsule or convex hull (the hull's vertices are referenced, not copied).
/// Other kinds give a Point core with zero radius.
GjkShape gjkShapeOf(const Shape& shape, const Transform& pose);

enum class GjkStatus : std::uint8_t {
    Separated,     ///< distance > 0: the shapes do not touch
    RadiiOverlap,  ///< the cores are apart but the swept radii overlap: distance < 0 is the exact penetration
    CoresOverlap,  ///< the cores intersect (or touch within tolerance): no depth, normal and points meaningless
};

struct GjkSettings {
    int maxIterations = 48;
    /// Stop when the lower bound on the core distance is within this fraction of the upper bound.
    float relativeTolerance = 1e-6f;
    /// Core distances below this (metres) count as overlap of the cores.
    float absoluteTolerance = 1e-6f;
    /// Optional warm start: the separating direction from A to B found last time (zero = start from the centres).
    Vec3 initialDirection;
};

struct GjkResult {
    GjkStatus status = GjkStatus::CoresOverlap;
    float distance = 0;   ///< between the swept shapes (core distance minus both radii); 0 for CoresOverlap
    Vec3 pointA, pointB;  ///< closest points on the surfaces of A and B (world space)
    Vec3 normal;          ///< unit, from A to B (reuse as initialDirection next step)
    int iterations = 0;
};

/// Distance between A and B. Works relative to A's position, so poses far from the origin keep their precision.
GjkResult gjkDistance(const GjkShape& a, const GjkShape& b, const GjkSettings& settings = {});

/// World-space support point of the core of `s` in direction `d` (no radius). Exposed for tests.
Vec3 gjkSupport(const GjkShape& s, Vec3 d);

}  // namespace rubble::detail
