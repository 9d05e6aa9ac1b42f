#pragma once
// Effects: which physical effects a step simulates. The scene declares a set; the engine drops the effects that
// the world's content cannot show, so that the step is assembled only from the stages it needs.
#include <vector>

#include "rubble/settings.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

/// Declared effects less those the content cannot show:
/// - gravity: needs a non-zero gravity vector and a moving body with a non-zero gravity scale;
/// - rotation: needs a moving body that can turn: one spinning or under torque now, or a dynamic body that
///   contacts can turn (any non-sphere, or a sphere with friction);
/// - friction / restitution: need a body with a non-zero coefficient;
/// - joints: need a joint that has not broken (`anyJoints`); a joint can turn its bodies, so it keeps rotation;
/// - sleeping and continuous collision are choices, kept as declared.
/// `anyDamping` reports, from the same pass over the bodies, whether a moving body has damping (which makes the
/// velocity stage necessary even without gravity, forces or rotation).
EffectSet resolveEffects(EffectSet declared, const WorldSettings& settings, const MovingBodies& moving,
                         const StaticBodies& statics, const std::vector<Shape>& shapes, bool anyJoints,
                         bool& anyDamping);

}  // namespace rubble::detail
