#pragma once
// The contact of two polytopes apart within the margin, when their separating-axis result misstates it.
//
// The separating-axis test finds the best of the face normals and edge-pair cross products. For polytopes that
// overlap, that axis is the least push-out direction; for polytopes apart, its separation equals their distance only
// where the closest features are a face and what lies over it, or two edges whose closest points lie inside both.
// Where a vertex or an edge's end is closest (a box falling corner first onto another's edge), the best axis
// understates the distance and points elsewhere, by tens of degrees, and a speculative contact built on it lets the
// bodies close by the wrong amount in the wrong direction. Box2D v3 takes the closest points of the reference and
// incident edges there; Jolt takes GJK's closest points for every speculative contact. Here the kernels keep their
// clipped manifold when it is exact -- its deepest point is a pair of surface points apart by at most the best
// axis's separation, which is a lower bound on the distance -- and otherwise replace it with one point at GJK's
// closest points, so GJK runs only for the pairs that need it. That includes pairs whose clipped manifold came out
// empty: the part of the incident face over the reference face lay beyond the margin, while a corner beside the
// face lay within it, and the pair was dropped.
#include <cstdint>

#include "narrowphase/gjk.h"
#include "narrowphase/manifold.h"

namespace rubble::detail {

/// A clipped contact is exact enough when its deepest point is within this fraction of the best axis's
/// separation (plus rounding, below): the direction between the true closest points is then within
/// acos(1 / 1.005), about 5.7 degrees, of the contact's normal, and the depth within 0.5%.
inline constexpr float kClosestPointsRelativeTolerance = 0.005f;
/// Rounding allowance, times the larger shape's size (largest half extent or vertex distance from the centre).
inline constexpr float kClosestPointsAbsoluteTolerance = 4e-6f;
/// Below this separation (times size) the shapes touch within rounding: the direction between closest points is
/// noise, and the clipped face contact is kept.
inline constexpr float kClosestPointsMinimumGap = 1e-4f;

/// Feature kind (bits 30-31) of a contact at the closest points: bits 8-15 (box) or 15-29 (hull) name A's vertex
/// nearest its closest point, bits 0-7 or 0-14 B's.
inline constexpr std::uint32_t kClosestPointsFeatureKind = 3u;

/// True when `m` (shapes apart by at least `bestSeparation`, the largest separation of the axes tested, which is
/// within the margin) is a speculative contact whose deepest point lies farther out than the tolerances above
/// allow, or is empty: every point clipped to the reference face lay beyond the margin while the closest points,
/// off the face, lie within it.
bool misstatesDistance(const Manifold& m, float bestSeparation, float size);

/// One point at the closest points of A and B: the normal from A to B between them, the depth minus their distance,
/// the position on B. Returns false (and leaves `out`) when GJK does not find them apart within the margin.
/// GJK's closest points, in A's and B's local frames, are returned for the feature ids.
bool contactAtClosestPoints(const GjkShape& a, const GjkShape& b, float margin, Manifold& out, Vec3& localA,
                            Vec3& localB);

}  // namespace rubble::detail
