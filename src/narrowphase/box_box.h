#pragma once
// Box-box narrow phase: separating-axis test over the 15 axes, then reference-face clipping reduced to at most 4
// points, or a single point for an edge-edge contact. Allocation-free. The axis tests and the face clipping are
// written once over a lane type: the batched form runs them for 16 pairs at a time in SIMD lanes (the stage's
// box-box bucket goes through it), the per-pair form runs the same code on one pair, so both agree bit for bit.
// Clipping: the incident face is a parallelogram and the reference face's side planes bound a rectangle, so the
// clipped polygon's vertices are among 24 fixed candidates -- the 4 incident vertices, the 16 crossings of an
// incident edge with a side plane, the 4 reference-face corners -- each kept where it lies inside every side plane
// (a corner: inside the incident face) and within the margin below the reference face. Fixed slots need no
// compaction, which is what lets 16 pairs clip in lanes; the points are what Sutherland-Hodgman would give, in slot
// order, and more than 4 are reduced as clip.h's chooseFourPoints does (deepest, farthest, largest area).
//
// Robustness choices (and why):
// - All work happens in the reference box's frame relative to its centre: only the centre difference of the two
//   bodies is taken in world space (exact for nearby bodies even 10 km from the origin), so depths and normals
//   keep full precision far from the origin; only the final world positions round to the world's float spacing.
// - Edge-edge axes whose cross product is shorter than kBoxEdgeParallelEpsilon (the sine of the angle between the
//   edges) are skipped: their direction would be mostly rounding noise. The face axes cover parallel edges exactly
//   (in the plane across the edges the problem is 2D, where the face normals of both boxes suffice), and for edges
//   within that angle of parallel they are off by at most about epsilon times the edge length.
// - Axis choice is biased for temporal coherence: face axes of A win unless a face axis of B is clearly better,
//   and a face axis wins unless an edge axis is clearly better ("clearly": separation larger by
//   kBoxAxisRelativeTolerance * |separation| + kBoxAxisAbsoluteTolerance * size). A resting box therefore keeps
//   its reference face, and with it its feature ids, step after step.
//
// Feature ids (ContactPoint::feature), 32 bits:
//   bits 30-31  kind: 0 = face contact with reference face on A, 1 = reference face on B, 2 = edge-edge contact,
//               3 = boxes apart whose clipped contact misstated their distance: one point at their closest points
//               (closest_points_contact.h), bits 8-15 A's corner nearest it, bits 0-7 B's (bit 0 +x, 1 +y, 2 +z)
//   face contacts (kind 0 or 1):
//     bits 16-18  reference face, bits 8-10 incident face; a face is 2 * axis + (1 if its normal is -axis)
//     bits 0-7    the point on the incident face:
//                   0..3                  an incident-face vertex, in the face's cyclic order
//                   0x20 | seg << 2 | p   where segment `seg` crosses side plane `p` of the reference face;
//                                         seg 0..3 is the incident edge from vertex seg to seg+1, seg 4..7 is a
//                                         piece of the reference face's side plane seg-4 (so a reference-face
//                                         corner is 0x20 | (4 + p1) << 2 | p2). Side planes p: 0 = +u, 1 = -u,
//                                         2 = +v, 3 = -v, where u, v are the two axes after the reference axis
//                                         in cyclic order (x -> y, z; y -> z, x; z -> x, y).
//   edge-edge contacts (kind 2):
//     bits 8-15   edge of A, bits 0-7 edge of B; an edge is 4 * axis + (1 if it lies on the -u side) + (2 if on
//                 the -v side), with u, v as above for the edge's axis.
// Every part derives from box-local indices and signs only, so ids survive small motions of a resting pose.
#include <cstddef>
#include <cstdint>

#include "narrowphase/manifold.h"
#include "rubble/math.h"

namespace rubble::detail {

/// Edge-edge axes from edges closer to parallel than this (sine of the angle) are skipped.
inline constexpr float kBoxEdgeParallelEpsilon = 1e-3f;
/// Hysteresis for axis choice: a later candidate must beat the current one by this fraction of |separation| ...
inline constexpr float kBoxAxisRelativeTolerance = 0.05f;
/// ... plus this fraction of the larger box's largest half extent.
inline constexpr float kBoxAxisAbsoluteTolerance = 1e-4f;

inline constexpr std::uint32_t kBoxFeatureKindShift = 30;
inline constexpr std::uint32_t kBoxFeatureFaceA = 0u;
inline constexpr std::uint32_t kBoxFeatureFaceB = 1u;
inline constexpr std::uint32_t kBoxFeatureEdgeEdge = 2u;

/// Contact manifold of two boxes (centre + rotation in `a`/`b`, half extents `halfA`/`halfB`, all positive).
/// Returns false, with out.pointCount = 0, when the boxes are farther apart than `margin` along some separating
/// axis (or, rarely, when no clipped point comes within the margin). Otherwise fills `out`: normal from A to B,
/// 1 to 4 points on B's surface with depth >= -margin (depth > 0 penetration, <= 0 speculative gap) and feature
/// ids as described at the top of this header. For an edge-edge contact the single point is the closest point on
/// B's edge; the midpoint of the two edges' closest points is position - normal * depth / 2.
bool collideBoxes(const Transform& a, Vec3 halfA, const Transform& b, Vec3 halfB, float margin, Manifold& out);

/// Box-box pairs in SoA form: centre, unit quaternion and half extents of A and of B, and each pair's margin.
struct BoxPairs {
    const float *ax, *ay, *az, *aqx, *aqy, *aqz, *aqw, *ahx, *ahy, *ahz;
    const float *bx, *by, *bz, *bqx, *bqy, *bqz, *bqw, *bhx, *bhy, *bhz;
    const float* margin;
};

/// Pairs [0, n): the 15 axis tests and the face clipping of 16 pairs at a time in SIMD lanes (an edge-edge pair's
/// single point is found on its own), and a scalar tail for the rest; with `padded`, the input arrays hold whole
/// SIMD batches (entries up to n rounded up to the lane count are readable) and the tail runs in lanes as well.
/// Pair k's manifold goes to out[outIndex[k]] (out[k] without an index) and is exactly what collideBoxes gives.
void collideBoxesBatch(const BoxPairs& in, std::size_t n, Manifold* out, const std::uint32_t* outIndex = nullptr,
                       bool padded = false);
/// The same, one pair at a time (the scalar reference).
void collideBoxesBatchScalar(const BoxPairs& in, std::size_t n, Manifold* out, const std::uint32_t* outIndex = nullptr);

}  // namespace rubble::detail
