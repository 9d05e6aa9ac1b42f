#pragma once
// Contact manifolds: what the narrow phase hands to the contact cache and the solver.
#include <cstdint>

#include "rubble/math.h"

namespace rubble::detail {

inline constexpr int kMaxManifoldPoints = 4;

/// One contact point. `depth` > 0 is penetration; depth <= 0 is a speculative point whose surfaces are still
/// -depth apart (reported while within the contact margin so that the solver can stop an approach in time).
struct ContactPoint {
    Vec3 position;              ///< world space, on the surface of body B (the incident side after clipping)
    float depth = 0;            ///< along the manifold normal
    std::uint32_t feature = 0;  ///< stable id of the pair of features that made the point (for warm starting)
};

/// Contact between bodies A and B: a shared normal and up to four points.
/// Each point anchors the contact on both bodies: on B at `position`, on A at `position + shiftA`. A manifold the
/// narrow phase computes has one world point for both (shiftA zero); a recycled one (manifold_reuse.h) keeps each
/// anchor at its offset from its own body's centre, so the two anchors part by the bodies' relative motion since.
struct Manifold {
    Vec3 normal;  ///< unit, pointing from A to B
    int pointCount = 0;
    Vec3 shiftA;  ///< A's anchors less B's (the points), world
    ContactPoint points[kMaxManifoldPoints];
};

}  // namespace rubble::detail
