#pragma once
// Early rejection of mesh triangles, many at a time in SIMD lanes: of the triangles a body's bounds overlap (about
// ten per body on a terrain), most lie out of its reach. Before the exact kernels of triangle_pairs.h run one triangle
// at a time, these tests take all of a body's triangles together and mark the ones that surely get no contact:
//   sphere and capsule: the exact distance of the core (centre, segment) from the triangle exceeds radius + margin
//     (the closest-point computations of the exact kernels -- point against the triangle's Voronoi regions, segment
//     against the edges, the segment's crossing of the plane -- in lanes, every branch computed and selected);
// A box needs no such test: most of the triangles it reaches touch it, and the box kernel's whole SAT runs in lanes
// instead (boxTriangleAxes, triangle_pairs.h).
// Each test is a necessary condition for a contact that the exact kernel would report, with slack: a triangle is
// marked out only when it is beyond reach by more than 1e-3 of the reach plus 1e-5 of the
// coordinates' size, far above the rounding of either computation. So the kernels' results are unchanged by the
// filter; it only spares them triangles they would reject themselves. NaN or infinite inputs are never marked out
// (their comparisons fail), so the exact kernels still see and refuse them.
//
// Each test is written once over the lane type (simd/): the wide form runs the triangles in full SIMD batches, the
// *Scalar form is the same template instantiated for float (the reference for tests and benchmarks); both give the
// same answer bit for bit.
#include <cstddef>

#include "narrowphase/convex_pairs.h"
#include "narrowphase/triangle_pairs.h"
#include "rubble/math.h"

namespace rubble::detail {

/// inReach[i] = false when triangle i surely gets no contact with the sphere (centre, radius) within `margin`.
void sphereTrianglesInReach(Vec3 center, float radius, float margin, const TriangleLanes& tris, std::size_t n,
                            bool* inReach);
/// The same for a capsule.
void capsuleTrianglesInReach(const CapsuleSegment& capsule, float margin, const TriangleLanes& tris, std::size_t n,
                             bool* inReach);

/// The same tests one triangle at a time (reads and writes only n entries).
void sphereTrianglesInReachScalar(Vec3 center, float radius, float margin, const TriangleLanes& tris, std::size_t n,
                                  bool* inReach);
void capsuleTrianglesInReachScalar(const CapsuleSegment& capsule, float margin, const TriangleLanes& tris,
                                   std::size_t n, bool* inReach);

}  // namespace rubble::detail
