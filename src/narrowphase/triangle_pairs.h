#pragma once
// Contact kernels of a moving sphere, capsule or box (body A) against one static triangle (body B) of a triangle
// mesh or heightfield. Each fills a Manifold like the other narrow-phase kernels: normal from A to B (from the body
// towards the triangle), points on the triangle's surface, depth > 0 penetrating, depth <= 0 speculative gap within
// `margin`, stable feature ids, at most 4 points. Triangles are two-sided: the face normal used is the one on the
// side of the body's centre (the front side, counter-clockwise winding, when the centre lies in the plane).
//
// Methods: sphere: closest point on the triangle (Voronoi regions of face, edges and vertices). Capsule: closest
// points of segment and triangle (endpoints against the face, segment against the three edges, segment through the
// face); a capsule lying along the face gets two points (the segment clipped to the triangle's prism). Box: SAT over
// the triangle normal, the 3 box faces and the 9 box-edge x triangle-edge cross products, then clipping: the box's
// incident face against the triangle's side planes when the triangle's face is the reference, the triangle against
// the box's reference face otherwise, one closest-point pair for an edge-edge axis; reduced to 4 points.
// Precision: sphere and capsule work relative to the triangle's first vertex, the box in its own frame relative to
// its centre; only differences of nearby world points are taken, so bodies 10 km from the origin keep their depths.
//
// Ghost contacts ("active edges", the idea Jolt uses for mesh collision): a triangle edge is active when it is a
// boundary or convex (shapes/mesh_adjacency.h); flat and concave edges are inactive because the neighbouring
// triangle's face covers them. The rule, identical in all three kernels:
//   after the kernel has found its normal, take the triangle feature the contact lies on (the closest point's
//   Voronoi region for sphere and capsule; for the box, the triangle vertices within a tolerance of the deepest
//   along the normal: 3 = face, 2 = edge, 1 = vertex). If that feature is an edge that is inactive, or a vertex
//   whose two edges of this triangle are both inactive, the normal is replaced by the triangle's face normal and
//   the depths and points are recomputed along it (the contact is kept, never dropped, so no neighbour has to be
//   trusted to report it).
// A box or sphere sliding across a flat tessellated floor therefore only ever sees the floor's normal, while a
// real ridge (convex) or the mesh border still rounds off correctly.
//
// Zero-area (and nearly zero-area, sine below about 1e-5) triangles return 0 without touching any division.
//
// Feature ids (ContactPoint::feature):
//   triangle feature codes: 0 face, 1 + e edge e, 4 + v vertex v.
//   sphere: the triangle feature code of the closest point.
//   capsule, one point: segment code * 8 + triangle code, segment code 0 interior, 1 end at center - halfAxis,
//     2 end at center + halfAxis; two points: 0x100 | end << 4 | clip, end 0 (towards center - halfAxis) or 1,
//     clip 0 when the capsule's own end point is used, 1 + e when the segment was cut by edge e's side plane.
//   box: bits 30-31 kind: 0 = triangle face is the reference, 1 = box face is the reference, 2 = edge-edge;
//     kind 0: bits 8-10 the box's incident face (2 * axis + (1 if -axis)), bits 0-7 the point: 0..3 an incident-face
//       vertex, 0x20 | seg << 2 | p where segment seg (0..3 incident edge, 4..6 the side plane of triangle edge
//       seg - 4) crosses the side plane of triangle edge p;
//     kind 1: bits 8-10 the box's reference face, bits 0-7: 0..2 a triangle vertex, 0x20 | seg << 2 | p with seg
//       0..2 a triangle edge, 3..6 the box face's side plane seg - 3 (0 +u, 1 -u, 2 +v, 3 -v), p a side plane;
//     kind 2: bits 8-15 box edge (4 * axis + (1 if on -u) + (2 if on -v)), bits 0-7 triangle edge.
#include <array>
#include <cstdint>

#include "narrowphase/convex_pairs.h"
#include "narrowphase/manifold.h"
#include "rubble/math.h"

namespace rubble::detail {

using TriangleVertices = std::array<Vec3, 3>;

/// Box edge x triangle edge axes whose cross product is shorter than this (sine of the angle) are skipped.
inline constexpr float kTriangleEdgeParallelEpsilon = 1e-3f;
/// A capsule gets two points on a face when the sine of the angle between its axis and the face is below this.
inline constexpr float kCapsuleFaceParallelSine = 0.05f;

/// Sphere A (centre, radius) against triangle B. `activeEdges`: bit e set when edge e (vertex e to e + 1) is active
/// (kAllEdgesActive for a lone triangle). Returns 0 or 1. A centre exactly on the triangle takes the face normal.
int collideSphereTriangle(Vec3 center, float radius, const TriangleVertices& tri, std::uint8_t activeEdges,
                          float margin, Manifold& out);

/// Capsule A against triangle B. Returns 0, 1 or 2.
int collideCapsuleTriangle(const CapsuleSegment& capsule, const TriangleVertices& tri, std::uint8_t activeEdges,
                           float margin, Manifold& out);

/// Box A (pose, half extents) against triangle B. Returns 0 to 4.
int collideBoxTriangle(const Transform& boxPose, Vec3 halfExtents, const TriangleVertices& tri,
                       std::uint8_t activeEdges, float margin, Manifold& out);

}  // namespace rubble::detail
