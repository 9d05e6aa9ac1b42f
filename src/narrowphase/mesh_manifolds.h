#pragma once
// One body against the triangles of a static mesh or heightfield: the triangle kernels give a manifold per triangle,
// and a body resting on a flat, finely tessellated floor would get one per triangle under it, each with its own
// share of the support. Manifolds whose normals agree (a flat or nearly flat patch) are merged into one, as Jolt's
// manifold reduction does: their points pooled, coincident ones (a point on an edge shared by two triangles) kept
// once, and four chosen by reduceContactPoints (clip.h). A box sliding over a tessellated floor is then held by the
// four corners it would have on a single face, whichever triangles they lie on, and a sphere by one point.
#include <cstddef>
#include <vector>

#include "narrowphase/manifold.h"

namespace rubble::detail {

struct ContactPair;

/// Normals whose cosine is at least this are merged (about 1 degree apart).
inline constexpr float kMergeNormalCosine = 0.99985f;
/// Points of merged manifolds closer than this are the same point (the deeper kept), m.
inline constexpr float kMergePointDistance = 1e-3f;

/// Merges manifolds [first, end) of one body against one mesh (pairs differ only in the triangle) that share a
/// normal; the merged manifold takes the normal of its deepest point's manifold and the lowest triangle index of
/// its group, in the position of its first member; feature ids that name a triangle's feature are mixed with the
/// triangle (featureOfTriangle, triangle_pairs.h), so that they are unique again. The order of the rest is kept.
/// Returns the new end.
std::size_t mergeTriangleManifolds(std::vector<ContactPair>& pairs, std::vector<Manifold>& manifolds,
                                   std::size_t first);

}  // namespace rubble::detail
