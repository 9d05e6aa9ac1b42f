#pragma once
// Contact kernels of a moving sphere, capsule, box or convex hull (body A) against one static triangle (body B) of a
// triangle mesh or heightfield. Each fills a Manifold like the other narrow-phase kernels: normal from A to B (from
// the body towards the triangle), points on the triangle's surface, depth > 0 penetrating, depth <= 0 speculative
// gap within `margin`, stable feature ids, at most 4 points. Triangles are two-sided: the face normal used is the one
// on the side of the body's centre (the front side, counter-clockwise winding, when the centre lies in the plane).
//
// Methods: sphere: closest point on the triangle (Voronoi regions of face, edges and vertices). Capsule: closest
// points of segment and triangle (endpoints against the face, segment against the three edges, segment through the
// face); a capsule lying along the face gets two points (the segment clipped to the triangle's prism).
// Box and hull: SAT over the triangle normal, the body's face normals and the body-edge x triangle-edge cross
// products, each edge axis only in the direction in which the triangle edge is the triangle's support towards the
// body, i.e. where the pair makes a face of the Minkowski difference (Gregorius, GDC 2013, as in hull_pairs.h: the
// triangle's Gauss map is the two points +-n joined, for each edge, by the half great circle through the edge's
// outward side direction; the hull's edges are pruned by the same arc test, a box edge supports every direction
// orthogonal to it). Other directions would still prove a separation, but their edge points are not the contact.
// Axis choice has hysteresis (box_box.h): the triangle face stays the reference unless a face of the body is clearly
// better, and an edge pair must be clearly better still (the box compares each axis with the best so far; the hull
// takes each family's best first, so that its choice does not depend on its face and edge order). The hull's centre
// is its vertex centroid (HullAdjacency::interior).
// Contacts: the body's incident face (the box face most aligned with the normal; for the hull, among the faces
// through its deepest vertex the most aligned one) clipped by the triangle's side planes when the triangle's face is
// the reference, the triangle clipped by the side planes of the body's reference face otherwise, one closest-point
// pair for an edge-edge axis; reduced to 4 points with reduceContactPoints (clip.h: deepest first, then the largest
// area). When clipping leaves nothing within the margin the deepest vertex alone is the contact (the body's, over
// its closest triangle point, or the triangle's), so a pair the SAT finds within the margin is never dropped. The
// hull's clipping planes are pushed out by 1e-6 of the size and its candidates within 1e-4 of the size of a deeper
// one are merged, so shared boundaries (a face coplanar with the triangle, an edge on a side plane) give their
// vertices once. Each point's depth is the gap along the normal at that point. Apart, where that misstates the
// distance (the closest features are not a face and what lies over it, or two edges meeting inside both: a box
// corner beside a triangle edge), the contact is one point at GJK's closest points instead, as the convex kernels do
// (closest_points_contact.h), unless the triangle's closest point lies on a feature the ghost rule below makes
// inactive; tests/narrowphase/speculative_contacts_test.cpp checks depth and normal against brute force.
// Precision: sphere and capsule work relative to the triangle's first vertex, box and hull in their own frame
// relative to their origin; only differences of nearby world points are taken, so bodies 10 km from the origin keep
// their depths.
//
// Ghost contacts ("active edges", the idea Jolt uses for mesh collision): a triangle edge is active when it is a
// boundary or convex (shapes/mesh_adjacency.h); flat and concave edges are inactive because the neighbouring
// triangle's face covers them. The rule, identical in all four kernels:
//   after the kernel has found its normal, take the triangle feature the contact lies on (the closest point's
//   Voronoi region for sphere and capsule; for box and hull, the triangle edge of an edge-edge axis, or for a face
//   axis of the body the triangle vertices within a tolerance of the deepest along the normal: 3 = face, 2 = edge,
//   1 = vertex). If that feature is an edge that is inactive, or a vertex whose two edges of this triangle are both
//   inactive, the normal is replaced by the triangle's face normal and the depths and points are recomputed along
//   it (the contact is kept, never dropped, so no neighbour has to be trusted to report it).
// A box, hull or sphere sliding across a flat tessellated floor therefore only ever sees the floor's normal, while a
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
//   box and hull: bits 30-31 kind: 0 = triangle face is the reference, 1 = the body's face is the reference,
//     2 = edge-edge, 3 = the closest points. Points of face contacts (bits 0-15) are named as clip.h names them: an
//     incident-polygon vertex by its index, a crossing by clipPointId(label, plane), label an incident edge
//     (starting at that vertex) or sidePlaneLabel(p) for a piece along side plane p.
//     kind 0: the body's incident face in bits 16-29 (box: 2 * axis + (1 if -axis); hull: face index mod 2^14),
//       the incident polygon is that face (box: the corners (+u +v), (-u +v), (-u -v), (+u -v), u, v the next
//       axes in cyclic order; hull: its vertices in ConvexHull order), side plane p is triangle edge p's;
//     kind 1: the body's reference face in bits 16-29 (numbered as above), the incident polygon is the triangle
//       (vertex i, edge i from vertex i to i + 1), side planes are the face's sides: box 0 +u, 1 -u, 2 +v, 3 -v;
//       hull p = the side starting at the face's p-th vertex;
//     kind 2: box: bits 8-15 box edge (4 * axis + (1 if on -u) + (2 if on -v)), bits 0-7 triangle edge; hull:
//       bits 2-29 hull edge (index into ConvexHull::edges / 2, mod 2^28), bits 0-1 triangle edge;
//     kind 3: bits 8-29 the body's vertex nearest its closest point (box corner (x > 0) + 2 (y > 0) + 4 (z > 0),
//       hull vertex index), bits 0-7 the triangle feature code of the triangle's closest point;
//     0x7FFF in bits 0-15 marks the lone deepest-vertex point when clipping kept nothing, unless it is a vertex of
//       the incident polygon (then its index).
#include <array>
#include <cstddef>
#include <cstdint>

#include "narrowphase/convex_pairs.h"
#include "narrowphase/manifold.h"
#include "rubble/math.h"

namespace rubble::detail {

struct ConvexHull;
struct HullAdjacency;

using TriangleVertices = std::array<Vec3, 3>;

/// Whether a feature id (above) depends on the triangle: anything but a vertex of the body's own incident face (box
/// and hull, kind 0) or a sphere's or capsule's code. Ids that do not stay the same as the body moves from one
/// triangle to the next of a flat floor, so warm starting can follow a box's corner across the floor.
inline bool featureOfTriangle(std::uint32_t feature) {
    const std::uint32_t kind = feature >> 30, point = feature & 0xFFFFu;
    return kind != 0 || (point & 0x8000u) != 0 || point == 0x7FFFu;
}

/// Box or hull edge x triangle edge axes whose cross product is shorter than this (sine of the angle) are skipped.
inline constexpr float kTriangleEdgeParallelEpsilon = 1e-3f;
/// A capsule gets two points on a face when the sine of the angle between its axis and the face is below this.
inline constexpr float kCapsuleFaceParallelSine = 0.05f;

/// Sphere A (centre, radius) against triangle B. `activeEdges`: bit e set when edge e (vertex e to e + 1) is active
/// (kAllEdgesActive for a lone triangle). Returns 0 or 1. A centre exactly on the triangle takes the face normal.
int collideSphereTriangle(Vec3 center, float radius, const TriangleVertices& tri, std::uint8_t activeEdges,
                          float margin, Manifold& out);

/// Capsule A against triangle B. Returns 0, 1 or 2. `inReach`: the caller has found the triangle within the
/// capsule's reach (capsuleTrianglesInReach, triangle_reach.h); the kernel then skips its quick rejections, which
/// never change its result.
int collideCapsuleTriangle(const CapsuleSegment& capsule, const TriangleVertices& tri, std::uint8_t activeEdges,
                           float margin, Manifold& out, bool inReach = false);

/// Box A (pose, half extents) against triangle B. Returns 0 to 4.
int collideBoxTriangle(const Transform& boxPose, Vec3 halfExtents, const TriangleVertices& tri,
                       std::uint8_t activeEdges, float margin, Manifold& out);

/// A box posed once for all the triangles it meets: its rotation as matrices both ways (the kernel moves each
/// triangle into the box frame and the contacts back).
struct TriangleBox {
    Transform pose;
    Mat3 toWorld;  ///< columns: the box axes in the world
    Mat3 toBox;    ///< transpose of toWorld
    Vec3 halfExtents;
};
TriangleBox triangleBox(const Transform& pose, Vec3 halfExtents);
/// The rotation of a unit quaternion as a matrix (columns: the rotated axes).
Mat3 rotationMatrix(Quat q);
/// The same kernel for a box made by triangleBox.
int collideBoxTriangle(const TriangleBox& box, const TriangleVertices& tri, std::uint8_t activeEdges, float margin,
                       Manifold& out);

/// Triangles in SoA form: vertex k of triangle i is (x[k][i], y[k][i], z[k][i]). Functions that take them in SIMD
/// lanes read and write whole batches: every array must hold triangleLanesPadded(n) readable entries (the padding any
/// finite values), and so must their outputs.
struct TriangleLanes {
    const float* x[3];
    const float* y[3];
    const float* z[3];
};
/// n rounded up to whole SIMD batches.
std::size_t triangleLanesPadded(std::size_t n);

/// What the SAT of the box kernel chose for a triangle: kind -1 when there is no contact (some axis separates by
/// more than the margin, or the triangle is degenerate or not finite), else 0 the triangle's face, 1 the box face
/// along boxAxis, 2 box axis boxAxis x triangle edge triEdge; n the unit axis in the box's frame, from the box
/// towards the triangle, before the ghost rule.
struct BoxTriangleAxis {
    int kind = -1;
    int boxAxis = 0;
    int triEdge = 0;
    Vec3 n;
};
/// The box kernel's SAT for triangles [0, n) in SIMD lanes (one template with the kernel's own, so the choices are
/// the same; tests/narrowphase/triangle_reach_test.cpp checks that the manifolds are too, bit for bit); `out` holds
/// triangleLanesPadded(n) entries.
void boxTriangleAxes(const TriangleBox& box, float margin, const TriangleLanes& tris, std::size_t n,
                     BoxTriangleAxis* out);
/// The same one triangle at a time (n entries).
void boxTriangleAxesScalar(const TriangleBox& box, float margin, const TriangleLanes& tris, std::size_t n,
                           BoxTriangleAxis* out);
/// The box kernel after its SAT, given the SAT's answer (from boxTriangleAxes): the same manifold as the kernel.
int collideBoxTriangle(const TriangleBox& box, const TriangleVertices& tri, std::uint8_t activeEdges, float margin,
                       const BoxTriangleAxis& axis, Manifold& out);

/// Hull A (posed by `hullPose`, with its adjacency from buildHullAdjacency in hull_pairs.h) against triangle B.
/// Returns 0 to 4.
int collideHullTriangle(const ConvexHull& hull, const HullAdjacency& adjacency, const Transform& hullPose,
                        const TriangleVertices& tri, std::uint8_t activeEdges, float margin, Manifold& out);

}  // namespace rubble::detail
