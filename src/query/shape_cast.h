#pragma once
// Swept shapes and overlap tests between one pair of convex shapes, or a convex shape and one triangle.
//
// Convex against convex: conservative advancement on GJK distance (narrowphase/gjk.h). For a pure translation the
// distance between two convex shapes is a convex function of the travel t whose slope is -dot(normal, dir), so
// t + distance / dot(normal, dir) never passes the time of impact; for flat contacts it lands on it in one step and
// near curved ones it converges like Newton's method from the safe side. Spheres against spheres, capsules and
// triangles are closed forms (ray against the Minkowski sum).
#include <cstdint>

#include "narrowphase/gjk.h"
#include "rubble/math.h"

namespace rubble::detail {

/// Gap at which a sweep counts as touching, m. GJK runs in double, but a float pose far along the sweep cannot
/// place a shape closer than about 1e-5 m; a tenth of a millimetre is well below anything a game can see.
inline constexpr float kSweepTolerance = 1e-4f;

/// Where a swept shape first touches another: travel t, the contact point on the other shape and its unit normal,
/// pointing back at the swept shape.
struct SweepHit {
    float t = 0;
    Vec3 point;
    Vec3 normal;
};

enum class SweepResult : std::uint8_t { Miss, Hit, StartsInside };

/// Sweeps `moving` from its pose along unit `dir` up to `maxT` against `target` (sphere, box, capsule or hull cores).
/// StartsInside when they already overlap (within the tolerance, hit.t = 0, hit left for the caller). A sweep still
/// approaching after its advances run out is a Hit where it stands: short of the contact, never past it.
SweepResult sweepConvex(const GjkShape& moving, Vec3 dir, float maxT, const GjkShape& target, SweepHit& hit);

/// Sphere against triangle (a, b, c), closed form: the triangle's face offset by the radius, its edges as capsules and
/// its vertices as spheres. Triangles facing away from the sweep (dot(normal, dir) >= 0) are skipped unless
/// `backFaces`; zero-area triangles always.
SweepResult sweepSphereTriangle(Vec3 center, float radius, Vec3 dir, float maxT, Vec3 a, Vec3 b, Vec3 c, bool backFaces,
                                SweepHit& hit);

/// A GJK view of a triangle posed by `pose`; it points at `vertices`, which must outlive it.
GjkShape gjkTriangle(const Vec3 (&vertices)[3], const Transform& pose);

/// Closest point of triangle (a, b, c) to p (Voronoi regions; degenerate triangles give a point of an edge).
Vec3 closestPointOnTriangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

/// True when the shapes touch or overlap (GJK distance not positive).
bool overlapConvex(const GjkShape& a, const GjkShape& b);

}  // namespace rubble::detail
