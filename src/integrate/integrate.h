#pragma once
// Integration stage: motion from forces (integrate velocities, before the solver) and velocities to poses
// (integrate positions, after it). Both run over the SoA arrays of the moving bodies in SIMD lanes and in
// parallel chunks. Non-default integrators keep a per-body offset between the two halves (see integrate.cpp).
#include <cstdint>
#include <vector>

#include "rubble/math.h"
#include "rubble/settings.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

struct IntegrationParams {
    float dt = 1.0f / 60.0f;
    Vec3 gravity;          ///< zero when the Gravity effect is off
    bool rotation = true;  ///< false when the Rotation effect is off: angular motion is not integrated
    Integrator integrator = Integrator::SemiImplicitEuler;
    /// The force and torque accumulators may be non-zero. When false they are neither read nor cleared, which
    /// saves a sixth of the stage's memory traffic in the common case of gravity alone.
    bool forces = true;
    /// Clear the accumulators after use. With substeps, forces act over every substep and are cleared after the
    /// last one.
    bool clearForces = true;
    /// Leave bodies flagged asleep alone (Effect::Sleeping). When false the flags are not read.
    bool skipAsleep = false;
};

/// Per-body state carried from integrateVelocities to integratePositions for the non-default integrators.
struct IntegrationScratch {
    AlignedVector<float> dx, dy, dz;  ///< linear offset: positions use v + d
    AlignedVector<float> ex, ey, ez;  ///< angular offset: orientations use w + e
};

/// Applies gravity, accumulated forces and torques, gyroscopic motion and damping to the velocities of all
/// moving bodies; refreshes the world inverse inertia; clears the accumulators.
/// Dense indices of bodies whose state became non-finite are appended to `nonFinite` in ascending order;
/// their state is left as it was before the stage.
void integrateVelocities(MovingBodies& bodies, const IntegrationParams& params, IntegrationScratch& scratch,
                         TaskPool& pool, std::vector<std::uint32_t>& nonFinite);

/// Moves positions and orientations by the (solved) velocities; renormalises orientations.
/// Non-finite results are reported and left unapplied as above.
void integratePositions(MovingBodies& bodies, const IntegrationParams& params, const IntegrationScratch& scratch,
                        TaskPool& pool, std::vector<std::uint32_t>& nonFinite);

/// Same as the two functions above but one body at a time in plain scalar code, for the agreement test and as
/// the reference the SIMD kernels are measured against in perf/.
void integrateVelocitiesScalar(MovingBodies& bodies, const IntegrationParams& params, IntegrationScratch& scratch,
                               std::vector<std::uint32_t>& nonFinite);
void integratePositionsScalar(MovingBodies& bodies, const IntegrationParams& params, const IntegrationScratch& scratch,
                              std::vector<std::uint32_t>& nonFinite);

}  // namespace rubble::detail
