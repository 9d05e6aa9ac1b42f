#pragma once
// Polytope narrow phase: hull-hull, box-hull, capsule-box and capsule-hull contact manifolds.
//
// Hull-hull (and box-hull, the box taken as an 8-vertex hull) follows Gregorius, "The Separating Axis Test between
// Convex Polyhedra" (GDC 2013): the face normals of A and of B, then the edge pairs. Of the edge pairs only those
// whose arcs on the Gauss map cross are tested -- exactly the pairs that make a face of the Minkowski difference;
// every other pair's cross product is dominated by a face axis. The best face axis gives the reference face; the
// incident face is, among the other hull's faces through its deepest vertex, the most anti-parallel one (the most
// anti-parallel face overall can lie beside the reference face on general hulls and clip to nothing). The incident
// polygon is clipped against the reference face's side planes (Sutherland-Hodgman, clip.h) and reduced to 4 points
// (deepest first, then the largest area). If nothing survives (deep, lopsided overlaps where hysteresis kept a face
// axis) the deepest incident vertex is the one point. An edge pair that wins gives one point at the closest points
// of the two edges.
//
// Pair order: A is the first argument. For capsule-box that is the capsule (normal from the capsule to the box),
// the reverse of ShapeKind order (Box < Capsule): a caller that wants the box as A negates the normal and moves
// the points by normal * depth onto the capsule.
//
// Robustness choices, as in box_box.h (and why):
// - Everything is computed in A's local frame relative to A's centre: only the centre difference is taken in world
//   space, so contacts 10 km from the origin keep full precision; only the final positions round.
// - Edge pairs closer to parallel than kBoxEdgeParallelEpsilon (sine) are skipped (face axes cover them).
// - Axis choice has hysteresis: A's faces, then B's faces only if clearly better, then edges only if clearly better
//   than the chosen face (kBoxAxisRelativeTolerance * |separation| + kBoxAxisAbsoluteTolerance * size, size =
//   the larger hull's largest vertex distance from its centroid). A resting hull keeps its reference face.
//
// Capsules (segment core + radius) against a box or hull: first the exact distance between the cores. For a hull
// that is GJK (gjk.h). For a box it is closed form: the squared distance of the segment point s(t) from the box is a
// convex, continuously differentiable, piecewise quadratic function of t (a piece between each two crossings of a face
// plane), so its minimum is found by walking the at most six crossings to where the slope changes sign and solving
// one linear equation there; a face axis beyond the margin exits early. (Measured on one core, random pairs: 1.9 M/s
// with GJK, 9.0 M/s with the earlier best-of-candidate-axes form -- box faces, segment x box axes, vertex and end
// point directions, about 20 square roots -- 17 M/s closed form.) When the cores are apart (the
// common case: a resting capsule touches with its radius only) the direction of the closest points is the manifold
// normal. If it lies
// within kCapsuleFaceAlignCos of a face normal of the polytope, the segment is clipped against that face's side
// planes and each surviving end whose depth (from the face plane) is within the margin becomes a point (a capsule
// lying flat gives 2 points, standing on end 1) -- unless the clipped ends are shallower than the exact depth
// (the capsule hangs over the face's boundary), when the single closest point is the contact, as it is when no
// face is aligned. When the cores overlap (deep penetration) there is no distance, and a SAT over the polytope's
// face normals and the cross products of the segment with the Gauss-map-admissible polytope edges (the edge's arc
// must cross the great circle orthogonal to the segment) decides, with the hysteresis above: a face axis clips the
// segment as above, an edge axis gives one point at the closest points of segment and edge.
//
// Feature ids (ContactPoint::feature), 32 bits:
//   bits 30-31  kind: 0 = face contact with reference face on A, 1 = reference face on B, 2 = edge-edge (or, for
//               capsules, the single closest point), 3 = hulls apart whose clipped or edge contact misstated their
//               distance: one point at their closest points (closest_points_contact.h), bits 15-29 A's vertex
//               nearest it, bits 0-14 B's
//   hull-hull face contacts: bits 22-29 reference face (mod 256), bits 16-21 incident face (mod 64), bits 0-15 the
//               point on the incident face: the face-local vertex index (bit 15 clear) or clipPointId(label, plane)
//               from clip.h, where label is the incident edge (starting at that face-local vertex) or
//               sidePlaneLabel(p), and plane p is the reference face's side starting at its face-local vertex p;
//               0x7FFF for a lone deepest vertex off the incident face (not expected from valid hulls).
//   hull-hull edge-edge: bits 15-29 edge of A, bits 0-14 edge of B (indices into ConvexHull::edges / 2).
//   capsule face contacts (kind 1, the polytope is B): bits 8-15 face, bits 0-7 the end: 0 (centre - halfAxis) or
//               1 (centre + halfAxis), plus 0x40 | (side plane << 1) when a side plane of the face cut the end.
//   capsule edge or closest point (kind 2): bits 2-17 polytope vertex nearest the point, bits 0-1 the segment feature
//               (0 interior, 1 end at centre - halfAxis, 2 end at centre + halfAxis).
// Box faces (box-hull, capsule-box) are numbered as in box_box.h: 2 * axis + (1 if the normal is -axis).
// Every part derives from shape-local indices only, so ids survive small motions of a resting pose.
#include <cstdint>
#include <vector>

#include "narrowphase/convex_pairs.h"
#include "narrowphase/manifold.h"
#include "rubble/math.h"

namespace rubble::detail {

struct ConvexHull;

/// A capsule is treated as lying on a polytope face when the closest-point direction is within this cosine of the face
/// normal (about 1.1 degrees).
inline constexpr float kCapsuleFaceAlignCos = 0.9998f;

/// An edge of a hull with its two faces: face0 holds the directed edge v0 -> v1 (counter-clockwise from outside),
/// face1 holds v1 -> v0.
struct HullEdge {
    std::uint32_t v0 = 0, v1 = 0, face0 = 0, face1 = 0;
};

/// Per-hull data the SAT needs beyond ConvexHull: edge-face adjacency (in ConvexHull::edges order), an interior
/// point (vertex centroid) and the largest vertex distance from it. Build once per hull and pass it to the
/// overloads below; the overloads without it rebuild it per call in thread-local scratch.
struct HullAdjacency {
    std::vector<HullEdge> edges;
    Vec3 interior;
    float size = 0;
    /// Per edge, in SoA rows padded with zeros to a multiple of kHullArcPadding: the normals of its faces (face0
    /// `a`, face1 `b`) and their cross product b x a, the edge's arc on the Gauss map. Rows: ax ay az bx by bz cx cy
    /// cz. The SAT's edge-pair test reads them for the hull on side A, several edges at a time in SIMD lanes.
    std::vector<float> arcs[9];
    /// The face normals in SoA rows x y z, padded like the arcs: the SAT's face tests take several faces at a time.
    std::vector<float> normalRows[3];
    /// The radius of a ball around `interior` that lies inside the hull (the nearest face plane's distance). Along
    /// a unit axis n two hulls are apart by at most n . (interiorB - interiorA) - inradiusA - inradiusB, so only axes
    /// near the line between the interiors can separate them by much: the SAT tests only the faces and edges whose
    /// axes can reach that cone (zero tests them all).
    float inradius = 0;
    /// Per edge, a cone around its arc on the Gauss map: the unit midpoint of its two face normals (rows x y z) and
    /// the cosine and sine of half the angle between them (rows 3 and 4), in SoA rows padded like the arcs.
    std::vector<float> arcCones[5];
    /// The faces around each vertex, ascending: vertex v's are vertexFaces[vertexFaceStart[v] .. [v + 1]).
    std::vector<std::uint32_t> vertexFaceStart, vertexFaces;
};
/// The face scans first test only the faces that can be apart by more than this fraction of the larger hull's size
/// in overlap (HullAdjacency::inradius), and all faces when the pair overlaps more.
inline constexpr float kFaceConeDepth = 0.1f;
/// The widest SIMD batch of any build of the core (AVX-512, 16 floats): the arcs are padded for every level.
inline constexpr std::size_t kHullArcPadding = 16;
HullAdjacency buildHullAdjacency(const ConvexHull& hull);

/// The SAT axis that decided a pair's last result: the axis that separated it by more than the margin, or the
/// contact's reference face or edge pair. Given back on the pair's next call:
/// - a separating axis is tested before the whole search: if it still separates, the pair is done for the cost of
///   one axis. Every axis it can name is one the whole search tests too, with the same arithmetic, so the answer is
///   the same with or without it; only the time differs.
/// - a contact feature, with a featureDrift above zero, makes the contact again without the search while the
///   feature's separation stays within featureDrift of `separation` (what the search found); when it drifts the
///   search runs again. This one trades exactness for time: the search could have chosen another feature, deeper by
///   up to about the drift (HullPairs.FeatureReuseStaysCloseToTheSearch, HullPile.KeptContactFeaturesStandLikeThe
///   FullSearch). There is no cap on how long a feature is kept: searching again every few steps made resting
///   bodies jitter (the search would take a neighbouring feature and the contact jumped). With featureDrift zero the
///   answer is the search's, bit for bit.
/// A hint for other hulls (indices out of range) is ignored.
struct SatHint {
    enum Kind : std::uint8_t { kNone, kFaceA, kFaceB, kEdges };
    Kind kind = kNone;
    bool separated = false;      ///< the axis separated the pair (else it made the contact)
    std::uint8_t reuses = 0;     ///< contacts made from this feature since the search found it (up to 255)
    std::uint16_t a = 0, b = 0;  ///< face of A or of B (in `a`), or edge of A and edge of B
    float separation = 0;        ///< a contact feature's separation when the search found it
};

/// Contact manifold of hull A and hull B (posed by poseA / poseB). Returns false with out.pointCount = 0 when the
/// hulls are farther apart than `margin` along some axis. Otherwise: normal A -> B, 1 to 4 points on B's surface
/// with depth >= -margin, feature ids as above. `hint`, when given, is read and rewritten (SatHint, which also says
/// what featureDrift does).
bool collideHulls(const ConvexHull& a, const Transform& poseA, const ConvexHull& b, const Transform& poseB,
                  float margin, Manifold& out);
bool collideHulls(const ConvexHull& a, const HullAdjacency& adjA, const Transform& poseA, const ConvexHull& b,
                  const HullAdjacency& adjB, const Transform& poseB, float margin, Manifold& out,
                  SatHint* hint = nullptr, float featureDrift = 0);

/// Box A (half extents `half`) against hull B: the box as an 8-vertex hull built from a static unit cube.
bool collideBoxHull(const Transform& box, Vec3 half, const ConvexHull& hull, const Transform& poseHull, float margin,
                    Manifold& out);
bool collideBoxHull(const Transform& box, Vec3 half, const ConvexHull& hull, const HullAdjacency& adj,
                    const Transform& poseHull, float margin, Manifold& out, SatHint* hint = nullptr,
                    float featureDrift = 0);

/// Capsule A against box B. Normal from the capsule to the box; points on the box surface; 1 or 2 points.
bool collideCapsuleBox(const CapsuleSegment& capsule, const Transform& box, Vec3 half, float margin, Manifold& out);

/// Capsule A against hull B. Normal from the capsule to the hull; points on the hull surface; 1 or 2 points.
bool collideCapsuleHull(const CapsuleSegment& capsule, const ConvexHull& hull, const Transform& poseHull, float margin,
                        Manifold& out);
bool collideCapsuleHull(const CapsuleSegment& capsule, const ConvexHull& hull, const HullAdjacency& adj,
                        const Transform& poseHull, float margin, Manifold& out);

}  // namespace rubble::detail
