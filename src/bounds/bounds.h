#pragma once
// Update-bounds stage: the world AABB of every moving body, enlarged by its motion over the coming step (linear and
// rotational) and a contact margin, so that the broad phase finds pairs before they touch (speculative contacts).
#include <cstdint>
#include <span>
#include <vector>

#include "broadphase/broadphase.h"
#include "rubble/math.h"
#include "shapes/shape.h"
#include "shapes/shape_extents.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

/// Per-shape tables in SoA form, indexed by shape slot, for SIMD gathers.
struct ShapeBoundsTable {
    std::vector<float> centerX, centerY, centerZ, halfX, halfY, halfZ, radius, reach, inner;
    void set(std::uint32_t shape, const ShapeBoundsInfo& info);
};

struct BoundsParams {
    /// The step the boxes must cover: each box is swept by velocity * dt and grown by how far the angular velocity
    /// can turn the shape in dt (|w| dt times its reach, at most twice the reach).
    float dt = 1.0f / 60.0f;
    float margin = 0.0f;  ///< added on every side
};

/// Writes the world boxes of all moving bodies into `out` (resized to the body count). With `keepSleepers`, the
/// caller vouches that `out` holds the boxes of the same rows (rows may have been appended since) from a call with
/// the same params, and recomputes with updateBoundsOf the rows that fell asleep since: a batch of lanes that holds
/// only sleepers is left as it is (a sleeper's pose and zero velocity do not change while it sleeps, so its box is
/// the one computed before, to the bit), so that a world that sleeps pays for its awake bodies.
void updateBounds(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                  TaskPool& pool, Bounds& out, bool keepSleepers = false);
/// The boxes of the given rows only (the same values as updateBounds writes), into `out` of the body count.
void updateBoundsOf(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                    std::span<const std::uint32_t> rows, Bounds& out);
/// The same, one body at a time, as the reference for the SIMD path.
void updateBoundsScalar(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                        Bounds& out);

}  // namespace rubble::detail
